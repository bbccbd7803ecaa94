//! Helfrich bending (placeholder until Method C lands).
