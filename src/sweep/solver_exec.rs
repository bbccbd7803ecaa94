//! The real run executor: the solver's time loop with an observer that writes results.h5, detects the steady state (stopping the run there) and classifies the final shape.
//!
//! [`SweepObserver`] receives the solver's samples (`rbc_solver::run::Observer`):
//! it appends every sample to the run (the rows and the snapshot cadence of
//! `rbc_solver::run::results::SampleRows`, shared with `rbc-simulate`'s `ResultsObserver`), feeds the observables of
//! `rbc_solver::steady::observables` to a [`SteadyDetector`], and keeps the
//! last `frames` classification frames in a ring, one every `frame_every` output samples
//! ([`frame_every`]: the classifier needs a window that holds `min_tt_turns` (0.1 turn; a quarter
//! turn until session 51) of a slow tank-treading, 25 consecutive outputs of 0.2 ms hold 0.06
//! turn at 12.8 Hz); the
//! `snapshot_every`-th samples between them and the latest sample wait in the same ring, and an entry leaving it is
//! stored as a snapshot when it is an `snapshot_every`-th sample; at the end every
//! entry of the ring is stored (so the file holds every `snapshot_every`-th
//! shape and all classification frames, in time order). When the
//! detector decides (steady, periodic, or unsteady at the maximal time) it
//! asks the solver to stop by returning the error [`STOP`] from `sample`; in
//! `finish` it recognises its own request and writes the summary: status,
//! window statistics ([`rbc_solver::steady::window_stats`]) and the
//! classification of the kept frames ([`rbc_solver::classify`]), whose
//! evidence goes into the `evidence_*` attributes; the classification can be
//! repeated from the file's last snapshots.
//! A genuine failure is recorded with `RunWriter::fail`.
//!
//! Transit records ([`TRANSIT_DISTANCES_MM`]): the experiments film the cells at the channel's
//! entrance and 10 mm downstream, i.e. after `10 mm / u` (1.5 s at 6.5 mm/s), not at their
//! steady state. When the centroid has travelled each distance along x from its start and the
//! ring holds its `frames` frames, the observer classifies the ring (as at the end of a run) and
//! writes the label, the centroid and the x-velocity over the ring as the run's transit record
//! (`RunWriter::set_transit`, at once, any status). At 0 mm that is the first full ring (the
//! cell as it enters, after `frames` outputs). A resumed run records the distances its file
//! does not hold yet and its checkpoint has not passed (a record lost with a kill is written
//! again with the same values; one passed by a build without transit records stays absent).
//!
//! Checkpoints (`rbc_solver::run::persist`): the observer takes them as
//! `rbc-simulate` does (at the first sample, then by [`CheckpointPolicy`]), with
//! its own state: the sample count, the snapshot cadence and the ring of
//! classification frames (the samples are rebuilt from the stored rows, and the detector is
//! handed them and judges the window ending at the last one,
//! [`rbc_solver::steady::SteadyDetector::resume_with`]: for a run that went on undecided under
//! the same criterion that is the state it had, bit-for-bit; under a criterion changed since, the
//! verdict is about where the run is, as its classification frames are). A run
//! killed mid-way (its part file holds it `running` with a checkpoint of the same
//! scene) continues from its checkpoint; one killed before its first checkpoint starts afresh;
//! one whose checkpoint is damaged or foreign while the file holds its simulated time is refused
//! with one line naming the file (the time is kept: restore the checkpoint from a copy, or delete
//! the file to start again), and so is one whose whole checkpoint holds a state no run could
//! continue from (a value not finite, fewer vertices than the cell's: refused by
//! `rbc_solver::run::persist::reopen` before anything is cut back) or that does not fit this run
//! (the observer's fields, the vertex count with the walls, the scheme's state:
//! [`SolverError::Resume`], after the rows are cut back to the checkpoint): the run stays
//! `running` with its checkpoint. A run that ends (its verdict, or its largest time) keeps the
//! checkpoint of its end state beside the results, written at its last sample, so that
//! `rbc-sweep reopen` continues it exactly from there ([`super::reopen`]), penalty walls' displacements
//! included; a failed run keeps none.

