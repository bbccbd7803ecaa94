//! Figures of the experiment (paper Fig. 3a, 3b, 4 and per-shape densities).
