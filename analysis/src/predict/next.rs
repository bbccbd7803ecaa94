//! The next runs to simulate (`next_runs.csv` of `rbc-predict`): per start shape and pressure
//! group, the start offset whose outcome halves the entering cells that the simulated bracket of
//! r_trans leaves undecided.
//!
//! phi counts the entering cells with `|y| < y_trans` ([`super::fraction`]). While r_trans is
//! known only to lie in `(r_lo, r_hi)` (um: the largest croissant start and the smallest slipper
//! start, [`crate::simulated::threshold`]) at the group's velocity, the cells with
//! `y(r_lo) < |y| < y(r_hi)` are undecided (`y(r) = r 9 / sqrt(106)`, [`super::fraction::y_trans`]):
//! their fraction is the part of phi's interval that simulations can narrow (the rest is the
//! position uncertainty `s_P` and the finite sample). A run started at `r_init` inside the bracket
//! ends a croissant (then `r_lo` rises to `r_init`) or a slipper (`r_hi` falls to it), so the run
//! that halves the undecided cells whichever way it ends starts at their median `|y|`, projected
//! back onto the paper's initial-offset line: `r_init = |y| sqrt(106) / 9`.
//!
//! # Decisions
//!
//! - **Velocity**: a simulated column within the velocity tolerance of the group's velocity is
//!   joined: the run splits that column's bracket. Otherwise the run opens a column at the
//!   group's velocity (also outside the simulated range). A column knows nothing of its
//!   neighbours ([`ThresholdCurve::at`] returns a column's own bracket at its velocity), so until
//!   both shapes have ended in it r_trans there lies anywhere in `[0, inf)`: the first run of a
//!   new column starts at the median `|y|` of all the group's cells (either outcome decides half
//!   of them: a croissant those below, a slipper those above). The group's velocity spread
//!   `sigma_u` is not searched: the run narrows the bracket where the group's cells move on
//!   average.
//! - **A column whose croissants and slippers overlap** (the largest croissant start above the
//!   smallest slipper start; r_trans is then the fewest-misclassifications offset): a run between
//!   them moves neither end, so none is suggested (a warning says so).
//! - **Mean flow** to impose (the sweep's `mean_velocity_mm_s`): the cell velocity times the mean
//!   ratio of mean flow to cell velocity of the runs within the velocity tolerance of the nearest
//!   column (their scenes' `walls.mean_velocity_um_s`, [`mean_flow_mm_s`]); unknown (an empty
//!   cell of `next_runs.csv`, never a NaN) when none of them has a channel. Approximate: slippers move a little slower than croissants at one flow.
//! - **On the 0.01 um grid, strictly inside the bracket, no farther out than the grid**: the
//!   median's offset is rounded to 0.01 um and moved onto the nearest grid point inside the
//!   bracket. It is at most the largest offset any run of the start shape started from (farther
//!   starts may overlap the wall; the sweep records those as `overlaps-wall`), rounded down: when
//!   the median lies beyond it, the run starts there while that is inside the bracket. Otherwise
//!   (and when the bracket holds no grid point) no run is suggested and a warning says why.
//! - **Runs still going**: a run of the same start shape that has not ended (status `running`)
//!   whose mean flow is within the velocity tolerance of the suggested one and whose start lies
//!   inside the bracket will narrow it already: it is named in `awaits`; the suggestion stays (it
//!   is the one to queue after it, or instead of it).
//! - **Order**: most undecided cells first.

use super::fraction::y_trans;
use super::threshold::ThresholdCurve;
use crate::types::prediction::{NextRun, PressureGroup};
use rbc_schema::results::{RunRecord, RunStatus};
use rbc_schema::scene::{Scene, WallsSpec};
use std::path::Path;

/// The mean flow of a run's scene (mm/s): its periodic channel's `walls.mean_velocity_um_s`;
/// `None` for a scene without a channel or one that does not parse.
pub fn mean_flow_mm_s(run: &RunRecord) -> Option<f64> {
    let attrs = run.attrs.as_ref()?;
    match Scene::parse(&attrs.scene, Path::new(&run.run_id)).ok()?.walls {
        WallsSpec::PeriodicChannel { mean_velocity_um_s, .. } => Some(mean_velocity_um_s * 1e-3),
        WallsSpec::None => None,
    }
}