use super::observer_state::{observer_fields, RingEntry};
use super::verdict::{classify_config, criterion, steady_transits, summarize};
use super::{run_attrs, RunExecutor, SweepError};
use nalgebra::Vector3;
use rbc_schema::results::{
    FinalShape, ResultsFile, RunAttrs, RunWriter, TimeSample,
};
use rbc_schema::scene::Scene;
use rbc_schema::sweep::{Sweep, SweepRun};
use rbc_solver::classify::{classify, ClassifyConfig, Frame};
use rbc_solver::run::checkpoint::RunState;
use rbc_solver::run::persist::{self, CheckpointPolicy, CheckpointWriter, NotResumable, Reopened, SuspendRequest};
use rbc_solver::run::results::{append_snapshot_with_curvature, SampleRows};
use rbc_solver::run::{Observer, Sample};
use rbc_solver::steady::{drift_interval_s, SteadyCriterion, SteadyDetector, Verdict};
use rbc_solver::SolverError;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};

/// The message of the error by which the observer stops the solver at the steady state.
pub const STOP: &str = "steady-state detector: stop requested";

/// Distances travelled (mm) at which a run's transit record is written: the experiments'
/// windows at the entrance and 10 mm downstream (paper, "Experimental setup").
pub const TRANSIT_DISTANCES_MM: [f64; 2] = [0.0, 10.0];

pub use rbc_solver::run::persist::{suspend_path, SUSPEND};

/// Default number of classification frames.
pub const DEFAULT_CLASSIFY_FRAMES: usize = 25;

/// Default time between classification frames (s): 25 frames 2 ms apart span 48 ms, the 0.1 turn
/// of `min_tt_turns` of a 2.1 Hz tank-treading (a quarter turn of a 5.2 Hz one), and keep a 250 Hz
/// one below half a turn between frames (the classifier's limit; `rbc_solver::classify`).
pub const DEFAULT_FRAME_INTERVAL_S: f64 = 2e-3;

/// Output samples between two classification frames: `frame_interval_s / output_interval_s`
/// rounded, at least one.
pub fn frame_every(frame_interval_s: f64, output_interval_s: f64) -> usize {
    ((frame_interval_s / output_interval_s).round() as usize).max(1)
}

/// Observer writing one run of a sweep (see the module documentation).
pub struct SweepObserver {
    path: PathBuf,
    file: Option<ResultsFile>,
    run_id: String,
    attrs: RunAttrs,
    writer: Option<RunWriter>,
    rows: SampleRows,
    samples: Vec<TimeSample>,
    detector: SteadyDetector,
    /// Ring of the last `n_frames` classification frames and the `snapshot_every`-th samples among them.
    ring: VecDeque<RingEntry>,
    n_frames: usize,
    /// Output samples between two classification frames ([`frame_every`]).
    frame_every: usize,
    triangles: Vec<[usize; 3]>,
    classify: ClassifyConfig,
    stop_requested: bool,
    /// The last checkpoint is of the run's end (its verdict or its largest time): kept at the end.
    end_checkpoint: bool,
    /// `<out>.suspend` (see [`suspend_path`]): checkpoint, then stop.
    suspend: SuspendRequest,
    /// The part file holds this run with a checkpoint of another model: nothing was touched.
    refused: bool,
    /// Centroid x at the run's first sample (um) and the transit distances not yet recorded (mm).
    x0_um: Option<f64>,
    transits_pending: Vec<f64>,
    checkpoints: CheckpointWriter,
    resume_from: Option<RunState>,
    heartbeat: Heartbeat,
}

/// A plain log line per run every `interval` of wall time (simulated time, step, step size,
/// lateral position, the sharpest fold between adjacent triangles, time left): runs of a sweep last hours to days, and the sweep's own
/// progress display only counts finished runs.
struct Heartbeat {
    interval: Option<std::time::Duration>,
    t_end_s: f64,
    last: std::time::Instant,
    /// Simulated time and wall clock at the (re)start, for the time left.
    t0_s: f64,
    started: std::time::Instant,
}

