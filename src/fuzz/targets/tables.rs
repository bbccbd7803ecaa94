//! The CSV tables `rbc-predict` reads (entry.csv, summary.csv, kde.csv, tracks.csv): one mutated, the others valid,
//! read and predicted from with the example simulations as `rbc-predict` does (outputs not written).

use super::{examples, line, put, read, Target};
use crate::fuzz::mutate::mutate_text;
use anyhow::{Context, Result};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rbc_analysis::experiment::pipeline::{self, StageConfig};
use rbc_analysis::predict::{self, PredictInputs};
use rbc_analysis::types::prediction::PredictConfig;
use rbc_schema::results::{read_runs, RunRecord};
use rbc_schema::tables::{self, KdeRow, TrackRow};
use std::path::Path;

/// Seeds: the tables `rbc-analyze` writes for the example recordings (the README chain).
pub struct Tables {
    /// (file name, text) of entry.csv, summary.csv, kde.csv, tracks.csv.
    seeds: Vec<(&'static str, String)>,
    runs: Vec<RunRecord>,
}

const FILES: [&str; 4] = ["entry.csv", "summary.csv", "kde.csv", "tracks.csv"];

impl Tables {
    pub fn prepare(scratch: &Path) -> Result<Self> {
        let root = examples().join("frames");
        let found = pipeline::find_recordings(&root)?;
        let (outputs, _) = pipeline::analyse_all(&found, |d| pipeline::detect_dir(d, &root), &StageConfig::default(), |_| {})?;
        let out = scratch.join("analysis");
        pipeline::write_outputs(&out, &outputs, false)?;
        let seeds = FILES.into_iter().map(|f| Ok((f, String::from_utf8(read(&out.join(f))?)?))).collect::<Result<_>>()?;
        let runs = read_runs(&examples().join("results.h5")).context("reading the example simulations")?;
        Ok(Tables { seeds, runs })
    }
}

/// Read the tables in `dir` and predict from `runs`, as `rbc-predict --sims --entry DIR/entry.csv --observed DIR/summary.csv`
/// (kde.csv beside entry.csv when present, else the slipper densities of tracks.csv), with `--transit-mm 10`.
pub fn predict_from(dir: &Path, runs: &[RunRecord], sims: &Path) -> Result<(), String> {
    let entry_path = dir.join("entry.csv");
    let entry = tables::read_entry(&entry_path).map_err(line)?;
    let observed_path = dir.join("summary.csv");
    let observed = if observed_path.exists() { Some(tables::read_summary(&observed_path).map_err(line)?) } else { None };
    let kde: Option<Vec<KdeRow>> = if dir.join("kde.csv").exists() {
        Some(tables::read_table(&dir.join("kde.csv"), tables::columns::KDE).map_err(line)?)
    } else if dir.join("tracks.csv").exists() {
        let rows: Vec<TrackRow> = tables::read_table(&dir.join("tracks.csv"), tables::columns::TRACKS).map_err(line)?;
        Some(predict::offset::slipper_densities(&rows))
    } else {
        None
    };
    let inputs = PredictInputs {
        runs,
        sims_path: sims,
        entry: &entry,
        entry_path: &entry_path,
        observed: observed.as_deref().map(|o| (o, observed_path.as_path())),
        kde: kde.as_deref(),
    };
    let pred = predict::predict(&inputs, PredictConfig::default()).map_err(line)?;
    let (seen, _) = predict::transit::at_transit(runs, 10.0);
    if !seen.is_empty() {
        let at = PredictInputs { runs: &seen, ..inputs };
        std::hint::black_box(predict::predict(&at, PredictConfig::default()).map_err(line)?);
    }
    std::hint::black_box(pred);
    Ok(())
}

impl Target for Tables {
    fn write_case(&self, rng: &mut ChaCha8Rng, case: &Path) -> Result<(), String> {
        // entry.csv 4/10, summary.csv 3/10, kde.csv 2/10, tracks.csv (instead of kde.csv) 1/10
        let which = [0, 0, 0, 0, 1, 1, 1, 2, 2, 3][rng.random_range(0..10)];
        for (i, (name, text)) in self.seeds.iter().enumerate() {
            let skip = (i == 3 && which != 3) || (i == 2 && which == 3);
            if skip {
                continue;
            }
            let bytes = if i == which { mutate_text(text, rng) } else { text.clone().into_bytes() };
            put(&case.join(name), &bytes)?;
        }
        Ok(())
    }

    fn exercise(&self, case: &Path) -> Result<(), String> {
        predict_from(case, &self.runs, &examples().join("results.h5"))
    }
}
