//! The frozen real-space blocks and the precomputed spreading of fixed sources reproduce the plain Ewald sums (`rbc_solver::ewald::blocks`, `SpectralGrid::basis_spread`, `SpectralGrid::stresslet_basis_spread`).
//!
//! Sources are quadrature nodes of linearly interpolated nodal values (random nodes, random
//! barycentric weights), as the cell's and the wall's nodes are. The blocks regroup the same
//! floating-point terms, so they agree with the plain sums of the interpolated densities to
//! rounding (1e-12 relative, far below any Ewald tolerance).

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rbc_solver::ewald::lanes32::BlockPrecision;
use rbc_solver::ewald::{EwaldParams, Interp, NodeGroups, PeriodicStokes};

fn random_vectors(n: usize, scale: [f64; 3], offset: f64, rng: &mut ChaCha8Rng) -> Vec<Vector3<f64>> {
    (0..n).map(|_| Vector3::from_fn(|d, _| (rng.random::<f64>() - offset) * scale[d])).collect()
}

fn rel(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_squared()).sum();
    let den: f64 = b.iter().map(|y| y.norm_squared()).sum();
    (num / den).sqrt()
}

struct Case {
    ewald: PeriodicStokes,
    targets: Vec<Vector3<f64>>,
    sources: Vec<Vector3<f64>>,
    interp: Vec<Interp>,
    weights: Vec<f64>,
    normals: Vec<Vector3<f64>>,
    nodal: Vec<Vector3<f64>>,
}

impl Case {
    /// `n_basis` nodal values, `n` sources interpolating from three random nodes each; the targets
    /// include some sources themselves (coincident pairs) and points outside the box (wrapping).
    fn new(seed: u64) -> Self {
        let box_len = [6.0, 3.0, 2.5];
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (n, n_basis) = (300, 60);
        let sources = random_vectors(n, box_len, 0.1, &mut rng);
        let interp: Vec<Interp> = (0..n)
            .map(|_| {
                let (a, b) = (rng.random::<f64>(), rng.random::<f64>());
                let (l0, l1) = (a.min(b), (a.max(b) - a.min(b)));
                [(rng.random_range(0..n_basis), l0), (rng.random_range(0..n_basis), l1), (rng.random_range(0..n_basis), 1.0 - l0 - l1)]
            })
            .collect();
        let weights = (0..n).map(|_| 0.1 + rng.random::<f64>()).collect();
        let normals = random_vectors(n, [0.2; 3], 0.5, &mut rng);
        let nodal = random_vectors(n_basis, [1.0; 3], 0.5, &mut rng);
        let mut targets = sources[..40].to_vec();
        targets.extend(random_vectors(50, [7.0, 4.0, 3.5], 0.1, &mut rng));
        // a cutoff longer than half the box side along z: images seen more than once per direction
        let ewald = PeriodicStokes::new(box_len, EwaldParams::with_xi(box_len, 2.2, 1e-8).unwrap()).unwrap();
        Self { ewald, targets, sources, interp, weights, normals, nodal }
    }

    fn densities(&self) -> Vec<Vector3<f64>> {
        self.interp.iter().map(|ip| ip.iter().map(|&(v, l)| self.nodal[v] * l).sum()).collect()
    }
}

#[test]
fn stokeslet_blocks_match_real_space() {
    let c = Case::new(11);
    assert!(c.ewald.params().r_cut > 1.25, "the test wants a cutoff beyond half the smallest side");
    let forces: Vec<Vector3<f64>> = c.densities().iter().zip(&c.weights).map(|(d, w)| d * *w).collect();
    let mut plain = vec![Vector3::zeros(); c.targets.len()];
    c.ewald.stokeslet_real(&c.targets, &c.sources, &forces, &mut plain);
    let blocks = c.ewald.stokeslet_real_blocks(&c.targets, &c.sources, &c.weights, &c.interp, c.nodal.len()).unwrap();
    let mut out = vec![Vector3::zeros(); c.targets.len()];
    blocks.apply(&c.nodal, &mut out);
    let e = rel(&out, &plain);
    assert!(e < 1e-12, "Stokeslet blocks vs real-space sum: {e:e}");
}