impl Heartbeat {
    fn off() -> Self {
        let now = std::time::Instant::now();
        Heartbeat { interval: None, t_end_s: 0.0, last: now, t0_s: 0.0, started: now }
    }

    /// The line to log for `s`, when one is due.
    fn line(&mut self, run_id: &str, s: &Sample<'_>) -> Option<String> {
        let interval = self.interval?;
        if self.last.elapsed() < interval {
            return None;
        }
        self.last = std::time::Instant::now();
        Some(self.text(run_id, s, self.started.elapsed().as_secs_f64()))
    }

    /// The line for `s` when `wall_s` seconds of wall time have passed since the (re)start.
    fn text(&self, run_id: &str, s: &Sample<'_>, wall_s: f64) -> String {
        let left = rbc_solver::run::progress::time_left_s(self.t0_s, s.t_s, self.t_end_s, wall_s)
            .map(rbc_solver::run::progress::format_duration)
            .unwrap_or_else(|| "?".into());
        let c = s.centroid_um;
        // The sharpest fold tells early whether the mesh still resolves the shape (the run stops at
        // the scene's integrator.max_fold_deg).
        let fold = rbc_solver::integrate::check::sharpest_fold(s.vertices, s.triangles).0.to_degrees();
        format!(
            "{run_id}: t = {:.4e} s / {:.4e} s, step {}, h = {:.2e} s, centroid y = {:.3} um, z = {:.3} um, sharpest fold {fold:.0} deg, left {left} at most",
            s.t_s, self.t_end_s, s.step, s.h_s, c.y, c.z
        )
    }
}

impl SweepObserver {
    /// Observer for run `run_id` in the results file `path` (an earlier attempt of that run is replaced at the first sample).
    pub fn new(
        path: &Path,
        run_id: &str,
        attrs: RunAttrs,
        criterion: SteadyCriterion,
        classify: ClassifyConfig,
        n_frames: usize,
        frame_every: usize,
        snapshot_every: usize,
    ) -> Result<Self, SolverError> {
        let detector =
            SteadyDetector::new(criterion).map_err(|e| SolverError::Output(e.to_string()))?;
        let attrs_scene = attrs.scene.clone();
        Ok(SweepObserver {
            path: path.into(),
            file: None,
            run_id: run_id.into(),
            attrs,
            writer: None,
            rows: SampleRows::new(snapshot_every),
            samples: Vec::new(),
            detector,
            ring: VecDeque::new(),
            n_frames: n_frames.max(3),
            frame_every: frame_every.max(1),
            triangles: Vec::new(),
            checkpoints: CheckpointWriter::new(path, run_id, &attrs_scene, CheckpointPolicy::default()),
            classify,
            stop_requested: false,
            end_checkpoint: false,
            suspend: SuspendRequest::for_results(path),
            refused: false,
            x0_um: None,
            transits_pending: TRANSIT_DISTANCES_MM.to_vec(),
            resume_from: None,
            heartbeat: Heartbeat::off(),
        })
    }

    /// Log a line on standard error every `interval_s` of wall time (see `Heartbeat`);
    /// `t_end_s` is the run's largest simulated time (s), for the time left.
    pub fn with_heartbeat(mut self, interval_s: f64, t_end_s: f64) -> Self {
        let now = std::time::Instant::now();
        self.heartbeat = Heartbeat { interval: Some(std::time::Duration::from_secs_f64(interval_s)), t_end_s, last: now, t0_s: 0.0, started: now };
        self
    }

    /// Take checkpoints by `policy` (default: [`CheckpointPolicy::default`]).
    pub fn with_checkpoint_policy(mut self, policy: CheckpointPolicy) -> Self {
        self.checkpoints = CheckpointWriter::new(&self.path, &self.run_id, &self.attrs.scene, policy);
        self
    }

