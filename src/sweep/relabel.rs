//! Decide the labels of ended runs again from their stored evidence: `rbc-sweep relabel`, for
//! runs that ended under an earlier classification rule (e.g. before a croissant needed only one
//! mirror plane, `rbc_solver::classify`), without simulating anything again.
//!
//! The label is a pure function of the classifier's evidence and its thresholds
//! ([`rbc_solver::classify::decide`]); the evidence is stored with every ended run (attributes
//! `evidence_<name>`), so the label decided again is the label the run would have got at its end
//! under today's rule and the sweep's `[classify]` thresholds. Only `final_shape`,
//! `tank_treading` and `tumbling` are rewritten, and the transit records past the run's end:
//! a run that ended steady or periodic before it travelled a transit distance
//! ([`TRANSIT_DISTANCES_MM`]) gets its steady state carried there
//! ([`super::verdict::steady_transits`], as a run ending today gets it), with the label
//! decided again. Transit labels recorded as the cell passed (at 0 and 10 mm) are decided from
//! the frames of that moment, whose evidence is not stored: they stay as recorded.

use super::SweepError;
use super::solver_exec::TRANSIT_DISTANCES_MM;
use super::verdict::steady_transits;
use rbc_schema::results::{FinalShape, ResultsFile, RunSummary, Transit};
use rbc_solver::classify::{decide, ClassifyConfig, Evidence};
use std::path::Path;

/// One ended run's label before and after, and the transit distances (mm) written past its end.
#[derive(Debug, Clone, PartialEq)]
pub struct Relabelled {
    pub run_id: String,
    pub before: (FinalShape, bool, bool),
    pub after: (FinalShape, bool, bool),
    pub transits_mm: Vec<f64>,
}

impl Relabelled {
    /// Whether the label or a flag changed.
    pub fn changed(&self) -> bool {
        self.before != self.after
    }

    /// Whether anything was written for this run (a label or a transit).
    pub fn wrote(&self) -> bool {
        self.changed() || !self.transits_mm.is_empty()
    }
}

/// Decide the label of every ended run of `path` again under `cfg`, write the changed ones and
/// the transit records past each run's end (all runs checked first: a run whose evidence is incomplete is refused, naming the run and
/// the missing attribute, and nothing is written). A run that ended with no classifier evidence at
/// all (fewer than 3 shapes when it ended: `other`, nothing to decide from) keeps its label.
/// Returns every ended run, changed or not.
pub fn relabel(path: &Path, cfg: &ClassifyConfig) -> Result<Vec<Relabelled>, SweepError> {
    ResultsFile::open(path)?; // an existing results file (a missing one is not created)
    let mut file = ResultsFile::create_or_open(path)?;
    let mut todo = Vec::new();
    for rec in file.runs()? {
        let Some(summary) = rec.summary.as_ref() else { continue };
        if !Evidence::recorded_in(&summary.evidence) && summary.final_shape == FinalShape::Other {
            let label = (summary.final_shape, summary.tank_treading, summary.tumbling);
            todo.push((Relabelled { run_id: rec.run_id.clone(), before: label, after: label, transits_mm: Vec::new() }, Vec::new()));
            continue;
        }
        let evidence = Evidence::from_map(&summary.evidence).map_err(|name| SweepError::Io {
            path: path.into(),
            message: format!("run `{}`: attribute `evidence_{name}` is missing: its label cannot be decided again", rec.run_id),
        })?;
        let c = decide(&evidence, cfg);
        let relabelled = RunSummary { final_shape: c.shape, tank_treading: c.tank_treading, tumbling: c.tumbling, ..summary.clone() };
        let rows = file.timeseries(&rec.run_id)?;
        let carried = match (rows.first(), rows.last()) {
            (Some(first), Some(last)) => steady_transits(&TRANSIT_DISTANCES_MM, first, last, &relabelled),
            _ => Vec::new(),
        };
        // a record the cell made as it passed stays; one carried from the steady state is redone
        let carried: Vec<Transit> = carried
            .into_iter()
            .filter(|t| !rec.transits.iter().any(|r| r.distance_mm == t.distance_mm && (!r.from_steady || r == t)))
            .collect();
        let r = Relabelled {
            run_id: rec.run_id.clone(),
            before: (summary.final_shape, summary.tank_treading, summary.tumbling),
            after: (c.shape, c.tank_treading, c.tumbling),
            transits_mm: carried.iter().map(|t| t.distance_mm).collect(),
        };
        todo.push((r, carried));
    }
    for (r, carried) in &todo {
        if r.changed() {
            let (shape, tt, tumbling) = r.after;
            file.set_label(&r.run_id, shape, tt, tumbling)?;
        }
        for t in carried {
            file.set_transit_of_ended(&r.run_id, t)?;
        }
    }
    Ok(todo.into_iter().map(|(r, _)| r).collect())
}
