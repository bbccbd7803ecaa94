//! Failure detection on a proposed state: non-finite values, inverted triangles, excessive area change.
//!
//! The runner calls [`Checks::state`] on every accepted state before anything
//! is written, so a blow-up stops the run with a diagnosis instead of writing
//! NaNs or a tangled mesh.

use super::error::IntegrateError;
use super::geometry;
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
}

impl Default for Checks {
    fn default() -> Self {
        Self { max_area_change: 0.05, max_normal_turn_rad: std::f64::consts::FRAC_PI_2 }
    }
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
            let (n, a) = geometry::triangle_normal_area(x, tri);
            let (n0, _) = geometry::triangle_normal_area(prev, tri);
            let cosine = n.dot(&n0);
            if a <= 0.0 || cosine <= cos_limit {
                return Err(IntegrateError::InvertedTriangle { t_s, step, triangle: i, cosine, area_um2: a });
            }
            area += a;
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
        let a0 = geometry::area(&x, &t);
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
        let a0 = geometry::area(&x, &t);
        let mut y = x.clone();
        y[3].z = -0.5; // apex pushed through the base: every face touching vertex 3 flips
        let e = Checks { max_area_change: 10.0, ..Default::default() }.state(&y, &x, &t, a0, 0.0, 0).unwrap_err();
        assert!(matches!(e, IntegrateError::InvertedTriangle { triangle: 1, .. }), "{e:?}");
    }

    #[test]
    fn detects_area_change_above_limit_only() {
        let (x, t) = tetra();
        let a0 = geometry::area(&x, &t);
        let grow = |s: f64| x.iter().map(|p| p * s).collect::<Vec<_>>();
        // area scales as s^2: s = 1.02 gives +4.04 % (accepted), s = 1.03 gives +6.09 % (refused)
        assert!(Checks::default().state(&grow(1.02), &x, &t, a0, 0.0, 0).is_ok());
        let e = Checks::default().state(&grow(1.03), &x, &t, a0, 0.0, 0).unwrap_err();
        match e {
            IntegrateError::AreaChange { relative, .. } => assert!((relative - 0.0609).abs() < 1e-12),
            other => panic!("{other:?}"),
        }
    }
}