    /// Continue a run reopened at its checkpoint: rebuild the samples, the detector
    /// (judging the stored rows' last window) and the frame ring (from the checkpoint).
    fn restore(&mut self, file: ResultsFile, mut r: Reopened) -> Result<(), SolverError> {
        let bad = |k: &str| SolverError::Resume(format!("field `{}{k}` is missing or malformed", persist::OBSERVER_PREFIX));
        let every = SampleRows::saved_cadence(&r.observer)?;
        // (the run's triangles as `reopen` read them with the snapshots)
        let triangles = std::mem::take(&mut r.triangles);
        // the frames hold the cell's vertices, the state's first ones (penalty walls add their
        // displacements after them, rbc_solver::dynamics::penalty; `reopen` refused a state with
        // fewer)
        let nv = rbc_solver::mesh::slices::cell_len(&triangles);
        self.ring = super::observer_state::stored_ring(&r.observer, nv).map_err(bad)?.into();
        // a ring restored under another frame spacing is thinned by the new frames as they come
        self.rows = SampleRows::new(every);
        for row in &r.rows {
            self.rows.step(row.t_s, Vector3::from(row.centroid_um));
        }
        // judged where the run is (a criterion changed since the checkpoint, e.g. by `reopen`,
        // is not met by an earlier window of the stored samples instead)
        let observed: Vec<[f64; 5]> = r.rows.iter().map(rbc_solver::steady::observables).collect();
        self.detector
            .resume_with(r.rows.iter().zip(&observed).map(|(row, o)| (row.t_s, o.as_slice())))
            .map_err(|e| SolverError::Output(e.to_string()))?;
        self.x0_um = r.rows.first().map(|row| row.centroid_um[0]);
        let recorded = file.run(&self.run_id)?.transits;
        // a distance passed before the checkpoint with a full ring but not recorded (a run started
        // by a build without transit records) cannot be recorded faithfully any more: skipped
        let x0 = self.x0_um.unwrap_or(0.0);
        let first_full = (self.n_frames - 1) * self.frame_every;
        let passed = |d: f64| r.rows.iter().enumerate().any(|(k, row)| k >= first_full && row.centroid_um[0] - x0 >= d * 1e3);
        let run_id = self.run_id.clone();
        self.transits_pending.retain(|d| {
            let keep = !recorded.iter().any(|t| t.distance_mm == *d) && !passed(*d);
            if !keep && !recorded.iter().any(|t| t.distance_mm == *d) {
                eprintln!("{run_id}: the transit at {d} mm was passed before this build recorded transits: not recorded");
            }
            keep
        });
        self.samples = r.rows;
        self.triangles = triangles;
        self.writer = Some(r.writer);
        self.file = Some(file);
        self.checkpoints.restart_clock();
        self.heartbeat.t0_s = r.state.t_s;
        self.heartbeat.started = std::time::Instant::now();
        self.resume_from = Some(r.state);
        Ok(())
    }

    /// True when the observer stopped the run (the steady-state detector decided).
    pub fn stopped(&self) -> bool {
        self.stop_requested
    }

    /// The classification frames of the ring, in time order.
    fn frames(&self) -> impl Iterator<Item = &RingEntry> {
        self.ring.iter().filter(|e| e.frame)
    }

    /// The transit record at distance `d_mm`, from the ring's frames and the centroid `c` (um) at `t_s`.
    fn transit(&self, d_mm: f64, t_s: f64, c: Vector3<f64>) -> rbc_schema::results::Transit {
        let frames: Vec<Frame<'_>> = self.frames().map(|e| Frame { t_s: e.t_s, vertices: &e.vertices }).collect();
        let shape = classify(&frames, &self.triangles, &self.classify).map(|k| k.shape).unwrap_or(FinalShape::Other);
        let x_of = |f: &Frame<'_>| rbc_solver::classify::volume_centroid(f.vertices, &self.triangles).1[0];
        let velocity_mm_s = match (frames.first(), frames.last()) {
            (Some(a), Some(b)) if b.t_s > a.t_s => (x_of(b) - x_of(a)) / (b.t_s - a.t_s) * 1e-3,
            _ => 0.0,
        };
        rbc_schema::results::Transit { distance_mm: d_mm, t_s, x_um: c.x, y_um: c.y, z_um: c.z, velocity_mm_s, shape, from_steady: false }
    }

