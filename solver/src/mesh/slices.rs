//! Volume, area and centroid of a closed triangulated surface, the exact gradient of the discrete volume, and the number of its vertices at the head of a state.
//!
//! On raw vertex slices (the state vector of a run), independently of the [`super::Mesh`]
//! container: the runner, the failure checks and the volume-drift correction need them.
//! A state may carry extra entries after the surface's vertices (the wall displacements of
//! the penalty-wall dynamics); [`cell_len`] says where the surface's part ends.

use nalgebra::Vector3;

/// Number of cell vertices in a state whose cell has connectivity `triangles`: one past the
/// largest referenced vertex (the extra state follows the cell's vertices).
pub fn cell_len(triangles: &[[usize; 3]]) -> usize {
    triangles.iter().flatten().max().map_or(0, |&m| m + 1)
}

/// Enclosed volume (um^3) of a closed, outward-oriented triangulation:
/// `V = 1/6 sum_t x_a . (x_b x x_c)` (divergence theorem, exact for flat triangles).
pub fn volume(x: &[Vector3<f64>], triangles: &[[usize; 3]]) -> f64 {
    triangles.iter().map(|&[a, b, c]| x[a].dot(&x[b].cross(&x[c]))).sum::<f64>() / 6.0
}

/// Total area (um^2): `sum_t |(x_b - x_a) x (x_c - x_a)| / 2`.
pub fn area(x: &[Vector3<f64>], triangles: &[[usize; 3]]) -> f64 {
    triangles.iter().map(|&[a, b, c]| (x[b] - x[a]).cross(&(x[c] - x[a])).norm()).sum::<f64>() / 2.0
}

/// Volume centroid (um) of the enclosed body: `c = sum_t v_t (x_a + x_b + x_c) / 4 / V`
/// with `v_t` the signed volume of the tetrahedron spanned by the origin and triangle `t`.
pub fn centroid(x: &[Vector3<f64>], triangles: &[[usize; 3]]) -> Vector3<f64> {
    let mut m = Vector3::zeros();
    let mut v = 0.0;
    for &[a, b, c] in triangles {
        let vt = x[a].dot(&x[b].cross(&x[c])) / 6.0;
        m += vt * (x[a] + x[b] + x[c]) / 4.0;
        v += vt;
    }
    if v != 0.0 {
        m / v
    } else {
        // no enclosed volume (no triangles): fall back to the vertex mean
        x.iter().sum::<Vector3<f64>>() / x.len().max(1) as f64
    }
}

/// Gradient of the discrete volume with respect to each vertex (um^2):
/// `dV/dx_i = sum_{t containing i} A_t n_t / 3`, exactly, for a closed surface
/// (the terms that distinguish it from `1/6 sum x_b x x_c` cancel around each vertex fan).
/// So `dV/dt = sum_i g_i . u_i` holds exactly for the discrete surface moving with vertex velocities `u_i`.
pub fn volume_gradient(x: &[Vector3<f64>], triangles: &[[usize; 3]], out: &mut [Vector3<f64>]) {
    out.iter_mut().for_each(|g| *g = Vector3::zeros());
    for &[a, b, c] in triangles {
        let an = (x[b] - x[a]).cross(&(x[c] - x[a])) / 6.0; // A_t n_t / 3
        out[a] += an;
        out[b] += an;
        out[c] += an;
    }
}

/// Unit normal and area (um^2) of triangle `t`.
pub fn triangle_normal_area(x: &[Vector3<f64>], t: [usize; 3]) -> (Vector3<f64>, f64) {
    let n = (x[t[1]] - x[t[0]]).cross(&(x[t[2]] - x[t[0]]));
    let a = n.norm();
    if a > 0.0 {
        (n / a, a / 2.0)
    } else {
        (Vector3::zeros(), 0.0)
    }
}


/// Second moment of the enclosed volume about its centroid (um^5):
/// `M = Int_V (x - c)(x - c)^T dV`, summed over the tetrahedra `(c, x_a, x_b, x_c)`
/// with the exact tetrahedron formula `Int x x^T dV = V_t/20 (sum_k p_k p_k^T + S S^T)`,
/// `S = sum_k p_k` over its four corners.
pub fn second_moment(x: &[Vector3<f64>], triangles: &[[usize; 3]]) -> nalgebra::Matrix3<f64> {
    let c = centroid(x, triangles);
    let mut m = nalgebra::Matrix3::zeros();
    for &[a, b, d] in triangles {
        let (p1, p2, p3) = (x[a] - c, x[b] - c, x[d] - c);
        let vt = p1.dot(&p2.cross(&p3)) / 6.0;
        let s = p1 + p2 + p3;
        m += vt / 20.0 * (p1 * p1.transpose() + p2 * p2.transpose() + p3 * p3.transpose() + s * s.transpose());
    }
    m
}