/// The median of `v` (sorted ascending, not empty): the middle value, or the mean of the two.
fn median(v: &[f64]) -> f64 {
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Inverse of [`y_trans`]: the offset on the initial-offset line whose y is `y_um`.
fn r_of_y(y_um: f64) -> f64 {
    y_um * 106f64.sqrt() / 9.0
}

/// The bracket the run splits at the group's velocity `u`: the column within `rel_tol` of it
/// (`joins`), or a new column at `u` (`new`, r_trans anywhere in `[0, inf)`); `Err` for a column
/// whose croissants and slippers overlap. Returns `(velocity, r_lo, r_hi, column)`.
fn bracket_at(curve: &ThresholdCurve, u: f64, rel_tol: f64) -> Result<(f64, f64, f64, &'static str), String> {
    let near = curve.nodes().iter().filter(|t| (t.velocity_mm_s - u).abs() <= rel_tol * u).min_by(|a, b| (a.velocity_mm_s - u).abs().total_cmp(&(b.velocity_mm_s - u).abs()));
    match near {
        Some(t) if t.r_lo_um > t.r_hi_um => Err(format!(
            "at the {:.3} mm/s column croissants (up to {:.2} um) and slippers (from {:.2} um) overlap: a run between them moves neither end, so none narrows r_trans there",
            t.velocity_mm_s, t.r_lo_um, t.r_hi_um
        )),
        Some(t) => Ok((t.velocity_mm_s, t.r_lo_um, t.r_hi_um, "joins")),
        // a column knows nothing of its neighbours: until both shapes end in it, r_trans there
        // is anywhere in [0, inf)
        None => Ok((u, 0.0, f64::INFINITY, "new")),
    }
}

/// The start on the 0.01 um grid strictly inside `(lo, hi)` nearest `wanted` (um), at most
/// `reach` rounded down (when finite); `Err` with the reason when there is none.
fn grid_start(wanted: f64, reach: f64, lo: f64, hi: f64) -> Result<f64, String> {
    let (first, last) = (((lo * 100.0 + 1e-9).floor() + 1.0) / 100.0, ((hi * 100.0 - 1e-9).ceil() - 1.0) / 100.0);
    if first > last {
        return Err("the bracket holds no start on the 0.01 um grid".into());
    }
    if wanted > reach && reach.is_finite() {
        let capped = (reach * 100.0 + 1e-9).floor() / 100.0;
        if capped < first {
            return Err(format!("they lie beyond the largest start the runs reach ({reach:.2} um): no run of the grid narrows it"));
        }
        return Ok(capped.min(last));
    }
    Ok(((wanted * 100.0).round() / 100.0).clamp(first, last))
}

/// The mean flow (mm/s) for cells at `velocity_mm_s`: that velocity times the mean ratio of mean
/// flow to cell velocity of the ended runs (`run_velocities`) within `rel_tol` of the nearest
/// column; `None` when none of them has a channel.
fn mean_flow_for(curve: &ThresholdCurve, velocity_mm_s: f64, runs: &[RunRecord], run_velocities: &[(String, f64)], rel_tol: f64) -> Option<f64> {
    let nearest = curve.nodes().iter().map(|t| t.velocity_mm_s).min_by(|a, b| (a - velocity_mm_s).abs().total_cmp(&(b - velocity_mm_s).abs()));
    let ratios: Vec<f64> = run_velocities
        .iter()
        .filter(|(_, v)| nearest.is_some_and(|n| (v - n).abs() <= rel_tol * n))
        .filter_map(|(id, v)| runs.iter().find(|r| &r.run_id == id).and_then(mean_flow_mm_s).map(|f| f / v))
        .collect();
    (!ratios.is_empty()).then(|| velocity_mm_s * ratios.iter().sum::<f64>() / ratios.len() as f64)
}

/// The runs of `shape` still going (status `running`) at a mean flow within `rel_tol` of `flow`
/// from a start inside `(lo, hi)`, space-separated (none when `flow` is unknown).
fn awaited(runs: &[RunRecord], shape: &str, lo: f64, hi: f64, flow: Option<f64>, rel_tol: f64) -> String {
    let Some(flow) = flow else { return String::new() };
    runs.iter()
        .filter(|run| run.status == RunStatus::Running)
        .filter(|run| run.attrs.as_ref().is_some_and(|a| a.start_shape == shape && a.r_init_um > lo && a.r_init_um < hi))
        .filter(|run| mean_flow_mm_s(run).is_some_and(|f| (f - flow).abs() <= rel_tol * flow.abs()))
        .map(|run| run.run_id.as_str())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The run that halves the undecided cells of group `g` for start shape `shape` (see the module
/// documentation), or `Err` with why none does (for a warning); `Ok(None)` when the bracket
/// leaves no cell undecided.
///
/// `runs` are all the runs read (for the largest start of the shape, the mean flow of the
/// columns' runs and the runs still going); `run_velocities` the ended runs of this start shape
/// as `(run_id, cell velocity mm/s)`; `rel_tol` the velocity tolerance of the columns.
pub fn next_run(
    curve: &ThresholdCurve,
    shape: &str,
    g: &PressureGroup,
    runs: &[RunRecord],
    run_velocities: &[(String, f64)],
    rel_tol: f64,
) -> Result<Option<NextRun>, String> {
    let label = format!("start shape {shape}, {} mbar", g.pressure_mbar);
    let (velocity_mm_s, lo, hi, column) = bracket_at(curve, g.velocity_mm_s, rel_tol).map_err(|why| format!("{label}: {why}"))?;
    let mut undecided: Vec<f64> = g.entry_y_um.iter().map(|y| y.abs()).filter(|&y| y > y_trans(lo) && y < y_trans(hi)).collect();
    if undecided.is_empty() {
        return Ok(None);
    }
    undecided.sort_by(f64::total_cmp);
    let reach = runs
        .iter()
        .filter(|run| run.status != RunStatus::OverlapsWall)
        .filter_map(|run| run.attrs.as_ref().filter(|a| a.start_shape == shape).map(|a| a.r_init_um))
        .fold(f64::NEG_INFINITY, f64::max);
    let r = grid_start(r_of_y(median(&undecided)), reach, lo, hi).map_err(|why| {
        format!(
            "{label}: {} of {} entering cells are undecided (r_trans in [{lo:.2}, {hi:.2}] um at {velocity_mm_s:.3} mm/s), but {why}",
            undecided.len(),
            g.entry_y_um.len()
        )
    })?;
    let flow = mean_flow_for(curve, velocity_mm_s, runs, run_velocities, rel_tol);
    Ok(Some(NextRun {
        start_shape: shape.into(),
        pressure_mbar: g.pressure_mbar,
        velocity_mm_s,
        mean_flow_mm_s: flow,
        r_init_um: r,
        r_lo_um: lo,
        r_hi_um: hi,
        cells: g.entry_y_um.len(),
        undecided: undecided.len(),
        column: column.into(),
        awaits: awaited(runs, shape, lo, hi, flow, rel_tol),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulated::threshold::Threshold;
    use crate::types::prediction::VelocitySource;
    use rbc_schema::results::RunAttrs;

    fn column(u: f64, lo: f64, hi: f64) -> Threshold {
        let r = if hi.is_infinite() { f64::INFINITY } else { 0.5 * (lo + hi) };
        Threshold { start_shape: "discocyte".into(), velocity_mm_s: u, r_trans_um: r, r_lo_um: lo, r_hi_um: hi, n_croissant: 1, n_slipper: usize::from(hi.is_finite()) }
    }

    fn group(u: f64, ys: &[f64]) -> PressureGroup {
        PressureGroup { pressure_mbar: 200.0, velocity_mm_s: u, velocity_std_mm_s: 0.05, velocity_source: VelocitySource::Entry, entry_y_um: ys.to_vec(), observed: None }
    }

    /// A run of the study's scene (the paper's channel) at mean flow `flow_mm_s`.
    fn run(id: &str, status: RunStatus, r_init_um: f64, flow_mm_s: f64) -> RunRecord {
        let scene = include_str!("../../../examples/sweeps/science-6p5-scene.toml").replace("mean_velocity_um_s = 3800.0", &format!("mean_velocity_um_s = {}", flow_mm_s * 1e3));
        let attrs = RunAttrs { start_shape: "discocyte".into(), r_init_um, y_init_um: 0.0, z_init_um: 0.0, lambda: 5.0, scene };
        RunRecord { run_id: id.into(), status, attrs: Some(attrs), summary: None, failure: None, not_run: None, copied_from: None, transits: Vec::new(), n_samples: 0, n_snapshots: 0 }
    }

    /// A group within 5 % of a column joins it: the column's bracket [0.4, 1.2] um leaves the
    /// cells with y(0.4) = 0.350 < |y| < y(1.2) = 1.049 um undecided (0.5, 0.6, 0.7, 0.9 of the
    /// six), whose median 0.65 um lies on the offset line at 0.65 sqrt(106) / 9 = 0.743 um: two of
    /// them below it and two above, whichever way the run ends. The mean flow is the column's runs'
    /// ratio (1.2 mm/s for 2.0 mm/s cells); the run still going at that flow from 0.8 um is awaited,
    /// the one at another flow and the one outside the bracket are not.
    #[test]
    fn a_run_halves_the_undecided_cells_of_the_column_it_joins() {
        let curve = ThresholdCurve::new(&[column(2.0, 0.4, 1.2), column(4.0, 0.8, 1.6)], "discocyte").unwrap();
        let g = group(2.05, &[0.1, -0.5, 0.6, -0.7, 0.9, 1.3]);
        let runs = [
            run("c", RunStatus::Steady, 0.4, 1.2),
            run("s", RunStatus::Periodic, 1.2, 1.2),
            run("going", RunStatus::Running, 0.8, 1.21),
            run("faster", RunStatus::Running, 0.8, 2.4),
            run("outside", RunStatus::Running, 1.3, 1.2),
        ];
        let velocities = [("c".to_string(), 2.0), ("s".to_string(), 2.0)];
        let n = next_run(&curve, "discocyte", &g, &runs, &velocities, 0.05).unwrap().unwrap();
        assert_eq!((n.velocity_mm_s, n.r_init_um, n.r_lo_um, n.r_hi_um, n.cells, n.undecided), (2.0, 0.74, 0.4, 1.2, 6, 4), "{n:?}");
        assert_eq!((n.column.as_str(), n.awaits.as_str()), ("joins", "going"));
        assert!((n.mean_flow_mm_s.unwrap() - 1.2).abs() < 1e-12, "{n:?}");
        let below = g.entry_y_um.iter().filter(|y| y.abs() > y_trans(0.4) && y.abs() < y_trans(n.r_init_um)).count();
        assert_eq!(below, 2, "half the undecided cells below the run's start");
        // a bracket that decides every cell: no run
        assert_eq!(next_run(&curve, "discocyte", &group(2.0, &[0.1, 1.3]), &runs, &velocities, 0.05), Ok(None));
    }

    /// Between two columns (2 and 4 mm/s) the run opens a column at the group's 3 mm/s, which
    /// knows nothing of its neighbours' brackets: r_trans there lies anywhere in [0, inf), every
    /// cell is undecided, and the run starts at the median |y| of all of them, 1.0 um, on the
    /// offset line at 1.0 sqrt(106) / 9 = 1.144 um (not the interpolated bracket's middle, 1.0 um).
    #[test]
    fn between_columns_the_run_opens_one_at_the_groups_velocity() {
        let curve = ThresholdCurve::new(&[column(2.0, 0.4, 1.2), column(4.0, 0.8, 1.6)], "discocyte").unwrap();
        let ys: Vec<f64> = (0..200).map(|i| 0.01 * i as f64 + 0.005).collect();
        let runs = [run("c", RunStatus::Steady, 0.4, 1.2), run("s", RunStatus::Periodic, 1.6, 2.8)];
        let velocities = [("c".to_string(), 2.0), ("s".to_string(), 4.0)];
        let n = next_run(&curve, "discocyte", &group(3.0, &ys), &runs, &velocities, 0.05).unwrap().unwrap();
        assert_eq!((n.column.as_str(), n.velocity_mm_s, n.r_init_um, n.r_lo_um, n.r_hi_um, n.undecided), ("new", 3.0, 1.14, 0.0, f64::INFINITY, 200), "{n:?}");
        // of two equidistant columns the slower one's ratio (0.6, not the 4 mm/s column's 0.7)
        assert!((n.mean_flow_mm_s.unwrap() - 1.8).abs() < 1e-12, "{n:?}");
        // below the simulated range as well: a new column at the group's velocity
        let n = next_run(&curve, "discocyte", &group(0.5, &ys), &runs, &velocities, 0.05).unwrap().unwrap();
        assert_eq!((n.column.as_str(), n.velocity_mm_s, n.r_init_um), ("new", 0.5, 1.14), "{n:?}");
        assert!((n.mean_flow_mm_s.unwrap() - 0.3).abs() < 1e-12, "{n:?}");
    }

    /// The start lies on the 0.01 um grid strictly inside the bracket: a median 0.002 um above the
    /// largest croissant start (0.4 um) would round onto it, so the run starts at 0.41; a bracket
    /// holding no grid point ([0.40, 0.405]) and one whose croissants and slippers overlap (a
    /// croissant from 1.0 um, a slipper from 0.8) get no run, and a warning that says why.
    #[test]
    fn the_start_stays_strictly_inside_the_bracket_on_the_grid() {
        let runs = [run("c", RunStatus::Steady, 0.4, 1.2), run("s", RunStatus::Periodic, 1.2, 1.2)];
        let velocities = [("c".to_string(), 2.0), ("s".to_string(), 2.0)];
        let curve = ThresholdCurve::new(&[column(2.0, 0.4, 1.2)], "discocyte").unwrap();
        let n = next_run(&curve, "discocyte", &group(2.0, &[y_trans(0.402)]), &runs, &velocities, 0.05).unwrap().unwrap();
        assert_eq!((n.r_init_um, n.undecided), (0.41, 1), "{n:?}");
        let narrow = ThresholdCurve::new(&[column(2.0, 0.4, 0.405)], "discocyte").unwrap();
        let why = next_run(&narrow, "discocyte", &group(2.0, &[y_trans(0.402)]), &runs, &velocities, 0.05).unwrap_err();
        assert!(why.contains("1 of 1 entering cells are undecided") && why.contains("no start on the 0.01 um grid"), "{why}");
        let overlap = ThresholdCurve::new(&[Threshold { r_lo_um: 1.0, r_hi_um: 0.8, ..column(2.0, 0.4, 1.2) }], "discocyte").unwrap();
        let why = next_run(&overlap, "discocyte", &group(2.0, &[0.7]), &runs, &velocities, 0.05).unwrap_err();
        assert!(why.contains("overlap") && why.contains("2.000 mm/s"), "{why}");
    }

    /// A new column between a bistable one and a croissant-only one: the median of all the cells,
    /// 2.0 um on the offset line at 2.29 um, lies beyond the largest start the runs reach (1.2 um;
    /// the start that overlapped the wall does not count), so the run starts there. At the
    /// croissant-only column itself (croissants up to 1.2 um) the undecided cells lie beyond it:
    /// no run of the grid narrows that bracket, which is said, not suggested.
    #[test]
    fn no_run_starts_beyond_the_grids_largest_offset() {
        let curve = ThresholdCurve::new(&[column(1.0, 0.4, 1.2), column(2.5, 1.2, f64::INFINITY)], "discocyte").unwrap();
        let ys = [0.2, 1.5, 2.0, 2.5, 3.0];
        let runs = [run("c", RunStatus::Steady, 0.4, 0.6), run("s", RunStatus::Periodic, 1.2, 0.6), run("wall", RunStatus::OverlapsWall, 3.0, 0.6)];
        let velocities = [("c".to_string(), 1.0), ("s".to_string(), 1.0)];
        let n = next_run(&curve, "discocyte", &group(2.0, &ys), &runs, &velocities, 0.05).unwrap().unwrap();
        assert_eq!((n.r_init_um, n.r_lo_um, n.r_hi_um, n.undecided, n.column.as_str()), (1.2, 0.0, f64::INFINITY, 5, "new"), "{n:?}");
        let why = next_run(&curve, "discocyte", &group(2.5, &ys), &runs, &velocities, 0.05).unwrap_err();
        assert!(why.contains("200 mbar") && why.contains("4 of 5 entering cells are undecided") && why.contains("1.20 um"), "{why}");
    }
}