#[test]
fn stresslet_blocks_match_real_space() {
    let c = Case::new(12);
    let dens = c.densities();
    let mut plain = vec![Vector3::zeros(); c.targets.len()];
    c.ewald.stresslet_real(&c.targets, &c.sources, &dens, &c.normals, &mut plain);
    let blocks = c.ewald.stresslet_real_blocks(&c.targets, &c.sources, &c.normals, &c.interp, c.nodal.len()).unwrap();
    let mut out = vec![Vector3::zeros(); c.targets.len()];
    blocks.apply(&c.nodal, &mut out);
    let e = rel(&out, &plain);
    assert!(e < 1e-12, "stresslet blocks vs real-space sum: {e:e}");
}

/// The blocks built group by group (the quadrature nodes of flat triangles: 7 nodes around a
/// centroid, the same barycentric weights in every group) equal the plain real-space sum of the
/// interpolated densities, with targets on nodes (coincident pairs), outside the box (wrapping),
/// groups straddling the box faces, and a cutoff beyond half the box side (several images).
#[test]
fn grouped_stresslet_blocks_match_real_space() {
    let box_len = [6.0, 3.0, 2.5];
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let (n_groups, n_basis) = (60, 40);
    let bary: Vec<[f64; 3]> = (0..7)
        .map(|_| {
            let (a, b) = (rng.random::<f64>(), rng.random::<f64>());
            [a.min(b), a.max(b) - a.min(b), 1.0 - a.max(b)]
        })
        .collect();
    let groups: Vec<[usize; 3]> = (0..n_groups).map(|_| [0, 1, 2].map(|_| rng.random_range(0..n_basis))).collect();
    let centroids = random_vectors(n_groups, box_len, 0.0, &mut rng);
    let sources: Vec<Vector3<f64>> = centroids.iter().flat_map(|c| (0..7).map(|_| c + Vector3::from_fn(|_, _| (rng.random::<f64>() - 0.5) * 0.6)).collect::<Vec<_>>()).collect();
    let normals = random_vectors(sources.len(), [0.2; 3], 0.5, &mut rng);
    let nodal = random_vectors(n_basis, [1.0; 3], 0.5, &mut rng);
    let interp: Vec<Interp> = (0..sources.len()).map(|k| { let (g, j) = (k / 7, k % 7); [0, 1, 2].map(|c| (groups[g][c], bary[j][c])) }).collect();
    let dens: Vec<Vector3<f64>> = interp.iter().map(|ip| ip.iter().map(|&(v, l)| nodal[v] * l).sum()).collect();
    let mut targets: Vec<Vector3<f64>> = sources.iter().step_by(9).copied().collect();
    targets.extend(random_vectors(50, [7.0, 4.0, 3.5], 0.1, &mut rng));
    let ewald = PeriodicStokes::new(box_len, EwaldParams::with_xi(box_len, 2.2, 1e-8).unwrap()).unwrap();
    assert!(ewald.params().r_cut > 1.25, "the test wants a cutoff beyond half the smallest side");
    let mut plain = vec![Vector3::zeros(); targets.len()];
    ewald.stresslet_real(&targets, &sources, &dens, &normals, &mut plain);
    let src = NodeGroups { sources: &sources, normals: &normals, groups: &groups, bary: &bary };
    let blocks = ewald.stresslet_real_blocks_grouped(&targets, src, n_basis).unwrap();
    let mut out = vec![Vector3::zeros(); targets.len()];
    blocks.apply(&nodal, &mut out);
    let e = rel(&out, &plain);
    assert!(e < 1e-12, "grouped stresslet blocks vs real-space sum: {e:e}");
    // the single layer fused into the build: the same blocks, and the real-space Stokeslet sum of
    // the forces at the targets that no source coincides with (a coincident pair takes the
    // self term in the plain sum; the cell's vertices never meet its interior quadrature nodes)
    let forces = random_vectors(sources.len(), [1.0; 3], 0.5, &mut rng);
    let apart = &targets[sources.len().div_ceil(9)..];
    let (fused, single) = ewald.stresslet_real_blocks_with_single_layer(apart, src, Some(&forces), n_basis, BlockPrecision::Double).unwrap();
    let (alone, none) = ewald.stresslet_real_blocks_with_single_layer(apart, src, None, n_basis, BlockPrecision::Double).unwrap();
    assert!(none.is_none());
    let (mut a, mut b) = (vec![Vector3::zeros(); apart.len()], vec![Vector3::zeros(); apart.len()]);
    fused.apply(&nodal, &mut a);
    alone.apply(&nodal, &mut b);
    assert_eq!(a, b, "the blocks do not depend on the fused single layer");
    let mut stokeslet = vec![Vector3::zeros(); apart.len()];
    ewald.stokeslet_real(apart, &sources, &forces, &mut stokeslet);
    let e = rel(&single.unwrap(), &stokeslet);
    assert!(e < 1e-12, "fused single layer vs real-space Stokeslet sum: {e:e}");
    assert!(ewald.stresslet_real_blocks_with_single_layer(apart, src, Some(&forces[1..]), n_basis, BlockPrecision::Double).is_err(), "a force per source");
    // a vertex index beyond the basis and a source count that is not 7 per group are typed errors
    let bad = [[0, 1, n_basis]];
    assert!(ewald.stresslet_real_blocks_grouped(&targets, NodeGroups { groups: &bad, sources: &sources[..7], normals: &normals[..7], ..src }, n_basis).is_err());
    assert!(ewald.stresslet_real_blocks_grouped(&targets, NodeGroups { sources: &sources[..20], ..src }, n_basis).is_err());
}

