//! Typed errors of membrane-law construction.

/// Invalid membrane parameters or reference state.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MembraneError {
    #[error("{law}: parameter `{name}` = {value:e} must be {requirement}")]
    Parameter {
        law: &'static str,
        name: &'static str,
        value: f64,
        requirement: &'static str,
    },
    #[error("unknown {what} `{name}` (expected one of: {expected})")]
    UnknownName {
        what: &'static str,
        name: String,
        expected: &'static str,
    },
    #[error("{law}: reference triangle {triangle} is degenerate (area {area:e} um^2)")]
    DegenerateReference {
        law: &'static str,
        triangle: usize,
        area: f64,
    },
}

/// Checks `value` is finite and `>= 0` (or `> 0` if `strict`).
pub(crate) fn check_modulus(
    law: &'static str,
    name: &'static str,
    value: f64,
    strict: bool,
) -> Result<f64, MembraneError> {
    let ok = value.is_finite() && if strict { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(value)
    } else {
        Err(MembraneError::Parameter {
            law,
            name,
            value,
            requirement: if strict {
                "finite and > 0"
            } else {
                "finite and >= 0"
            },
        })
    }
}
