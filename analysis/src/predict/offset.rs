//! Slipper off-centre positions: the experiment's two peaks of the slipper-only y-density against the simulated mean |y| and |z| of slippers (paper Fig. 8).

use crate::simulated::phase::{bin_velocities, PhasePoint};
use crate::types::prediction::SimulatedOffset;
use rbc_schema::results::FinalShape;
use rbc_schema::tables::{KdeRow, TrackRow};

/// Vertex of the parabola through three points (x, f): the refined position of a sampled maximum.
fn parabola_vertex(x: [f64; 3], f: [f64; 3]) -> f64 {
    // f = a x^2 + b x + c through the points; vertex at -b / 2a (Lagrange form)
    let (x0, x1, x2) = (x[0], x[1], x[2]);
    let num = (x1 - x0).powi(2) * (f[1] - f[2]) - (x1 - x2).powi(2) * (f[1] - f[0]);
    let den = (x1 - x0) * (f[1] - f[2]) - (x1 - x2) * (f[1] - f[0]);
    if den == 0.0 {
        x1
    } else {
        (x1 - 0.5 * num / den).clamp(x0.min(x2), x0.max(x2))
    }
}

/// The two peaks `y_l < 0 < y_r` of a sampled density (um; `y` increasing):
/// the highest interior local maximum on each side of the axis, refined by a
/// parabola through the logarithm of it and its two neighbours (exact for a
/// Gaussian peak, which a kernel density estimate is near its maxima).
/// `None` when one side has no peak.
pub fn density_peaks(y_um: &[f64], density: &[f64]) -> Option<(f64, f64)> {
    let n = y_um.len().min(density.len());
    let mut left: Option<(f64, usize)> = None;
    let mut right: Option<(f64, usize)> = None;
    for i in 1..n.saturating_sub(1) {
        let d = density[i];
        if d > density[i - 1] && d >= density[i + 1] && d > 0.0 {
            let side = if y_um[i] < 0.0 { &mut left } else if y_um[i] > 0.0 { &mut right } else { continue };
            if side.is_none_or(|(best, _)| d > best) {
                *side = Some((d, i));
            }
        }
    }
    let refine = |i: usize| {
        let f = [density[i - 1], density[i], density[i + 1]];
        let f = if f.iter().all(|&v| v > 0.0) { f.map(f64::ln) } else { f };
        parabola_vertex([y_um[i - 1], y_um[i], y_um[i + 1]], f)
    };
    Some((refine(left?.1), refine(right?.1)))
}

/// Off-centre position `(y_r - y_l) / 2` from the two peaks (paper, "Comparison of cell positions").
pub fn slipper_offset(y_um: &[f64], density: &[f64]) -> Option<f64> {
    density_peaks(y_um, density).map(|(l, r)| 0.5 * (r - l))
}

/// Half-width of the channel support of the experiment's densities, um (ksdensity `'Support', [-6 6]`).
pub const SUPPORT_HALF_WIDTH_UM: f64 = 6.0;

/// Slipper-only y-densities computed from `tracks.csv` rows when `kde.csv` is
/// not available: for every (pressure, position > 0) group with at least 3
/// isolated slippers, MATLAB's `ksdensity(y_mean, 'Support', [-6 6])` on its
/// 100-point grid ([`crate::experiment::kde::ksdensity`]), as `rbc-analyze` writes `kde.csv`.
/// Cells at |y| >= 6 um (outside the open support) are left out.
pub fn slipper_densities(tracks: &[TrackRow]) -> Vec<KdeRow> {
    let mut keys: Vec<(f64, f64)> = tracks.iter().filter(|t| t.position_mm > 0.0).map(|t| (t.pressure_mbar, t.position_mm)).collect();
    keys.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    keys.dedup();
    let mut out = Vec::new();
    for (p, pos) in keys {
        let ys: Vec<f64> = tracks
            .iter()
            .filter(|t| t.pressure_mbar == p && t.position_mm == pos && t.isolated && t.shape == "slipper")
            .map(|t| t.y_mean_um)
            .filter(|y| y.abs() < SUPPORT_HALF_WIDTH_UM)
            .collect();
        if ys.len() < 3 {
            continue;
        }
        let Ok(k) = crate::experiment::kde::ksdensity(&ys, Some((-SUPPORT_HALF_WIDTH_UM, SUPPORT_HALF_WIDTH_UM)), crate::experiment::kde::DEFAULT_POINTS) else {
            continue;
        };
        out.extend(k.y.iter().zip(&k.density).map(|(&y, &d)| KdeRow { pressure_mbar: p, position_mm: pos, shape: "slipper".into(), y_um: y, density: d }));
    }
    out
}