/// The Stokeslet blocks built group by group (the wall's quadrature nodes: 7 per sub-triangle,
/// every node of a group interpolating from its parent triangle's three vertices with its own
/// barycentric and quadrature weights) equal the plain real-space sum of the interpolated forces,
/// with targets outside the box (wrapping), groups straddling the box faces and a cutoff beyond
/// half the box side; a target on a source takes the plain build (its self term); groups that do
/// not share their vertices are a typed error.
#[test]
fn grouped_stokeslet_blocks_match_real_space() {
    let box_len = [6.0, 3.0, 2.5];
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    let (n_groups, n_basis, m) = (70, 40, 7);
    let centroids = random_vectors(n_groups, box_len, 0.0, &mut rng);
    let mut sources = Vec::new();
    let mut interp: Vec<Interp> = Vec::new();
    for c in &centroids {
        let tri = [0, 1, 2].map(|_| rng.random_range(0..n_basis));
        for _ in 0..m {
            sources.push(c + Vector3::from_fn(|_, _| (rng.random::<f64>() - 0.5) * 0.8));
            let (a, b) = (rng.random::<f64>(), rng.random::<f64>());
            interp.push([(tri[0], a.min(b)), (tri[1], a.max(b) - a.min(b)), (tri[2], 1.0 - a.max(b))]);
        }
    }
    let weights: Vec<f64> = (0..sources.len()).map(|_| 0.05 + rng.random::<f64>()).collect();
    let nodal = random_vectors(n_basis, [1.0; 3], 0.5, &mut rng);
    let forces: Vec<Vector3<f64>> = interp.iter().zip(&weights).map(|(ip, w)| ip.iter().map(|&(v, l)| nodal[v] * l).sum::<Vector3<f64>>() * *w).collect();
    let targets = random_vectors(80, [7.0, 4.0, 3.5], 0.1, &mut rng);
    let ewald = PeriodicStokes::new(box_len, EwaldParams::with_xi(box_len, 2.2, 1e-8).unwrap()).unwrap();
    assert!(ewald.params().r_cut > 1.25, "the test wants a cutoff beyond half the smallest side");
    let apply = |targets: &[Vector3<f64>], grouped: bool| {
        let blocks = if grouped {
            ewald.stokeslet_real_blocks_grouped(targets, &sources, &weights, &interp, m, n_basis).unwrap()
        } else {
            ewald.stokeslet_real_blocks(targets, &sources, &weights, &interp, n_basis).unwrap()
        };
        let mut out = vec![Vector3::zeros(); targets.len()];
        blocks.apply(&nodal, &mut out);
        out
    };
    let mut plain = vec![Vector3::zeros(); targets.len()];
    ewald.stokeslet_real(&targets, &sources, &forces, &mut plain);
    let e = rel(&apply(&targets, true), &plain);
    assert!(e < 1e-12, "grouped Stokeslet blocks vs real-space sum: {e:e}");
    // a target on a source: the plain build with its self term, to the last bit
    let mut on = targets.clone();
    on[5] = sources[33];
    assert_eq!(apply(&on, true), apply(&on, false), "a coincident target takes the plain build");
    let mut plain_on = vec![Vector3::zeros(); on.len()];
    ewald.stokeslet_real(&on, &sources, &forces, &mut plain_on);
    assert!(rel(&apply(&on, true), &plain_on) < 1e-12);
    // a group whose nodes do not share their vertices, groups that do not divide the sources
    let mut bad = interp.clone();
    bad[9][1].0 = (bad[9][1].0 + 1) % n_basis;
    assert!(ewald.stokeslet_real_blocks_grouped(&targets, &sources, &weights, &bad, m, n_basis).is_err());
    assert!(ewald.stokeslet_real_blocks_grouped(&targets, &sources[..20], &weights[..20], &interp[..20], m, n_basis).is_err());
    assert!(ewald.stokeslet_real_blocks_grouped(&targets, &sources, &weights, &interp, 9, n_basis).is_err());
}

