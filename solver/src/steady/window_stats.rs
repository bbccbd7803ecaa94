//! Statistics of a run's steady window (velocity, radial position, extents) for its summary.

use rbc_schema::results::TimeSample;

/// Statistics of the steady window, for the run summary (results.h5 attributes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowStats {
    /// Samples in the window.
    pub n: usize,
    /// Window duration (s): the paper weights runs by their observation time in the steady state.
    pub duration_s: f64,
    /// Mean, min and max of the centroid's x velocity (mm/s).
    pub velocity_mean_mm_s: f64,
    pub velocity_min_mm_s: f64,
    pub velocity_max_mm_s: f64,
    /// Mean, min and max radial centroid position `sqrt(y^2 + z^2)` (um).
    pub radial_mean_um: f64,
    pub radial_min_um: f64,
    pub radial_max_um: f64,
    /// Mean centroid y and z (um, signed).
    pub y_mean_um: f64,
    pub z_mean_um: f64,
    /// Mean, min and max bounding-box extents along x, y, z (um).
    pub extents_mean_um: [f64; 3],
    pub extents_min_um: [f64; 3],
    pub extents_max_um: [f64; 3],
}

/// Statistics of the samples with `window.0 <= t_s <= window.1`; `None` when none lies inside.
///
/// The mean velocity is the centroid displacement along x over the window divided by
/// its duration (the time average of the sampled velocity, insensitive to the
/// sampling phase); min and max are those of the sampled velocities.
pub fn window_stats(samples: &[TimeSample], window: (f64, f64)) -> Option<WindowStats> {
    let eps = 1e-12 * window.1.abs().max(1.0);
    let w: Vec<&TimeSample> = samples
        .iter()
        .filter(|s| s.t_s >= window.0 - eps && s.t_s <= window.1 + eps)
        .collect();
    let (first, last) = (*w.first()?, *w.last()?);
    let n = w.len();
    let k = n as f64;
    let radial: Vec<f64> = w
        .iter()
        .map(|s| (s.centroid_um[1].powi(2) + s.centroid_um[2].powi(2)).sqrt())
        .collect();
    let duration_s = last.t_s - first.t_s;
    let vel: Vec<f64> = w.iter().map(|s| s.velocity_mm_s[0]).collect();
    let velocity_mean_mm_s = if duration_s > 0.0 {
        (last.centroid_um[0] - first.centroid_um[0]) / duration_s * 1e-3
    } else {
        vel.iter().sum::<f64>() / k
    };
    let min = |v: &mut dyn Iterator<Item = f64>| v.fold(f64::INFINITY, f64::min);
    let max = |v: &mut dyn Iterator<Item = f64>| v.fold(f64::NEG_INFINITY, f64::max);
    let ext = |j: usize| w.iter().map(move |s| s.extents_um[j]);
    Some(WindowStats {
        n,
        duration_s,
        velocity_mean_mm_s,
        velocity_min_mm_s: min(&mut vel.iter().copied()),
        velocity_max_mm_s: max(&mut vel.iter().copied()),
        radial_mean_um: radial.iter().sum::<f64>() / k,
        radial_min_um: min(&mut radial.iter().copied()),
        radial_max_um: max(&mut radial.iter().copied()),
        y_mean_um: w.iter().map(|s| s.centroid_um[1]).sum::<f64>() / k,
        z_mean_um: w.iter().map(|s| s.centroid_um[2]).sum::<f64>() / k,
        extents_mean_um: [0, 1, 2].map(|j| ext(j).sum::<f64>() / k),
        extents_min_um: [0, 1, 2].map(|j| min(&mut ext(j))),
        extents_max_um: [0, 1, 2].map(|j| max(&mut ext(j))),
    })
}