/// Taylor deformation `D = (L - B) / (L + B)` in the plane normal to `plane_normal`
/// (the shear plane; for `u = (rate z, 0, 0)` the normal is y), and the angle (rad)
/// of the long axis from the x axis towards z. `L`, `B` are the semi-axes of the
/// ellipsoid with the same second moment of volume (`M = V/5 diag(a_k^2)`), as in
/// Ramanujan & Pozrikidis, JFM 361, 117 (1998). The two principal axes closest to
/// the plane are used.
pub fn taylor_deformation(x: &[Vector3<f64>], triangles: &[[usize; 3]], plane_normal: &Vector3<f64>) -> (f64, f64) {
    let v = volume(x, triangles);
    let eig = second_moment(x, triangles).symmetric_eigen();
    let n = plane_normal.normalize();
    let mut axes: Vec<(f64, Vector3<f64>)> = (0..3)
        .map(|k| ((5.0 * eig.eigenvalues[k].max(0.0) / v).sqrt(), eig.eigenvectors.column(k).into_owned()))
        .collect();
    // drop the axis most aligned with the plane normal
    axes.sort_by(|p, q| p.1.dot(&n).abs().total_cmp(&q.1.dot(&n).abs()));
    let (mut l, mut b) = (axes[0], axes[1]);
    if b.0 > l.0 {
        std::mem::swap(&mut l, &mut b);
    }
    let mut dir = l.1;
    if dir.x < 0.0 {
        dir = -dir;
    }
    ((l.0 - b.0) / (l.0 + b.0), dir.z.atan2(dir.x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Octahedron with vertices at distance `r` from `c`, outward-oriented.
    pub(crate) fn octahedron(r: f64, c: Vector3<f64>) -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
        let v = vec![
            Vector3::new(r, 0.0, 0.0),
            Vector3::new(-r, 0.0, 0.0),
            Vector3::new(0.0, r, 0.0),
            Vector3::new(0.0, -r, 0.0),
            Vector3::new(0.0, 0.0, r),
            Vector3::new(0.0, 0.0, -r),
        ];
        let t = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        (v.into_iter().map(|p| p + c).collect(), t)
    }

    #[test]
    fn octahedron_volume_area_centroid_exact() {
        let c = Vector3::new(1.0, -2.0, 3.0);
        let (x, t) = octahedron(2.0, c);
        // Regular octahedron of circumradius r: V = 4 r^3 / 3, A = 4 sqrt(3) r^2.
        assert!((volume(&x, &t) - 4.0 * 8.0 / 3.0).abs() < 1e-12);
        assert!((area(&x, &t) - 4.0 * 3f64.sqrt() * 4.0).abs() < 1e-12);
        assert!((centroid(&x, &t) - c).norm() < 1e-12);
    }

    #[test]
    fn taylor_deformation_of_an_ellipsoid_is_exact() {
        // a sphere mesh stretched to semi-axes (1.2, 1, 0.8), rotated by 30 degrees about y:
        // the second moment of the polyhedron converges to the ellipsoid's, so D -> (1.2 - 0.8)/2 = 0.2
        let mesh = crate::mesh::sphere(4, 1.0);
        let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), -std::f64::consts::PI / 6.0);
        let x: Vec<Vector3<f64>> = mesh.vertices.iter().map(|p| rot * Vector3::new(1.2 * p.x, p.y, 0.8 * p.z)).collect();
        let (d, angle) = taylor_deformation(&x, &mesh.triangles, &Vector3::y());
        // the polyhedron is a linear map of the sphere mesh, hence an exact linear image: its moment
        // is A M_sphere A^T with M_sphere isotropic to O(h^2) only through the mesh's cubic symmetry
        assert!((d - 0.2).abs() < 1e-3, "D = {d}");
        assert!((angle - std::f64::consts::PI / 6.0).abs() < 1e-3, "angle = {angle}");
    }

    #[test]
    fn volume_gradient_matches_finite_differences() {
        let (mut x, t) = octahedron(1.3, Vector3::new(0.2, 0.1, -0.4));
        x[4] += Vector3::new(0.1, -0.05, 0.2); // break symmetry
        let mut g = vec![Vector3::zeros(); x.len()];
        volume_gradient(&x, &t, &mut g);
        let eps = 1e-6;
        for i in 0..x.len() {
            for k in 0..3 {
                let mut xp = x.clone();
                xp[i][k] += eps;
                let mut xm = x.clone();
                xm[i][k] -= eps;
                let fd = (volume(&xp, &t) - volume(&xm, &t)) / (2.0 * eps);
                // central difference of a cubic polynomial: error ~ eps^2, round-off ~ 1e-16/eps
                assert!((fd - g[i][k]).abs() < 1e-8, "vertex {i} comp {k}: {fd} vs {}", g[i][k]);
            }
        }
    }
}
