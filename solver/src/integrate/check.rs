//! Failure detection on a proposed state: non-finite values, inverted triangles, excessive area change, folds sharper than the mesh resolves.
//!
//! The runner calls [`Checks::state`] on every accepted state before anything
//! is written, so a blow-up stops the run with a diagnosis instead of writing
//! NaNs or a tangled mesh.

use super::error::IntegrateError;
use crate::mesh::slices;
use nalgebra::Vector3;

/// Limits a state must respect.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Checks {
    /// Maximal relative change `|A / A0 - 1|` of the total membrane area. Default 0.05:
    /// the paper's kappa_A = 100 kappa_S keeps it below 2 %, so 5 % means the
    /// elastic law or the integration has failed.
    pub max_area_change: f64,
    /// A triangle whose normal turns by more than this angle (rad) within one step
    /// counts as inverted (pi/2: the normal reversed its sign against the previous state).
    pub max_normal_turn_rad: f64,
    /// Largest angle (rad) between the normals of two triangles that share an edge. Default
    /// 2 pi / 3 (120 degrees): the surface then turns by more than a right angle across one
    /// edge, so the fold is far sharper than the mesh resolves and the curvature, bending force
    /// and quadrature there are meaningless. Measured on the paper's channel scene at 6.5 mm/s
    /// with a 512-triangle cell: the rear rim's fold grows from 33 degrees (the discocyte) to
    /// 90 degrees by 10 ms and 120-140 degrees by 15-22 ms, after which the steps collapse
    /// (solver/README.md, "Measured, sessions 1-12"). A state fails when its sharpest fold crosses the limit within a
    /// step; a (very coarse) mesh that is already beyond it is not stopped while it stays there.
    pub max_fold_rad: f64,
}

impl Default for Checks {
    fn default() -> Self {
        Self { max_area_change: 0.05, max_normal_turn_rad: std::f64::consts::FRAC_PI_2, max_fold_rad: 2.0 * std::f64::consts::FRAC_PI_3 }
    }
}

/// The sharpest fold of a closed mesh: the largest angle (rad) between the normals of two
/// triangles sharing an edge, and that edge's vertices (the edge-triangle pairs of
/// [`crate::mesh::Topology`]). `(0, [0, 0])` without shared edges.
pub fn sharpest_fold(x: &[Vector3<f64>], triangles: &[[usize; 3]]) -> (f64, [usize; 2]) {
    let topology = crate::mesh::Topology::new(&crate::mesh::Mesh { vertices: x.to_vec(), triangles: triangles.to_vec() });
    let normals: Vec<Vector3<f64>> = triangles.iter().map(|&t| slices::triangle_normal_area(x, t).0).collect();
    let mut worst = (1.0f64, [0usize, 0usize]);
    for (edge, &[t0, t1]) in topology.edges.iter().zip(&topology.edge_triangles) {
        if t0 == usize::MAX || t1 == usize::MAX {
            continue;
        }
        let c = normals[t0].dot(&normals[t1]);
        if c < worst.0 {
            worst = (c, *edge);
        }
    }
    if worst.0 == 1.0 {
        return (0.0, [0, 0]);
    }
    (worst.0.clamp(-1.0, 1.0).acos(), worst.1)
}

/// First non-finite component of `v`, as `(vertex, value)`.
pub fn first_non_finite(v: &[Vector3<f64>]) -> Option<(usize, f64)> {
    v.iter().enumerate().find_map(|(i, p)| p.iter().find(|c| !c.is_finite()).map(|&c| (i, c)))
}

