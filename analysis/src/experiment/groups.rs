//! Per (pressure, position) group statistics of isolated cells: counts, shape fractions with Wilson intervals, velocities, y-densities, entrance sample.
//!
//! Only cells with `isolated == true` enter any of the outputs (paper: cells
//! with no other object within 40 um). For every group that has at least one
//! isolated cell [`summarise`] produces
//! - one [`SummaryRow`]: `n_cells`, mean and sample standard deviation (n - 1,
//!   MATLAB `std`) of `velocity_mm_s`, fractions of `croissant`, `slipper`,
//!   `other` (any other label counts as `other`), and the **Wilson score 95 %
//!   interval** of the croissant and slipper fractions ([`wilson_interval`]), and beside them the
//!   classification uncertainty ([`expected_fraction`]): the expected croissant fraction
//!   `frac_croissant_expected` = mean of the cells' `p_croissant` and its standard deviation
//!   `frac_croissant_expected_sd` = sqrt(sum p (1 - p)) / n. The Wilson interval is the sampling
//!   error of the counted labels (which cells happened to be filmed); the expected fraction and
//!   its sd say how far the labels themselves may be off (the cell's shape is uncertain);
//! - [`KdeRow`]s: the density of `y_mean_um` estimated like MATLAB
//!   `ksdensity(y, 'Support', [-6 6])` ([`crate::experiment::kde`], 100 points) for the
//!   shapes `all`, `croissant`, `slipper`, `other` that have at least
//!   [`MIN_KDE_CELLS`] cells;
//! - at `position_mm == 0`, one [`EntryRow`] per isolated cell (the entrance
//!   sample `rbc-predict` maps the simulated thresholds onto).
//!
//! Groups are keyed by exact (pressure_mbar, position_mm) values (they come
//! from `recording.toml`) and sorted by pressure, then position.

use crate::experiment::kde::{ksdensity, DEFAULT_POINTS};
use rbc_schema::tables::{EntryRow, KdeRow, SummaryRow, TrackRow};

/// Support of the y-densities, um: the paper's `'Support', [-6 6]` (channel width ~12 um).
pub const Y_SUPPORT_UM: (f64, f64) = (-6.0, 6.0);

/// Fewest cells of a group and shape for which a density is estimated.
pub const MIN_KDE_CELLS: usize = 3;

/// Standard normal quantile $\Phi^{-1}(0.975)$ for two-sided 95 % intervals (to double precision).
pub const Z_95: f64 = 1.959_963_984_540_054;

/// The shape labels of `kde.csv`, in output order.
pub const KDE_SHAPES: [&str; 4] = ["all", "croissant", "slipper", "other"];

/// The tables derived from `tracks.csv`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Groups {
    pub summary: Vec<SummaryRow>,
    pub kde: Vec<KdeRow>,
    pub entry: Vec<EntryRow>,
    /// Human-readable notes on cells or densities left out (e.g. a y outside the support), one line each.
    pub notes: Vec<String>,
}

/// Wilson score interval of a binomial proportion `k / n` at normal quantile `z`
/// (Wilson 1927; Newcombe 1998, method 3):
/// $$\frac{\hat p + \frac{z^2}{2n} \pm z\sqrt{\frac{\hat p(1-\hat p)}{n} + \frac{z^2}{4n^2}}}{1 + \frac{z^2}{n}}.$$
/// Returns `(lo, hi)` within [0, 1]; `n = 0` gives the uninformative `(0, 1)`.
pub fn wilson_interval(k: u64, n: u64, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let n_f = n as f64;
    let p = k as f64 / n_f;
    let z2 = z * z;
    let denom = 1.0 + z2 / n_f;
    let centre = (p + z2 / (2.0 * n_f)) / denom;
    let half = z / denom * (p * (1.0 - p) / n_f + z2 / (4.0 * n_f * n_f)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// Mean and sample standard deviation (divisor n - 1; 0 for a single value), as MATLAB `mean` and `std`.
pub fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    if v.len() < 2 {
        return (mean, 0.0);
    }
    let ss: f64 = v.iter().map(|x| (x - mean) * (x - mean)).sum();
    (mean, (ss / (n - 1.0)).sqrt())
}

/// Expected croissant fraction and its standard deviation from the classification alone:
/// with independent cells, cell $i$ a croissant with probability $p_i$, the number of
/// croissants has mean $\sum p_i$ and variance $\sum p_i (1 - p_i)$ (Poisson binomial), so
/// $$\bar p = \frac{1}{n} \sum_i p_i, \qquad \sigma = \frac{1}{n} \sqrt{\sum_i p_i (1 - p_i)}.$$
/// `None` when `p` is empty or a value is missing (a table written without `p_croissant`).
pub fn expected_fraction(p: &[Option<f64>]) -> Option<(f64, f64)> {
    if p.is_empty() {
        return None;
    }
    let p: Vec<f64> = p.iter().copied().collect::<Option<Vec<f64>>>()?;
    let n = p.len() as f64;
    let mean = p.iter().sum::<f64>() / n;
    let var: f64 = p.iter().map(|&q| q * (1.0 - q)).sum();
    Some((mean, var.sqrt() / n))
}

/// Shape class of a track for counting: `croissant`, `slipper`, or `other` for anything else.
fn shape_class(shape: &str) -> &'static str {
    match shape {
        "croissant" => "croissant",
        "slipper" => "slipper",
        _ => "other",
    }
}

