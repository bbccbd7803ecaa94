//! Statistics of samples shared by the experiment and simulated sides (one home each).

pub mod median;
