//! Undisturbed background flows `u_inf(x)` (um/s at positions in um): quiescent fluid, rigid motion, simple shear, unbounded Poiseuille.
//!
//! Every flow here is an exact solution of the Stokes equations (linear or quadratic in
//! `x` with a constant pressure gradient), as the boundary integral equation requires.

use nalgebra::Vector3;

/// An undisturbed Stokes flow: velocity (um/s) at a position (um).
pub trait BackgroundFlow: Send + Sync {
    fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64>;
}

/// Fluid at rest: `u = 0`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Quiescent;

impl BackgroundFlow for Quiescent {
    fn velocity(&self, _x: &Vector3<f64>) -> Vector3<f64> {
        Vector3::zeros()
    }
}

/// Rigid-body motion `u = U + omega x (x - c)`: `U` in um/s, `omega` in rad/s, `c` in um.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidMotion {
    pub translation_um_per_s: Vector3<f64>,
    pub angular_velocity_per_s: Vector3<f64>,
    pub center_um: Vector3<f64>,
}

impl BackgroundFlow for RigidMotion {
    fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.translation_um_per_s + self.angular_velocity_per_s.cross(&(x - self.center_um))
    }
}

/// Simple shear `u = (gamma_dot z, 0, 0)`: flow along x, gradient along z (the channel
/// height), zero velocity on the plane `z = 0`. `gamma_dot` in 1/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimpleShear {
    pub shear_rate_per_s: f64,
}

impl BackgroundFlow for SimpleShear {
    fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(self.shear_rate_per_s * x.z, 0.0, 0.0)
    }
}

/// Unbounded Poiseuille flow along x about the x axis:
/// `u = (U_max (1 - (y^2 + z^2) / R^2), 0, 0)`, driven by the pressure gradient
/// `dp/dx = -4 mu U_max / R^2`. It is defined everywhere (negative beyond `r = R`), i.e. the
/// flow of a tube of radius `R` continued analytically, not a bounded tube.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnboundedPoiseuille {
    /// Centre-line velocity (um/s).
    pub max_velocity_um_per_s: f64,
    /// Radius (um) at which the velocity vanishes.
    pub radius_um: f64,
}

impl BackgroundFlow for UnboundedPoiseuille {
    fn velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
        let r2 = (x.y * x.y + x.z * x.z) / (self.radius_um * self.radius_um);
        Vector3::new(self.max_velocity_um_per_s * (1.0 - r2), 0.0, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Laplacian by central differences (exact for quadratics up to rounding).
    fn laplacian(f: &dyn BackgroundFlow, x: Vector3<f64>) -> Vector3<f64> {
        let h = 1e-2;
        let mut l = -6.0 * f.velocity(&x);
        for k in 0..3 {
            let e = Vector3::ith(k, h);
            l += f.velocity(&(x + e)) + f.velocity(&(x - e));
        }
        l / (h * h)
    }

    fn divergence(f: &dyn BackgroundFlow, x: Vector3<f64>) -> f64 {
        let h = 1e-3;
        (0..3).map(|k| {
            let e = Vector3::ith(k, h);
            (f.velocity(&(x + e))[k] - f.velocity(&(x - e))[k]) / (2.0 * h)
        }).sum()
    }

    /// Each flow is divergence-free and satisfies Stokes `mu Lap u = grad p` with a uniform
    /// pressure gradient: `Lap u = 0` for shear and rigid motion, `(-4 U_max / R^2, 0, 0)` for Poiseuille.
    #[test]
    fn flows_are_stokes_solutions() {
        let x = Vector3::new(1.3, -2.1, 0.7);
        let shear = SimpleShear { shear_rate_per_s: 250.0 };
        let pois = UnboundedPoiseuille { max_velocity_um_per_s: 6500.0, radius_um: 5.0 };
        let rigid = RigidMotion {
            translation_um_per_s: Vector3::new(1.0, 2.0, 3.0),
            angular_velocity_per_s: Vector3::new(0.5, -0.2, 0.1),
            center_um: Vector3::new(0.0, 1.0, 0.0),
        };
        for f in [&shear as &dyn BackgroundFlow, &pois, &rigid, &Quiescent] {
            assert!(divergence(f, x).abs() < 1e-6);
        }
        assert!(laplacian(&shear, x).norm() < 1e-6);
        assert!(laplacian(&rigid, x).norm() < 1e-6);
        let lp = laplacian(&pois, x);
        assert!((lp - Vector3::new(-4.0 * 6500.0 / 25.0, 0.0, 0.0)).norm() < 1e-4 * lp.norm());
        // Documented values: zero on the walls of the tube, U_max on the axis, gamma_dot z for shear.
        assert!(pois.velocity(&Vector3::new(3.0, 3.0, 4.0)).norm() < 1e-9);
        assert_eq!(pois.velocity(&Vector3::new(-7.0, 0.0, 0.0)).x, 6500.0);
        assert_eq!(shear.velocity(&x), Vector3::new(250.0 * 0.7, 0.0, 0.0));
    }
}