/// Group key; `+ 0.0` folds -0.0 into 0.0 so both land in one group.
fn key(t: &TrackRow) -> (f64, f64) {
    (t.pressure_mbar + 0.0, t.position_mm + 0.0)
}

/// Statistics of the isolated cells of `tracks`, grouped by (pressure, position).
pub fn summarise(tracks: &[TrackRow]) -> Groups {
    let mut out = Groups::default();
    let mut isolated: Vec<&TrackRow> = Vec::new();
    for t in tracks.iter().filter(|t| t.isolated) {
        if t.y_mean_um.is_finite()
            && t.velocity_mm_s.is_finite()
            && t.pressure_mbar.is_finite()
            && t.position_mm.is_finite()
        {
            isolated.push(t);
        } else {
            out.notes.push(format!(
                "track {} of {}: y = {} um, velocity = {} mm/s, pressure = {} mbar, position = {} mm is not a measurement; left out",
                t.track_id, t.recording, t.y_mean_um, t.velocity_mm_s, t.pressure_mbar, t.position_mm
            ));
        }
    }
    // stable sort keeps the input order (recording, track) inside a group
    isolated.sort_by(|a, b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.total_cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    });
    let mut start = 0;
    while start < isolated.len() {
        let k = key(isolated[start]);
        let end = start + isolated[start..].iter().take_while(|t| key(t) == k).count();
        summarise_group(k, &isolated[start..end], &mut out);
        start = end;
    }
    out
}

/// Append the rows of one group (all cells isolated, non-empty) to `out`.
fn summarise_group(
    (pressure_mbar, position_mm): (f64, f64),
    cells: &[&TrackRow],
    out: &mut Groups,
) {
    let n = cells.len() as u64;
    let count = |s: &str| cells.iter().filter(|t| shape_class(&t.shape) == s).count() as u64;
    let (n_c, n_s, n_o) = (count("croissant"), count("slipper"), count("other"));
    let velocities: Vec<f64> = cells.iter().map(|t| t.velocity_mm_s).collect();
    let (velocity_mean_mm_s, velocity_std_mm_s) = mean_std(&velocities);
    let (c_lo, c_hi) = wilson_interval(n_c, n, Z_95);
    let (s_lo, s_hi) = wilson_interval(n_s, n, Z_95);
    let p: Vec<Option<f64>> = cells.iter().map(|t| t.p_croissant).collect();
    let expected = expected_fraction(&p);
    out.summary.push(SummaryRow {
        pressure_mbar,
        position_mm,
        n_cells: n,
        velocity_mean_mm_s,
        velocity_std_mm_s,
        frac_croissant: n_c as f64 / n as f64,
        frac_slipper: n_s as f64 / n as f64,
        frac_other: n_o as f64 / n as f64,
        frac_croissant_lo: Some(c_lo),
        frac_croissant_hi: Some(c_hi),
        frac_slipper_lo: Some(s_lo),
        frac_slipper_hi: Some(s_hi),
        frac_croissant_expected: expected.map(|e| e.0),
        frac_croissant_expected_sd: expected.map(|e| e.1),
    });

    let (inside, outside): (Vec<&TrackRow>, Vec<&TrackRow>) = cells
        .iter()
        .copied()
        .partition(|t| t.y_mean_um > Y_SUPPORT_UM.0 && t.y_mean_um < Y_SUPPORT_UM.1);
    for t in &outside {
        out.notes.push(format!(
            "{pressure_mbar} mbar, {position_mm} mm: track {} of {} has y = {} um outside the support ({}, {}) um; left out of the densities",
            t.track_id, t.recording, t.y_mean_um, Y_SUPPORT_UM.0, Y_SUPPORT_UM.1
        ));
    }
    for shape in KDE_SHAPES {
        let members: Vec<&TrackRow> = inside
            .iter()
            .copied()
            .filter(|t| shape == "all" || shape_class(&t.shape) == shape)
            .collect();
        if members.len() < MIN_KDE_CELLS {
            continue;
        }
        let y: Vec<f64> = members.iter().map(|t| t.y_mean_um).collect();
        match ksdensity(&y, Some(Y_SUPPORT_UM), DEFAULT_POINTS) {
            Ok(kde) => {
                out.kde.extend(
                    kde.y
                        .iter()
                        .zip(&kde.density)
                        .map(|(&y_um, &density)| KdeRow {
                            pressure_mbar,
                            position_mm,
                            shape: shape.to_string(),
                            y_um,
                            density,
                        }),
                )
            }
            Err(e) => out.notes.push(format!(
                "{pressure_mbar} mbar, {position_mm} mm, {shape}: no density: {e}"
            )),
        }
    }

    if position_mm == 0.0 {
        out.entry.extend(cells.iter().map(|t| EntryRow {
            pressure_mbar,
            y_um: t.y_mean_um,
            velocity_mm_s: t.velocity_mm_s,
        }));
    }
}
