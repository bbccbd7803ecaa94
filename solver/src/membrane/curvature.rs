//! Discrete curvatures (placeholder until Method C lands).
