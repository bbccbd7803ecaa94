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
/// they hold, with the intervals' range and, from the second interval on, the last interval and
/// its change on the one before (s and %): how far a tumbling or folding orbit has settled.
pub fn summary(runs: &[RunEvents]) -> Vec<String> {
    runs.iter()
        .map(|r| {
            let iv: Vec<f64> = r.collapses.iter().filter_map(|c| c.interval_s).collect();
            let range = if iv.is_empty() { String::new() } else { format!(", intervals {:.3}-{:.3} s", iv.iter().copied().fold(f64::INFINITY, f64::min), iv.iter().copied().fold(f64::NEG_INFINITY, f64::max)) };
            let last = match iv.as_slice() {
                [.., before, last] => format!(", the last {last:.4} s ({:+.4} s, {:+.2} % on the one before)", last - before, 100.0 * (last - before) / before),
                _ => String::new(),
            };
            format!("{} ({}): samples to {:.4} s, {} collapse(s){range}{last}", r.run_id, r.file.display(), r.t_end_s, r.collapses.len())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn collapse(t_s: f64, interval_s: Option<f64>) -> Collapse {
        Collapse { t_s, start_s: t_s - 0.01, end_s: t_s + 0.01, x_min_um: 5.7, x_min_rel: 0.75, y_max_um: 6.0, across: 0.79, interval_s }
    }

    /// The summary's last interval and its change are those of the collapses' times; a run with
    /// one interval has no change to give, one without collapses no intervals.
    #[test]
    fn the_summary_gives_the_last_interval_and_its_change() {
        let run = |times: &[f64]| RunEvents {
            file: "r.h5".into(),
            run_id: "a".into(),
            t_end_s: 4.0,
            collapses: times.iter().enumerate().map(|(k, &t)| collapse(t, (k > 0).then(|| t - times[k - 1]))).collect(),
        };
        let lines = summary(&[run(&[0.5, 1.5, 2.6, 3.75]), run(&[0.5, 1.5]), run(&[])]);
        assert_eq!(lines[0], "a (r.h5): samples to 4.0000 s, 4 collapse(s), intervals 1.000-1.150 s, the last 1.1500 s (+0.0500 s, +4.55 % on the one before)");
        assert_eq!(lines[1], "a (r.h5): samples to 4.0000 s, 2 collapse(s), intervals 1.000-1.000 s");
        assert_eq!(lines[2], "a (r.h5): samples to 4.0000 s, 0 collapse(s)");
    }
}
