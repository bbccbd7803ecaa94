//! Volume-drift correction: no-flux projection of the velocity and rescaling about the centroid.
//!
//! The paper (Simulation setup; Farutin et al. 2014) counters the artificial
//! volume drift of the cell "by adjusting the velocity to obey the no-flux
//! condition and by a subsequent rescaling of the object". Both are done here
//! on the discrete surface:
//! 1. [`remove_flux`]: `u_i <- u_i - alpha n_i` with the unit vertex normals
//!    `n_i = g_i / |g_i|`, `g_i = dV/dx_i`, and `alpha = sum g.u / sum g.n`,
//!    so that the discrete `dV/dt = sum_i g_i . u_i` is exactly zero;
//! 2. [`rescale_to_volume`]: after an accepted step the vertices are scaled about
//!    the volume centroid by `s = (V0 / V)^(1/3)`, which restores `V0` exactly
//!    (a scaling multiplies the volume by `s^3`) and keeps the centroid fixed.

use crate::mesh::slices;
use super::projected::Projected;
use nalgebra::Vector3;

/// Remove the net flux of the vertex velocities `u` (um/s) through the surface `x`.
/// Returns the removed uniform normal velocity `alpha` (um/s); `g` is scratch of length `x.len()`.
pub fn remove_flux(x: &[Vector3<f64>], triangles: &[[usize; 3]], u: &mut [Vector3<f64>], g: &mut [Vector3<f64>]) -> f64 {
    slices::volume_gradient(x, triangles, g);
    let mut flux = 0.0; // dV/dt, um^3/s
    let mut gn = 0.0; // sum_i |g_i| ~ area, um^2
    for (gi, ui) in g.iter().zip(u.iter()) {
        flux += gi.dot(ui);
        gn += gi.norm();
    }
    if gn <= 0.0 {
        return 0.0;
    }
    let alpha = flux / gn;
    for (gi, ui) in g.iter().zip(u.iter_mut()) {
        let n = gi.norm();
        if n > 0.0 {
            *ui -= alpha * gi / n;
        }
    }
    alpha
}

/// The volume-drift correction applied after each accepted step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeCorrection {
    /// Target volume (um^3), normally the initial volume.
    pub volume_um3: f64,
    /// Relative drift `|V / V0 - 1|` below which the shape is left alone
    /// (each rescaling invalidates the first-same-as-last stage of Bogacki-Shampine
    /// and so costs one extra velocity evaluation). Default 1e-9.
    pub threshold: f64,
}

impl VolumeCorrection {
    pub fn new(volume_um3: f64) -> Self {
        Self { volume_um3, threshold: 1e-9 }
    }

    /// Rescale `x` when the drift exceeds the threshold; returns whether `x` changed.
    pub fn apply(&self, x: &mut [Vector3<f64>], triangles: &[[usize; 3]]) -> bool {
        let v = slices::volume(x, triangles);
        if (v / self.volume_um3 - 1.0).abs() <= self.threshold {
            return false;
        }
        rescale_to_volume(x, triangles, self.volume_um3);
        true
    }
}

/// Scale `x` about its volume centroid so that its volume becomes `target_um3`.
/// Returns the scale factor `s = (V0 / V)^(1/3)`. Entries past the last vertex the triangles
/// reference are not vertices of the surface (extra state, e.g. the wall displacements of
/// [`super::penalty`]) and are left alone.
pub fn rescale_to_volume(x: &mut [Vector3<f64>], triangles: &[[usize; 3]], target_um3: f64) -> f64 {
    let v = slices::volume(x, triangles);
    let c = slices::centroid(x, triangles);
    let s = (target_um3 / v).cbrt();
    let n = if triangles.is_empty() { x.len() } else { slices::cell_len(triangles) };
    for p in x[..n].iter_mut() {
        *p = c + s * (*p - c);
    }
    s
}


