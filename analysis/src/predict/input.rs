//! The experiment's side of the prediction: pressure groups from `entry.csv`, with velocities and observed fractions from `summary.csv`.

use crate::error::AnalysisError;
use crate::types::prediction::{Observed, PressureGroup, VelocitySource};
use rbc_schema::tables::{EntryRow, SummaryRow};
use std::path::Path;

/// Position along the channel where the observed fractions are taken, mm (paper Fig. 3a).
pub const OBSERVED_POSITION_MM: f64 = 10.0;

/// Same pressure drop (the CSVs are written from the same `recording.toml` values).
fn same_pressure(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1.0)
}

fn mean_std(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = if v.len() > 1 { v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
    (m, var.sqrt())
}

/// Largest plausible driving pressure (mbar): 100 bar, far beyond any PDMS chip.
pub const MAX_PRESSURE_MBAR: f64 = 1e5;
/// Largest plausible lateral offset (um) of a cell from the channel axis.
pub const MAX_OFFSET_UM: f64 = 1e3;
/// Largest plausible cell velocity (mm/s): 1 m/s, ~100x the paper's fastest cells.
pub const MAX_VELOCITY_MM_S: f64 = 1e3;

/// A plausible range: `[lo, hi]`, or `(0, hi]`.
#[derive(Clone, Copy)]
enum Range {
    Closed(f64, f64),
    AboveZero(f64),
}

/// A number as a reader wants it in a message: plain when moderate, else in exponent form.
fn shown(v: f64) -> String {
    if v == 0.0 || (1e-3..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Refuse `v` (row `row`, column `col` of `path`) outside `range`, naming both.
fn plausible(path: &Path, row: usize, col: &str, v: f64, range: Range, unit: &str) -> Result<(), AnalysisError> {
    let (inside, text) = match range {
        Range::Closed(lo, hi) => ((lo..=hi).contains(&v), format!("[{}, {}]", shown(lo), shown(hi))),
        Range::AboveZero(hi) => (v > 0.0 && v <= hi, format!("(0, {}]", shown(hi))),
    };
    if inside {
        return Ok(());
    }
    Err(AnalysisError::Input { path: path.into(), message: format!("row {row}, column `{col}`: {} is outside the plausible range {text} {unit}", shown(v)) })
}

/// Group `entry.csv` rows by pressure and attach the observed row of each
/// pressure from `summary.csv` (if given). Returns the groups (by increasing
/// pressure) and warnings (observed groups without entrance cells).
///
/// Errors name the file and the row (1-based after the header) for a
/// non-finite `y_um` or `velocity_mm_s`, a value outside its plausible range (pressure in
/// [0, 1e5] mbar, |y| <= 1e3 um, velocity in (0, 1e3] mm/s), a fraction outside [0, 1], or a
/// second `summary.csv` row of one (pressure, position) group.
pub fn pressure_groups(
    entry: &[EntryRow],
    entry_path: &Path,
    summary: Option<(&[SummaryRow], &Path)>,
) -> Result<(Vec<PressureGroup>, Vec<String>), AnalysisError> {
    let bad = |path: &Path, row: usize, col: &str, v: f64| AnalysisError::Input {
        path: path.into(),
        message: format!("row {row}, column `{col}`: {v} is not a finite value"),
    };
    if entry.is_empty() {
        return Err(AnalysisError::Input { path: entry_path.into(), message: "no cells (empty table)".into() });
    }
    for (i, r) in entry.iter().enumerate() {
        for (col, v) in [("pressure_mbar", r.pressure_mbar), ("y_um", r.y_um), ("velocity_mm_s", r.velocity_mm_s)] {
            if !v.is_finite() {
                return Err(bad(entry_path, i + 1, col, v));
            }
        }
        // physically meaningful ranges (a cell in a microchannel; no lab's entry table leaves them)
        plausible(entry_path, i + 1, "pressure_mbar", r.pressure_mbar, Range::Closed(0.0, MAX_PRESSURE_MBAR), "mbar")?;
        plausible(entry_path, i + 1, "y_um", r.y_um, Range::Closed(-MAX_OFFSET_UM, MAX_OFFSET_UM), "um")?;
        plausible(entry_path, i + 1, "velocity_mm_s", r.velocity_mm_s, Range::AboveZero(MAX_VELOCITY_MM_S), "mm/s")?;
    }
    let mut pressures: Vec<f64> = entry.iter().map(|r| r.pressure_mbar).collect();
    pressures.sort_by(f64::total_cmp);
    pressures.dedup_by(|a, b| same_pressure(*a, *b));

    let mut observed_rows: Vec<(f64, Observed)> = Vec::new();
    if let Some((rows, path)) = summary {
        for (i, r) in rows.iter().enumerate() {
            let fields = [
                ("pressure_mbar", r.pressure_mbar),
                ("position_mm", r.position_mm),
                ("velocity_mean_mm_s", r.velocity_mean_mm_s),
                ("velocity_std_mm_s", r.velocity_std_mm_s),
                ("frac_croissant", r.frac_croissant),
            ];
            for (col, v) in fields {
                if !v.is_finite() {
                    return Err(bad(path, i + 1, col, v));
                }
            }
            plausible(path, i + 1, "pressure_mbar", r.pressure_mbar, Range::Closed(0.0, MAX_PRESSURE_MBAR), "mbar")?;
            plausible(path, i + 1, "velocity_mean_mm_s", r.velocity_mean_mm_s, Range::AboveZero(MAX_VELOCITY_MM_S), "mm/s")?;
            plausible(path, i + 1, "velocity_std_mm_s", r.velocity_std_mm_s, Range::Closed(0.0, MAX_VELOCITY_MM_S), "mm/s")?;
            if !(0.0..=1.0).contains(&r.frac_croissant) {
                return Err(AnalysisError::Input {
                    path: path.into(),
                    message: format!("row {}, column `frac_croissant`: {} is outside [0, 1]", i + 1, r.frac_croissant),
                });
            }
            // one row a (pressure, position) group, as rbc-analyze writes them (its groups are
            // the exact values): a second one would silently lose to the first
            if let Some(j) = rows[..i].iter().position(|q| q.pressure_mbar == r.pressure_mbar && q.position_mm == r.position_mm) {
                return Err(AnalysisError::Input {
                    path: path.into(),
                    message: format!("row {}: the group at {} mbar, {} mm again (row {} has it)", i + 1, r.pressure_mbar, r.position_mm, j + 1),
                });
            }
            if r.position_mm <= 0.0 {
                continue;
            }
            let (lo, hi) = match (r.frac_croissant_lo, r.frac_croissant_hi) {
                (Some(lo), Some(hi)) if lo.is_finite() && hi.is_finite() => (lo.min(r.frac_croissant), hi.max(r.frac_croissant)),
                _ => super::fraction::wilson(r.frac_croissant, r.n_cells as usize, 1.96),
            };
            let obs = Observed {
                position_mm: r.position_mm,
                n_cells: r.n_cells,
                frac_croissant: r.frac_croissant,
                frac_croissant_lo: lo,
                frac_croissant_hi: hi,
                velocity_mean_mm_s: r.velocity_mean_mm_s,
                velocity_std_mm_s: r.velocity_std_mm_s,
            };
            // keep, per pressure, the row closest to 10 mm
            match observed_rows.iter_mut().find(|(p, _)| same_pressure(*p, r.pressure_mbar)) {
                Some((_, o)) if (o.position_mm - OBSERVED_POSITION_MM).abs() > (r.position_mm - OBSERVED_POSITION_MM).abs() => *o = obs,
                Some(_) => {}
                None => observed_rows.push((r.pressure_mbar, obs)),
            }
        }
    }

    let mut warnings = Vec::new();
    for (p, _) in &observed_rows {
        if !pressures.iter().any(|q| same_pressure(*p, *q)) {
            warnings.push(format!("observed group at {p} mbar has no entering cells in the entry table: no prediction for it"));
        }
    }
    let groups = pressures
        .iter()
        .map(|&p| {
            let cells: Vec<&EntryRow> = entry.iter().filter(|r| same_pressure(r.pressure_mbar, p)).collect();
            let entry_y_um: Vec<f64> = cells.iter().map(|r| r.y_um).collect();
            let observed = observed_rows.iter().find(|(q, _)| same_pressure(*q, p)).map(|(_, o)| o.clone());
            let (velocity_mm_s, velocity_std_mm_s, velocity_source) = match &observed {
                Some(o) => (o.velocity_mean_mm_s, o.velocity_std_mm_s, VelocitySource::Observed),
                None => {
                    let v: Vec<f64> = cells.iter().map(|r| r.velocity_mm_s).collect();
                    let (m, s) = mean_std(&v);
                    (m, s, VelocitySource::Entry)
                }
            };
            PressureGroup { pressure_mbar: p, velocity_mm_s, velocity_std_mm_s, velocity_source, entry_y_um, observed }
        })
        .collect();
    Ok((groups, warnings))
}
