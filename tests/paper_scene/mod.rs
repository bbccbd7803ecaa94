//! The paper's membrane, fluid and channel as scene TOML blocks, shared by the test fixtures (channel scene runs, sweeps).
#![allow(dead_code)]

/// `[membrane]` (Skalak in the Krueger convention, kappa_S = 5e-6 N/m, kappa_A = 5e-4 N/m,
/// Helfrich bending 3e-19 N m, discocyte reference), `[fluid]` (1.2 mPa s, viscosity ratio
/// `lambda`) and `[walls]` (the periodic 12 x 10 um channel, L_x = 42.7 um, mean flow
/// `mean_velocity_um_s`) of the paper's scene (physics.md, "Parameters"); further `[walls]`
/// keys may follow directly.
pub fn paper_blocks(lambda: f64, mean_velocity_um_s: f64) -> String {
    format!(
        r#"[membrane]
reference = "discocyte"
[membrane.skalak]
convention = "krueger"
kappa_s_n_m = 5e-6
kappa_a_n_m = 5e-4
[membrane.bending]
kappa_b_n_m = 3e-19
[fluid]
viscosity_pa_s = 1.2e-3
lambda = {lambda:?}
[walls]
kind = "periodic-channel"
length_x_um = 42.7
width_y_um = 12.0
height_z_um = 10.0
mean_velocity_um_s = {mean_velocity_um_s:?}
"#
    )
}