    /// True when the run stopped at a checkpoint on a suspend request ([`suspend_path`]).
    pub fn suspended(&self) -> bool {
        self.suspend.served()
    }

    /// The detector's verdict so far.
    pub fn verdict(&self) -> Verdict {
        self.detector.verdict()
    }

    fn begin(&mut self, triangles: &[[usize; 3]]) -> Result<(), SolverError> {
        let mut file = ResultsFile::create_or_open(&self.path)?;
        if file.has_run(&self.run_id) {
            file.remove_run(&self.run_id)?; // an interrupted earlier attempt without a usable checkpoint: start afresh
        }
        self.checkpoints.remove()?;
        let tri: Vec<[u32; 3]> = triangles
            .iter()
            .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
            .collect();
        self.writer = Some(file.begin_run(&self.run_id, &self.attrs, &tri)?);
        self.file = Some(file);
        self.triangles = triangles.to_vec();
        Ok(())
    }
}

impl Observer for SweepObserver {
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError> {
        if self.writer.is_none() {
            self.begin(s.triangles)?;
        }
        let w = self
            .writer
            .as_mut()
            .ok_or_else(|| SolverError::Output("run not open".into()))?;
        let c = s.centroid_um;
        let (sample, _, _, regular) = self.rows.row(s);
        w.append_sample(&sample)?;
        if let Some(line) = self.heartbeat.line(&self.run_id, s) {
            eprintln!("{line}");
        }
        // the output index of this sample (rows kept before it, also across a resume)
        let frame = self.samples.len().is_multiple_of(self.frame_every);
        // the ring ends at the latest sample (the final state is stored at the end); one that is
        // neither a frame nor a snapshot is replaced by the next
        if self.ring.back().is_some_and(|e| !e.frame && !e.regular) {
            self.ring.pop_back();
        }
        let vertices: Vec<[f64; 3]> = s.vertices.iter().map(|p| [p.x, p.y, p.z]).collect();
        self.ring.push_back(RingEntry { t_s: s.t_s, vertices, regular, frame });
        let mut n = self.ring.iter().filter(|e| e.frame).count();
        while n > self.n_frames {
            let Some(e) = self.ring.pop_front() else { break };
            n -= usize::from(e.frame);
            if e.regular {
                append_snapshot_with_curvature(w, e.t_s, &e.vertices, &self.triangles)?;
                w.flush()?;
            }
        }
        let x0 = *self.x0_um.get_or_insert(c.x);
        while let Some(&d) = self.transits_pending.first() {
            if c.x - x0 < d * 1e3 || n < self.n_frames || !frame {
                break;
            }
            let transit = self.transit(d, s.t_s, c);
            if let Some(w) = self.writer.as_mut() {
                w.set_transit(&transit)?;
            }
            self.transits_pending.remove(0);
        }
        let obs = rbc_solver::steady::observables(&sample);
        self.samples.push(sample);
        let verdict = self
            .detector
            .push(s.t_s, &obs)
            .map_err(|e| SolverError::Output(e.to_string()))?;
        if verdict.is_decided() {
            self.stop_requested = true;
            return Err(SolverError::Output(STOP.into()));
        }
        Ok(())
    }

