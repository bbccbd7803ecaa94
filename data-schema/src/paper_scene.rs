//! The paper's membrane, fluid and channel parameters as scene TOML blocks, for the scenes that benches, studies and tests generate.
//!
//! Guckenberger et al. 2018, "Simulation setup" (../shared/spec/physics.md, "Parameters"):
//! Skalak law in Krueger's convention with kappa_S = 5e-6 N/m and kappa_A = 100 kappa_S,
//! Helfrich bending 3e-19 N m, the discocyte as reference shape, outer viscosity 1.2 mPa s,
//! and the periodic 12 x 10 um channel of length 42.7 um. The blocks parse with
//! [`crate::scene::Scene::parse`] once `[cell]` and `[time]` tables (and optionally
//! `[integrator]`) are added; further `[walls]` keys may directly follow [`channel_walls`].

/// `[membrane]` and `[fluid]` with viscosity ratio `lambda` (inner / outer viscosity).
pub fn membrane_and_fluid(lambda: f64) -> String {
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
"#
    )
}

/// `[walls]` of the periodic channel carrying the mean flow `mean_velocity_um_s` (um/s).
pub fn channel_walls(mean_velocity_um_s: f64) -> String {
    format!(
        r#"[walls]
kind = "periodic-channel"
length_x_um = 42.7
width_y_um = 12.0
height_z_um = 10.0
mean_velocity_um_s = {mean_velocity_um_s:?}
"#
    )
}

/// [`membrane_and_fluid`] followed by [`channel_walls`].
pub fn channel_blocks(lambda: f64, mean_velocity_um_s: f64) -> String {
    membrane_and_fluid(lambda) + &channel_walls(mean_velocity_um_s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Scene, WallsSpec};
    use std::path::Path;

    /// The blocks parse into the paper's values once a cell is added, walls keys can follow.
    #[test]
    fn blocks_parse_into_the_papers_scene() {
        let text = format!("name = \"p\"\n[cell]\nshape = \"discocyte\"\nlevel = 2\n{}wall_edge_um = 2.0\n[time]\nend_s = 1e-3\noutput_interval_s = 1e-4\n", channel_blocks(5.0, 4300.0));
        let s = Scene::parse(&text, Path::new("p.toml")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.fluid.lambda, 5.0);
        assert_eq!(s.fluid.viscosity_pa_s, 1.2e-3);
        match s.walls {
            WallsSpec::PeriodicChannel { mean_velocity_um_s, length_x_um, width_y_um, height_z_um, .. } => {
                assert_eq!((mean_velocity_um_s, length_x_um, width_y_um, height_z_um), (4300.0, 42.7, 12.0, 10.0))
            }
            other => panic!("{other:?}"),
        }
    }
}
