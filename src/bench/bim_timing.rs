//! Speed of the free-space boundary-integral kernels, operators and solve, for [`super::solver`] (`rbc-bench solver`).

use std::time::Instant;

use nalgebra::Vector3;
use rayon::prelude::*;

use super::clock::{min_wall_s, pool};
use rbc_solver::bim::double_layer::DoubleLayer;
use rbc_solver::viscosity::ViscosityContrast;
use rbc_solver::bim::kernels::{
    avx512_available, stokeslet, stokeslet_sum, stokeslet_sum_portable, stresslet, stresslet_sum, stresslet_sum_portable,
    tiled_sums, SourceChunk, LANES,
};
use rbc_solver::bim::single_layer::SingleLayer;
use rbc_solver::bim::surface::Surface;
use rbc_solver::bim::{BimError, BimOptions, FreeSpaceStokes, SolveStats};
use rbc_solver::flow::SimpleShear;
use rbc_solver::mesh::{discocyte, sphere};

/// Throughput of the kernel sums (pairs per second), all through the tiled driver
/// [`tiled_sums`] that the operators use, except the naive loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KernelThroughput {
    pub targets: usize,
    pub sources: usize,
    pub threads: usize,
    /// Whether the explicit AVX-512 kernels ran (else the portable ones are measured twice).
    pub avx512: bool,
    /// Stokeslet (single-layer) pairs per second, the kernels the operators use.
    pub stokeslet_pairs_per_s: f64,
    /// Stresslet (double-layer) pairs per second, the kernels the operators use.
    pub stresslet_pairs_per_s: f64,
    /// Portable lane loops (compiler-vectorised, exact `1/sqrt`): Stokeslet pairs per second.
    pub portable_stokeslet_pairs_per_s: f64,
    /// Portable lane loops: stresslet pairs per second.
    pub portable_stresslet_pairs_per_s: f64,
    /// Naive array-of-structs loop over nalgebra vectors, Stokeslet + stresslet per pair, pairs per second.
    pub naive_pairs_per_s: f64,
}

impl KernelThroughput {
    /// Time (s) of one single + double layer sum over `targets x sources` pairs at the measured rates.
    pub fn single_plus_double_seconds(&self, targets: usize, sources: usize) -> f64 {
        let p = (targets * sources) as f64;
        p / self.stokeslet_pairs_per_s + p / self.stresslet_pairs_per_s
    }
}

/// Kernel microbenchmark: `targets x sources` Stokeslet and stresslet sums on `threads` threads
/// (quasi-random points in a cube of side 8 um), best of `repeats`.
pub fn kernel_throughput(targets: usize, sources: usize, threads: usize, repeats: usize) -> KernelThroughput {
    // Additive recurrence with irrational steps (a Kronecker sequence): deterministic, well
    // spread, and no RNG dependency.
    let mut k = 0.0f64;
    let mut v = || {
        k += 1.0;
        let frac = |a: f64| (k * a).fract() * 8.0 - 4.0;
        Vector3::new(frac(0.754_877_666_246_692_7), frac(0.569_840_290_998_053_2), frac(0.430_159_709_001_946_8))
    };
    let xs: Vec<Vector3<f64>> = (0..targets).map(|_| v()).collect();
    let src: Vec<[Vector3<f64>; 3]> = (0..sources).map(|_| [v(), v() * 0.01, v()]).collect();
    let mut chunks = vec![SourceChunk::padding(); sources.div_ceil(LANES)];
    for (p, [y, n, d]) in src.iter().enumerate() {
        let (c, l) = (&mut chunks[p / LANES], p % LANES);
        (c.x[l], c.y[l], c.z[l]) = (y.x, y.y, y.z);
        (c.nx[l], c.ny[l], c.nz[l]) = (n.x, n.y, n.z);
        (c.dx[l], c.dy[l], c.dz[l]) = (d.x, d.y, d.z);
    }
    let pool = pool(threads);
    let pairs = (targets * sources) as f64;
    let u0 = Vector3::new(0.1, 0.2, 0.3);
    let mut out = vec![Vector3::zeros(); targets];
    let mut time = |kernel: &(dyn Fn(usize, &[SourceChunk]) -> Vector3<f64> + Sync)| {
        pool.install(|| min_wall_s(repeats, || tiled_sums(&chunks, &mut out, kernel)))
    };
    let ts = time(&|i, tile| stokeslet_sum(&xs[i], 0.5, tile));
    let td = time(&|i, tile| stresslet_sum(&xs[i], &u0, tile));
    let tps = time(&|i, tile| stokeslet_sum_portable(&xs[i], 0.5, tile));
    let tpd = time(&|i, tile| stresslet_sum_portable(&xs[i], &u0, tile));
    let mut sink = 0.0;
    let tn = pool.install(|| {
        min_wall_s(repeats.min(3), || {
            let s: f64 = xs
                .par_iter()
                .with_min_len(4)
                .map(|x| {
                    let mut acc = Vector3::zeros();
                    for [y, n, d] in &src {
                        let r = x - y;
                        acc += stokeslet(&r, &(d - n * 0.5)) + stresslet(&r, &(d - u0), n);
                    }
                    acc.x
                })
                .sum();
            sink += s;
        })
    });
    std::hint::black_box((sink, &out));
    KernelThroughput {
        targets,
        sources,
        threads,
        avx512: avx512_available(),
        stokeslet_pairs_per_s: pairs / ts,
        stresslet_pairs_per_s: pairs / td,
        portable_stokeslet_pairs_per_s: pairs / tps,
        portable_stresslet_pairs_per_s: pairs / tpd,
        naive_pairs_per_s: pairs / tn,
    }
}