    fn finish(
        &mut self,
        summary: &rbc_solver::run::RunSummary,
        failure: Option<&SolverError>,
    ) -> Result<(), SolverError> {
        let Some(mut w) = self.writer.take() else {
            return Ok(()); // never started (failed before the first sample): nothing to record
        };
        // a resumed state refused before any step: the run is kept as it was (execute_run reports it)
        if self.suspend.served() || matches!(failure, Some(SolverError::Resume(_))) {
            // unfinished on purpose: rows and snapshots up to the checkpoint are flushed, the
            // classification frames are in the checkpoint, the status stays `running`
            w.flush()?;
            return Ok(());
        }
        let failed = failure.is_some() && !self.stop_requested;
        let last = self.ring.len().saturating_sub(1);
        for (k, e) in self.ring.iter().enumerate() {
            // all entries; after a failure only the regular ones and the last state
            if !failed || e.regular || k == last {
                append_snapshot_with_curvature(&mut w, e.t_s, &e.vertices, &self.triangles)?;
            }
        }
        if let (true, Some(e)) = (failed, failure) {
            w.fail(&e.to_string())?;
            return self.checkpoints.remove();
        }
        let frames: Vec<(f64, Vec<[f64; 3]>)> = self.frames().map(|e| (e.t_s, e.vertices.clone())).collect();
        let window_s = self.detector.criterion().window_s;
        let mut out = summarize(
            self.detector.verdict(),
            window_s,
            &self.samples,
            &frames,
            &self.triangles,
            &self.classify,
        );
        out.evidence
            .insert("steps_accepted".into(), summary.accepted as f64);
        out.evidence
            .insert("steps_rejected".into(), summary.rejected as f64);
        out.evidence.insert("wall_s".into(), summary.wall_s);
        if let (Some(first), Some(last)) = (self.samples.first(), self.samples.last()) {
            for t in steady_transits(&self.transits_pending, first, last, &out) {
                w.set_transit(&t)?;
            }
        }
        w.finish(&out)?;
        if self.end_checkpoint {
            Ok(()) // the checkpoint of the end state stays, for `rbc-sweep reopen`
        } else {
            self.checkpoints.remove()
        }
    }

    fn checkpoint_due(&mut self, _t_s: f64) -> bool {
        if self.writer.is_none() {
            return false;
        }
        let due = self.checkpoints.due();
        self.suspend.poll() || due
    }

    /// The state of the sample at which the detector decided: kept as the run's end checkpoint.
    fn checkpoint_at_stop(&mut self) -> bool {
        self.end_checkpoint = self.stop_requested && self.writer.is_some();
        self.end_checkpoint
    }

    /// The state at the run's largest time (it ends unsteady): kept as the run's end checkpoint.
    fn checkpoint_at_end(&mut self) -> bool {
        self.end_checkpoint = self.writer.is_some();
        self.end_checkpoint
    }

    fn checkpoint(&mut self, state: &RunState) -> Result<(), SolverError> {
        let Some(w) = self.writer.as_mut() else { return Ok(()) };
        let orbit = self.detector.periodic_gap();
        let drift = self.detector.orbit_drift(drift_interval_s(orbit.as_ref(), self.detector.criterion().window_s));
        let own = observer_fields(&self.rows, &self.ring.iter().collect::<Vec<_>>(), self.detector.gap(), orbit, drift);
        self.checkpoints.write(w, state, &own)?;
        self.suspend.after_checkpoint()
    }

    /// Logged once the runner took the restored state.
    fn resumed(&mut self, state: &RunState) {
        eprintln!("{}: resumed from its checkpoint at t = {:.6} s (step {}, {} output rows kept)", self.run_id, state.t_s, state.summary.accepted, self.samples.len());
    }