#[test]
fn basis_spreading_matches_fourier_part() {
    let c = Case::new(13);
    let forces: Vec<Vector3<f64>> = c.densities().iter().zip(&c.weights).map(|(d, w)| d * *w).collect();
    let mut plain = vec![Vector3::zeros(); c.targets.len()];
    c.ewald.stokeslet_fourier_add(&c.targets, &c.sources, &forces, &mut plain);
    let spread = c.ewald.basis_spread(&c.sources, &c.weights, &c.interp, c.nodal.len()).unwrap();
    let mut out = vec![Vector3::zeros(); c.targets.len()];
    c.ewald.stokeslet_fourier_basis_add(&spread, &c.nodal, &c.targets, &mut out).unwrap();
    let e = rel(&out, &plain);
    // the map's weights are stored in single precision (6e-8 relative each)
    assert!(e < 1e-6, "precomputed spreading vs Fourier part: {e:e}");
}

#[test]
fn stresslet_basis_spreading_matches_fourier_part() {
    let c = Case::new(15);
    let mut plain = vec![Vector3::zeros(); c.targets.len()];
    c.ewald.stresslet_fourier_add(&c.targets, &c.sources, &c.densities(), &c.normals, &mut plain);
    let spread = c.ewald.stresslet_basis_spread(&c.sources, &c.normals, &c.interp, c.nodal.len()).unwrap();
    let mut out = vec![Vector3::zeros(); c.targets.len()];
    c.ewald.stresslet_fourier_basis_add(&spread, &c.nodal, &c.targets, &mut out).unwrap();
    let e = rel(&out, &plain);
    // the map's weights are stored in single precision (6e-8 relative each)
    assert!(e < 1e-6, "precomputed stresslet spreading vs Fourier part: {e:e}");
    assert!(c.ewald.stresslet_fourier_basis_add(&spread, &c.nodal[1..], &c.targets, &mut out).is_err(), "nodal densities of another basis");
}

/// A source index beyond the basis is a typed error, not a panic.
#[test]
fn bad_interpolation_is_an_error() {
    let c = Case::new(14);
    let mut interp = c.interp.clone();
    interp[7][1].0 = c.nodal.len();
    assert!(c.ewald.stresslet_real_blocks(&c.targets, &c.sources, &c.normals, &interp, c.nodal.len()).is_err());
    assert!(c.ewald.basis_spread(&c.sources, &c.weights, &interp, c.nodal.len()).is_err());
    assert!(c.ewald.stresslet_basis_spread(&c.sources, &c.normals, &interp, c.nodal.len()).is_err());
}