impl Checks {
    /// Check the proposed state `x` against the last accepted state `prev`.
    /// `t_s` and `step` only label the error. `initial_area_um2` is the area at t = 0.
    pub fn state(
        &self,
        x: &[Vector3<f64>],
        prev: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        initial_area_um2: f64,
        t_s: f64,
        step: usize,
    ) -> Result<(), IntegrateError> {
        if let Some((vertex, value)) = first_non_finite(x) {
            return Err(IntegrateError::NonFinite { quantity: "position", t_s, step, vertex, value });
        }
        let cos_limit = self.max_normal_turn_rad.cos();
        let mut area = 0.0;
        for (i, &tri) in triangles.iter().enumerate() {
            let (n, a) = slices::triangle_normal_area(x, tri);
            let (n0, _) = slices::triangle_normal_area(prev, tri);
            let cosine = n.dot(&n0);
            if a <= 0.0 || cosine <= cos_limit {
                return Err(IntegrateError::InvertedTriangle { t_s, step, triangle: i, cosine, area_um2: a });
            }
            area += a;
        }
        let (fold, edge) = sharpest_fold(x, triangles);
        if fold > self.max_fold_rad && sharpest_fold(prev, triangles).0 <= self.max_fold_rad {
            return Err(IntegrateError::UnresolvedFold {
                t_s,
                step,
                edge,
                angle_deg: fold.to_degrees(),
                limit_deg: self.max_fold_rad.to_degrees(),
            });
        }
        let relative = area / initial_area_um2 - 1.0;
        if initial_area_um2 > 0.0 && relative.abs() > self.max_area_change {
            return Err(IntegrateError::AreaChange {
                t_s,
                step,
                relative,
                limit: self.max_area_change,
                area_um2: area,
                initial_um2: initial_area_um2,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
        let x = vec![Vector3::new(0.0, 0.0, 0.0), Vector3::x(), Vector3::y(), Vector3::z()];
        let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        (x, t)
    }

    #[test]
    fn detects_nan_with_vertex() {
        let (x, t) = tetra();
        let a0 = slices::area(&x, &t);
        let mut y = x.clone();
        y[2].z = f64::NAN;
        match Checks::default().state(&y, &x, &t, a0, 1.5, 7) {
            Err(IntegrateError::NonFinite { vertex: 2, step: 7, t_s, .. }) => assert_eq!(t_s, 1.5),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn detects_inverted_triangle() {
        let (x, t) = tetra();
        let a0 = slices::area(&x, &t);
        let mut y = x.clone();
        y[3].z = -0.5; // apex pushed through the base: every face touching vertex 3 flips
        let e = Checks { max_area_change: 10.0, ..Default::default() }.state(&y, &x, &t, a0, 0.0, 0).unwrap_err();
        assert!(matches!(e, IntegrateError::InvertedTriangle { triangle: 1, .. }), "{e:?}");
    }

    #[test]
    fn detects_area_change_above_limit_only() {
        let (x, t) = tetra();
        let a0 = slices::area(&x, &t);
        let grow = |s: f64| x.iter().map(|p| p * s).collect::<Vec<_>>();
        // area scales as s^2: s = 1.02 gives +4.04 % (accepted), s = 1.03 gives +6.09 % (refused)
        assert!(Checks::default().state(&grow(1.02), &x, &t, a0, 0.0, 0).is_ok());
        let e = Checks::default().state(&grow(1.03), &x, &t, a0, 0.0, 0).unwrap_err();
        match e {
            IntegrateError::AreaChange { relative, .. } => assert!((relative - 0.0609).abs() < 1e-12),
            other => panic!("{other:?}"),
        }
    }

    /// The corner tetrahedron: the outward normals are -x, -y, -z on the faces through the
    /// origin (90 degrees apart) and (1, 1, 1)/sqrt(3) on the slanted face, which turns by
    /// acos(-1/sqrt(3)) = 125.26 degrees against each of the others, at the edges not touching vertex 0.
    #[test]
    fn sharpest_fold_of_a_tetrahedron() {
        let (x, t) = tetra();
        let (angle, edge) = sharpest_fold(&x, &t);
        assert!((angle - (-1.0 / 3f64.sqrt()).acos()).abs() < 1e-12, "{}", angle.to_degrees());
        assert!(edge[0] > 0 && edge[0] < edge[1] && edge[1] < 4, "{edge:?}");
    }

    /// A roof of two triangles on the edge (0, 1): opened flat (0 degrees), then closed until
    /// the normals differ by 100 (accepted with the 120-degree limit) and 130 degrees (refused,
    /// naming the edge); a state already beyond the limit is not refused again.
    #[test]
    fn detects_a_fold_sharper_than_the_limit() {
        let roof = |deg: f64| {
            let half = (deg / 2.0).to_radians();
            vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.0, 0.0),
                Vector3::new(0.5, half.cos(), -half.sin()),
                Vector3::new(0.5, -half.cos(), -half.sin()),
            ]
        };
        let t = vec![[0, 1, 2], [1, 0, 3]];
        let flat = roof(0.0);
        assert!(sharpest_fold(&flat, &t).0.abs() < 1e-12);
        let a0 = slices::area(&flat, &t);
        let checks = Checks { max_normal_turn_rad: std::f64::consts::PI, ..Checks::default() };
        assert!((sharpest_fold(&roof(100.0), &t).0.to_degrees() - 100.0).abs() < 1e-9);
        assert!(checks.state(&roof(100.0), &flat, &t, a0, 0.0, 3).is_ok());
        match checks.state(&roof(130.0), &roof(100.0), &t, a0, 2e-3, 4) {
            Err(IntegrateError::UnresolvedFold { edge: [0, 1], angle_deg, step: 4, .. }) => assert!((angle_deg - 130.0).abs() < 1e-9),
            other => panic!("{other:?}"),
        }
        assert!(checks.state(&roof(135.0), &roof(130.0), &t, a0, 0.0, 5).is_ok());
    }
}