/// Wraps a [`Dynamics`](crate::integrate::Dynamics) so that every velocity it returns has zero net flux
/// through the surface ([`remove_flux`]); the Jacobian of a [`Linearised`](crate::integrate::Linearised)
/// inner dynamics is projected the same way (the projection frozen at the
/// linearisation point).
pub fn no_flux<D>(inner: D, triangles: &[[usize; 3]]) -> Projected<'_, D> {
    Projected::new(inner, triangles, |x, t, u, g| {
        remove_flux(x, t, u, g);
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::slices::{centroid, volume};

    /// Icosphere-like test surface: octahedron subdivided `levels` times and projected on a sphere of radius `r` about `c`.
    fn sphere(levels: usize, r: f64, c: Vector3<f64>) -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
        let mut v: Vec<Vector3<f64>> = vec![
            Vector3::x(), -Vector3::x(), Vector3::y(), -Vector3::y(), Vector3::z(), -Vector3::z(),
        ];
        let mut t = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        for _ in 0..levels {
            let mut mid = std::collections::HashMap::new();
            let mut nt = Vec::new();
            let mut m = |a: usize, b: usize, v: &mut Vec<Vector3<f64>>| {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    v.push((v[a] + v[b]).normalize());
                    v.len() - 1
                })
            };
            for &[a, b, c] in &t {
                let ab = m(a, b, &mut v);
                let bc = m(b, c, &mut v);
                let ca = m(c, a, &mut v);
                nt.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
            t = nt;
        }
        (v.into_iter().map(|p| c + r * p).collect(), t)
    }

    #[test]
    fn rescaling_a_scaled_sphere_restores_it_exactly() {
        let c = Vector3::new(0.5, -1.0, 2.0);
        let (x0, t) = sphere(3, 4.0, c);
        let v0 = volume(&x0, &t);
        let c0 = centroid(&x0, &t);
        // inflate by 1 % about the centroid, as a volume drift would
        let mut x: Vec<_> = x0.iter().map(|p| c0 + 1.01 * (p - c0)).collect();
        let s = rescale_to_volume(&mut x, &t, v0);
        assert!((s - 1.0 / 1.01).abs() < 1e-14, "scale {s}");
        for (p, q) in x.iter().zip(&x0) {
            assert!((p - q).norm() < 1e-13, "vertex moved by {}", (p - q).norm());
        }
        assert!((volume(&x, &t) / v0 - 1.0).abs() < 1e-14);
    }

    #[test]
    fn threshold_leaves_small_drift_alone() {
        let (mut x, t) = sphere(2, 1.0, Vector3::zeros());
        let v0 = volume(&x, &t);
        let corr = VolumeCorrection { volume_um3: v0 * (1.0 + 1e-12), threshold: 1e-9 };
        assert!(!corr.apply(&mut x, &t));
        let corr = VolumeCorrection { volume_um3: v0 * 1.001, threshold: 1e-9 };
        assert!(corr.apply(&mut x, &t));
        assert!((volume(&x, &t) / (v0 * 1.001) - 1.0).abs() < 1e-13);
    }

    #[test]
    fn flux_removal_makes_discrete_volume_rate_zero_and_keeps_tangential_motion() {
        let (x, t) = sphere(2, 2.0, Vector3::new(1.0, 0.0, 0.0));
        let c = centroid(&x, &t);
        // radial inflation (pure flux) plus a rigid rotation (no flux)
        let omega = Vector3::new(0.3, -0.2, 1.0);
        let rot: Vec<Vector3<f64>> = x.iter().map(|p| omega.cross(&(p - c))).collect();
        let mut u: Vec<Vector3<f64>> = x.iter().zip(&rot).map(|(p, r)| 0.7 * (p - c) + r).collect();
        let mut g = vec![Vector3::zeros(); x.len()];
        remove_flux(&x, &t, &mut u, &mut g);
        let rate: f64 = g.iter().zip(&u).map(|(g, u)| g.dot(u)).sum();
        assert!(rate.abs() < 1e-12, "dV/dt after correction {rate}");
        // a rigid rotation has no flux, so it must pass unchanged
        let mut u2 = rot.clone();
        let alpha = remove_flux(&x, &t, &mut u2, &mut g);
        assert!(alpha.abs() < 1e-12);
    }
}