    /// A part file holding this run unfinished with a checkpoint of the same scene: continue from it.
    fn resume(&mut self) -> Result<Option<RunState>, SolverError> {
        if !self.path.exists() {
            return Ok(None);
        }
        let mut file = ResultsFile::create_or_open(&self.path)?;
        let text = self.attrs.scene.clone();
        let here = self.path.clone();
        let current = Scene::parse(&text, &here).ok();
        // the same text, or the same model with another step method (a faster scheme may take over)
        let same = |stored: &str| stored == text || current.as_ref().is_some_and(|c| c.runs_as(stored).unwrap_or(false));
        match persist::reopen(&mut file, &self.run_id, &same) {
            Ok(Ok(r)) => {
                if let (Some(c), Ok(old)) = (&current, Scene::parse(&r.scene, &here)) {
                    if old.integrator != c.integrator {
                        eprintln!("{}: the step method changed: was {}, now {}", self.run_id, old.stepping_summary(), c.stepping_summary());
                    }
                }
                // whatever keeps the stored state from being restored is not the run's failure:
                // the run is kept as it is and the sweep reports it (execute_run)
                self.restore(file, r).map_err(|e| match e {
                    e @ SolverError::Resume(_) => e,
                    e => SolverError::Resume(e.to_string()),
                })?;
                Ok(self.resume_from.take())
            }
            // hours of simulated time are not thrown away because a value of the scene changed
            Ok(Err(NotResumable::OtherScene)) => {
                self.refused = true;
                Err(SolverError::Output(format!(
                "{}: run `{}` has a checkpoint of a different scene (beyond the step method and end time); restore the scene it was started with, or delete this file to start the run again",
                    self.path.display(),
                    self.run_id
                )))
            }
            // a damaged or foreign checkpoint of a run that has simulated time stored: that time is
            // not thrown away (restarting would replace the run's rows and shapes); the user decides
            Ok(Err(NotResumable::Mismatch(why))) if file.run(&self.run_id).is_ok_and(|r| r.n_samples > 1) => {
                self.refused = true;
                let (n, t) = file.run(&self.run_id).map(|r| (r.n_samples, file.timeseries(&self.run_id).ok().and_then(|rows| rows.last().map(|s| s.t_s)))).unwrap_or((0, None));
                Err(SolverError::Output(format!(
                    "{}: run `{}` cannot continue from its checkpoint ({why}); its {n} samples (to t = {} s) are kept: restore the checkpoint from a copy, or delete this file to start the run again",
                    self.path.display(),
                    self.run_id,
                    t.map_or("?".to_string(), |t| t.to_string())
                )))
            }
            // no checkpoint yet (killed before its first), or an unusable one of a run with nothing
            // stored: nothing worth keeping, start afresh at the first sample
            Ok(Err(why)) => {
                eprintln!("{}: no usable checkpoint ({why:?}); starting from t = 0", self.run_id);
                Ok(None)
            }
            Err(e) => {
                eprintln!("{}: the part file cannot be reopened ({e}); starting from t = 0", self.run_id);
                Ok(None)
            }
        }
    }
}

/// Wall seconds between two log lines of a running sweep run.
pub const HEARTBEAT_S: f64 = 300.0;

/// Executes a sweep run with a solver given as a function `solve(scene, observer)`
/// (normally `rbc_solver::scene::build(scene)?.run(observer)`), checkpointing every
/// `checkpoint_interval_s` seconds of wall time (the sweep file's setting).
pub struct SolverExecutor<F> {
    pub solve: F,
}

impl<F> RunExecutor for SolverExecutor<F>
where
    F: Fn(&Scene, &mut dyn Observer) -> Result<(), SolverError> + Sync,
{
    fn execute(&self, sweep: &Sweep, run: &SweepRun, out: &Path) -> Result<(), SweepError> {
        let policy = CheckpointPolicy { every_outputs: 0, every_wall_s: sweep.checkpoint_interval_s };
        execute_run(&self.solve, policy, sweep, run, out)
    }
}

