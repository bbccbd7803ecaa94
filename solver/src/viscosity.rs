//! The viscosity contrast `lambda = mu_in / mu` of a cell: one validated value and the coefficients of the boundary integral equation it enters.
//!
//! With outer viscosity `mu` and inner viscosity `lambda mu`, the membrane velocity `u` solves
//! the second-kind equation (Pozrikidis, "Boundary integral and singularity methods for
//! linearized viscous flow", 1992, ch. 5-6; Guckenberger et al. 2018, "Simulation setup"; the
//! discretisation in [`crate::bim`])
//!
//! ```text
//! (1+lambda)/2 u(x) = u_inf(x) + 1/(8 pi mu) Int_S G . f dS + (1-lambda)/(8 pi) PV Int_S u . T . n dS
//! ```
//!
//! i.e. `u - kappa K[u] = 2/(1+lambda) (u_inf + SL[f]/mu)` with `kappa = (1-lambda)/(1+lambda)`
//! ([`ViscosityContrast::kappa`], [`ViscosityContrast::rhs_scale`]); the double layer `K` is
//! not built at `lambda = 1` ([`ViscosityContrast::is_matched`]). A flow evaluated off the
//! membrane adds `(1-lambda)/2` times the double layer of `u` ([`ViscosityContrast::half_one_minus`]).
//!
//! Rule (one for every operator): `lambda` is a finite number > 0. `lambda -> 0` (a bubble) makes
//! the equation singular and `lambda -> inf` a rigid particle; neither is a cell. The scene's
//! `fluid.lambda` is checked by the same rule where the scene is read (`rbc_schema::scene`,
//! which also bounds it to a plausible range), and [`crate::scene::build`] makes the one
//! [`ViscosityContrast`] every operator and the stiff-mode preconditioner receive.

/// The viscosity ratio `lambda = mu_in / mu` (dimensionless, finite, > 0), checked once when
/// made ([`ViscosityContrast::new`]); the operators take it as it is.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct ViscosityContrast(f64);

/// A viscosity ratio that breaks the rule of [`ViscosityContrast`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("the viscosity ratio lambda = mu_in / mu must be a finite number > 0, got {0}")]
pub struct InvalidViscosityRatio(pub f64);

impl ViscosityContrast {
    /// `lambda = 1`: inner and outer fluid alike, no double layer.
    pub const MATCHED: Self = Self(1.0);

    /// The contrast `lambda = mu_in / mu`, if it is a finite number > 0.
    pub fn new(lambda: f64) -> Result<Self, InvalidViscosityRatio> {
        if lambda > 0.0 && lambda.is_finite() {
            Ok(Self(lambda))
        } else {
            Err(InvalidViscosityRatio(lambda))
        }
    }

    /// `lambda = mu_in / mu`.
    pub fn lambda(self) -> f64 {
        self.0
    }

    /// `lambda == 1`: the equation has no double layer (`kappa = 0`).
    pub fn is_matched(self) -> bool {
        self.0 == 1.0
    }

    /// `kappa = (1 - lambda)/(1 + lambda)`, the double layer's coefficient in the second-kind
    /// equation `u - kappa K[u] = b`; in (-1, 1).
    pub fn kappa(self) -> f64 {
        (1.0 - self.0) / (1.0 + self.0)
    }

    /// `2/(1 + lambda)`, the factor of the right-hand side `b = 2/(1+lambda) (u_inf + SL[f]/mu)`
    /// and of the two-fluid mobility (the single-fluid mobility at `lambda = 1`).
    pub fn rhs_scale(self) -> f64 {
        2.0 / (1.0 + self.0)
    }

    /// `(1 - lambda)/2`, the coefficient of the double layer in the flow off the membrane
    /// (the wall's answer to it in the channel).
    pub fn half_one_minus(self) -> f64 {
        0.5 * (1.0 - self.0)
    }
}

impl Default for ViscosityContrast {
    /// [`ViscosityContrast::MATCHED`] (no contrast).
    fn default() -> Self {
        Self::MATCHED
    }
}

impl std::fmt::Display for ViscosityContrast {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_and_the_coefficients() {
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = ViscosityContrast::new(bad).unwrap_err();
            assert!(e.to_string().contains("finite number > 0"), "{e}");
        }
        let c = ViscosityContrast::new(5.0).unwrap();
        assert_eq!((c.lambda(), c.kappa(), c.rhs_scale(), c.half_one_minus()), (5.0, -4.0 / 6.0, 2.0 / 6.0, -2.0));
        assert!(!c.is_matched());
        let m = ViscosityContrast::MATCHED;
        assert!(m.is_matched() && m.kappa() == 0.0 && m.rhs_scale() == 1.0 && m.half_one_minus() == 0.0);
        assert_eq!(format!("{c}"), "5");
    }
}