/// The cell's stresslet blocks with their kernels in single precision
/// ([`BlockPrecision::Single`]) against the double ones, as the channel builds them: the paper's
/// discocyte (2048 triangles) off the axis of the channel's periodic box, its vertices as the
/// targets plus points 0.3-1 um off the membrane, the splitting of Ewald tolerance 1e-4 (`xi r_cut`
/// 3.2), random nodal velocities and forces. The applied blocks agree to 1e-6 of their rms and
/// the fused single layer to 1e-6 of its (two orders of magnitude below the Ewald tolerance); on
/// a CPU with AVX-512 the single path must actually have run (the results differ from the
/// double ones), elsewhere both are the double path.
#[test]
fn single_precision_stresslet_blocks_match_double_ones() {
    use rbc_solver::bim::surface::Surface;
    use rbc_solver::channel::cell_layer::CellNodes;
    use rbc_solver::channel::double_layer::rule_bary;
    use rbc_solver::mesh::discocyte;

    let box_len = [42.7, 16.0, 14.0];
    let mesh = discocyte(4).transformed(&nalgebra::Rotation3::from_euler_angles(0.3, 0.2, 0.1), &Vector3::new(21.0, 9.2, 7.1));
    let surface = Surface::new(&mesh).unwrap();
    let nodes = CellNodes::new(&surface);
    let bary = rule_bary(&surface);
    let n_basis = surface.n_vertices();
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let mut targets = surface.vertices.clone();
    targets.extend(surface.vertices.iter().step_by(7).map(|v| v + Vector3::from_fn(|_, _| rng.random::<f64>() - 0.5).normalize() * (0.3 + 0.7 * rng.random::<f64>())));
    let forces = random_vectors(nodes.positions.len(), [1.0; 3], 0.5, &mut rng);
    let nodal = random_vectors(n_basis, [1.0; 3], 0.5, &mut rng);
    let ewald = PeriodicStokes::new(box_len, EwaldParams::with_xi(box_len, 0.933, 1e-4).unwrap()).unwrap();
    let p = ewald.params();
    assert!(p.xi * p.r_cut > 3.0 && p.xi * p.r_cut < 4.0, "the channel's splitting: xi r_cut = {}", p.xi * p.r_cut);
    let src = NodeGroups { sources: &nodes.positions, normals: &nodes.weighted_normals, groups: &surface.triangles, bary: &bary };
    let build = |precision| {
        let (blocks, single) = ewald.stresslet_real_blocks_with_single_layer(&targets, src, Some(&forces), n_basis, precision).unwrap();
        let mut out = vec![Vector3::zeros(); targets.len()];
        blocks.apply(&nodal, &mut out);
        (blocks.n_blocks(), out, single.unwrap())
    };
    let (n_double, double, single_layer_double) = build(BlockPrecision::Double);
    let (n_single, single, single_layer_single) = build(BlockPrecision::Single);
    assert_eq!(n_double, n_single, "the same blocks");
    let e_blocks = rel(&single, &double);
    let e_layer = rel(&single_layer_single, &single_layer_double);
    eprintln!("single vs double: blocks {e_blocks:e}, single layer {e_layer:e}");
    assert!(e_blocks < 1e-6, "applied blocks: relative rms difference {e_blocks:e}");
    assert!(e_layer < 1e-6, "fused single layer: relative rms difference {e_layer:e}");
    if rbc_solver::bim::kernels::avx512_available() {
        assert!(e_blocks > 0.0 && e_layer > 0.0, "the single-precision path ran");
    } else {
        // (single precision would differ by ~1e-7)
        assert!(e_blocks < 1e-14 && e_layer < 1e-14, "without AVX-512 `Single` builds the double-precision blocks: {e_blocks:e}, {e_layer:e}");
    }
}