/// Tank-treading slippers binned by velocity (`rel_tol` as for the thresholds).
/// Runs are weighted equally (the paper weights by the observed steady time,
/// which `results.h5` does not record separately).
pub fn simulated_offsets(points: &[PhasePoint], rel_tol: f64) -> Vec<SimulatedOffset> {
    let sl: Vec<&PhasePoint> = points.iter().filter(|p| p.final_shape == FinalShape::Slipper && p.tank_treading).collect();
    let bins = bin_velocities(&sl.iter().map(|p| p.velocity_mm_s).collect::<Vec<_>>(), rel_tol);
    let nb = bins.iter().copied().max().map_or(0, |m| m + 1);
    (0..nb)
        .map(|b| {
            let col: Vec<&PhasePoint> = sl.iter().zip(&bins).filter(|(_, &bb)| bb == b).map(|(p, _)| *p).collect();
            let n = col.len() as f64;
            let ys: Vec<f64> = col.iter().map(|p| p.mean_y_um.abs()).collect();
            let zs: Vec<f64> = col.iter().map(|p| p.mean_z_um.abs()).collect();
            let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
            let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            SimulatedOffset {
                velocity_mm_s: col.iter().map(|p| p.velocity_mm_s).sum::<f64>() / n,
                velocity_min_mm_s: col.iter().map(|p| p.min_velocity_mm_s).fold(f64::INFINITY, f64::min),
                velocity_max_mm_s: col.iter().map(|p| p.max_velocity_mm_s).fold(f64::NEG_INFINITY, f64::max),
                abs_y_um: ys.iter().sum::<f64>() / n,
                abs_y_min_um: min(&ys),
                abs_y_max_um: max(&ys),
                abs_z_um: zs.iter().sum::<f64>() / n,
                abs_z_min_um: min(&zs),
                abs_z_max_um: max(&zs),
                n_runs: col.len(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slipper_density_from_tracks_has_its_peaks_near_the_two_clusters() {
        let track = |y: f64, shape: &str, isolated: bool| TrackRow {
            recording: "r".into(), pressure_mbar: 100.0, position_mm: 10.0, track_id: 0, n_frames: 10, x_first_um: 0.0,
            y_mean_um: y, y_std_um: 0.1, velocity_mm_s: 5.0, velocity_se_mm_s: 0.01, isolated, gap_um: 100.0,
            shape: shape.into(), shape_score: -0.5, p_croissant: None,
        };
        // 40 slippers in two symmetric clusters at -+1.2 um (spread +-0.2), plus croissants and a crowded slipper that must not count
        let mut t: Vec<TrackRow> = (0..40).map(|i| {
            let side = if i % 2 == 0 { 1.0 } else { -1.0 };
            track(side * (1.2 + 0.2 * ((i / 2) as f64 / 19.0 * 2.0 - 1.0)), "slipper", true)
        }).collect();
        t.extend((0..30).map(|_| track(0.0, "croissant", true)));
        t.push(track(0.0, "slipper", false));
        let rows = slipper_densities(&t);
        assert_eq!(rows.len(), crate::experiment::kde::DEFAULT_POINTS);
        let (y, d): (Vec<f64>, Vec<f64>) = rows.iter().map(|r| (r.y_um, r.density)).unzip();
        let (l, r) = density_peaks(&y, &d).unwrap();
        // symmetric sample: symmetric peaks; the smoothing keeps them within the clusters' +-0.2 um
        assert!((l + r).abs() < 1e-6 && (r - 1.2).abs() < 0.2, "{l} {r}");
        // under 3 slippers: no density
        assert!(slipper_densities(&t[40..]).is_empty());
    }

    #[test]
    fn parabola_vertex_is_exact_for_a_parabola() {
        let f = |x: f64| -2.0 * (x - 0.37).powi(2) + 1.0;
        let v = parabola_vertex([0.1, 0.4, 0.8], [f(0.1), f(0.4), f(0.8)]);
        assert!((v - 0.37).abs() < 1e-12, "{v}");
    }

    #[test]
    fn two_gaussian_peaks_give_their_half_distance() {
        // density of two equal Gaussians at -1.1 and +1.3 (sigma 0.4) on ksdensity's 100-point grid over [-6, 6]
        let y: Vec<f64> = (0..100).map(|i| -6.0 + 12.0 * i as f64 / 99.0).collect();
        let g = |x: f64, m: f64| (-(x - m).powi(2) / (2.0 * 0.16)).exp();
        let d: Vec<f64> = y.iter().map(|&x| g(x, -1.1) + g(x, 1.3)).collect();
        let (l, r) = density_peaks(&y, &d).unwrap();
        // the parabola through log-density is exact for one Gaussian; the tail of the
        // other Gaussian (6 sigma away) moves each peak by ~1e-7 um: 1e-5 leaves room
        assert!((l + 1.1).abs() < 1e-5 && (r - 1.3).abs() < 1e-5, "{l} {r}");
        assert!((slipper_offset(&y, &d).unwrap() - 1.2).abs() < 1e-5);
        // one-sided density: no offset
        let d1: Vec<f64> = y.iter().map(|&x| g(x, 1.3)).collect();
        assert_eq!(slipper_offset(&y, &d1), None);
    }
}