/// Execute `run` into `out` with `solve`, taking checkpoints by `policy`; a run that `out`
/// holds unfinished with a checkpoint of the same scene continues from it.
pub fn execute_run<F>(solve: &F, policy: CheckpointPolicy, sweep: &Sweep, run: &SweepRun, out: &Path) -> Result<(), SweepError>
where
    F: Fn(&Scene, &mut dyn Observer) -> Result<(), SolverError>,
{
    let err = |m: String| SweepError::Run {
        run_id: run.run_id.clone(),
        message: m,
    };
    let scene = Scene::parse(&run.scene_text, &sweep.base_scene).map_err(|e| err(e.to_string()))?;
    let mut obs = SweepObserver::new(
        out,
        &run.run_id,
        run_attrs(run, scene.fluid.lambda),
        criterion(&sweep.steady, scene.time.end_s),
        classify_config(&sweep.classify),
        sweep.classify.frames.unwrap_or(DEFAULT_CLASSIFY_FRAMES),
        frame_every(sweep.classify.frame_interval_s_at(run.velocity_mm_s).unwrap_or(DEFAULT_FRAME_INTERVAL_S), scene.time.output_interval_s),
        sweep.snapshot_every,
    )
    .map_err(|e| err(e.to_string()))?
    .with_checkpoint_policy(policy)
    .with_heartbeat(HEARTBEAT_S, scene.time.end_s);
    let result = solve(&scene, &mut obs);
    match result {
        Ok(()) => Ok(()),
        Err(_) if obs.stopped() || obs.suspended() => Ok(()),
        Err(e) if obs.refused => Err(err(e.to_string())),
        Err(e @ SolverError::Resume(_)) => Err(err(format!(
            "{}: run `{}` {e}; its rows up to the checkpoint and the checkpoint ({}) are kept: restore the checkpoint from a copy, or delete this file to start the run again",
            out.display(),
            run.run_id,
            rbc_schema::checkpoint::checkpoint_path(out, &run.run_id).display()
        ))),
        // a failure after the first sample was recorded by `finish` (status failed)
        Err(e) => {
            drop(obs);
            let recorded = ResultsFile::open(out)
                .map(|f| f.has_run(&run.run_id))
                .unwrap_or(false);
            if recorded {
                Ok(())
            } else {
                Err(err(e.to_string()))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample<'a>(t_s: f64, vertices: &'a [Vector3<f64>], triangles: &'a [[usize; 3]]) -> Sample<'a> {
        Sample { t_s, step: 7, h_s: 2.5e-5, vertices, triangles, area_um2: 1.0, volume_um3: 1.0, centroid_um: Vector3::new(3.0, 0.25, -0.5) }
    }

    /// Off by default; when due it names the run, the simulated time against the end, the step
    /// and the lateral position, and the time left extrapolates the rate since the start (the
    /// wall time given, so the line does not depend on how long this test takes).
    #[test]
    fn heartbeat_lines_are_due_by_wall_time() {
        let v = [Vector3::zeros(); 3];
        let t = [[0, 1, 2]];
        assert_eq!(Heartbeat::off().line("r", &sample(1e-3, &v, &t)), None);
        let now = std::time::Instant::now();
        let mut hb = Heartbeat { interval: Some(std::time::Duration::ZERO), t_end_s: 2.0, last: now, t0_s: 0.0, started: now };
        // due at once with a zero interval
        assert!(hb.line("disc_r0.4", &sample(1.0, &v, &t)).is_some());
        // half done after 100 s of wall time from t = 0: the other half takes another 100 s
        assert_eq!(hb.text("disc_r0.4", &sample(1.0, &v, &t), 100.0), "disc_r0.4: t = 1.0000e0 s / 2.0000e0 s, step 7, h = 2.50e-5 s, centroid y = 0.250 um, z = -0.500 um, sharpest fold 0 deg, left 1m40s at most");
        // restarted at t = 0.5 s: 0.5 s done in 30 s, the 1 s left in 60 s; before any progress `?`
        let resumed = Heartbeat { t0_s: 0.5, ..hb };
        assert!(resumed.text("r", &sample(1.0, &v, &t), 30.0).ends_with("left 1m00s at most"));
        assert!(resumed.text("r", &sample(0.5, &v, &t), 30.0).ends_with("left ? at most"));
        let mut hourly = Heartbeat { interval: Some(std::time::Duration::from_secs(3600)), ..hb };
        assert_eq!(hourly.line("r", &sample(1.5, &v, &t)), None, "not due yet");
    }
}
