//! The turn-overs and folds of the runs of results files (`rbc-sweep events`): the moments each
//! cell stopped lying along the flow, found in its stored samples by
//! [`rbc_analysis::simulated::orbit_events::length_collapses`], as a CSV table.

use super::SweepError;
use rbc_analysis::simulated::orbit_events::{length_collapses, Collapse};
use rbc_schema::results::ResultsFile;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The collapses of one run's samples.
#[derive(Debug, Clone)]
pub struct RunEvents {
    pub file: PathBuf,
    pub run_id: String,
    /// The run's last sample, s.
    pub t_end_s: f64,
    pub collapses: Vec<Collapse>,
}

/// The collapses below `fraction` of the median x extent of every run of `paths` (or of run
/// `only` alone, which one of them must hold), in the files' and runs' order. A run without
/// samples has none.
pub fn events(paths: &[&Path], only: Option<&str>, fraction: f64) -> Result<Vec<RunEvents>, SweepError> {
    let mut out = Vec::new();
    for &path in paths {
        let file = ResultsFile::open(path)?;
        for id in file.run_ids()? {
            if only.is_some_and(|r| r != id) {
                continue;
            }
            let rows = file.timeseries(&id)?;
            let t_end_s = rows.last().map_or(0.0, |r| r.t_s);
            out.push(RunEvents { file: path.to_path_buf(), run_id: id, t_end_s, collapses: length_collapses(&rows, fraction) });
        }
    }
    if let Some(id) = only {
        if out.is_empty() {
            let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
            return Err(SweepError::Run { run_id: id.into(), message: format!("in none of {}", names.join(", ")) });
        }
    }
    Ok(out)
}

/// The CSV table of `runs`: a header, then one row per collapse (`event` counts from 1 within a
/// run; `interval_s` empty for a run's first). Times in s, extents in um.
pub fn csv(runs: &[RunEvents]) -> String {
    let mut s = String::from("file,run_id,event,t_s,start_s,end_s,x_min_um,x_min_rel,y_max_um,across,interval_s\n");
    for r in runs {
        for (k, c) in r.collapses.iter().enumerate() {
            let interval = c.interval_s.map_or(String::new(), |i| format!("{i:.4}"));
            let _ = writeln!(
                s,
                "{},{},{},{:.4},{:.4},{:.4},{:.3},{:.3},{:.3},{:.3},{interval}",
                r.file.display(),
                r.run_id,
                k + 1,
                c.t_s,
                c.start_s,
                c.end_s,
                c.x_min_um,
                c.x_min_rel,
                c.y_max_um,
                c.across
            );
        }
    }
    s
}