/// Wall time of one operator application on a sphere mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OperatorTiming {
    pub triangles: usize,
    pub vertices: usize,
    pub quadrature_nodes: usize,
    pub threads: usize,
    /// Single layer incl. density interpolation and Duffy corrections (s).
    pub single_layer_s: f64,
    /// Double layer incl. density interpolation (s).
    pub double_layer_s: f64,
}

/// One single-layer and one double-layer application on the octahedron-subdivision sphere ([`rbc_solver::mesh::sphere`]) of `level`
/// (radius 4 um, smooth random-ish densities), best of `repeats`, on `threads` threads.
pub fn operator_timing(level: usize, threads: usize, repeats: usize) -> Result<OperatorTiming, BimError> {
    let mesh = sphere(level, 4.0);
    let s = Surface::new(&mesh)?;
    let q: Vec<Vector3<f64>> = s.vertices.iter().map(|x| Vector3::new(x.y.sin(), x.z * x.x, 1.0 + x.x)).collect();
    let sl = SingleLayer::new(&s, BimOptions::default().duffy_nodes, true);
    let dl = DoubleLayer::new(&s);
    let pool = pool(threads);
    let mut out = vec![Vector3::zeros(); s.n_vertices()];
    let tsl = pool.install(|| min_wall_s(repeats, || out = sl.apply(&q)));
    let tdl = pool.install(|| min_wall_s(repeats, || dl.apply_into(&q, &mut out)));
    std::hint::black_box(&out);
    Ok(OperatorTiming {
        triangles: s.triangles.len(),
        vertices: s.n_vertices(),
        quadrature_nodes: s.n_nodes,
        threads,
        single_layer_s: tsl,
        double_layer_s: tdl,
    })
}

/// A full solve on the paper's cell: the Evans-Fung discocyte ([`rbc_solver::mesh::discocyte`]) of
/// `level`, a smooth load without symmetry (`|f| ~ 1 Pa`), simple shear 200/s, mu = 1.2e-3 Pa s,
/// viscosity ratio `lambda`, default options, on `threads` threads.
/// Returns the stats and the wall time (s) of [`FreeSpaceStokes::velocity`].
pub fn solve_timing(level: usize, lambda: f64, threads: usize) -> Result<(SolveStats, f64), BimError> {
    let mesh = discocyte(level);
    let f: Vec<Vector3<f64>> = mesh
        .vertices
        .iter()
        .map(|x| {
            Vector3::new((0.6 * x.x + 0.7 * x.y + 0.3).sin(), (0.5 * x.z - 0.4 * x.y).cos(), 0.2 + (0.5 * x.z + 0.3 * x.x).sin())
        })
        .collect();
    let solver = FreeSpaceStokes::new(1.2e-3, ViscosityContrast::new(lambda).unwrap(), BimOptions::default());
    let pool = pool(threads);
    let t = Instant::now();
    let (_, stats) = pool.install(|| solver.velocity(&mesh, &f, &SimpleShear { shear_rate_per_s: 200.0 }))?;
    Ok((stats, t.elapsed().as_secs_f64()))
}
