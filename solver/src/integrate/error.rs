//! Failures of time integration, each with the time, step and vertex (or triangle) that triggered it.

/// Why a time integration stopped. Every variant names the simulated time (s),
/// the number of the step that failed (accepted steps so far) and the offending
/// vertex or triangle with its value, so that a failed run can be diagnosed
/// without re-running it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegrateError {
    /// A position or velocity component became NaN or infinite.
    #[error("non-finite {quantity} at t = {t_s:.6e} s, step {step}, vertex {vertex}: {value}")]
    NonFinite { quantity: &'static str, t_s: f64, step: usize, vertex: usize, value: f64 },
    /// A triangle flipped its orientation (normal reversed against the last accepted state) or collapsed.
    #[error("inverted triangle {triangle} at t = {t_s:.6e} s, step {step}: normal . previous normal = {cosine:.3e}, area {area_um2:.3e} um^2")]
    InvertedTriangle { t_s: f64, step: usize, triangle: usize, cosine: f64, area_um2: f64 },
    /// The membrane area left the allowed band around its initial value.
    #[error("area change {relative:+.3e} exceeds the limit {limit:.3e} at t = {t_s:.6e} s, step {step} (area {area_um2:.4} um^2, initial {initial_um2:.4} um^2)")]
    AreaChange { t_s: f64, step: usize, relative: f64, limit: f64, area_um2: f64, initial_um2: f64 },
    /// Two triangles sharing an edge turned their normals apart by more than the limit: the
    /// membrane folds more sharply than the mesh resolves.
    #[error("the mesh no longer resolves the shape at t = {t_s:.6e} s, step {step}: the normals of the two triangles at edge {edge:?} differ by {angle_deg:.1} degrees (limit {limit_deg:.1}); use a finer cell mesh (cell.level) or raise integrator.max_fold_deg")]
    UnresolvedFold { t_s: f64, step: usize, edge: [usize; 2], angle_deg: f64, limit_deg: f64 },
    /// The step-size controller asked for a step below the minimum.
    #[error("step size collapsed to {h_s:.3e} s (< minimum {h_min_s:.3e} s) at t = {t_s:.6e} s, step {step}; worst error at vertex {vertex} ({error_um:.3e} um vs tolerance {atol_um:.3e} um)")]
    StepSizeCollapse { t_s: f64, step: usize, h_s: f64, h_min_s: f64, vertex: usize, error_um: f64, atol_um: f64 },
    /// Too many steps for the requested end time.
    #[error("step budget of {max_steps} steps exhausted at t = {t_s:.6e} s (end time {t_end_s:.6e} s)")]
    TooManySteps { t_s: f64, max_steps: usize, t_end_s: f64 },
    /// The linear solve inside a (semi-)implicit stage did not converge.
    #[error("linear solve of the implicit stage did not converge at t = {t_s:.6e} s, step {step}: residual {residual:.3e} after {iterations} iterations (target {target:.3e})")]
    LinearSolve { t_s: f64, step: usize, iterations: usize, residual: f64, target: f64 },
    /// The mesh and the state vector disagree.
    #[error("state has {found} points but the mesh has {expected} vertices")]
    Shape { expected: usize, found: usize },
}
