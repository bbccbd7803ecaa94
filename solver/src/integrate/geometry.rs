//! Volume, area and centroid of a closed triangulated surface, and the exact gradient of the discrete volume.
//!
//! The integrator needs these on raw vertex slices (the state vector) for the
//! volume-drift correction and the failure checks, independently of the
//! [`crate::mesh::Mesh`] container.

use nalgebra::Vector3;

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
