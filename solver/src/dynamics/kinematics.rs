//! Normal-only kinematics for interfaces without in-plane elasticity (drops): vertices move with `(u . n) n`.
//!
//! For a drop the surface tension resists only changes of area, so the vertex
//! positions along the surface are arbitrary: moving them with the full fluid
//! velocity makes them drift with the tank-treading interface until the mesh
//! degrades. Moving them with the normal component only, `dx_i/dt = (u_i . n_i) n_i`,
//! describes the same surface evolution (Loewenberg & Hinch, JFM 321, 395 (1996)).
//! `n_i` is the unit volume gradient at vertex `i` (see [`crate::mesh::slices::volume_gradient`]),
//! so the discrete volume rate `sum_i g_i . u_i` is unchanged by the projection.
//! Not for capsules: their elastic reference is attached to material points.

use crate::mesh::slices;
use super::projected::Projected;
use nalgebra::Vector3;

/// Project velocities onto the vertex normals of the surface `x`; `g` is scratch.
pub fn project_normal(x: &[Vector3<f64>], triangles: &[[usize; 3]], u: &mut [Vector3<f64>], g: &mut [Vector3<f64>]) {
    slices::volume_gradient(x, triangles, g);
    for (gi, ui) in g.iter().zip(u.iter_mut()) {
        let n = gi.norm();
        *ui = if n > 0.0 { gi * (gi.dot(ui) / (n * n)) } else { Vector3::zeros() };
    }
}

/// Wraps a [`Dynamics`](crate::integrate::Dynamics) so that vertices move with the normal velocity only ([`project_normal`]).
pub fn normal_only<D>(inner: D, triangles: &[[usize; 3]]) -> Projected<'_, D> {
    Projected::new(inner, triangles, project_normal)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_keeps_the_volume_rate_and_removes_tangential_motion() {
        let m = crate::mesh::sphere(2, 2.0);
        let mut g = vec![Vector3::zeros(); m.vertices.len()];
        // rigid rotation about z: purely tangential on a sphere up to the mesh's faceting
        let mut u: Vec<Vector3<f64>> = m.vertices.iter().map(|p| Vector3::z().cross(p) + 0.1 * p).collect();
        let u0 = u.clone();
        project_normal(&m.vertices, &m.triangles, &mut u, &mut g);
        let rate = |u: &[Vector3<f64>]| g.iter().zip(u).map(|(g, u)| g.dot(u)).sum::<f64>();
        assert!((rate(&u) - rate(&u0)).abs() < 1e-12 * rate(&u0).abs());
        for (ui, gi) in u.iter().zip(&g) {
            assert!(ui.cross(gi).norm() < 1e-12 * gi.norm() * (1.0 + ui.norm()));
        }
    }
}
