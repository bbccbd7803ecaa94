//! The turn-overs and folds of the runs of results files (`rbc-sweep events`): the moments each
//! cell stopped lying along the flow, found in its stored samples by
//! [`rbc_analysis::simulated::orbit_events::length_collapses`], as a CSV table.

use super::SweepError;
use rbc_analysis::simulated::orbit_events::{length_collapses, Collapse};
use rbc_schema::results::ResultsFile;
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
/// run; `interval_s` empty for a run's first), fields quoted where a path or run id needs it.
/// Times in s, extents in um, `x_min_rel` and `across` dimensionless.
pub fn csv(runs: &[RunEvents]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let header = ["file", "run_id", "event", "t_s", "start_s", "end_s", "x_min_um", "x_min_rel", "y_max_um", "across", "interval_s"];
    // (writing into memory cannot fail)
    w.write_record(header).expect("in memory");
    for r in runs {
        for (k, c) in r.collapses.iter().enumerate() {
            let f4 = |v: f64| format!("{v:.4}");
            let f3 = |v: f64| format!("{v:.3}");
            let interval = c.interval_s.map_or(String::new(), f4);
            let row = [r.file.display().to_string(), r.run_id.clone(), (k + 1).to_string(), f4(c.t_s), f4(c.start_s), f4(c.end_s), f3(c.x_min_um), f3(c.x_min_rel), f3(c.y_max_um), f3(c.across), interval];
            w.write_record(&row).expect("in memory");
        }
    }
    String::from_utf8(w.into_inner().expect("in memory")).expect("UTF-8 fields")
}

/// One line per run for a reader of the terminal: how far its samples go and how many collapses
/// they hold, with the intervals' range.
pub fn summary(runs: &[RunEvents]) -> Vec<String> {
    runs.iter()
        .map(|r| {
            let iv: Vec<f64> = r.collapses.iter().filter_map(|c| c.interval_s).collect();
            let range = if iv.is_empty() { String::new() } else { format!(", intervals {:.3}-{:.3} s", iv.iter().copied().fold(f64::INFINITY, f64::min), iv.iter().copied().fold(f64::NEG_INFINITY, f64::max)) };
            format!("{} ({}): samples to {:.4} s, {} collapse(s){range}", r.run_id, r.file.display(), r.t_end_s, r.collapses.len())
        })
        .collect()
}
