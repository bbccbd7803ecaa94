//! results.h5: the example results with bytes mutated (mostly in the HDF5 metadata), read as `rbc-predict`,
//! `rbc-sweep --study-status`, `rbc-sweep events` and the `mesh-from-results` scenes read it.

use super::{examples, hdf5_metadata_offsets, line, mutate_hdf5, put, read, Target};
use anyhow::Result;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rbc_analysis::predict::{self, PredictInputs};
use rbc_analysis::types::prediction::PredictConfig;
use rbc_schema::results::{read_runs, read_snapshots, read_timeseries};
use rbc_schema::tables::EntryRow;
use std::path::Path;

/// Seeds: `examples/demo-results.h5` (finished free-space runs) and the channel fixture (a running run with snapshots).
pub struct ResultsH5 {
    /// (bytes, metadata offsets).
    seeds: Vec<(Vec<u8>, Vec<usize>)>,
}

impl ResultsH5 {
    pub fn prepare(_scratch: &Path) -> Result<Self> {
        let seeds = [examples().join("demo-results.h5"), examples().join("fixtures/science-6p5-r1.2.h5")]
            .iter()
            .map(|p| {
                let b = read(p)?;
                let o = hdf5_metadata_offsets(&b);
                Ok((b, o))
            })
            .collect::<Result<_>>()?;
        Ok(ResultsH5 { seeds })
    }
}

impl Target for ResultsH5 {
    fn write_case(&self, rng: &mut ChaCha8Rng, case: &Path) -> Result<(), String> {
        let (bytes, offsets) = &self.seeds[rng.random_range(0..self.seeds.len())];
        put(&case.join("results.h5"), &mutate_hdf5(bytes, offsets, rng))
    }

    fn exercise(&self, case: &Path) -> Result<(), String> {
        let path = case.join("results.h5");
        let runs = read_runs(&path).map_err(line)?;
        for r in runs.iter().take(4) {
            read_timeseries(&path, &r.run_id).map_err(line)?;
            read_snapshots(&path, &r.run_id).map_err(line)?;
        }
        crate::sweep::study::progress(&[path.as_path()], &Default::default(), Some(&rbc_solver::steady::SteadyCriterion::paper_default())).map_err(line)?;
        let events = crate::sweep::events::events(&[path.as_path()], None, rbc_analysis::simulated::orbit_events::DEFAULT_FRACTION).map_err(line)?;
        std::hint::black_box(crate::sweep::events::csv(&events));
        let entry: Vec<EntryRow> = [-1.5, -0.4, 0.0, 0.3, 1.2, 2.0].iter().map(|&y| EntryRow { pressure_mbar: 100.0, y_um: y, velocity_mm_s: 3.0 }).collect();
        let entry_path = case.join("entry.csv");
        let inputs = PredictInputs { runs: &runs, sims_path: &path, entry: &entry, entry_path: &entry_path, observed: None, kde: None };
        // a file without a finished croissant/slipper run is refused by predict: not the reader's business here
        std::hint::black_box(predict::predict(&inputs, PredictConfig::default()).ok());
        Ok(())
    }
}
