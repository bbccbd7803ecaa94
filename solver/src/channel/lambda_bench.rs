//! Cost of the viscosity-contrast channel solve (placeholder filled below).
