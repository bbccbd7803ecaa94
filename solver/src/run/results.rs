//! Writes a run into `results.h5` (layout in `rbc_schema::results`): timeseries at every sample, snapshots every k-th, checkpoints beside it.
//!
//! [`SampleRows`] is what every results observer writes per sample (the row with its centroid
//! velocity, the snapshot cadence, both continued across a resume); [`ResultsObserver`] (used by
//! `rbc-simulate`) adds the snapshots, the summary and the checkpoints, and `rbc-sweep`'s observer
//! (`src/sweep/solver_exec.rs`) adds the steady-state detector, the classification ring and the
//! transit records on the same rows.

use super::checkpoint::RunState;
use super::persist::{CheckpointWriter, Reopened, SuspendRequest, OBSERVER_PREFIX};
use super::{Observer, RunSummary, Sample};
use crate::error::SolverError;
use crate::state::StateMap;
use nalgebra::{Matrix3, Vector3};
use rbc_schema::results::{FinalShape, RunStatus, RunWriter, TimeSample};
use std::collections::BTreeMap;

/// Asphericity of the vertex cloud's gyration tensor,
/// `((l1 - l2)^2 + (l2 - l3)^2 + (l3 - l1)^2) / (2 (l1 + l2 + l3)^2)` with `l_k`
/// its eigenvalues: 0 for a sphere (any isotropic point cloud), 1 for a rod.
pub fn asphericity(x: &[Vector3<f64>]) -> f64 {
    let n = x.len().max(1) as f64;
    let c: Vector3<f64> = x.iter().sum::<Vector3<f64>>() / n;
    let g: Matrix3<f64> = x.iter().map(|p| (p - c) * (p - c).transpose()).sum::<Matrix3<f64>>() / n;
    let l = g.symmetric_eigenvalues();
    let s = l.sum();
    if s <= 0.0 {
        return 0.0;
    }
    ((l[0] - l[1]).powi(2) + (l[1] - l[2]).powi(2) + (l[2] - l[0]).powi(2)) / (2.0 * s * s)
}

/// Bounding-box lengths (um) along x, y, z.
pub fn extents(x: &[Vector3<f64>]) -> [f64; 3] {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for p in x {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let d = hi - lo;
    [d.x, d.y, d.z]
}

/// Name of the per-vertex mean curvature field the solver stores with every snapshot
/// (`snapshots/mean_curvature_per_um`, 1/um).
pub const MEAN_CURVATURE_FIELD: &str = "mean_curvature_per_um";

/// Mean curvature `H` (1/um) at every vertex of the closed triangle mesh `(vertices, triangles)`:
/// the cotangent formula of [`crate::membrane::curvature::cotangent_curvatures`], positive on a
/// sphere (`1/R`). Stored with each snapshot so that viewers can colour the shape by it.
pub fn mean_curvature(vertices: &[[f64; 3]], triangles: &[[usize; 3]]) -> Vec<f64> {
    let mesh = crate::mesh::Mesh { vertices: vertices.iter().map(|p| Vector3::from(*p)).collect(), triangles: triangles.to_vec() };
    crate::membrane::curvature::cotangent_curvatures(&mesh).mean
}

/// Append a snapshot with its per-vertex mean curvature (a run begun by an older build, without
/// the field, gets positions only: [`RunWriter::append_snapshot_with`]).
pub fn append_snapshot_with_curvature(w: &mut RunWriter, t_s: f64, vertices: &[[f64; 3]], triangles: &[[usize; 3]]) -> Result<(), rbc_schema::SchemaError> {
    // a state that does not fit its triangles (a damaged checkpoint) has no curvature: the writer
    // refuses the snapshot itself, naming the vertex count
    if triangles.iter().flatten().any(|&i| i >= vertices.len()) {
        return w.append_snapshot(t_s, vertices);
    }
    let h = mean_curvature(vertices, triangles);
    w.append_snapshot_with(t_s, vertices, &[(MEAN_CURVATURE_FIELD, &h)])
}

/// The time-series rows of a run as every results observer writes them ([`ResultsObserver`],
/// and the sweep's observer in `rbc-sweep`): each sample's row with the centroid velocity by
/// backward difference over the output interval (as the paper: "difference of the centroids
/// between successive time steps"; 0 at the first sample), and the snapshot cadence (every
/// `snapshot_every`-th sample), continued exactly across a resume.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleRows {
    snapshot_every: usize,
    n: usize,
    prev: Option<(f64, Vector3<f64>)>,
}

impl SampleRows {
    /// Rows of a new run with a snapshot every `snapshot_every`-th sample (at least every one).
    pub fn new(snapshot_every: usize) -> Self {
        Self { snapshot_every: snapshot_every.max(1), n: 0, prev: None }
    }

    /// The cadence saved in a checkpoint's observer fields by [`SampleRows::save`].
    pub fn saved_cadence(observer: &StateMap) -> Result<usize, SolverError> {
        match observer.get("snapshot_every").map(|v| v.as_slice()) {
            Some([k]) if *k >= 1.0 && k.fract() == 0.0 => Ok(*k as usize),
            _ => Err(SolverError::Output(format!("checkpoint: field `{OBSERVER_PREFIX}snapshot_every` is missing or malformed"))),
        }
    }

    /// Save the cadence into a checkpoint's observer fields.
    pub fn save(&self, own: &mut StateMap) {
        own.insert("snapshot_every".into(), vec![self.snapshot_every as f64]);
    }

    /// Advance by a sample at `t_s` (s) with centroid `c` (um): its centroid velocity (um/s),
    /// whether it had a predecessor, and whether it is a snapshot (`snapshot_every`-th) sample.
    pub fn step(&mut self, t_s: f64, c: Vector3<f64>) -> (Vector3<f64>, bool, bool) {
        let v = match self.prev {
            Some((t0, c0)) if t_s > t0 => (c - c0) / (t_s - t0),
            _ => Vector3::zeros(),
        };
        let had_prev = self.prev.is_some();
        #[allow(clippy::manual_is_multiple_of)] // usize::is_multiple_of needs Rust 1.87; rust-version is 1.85
        let regular = self.n % self.snapshot_every == 0;
        self.prev = Some((t_s, c));
        self.n += 1;
        (v, had_prev, regular)
    }

    /// The row of sample `s` ([`SampleRows::step`] with the row built).
    pub fn row(&mut self, s: &Sample<'_>) -> (TimeSample, Vector3<f64>, bool, bool) {
        let c = s.centroid_um;
        let (v, had_prev, regular) = self.step(s.t_s, c);
        let sample = TimeSample {
            t_s: s.t_s,
            centroid_um: [c.x, c.y, c.z],
            velocity_mm_s: [v.x * 1e-3, v.y * 1e-3, v.z * 1e-3],
            area_um2: s.area_um2,
            volume_um3: s.volume_um3,
            asphericity: asphericity(s.vertices),
            extents_um: extents(s.vertices),
        };
        (sample, v, had_prev, regular)
    }
}

/// An [`Observer`] that appends one run to a results file.
pub struct ResultsObserver {
    writer: Option<RunWriter>,
    /// Rows, with a snapshot of all vertices every `snapshot_every`-th sample (and at the last one).
    rows: SampleRows,
    last: Option<(f64, Vec<[f64; 3]>)>,
    last_snapshot_t: f64,
    /// The mesh's triangles (from the first sample), for the curvature of the snapshots.
    triangles: Vec<[usize; 3]>,
    history: Vec<(f64, Vector3<f64>, f64)>,
    checkpoints: Option<CheckpointWriter>,
    resume_from: Option<RunState>,
    /// A suspend request ([`super::persist::suspend_path`]): checkpoint, then stop unfinished.
    suspend: Option<SuspendRequest>,
}

fn schema(e: rbc_schema::SchemaError) -> SolverError {
    SolverError::Schema(e)
}

impl ResultsObserver {
    /// Write into `writer` (a run begun with `ResultsFile::begin_run`).
    pub fn new(writer: RunWriter, snapshot_every: usize) -> Self {
        Self {
            writer: Some(writer),
            rows: SampleRows::new(snapshot_every),
            last: None,
            last_snapshot_t: f64::NAN,
            triangles: Vec::new(),
            history: Vec::new(),
            checkpoints: None,
            resume_from: None,
            suspend: None,
        }
    }

    /// Stop at a checkpoint, unfinished (status `running`, resumable), when `suspend` is
    /// requested; needs checkpoints ([`ResultsObserver::with_checkpoints`]).
    pub fn with_suspend(mut self, suspend: SuspendRequest) -> Self {
        self.suspend = Some(suspend);
        self
    }

    /// True when the run stopped at a checkpoint on its suspend request.
    pub fn suspended(&self) -> bool {
        self.suspend.as_ref().is_some_and(SuspendRequest::served)
    }

    /// Take checkpoints with `checkpoints`: deleted when the run fails, the one of the end state
    /// kept when it reaches its end time (a later end time continues it: [`super::persist::reopen_to`]).
    pub fn with_checkpoints(mut self, checkpoints: CheckpointWriter) -> Self {
        self.checkpoints = Some(checkpoints);
        self
    }

    /// Continue a run reopened at its checkpoint ([`super::persist::reopen`]): the runner
    /// gets the checkpoint's state from [`Observer::resume`], and the snapshot cadence,
    /// sample count, centroid-velocity difference and summary statistics continue from the
    /// stored rows exactly as in an uninterrupted run.
    pub fn resumed(r: Reopened, checkpoints: CheckpointWriter) -> Result<Self, SolverError> {
        let snapshot_every = SampleRows::saved_cadence(&r.observer)?;
        let mut o = Self::new(r.writer, snapshot_every).with_checkpoints(checkpoints);
        for row in &r.rows {
            let c = Vector3::from(row.centroid_um);
            let (v, had_prev, _) = o.rows.step(row.t_s, c);
            if had_prev {
                o.history.push((row.t_s, c, v.x));
            }
        }
        o.last_snapshot_t = r.snapshot_times_s.last().copied().unwrap_or(f64::NAN);
        // the cell's vertices: the state's first ones (penalty walls add their displacements after them)
        let n_cell = crate::mesh::slices::cell_len(&r.triangles).min(r.state.vertices.len());
        o.last = Some((r.state.t_s, r.state.vertices[..n_cell].iter().map(|p| [p.x, p.y, p.z]).collect()));
        o.triangles = r.triangles;
        if let Some(c) = &mut o.checkpoints {
            c.restart_clock();
        }
        o.resume_from = Some(r.state);
        Ok(o)
    }
}

impl Observer for ResultsObserver {
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError> {
        let c = s.centroid_um;
        let w = self.writer.as_mut().ok_or_else(|| SolverError::Output("run already closed".into()))?;
        let (sample, v_um_s, had_prev, regular) = self.rows.row(s);
        w.append_sample(&sample).map_err(schema)?;
        let verts: Vec<[f64; 3]> = s.vertices.iter().map(|p| [p.x, p.y, p.z]).collect();
        if self.triangles.is_empty() {
            self.triangles = s.triangles.to_vec();
        }
        if regular {
            append_snapshot_with_curvature(w, s.t_s, &verts, &self.triangles).map_err(schema)?;
            w.flush().map_err(schema)?;
            self.last_snapshot_t = s.t_s;
        }
        if had_prev {
            self.history.push((s.t_s, c, v_um_s.x));
        }
        self.last = Some((s.t_s, verts));
        Ok(())
    }

    fn finish(&mut self, summary: &RunSummary, failure: Option<&SolverError>) -> Result<(), SolverError> {
        let mut w = self.writer.take().ok_or_else(|| SolverError::Output("run already closed".into()))?;
        if self.suspended() || matches!(failure, Some(SolverError::Resume(_))) {
            // unfinished on purpose, or not continued from its checkpoint: the rows and
            // snapshots up to the checkpoint are flushed, the status stays `running` and the
            // checkpoint stays for `--resume`
            return w.flush().map_err(schema);
        }
        if let Some((t, verts)) = &self.last {
            if *t != self.last_snapshot_t {
                append_snapshot_with_curvature(&mut w, *t, verts, &self.triangles).map_err(schema)?;
            }
        }
        if let Some(e) = failure {
            w.fail(&e.to_string()).map_err(schema)?;
            return self.checkpoints.as_ref().map_or(Ok(()), |c| c.remove());
        }
        // statistics over the second half of the run; the classification of the
        // final shape (croissant/slipper) is not made here
        let tail = &self.history[self.history.len() / 2..];
        let k = tail.len().max(1) as f64;
        type Row = (f64, Vector3<f64>, f64);
        let mean = |f: &dyn Fn(&Row) -> f64| tail.iter().map(f).sum::<f64>() / k;
        let mut evidence = BTreeMap::new();
        evidence.insert("steps_accepted".to_string(), summary.accepted as f64);
        evidence.insert("steps_rejected".to_string(), summary.rejected as f64);
        evidence.insert("h_min_s".to_string(), summary.h_min_s);
        evidence.insert("h_max_s".to_string(), summary.h_max_s);
        evidence.insert("wall_s".to_string(), summary.wall_s);
        let out = rbc_schema::results::RunSummary {
            status: RunStatus::Unsteady,
            final_shape: FinalShape::Other,
            tank_treading: false,
            tumbling: false,
            mean_velocity_mm_s: mean(&|s| s.2) * 1e-3,
            min_velocity_mm_s: tail.iter().map(|s| s.2).fold(f64::INFINITY, f64::min).min(f64::MAX) * 1e-3,
            max_velocity_mm_s: tail.iter().map(|s| s.2).fold(f64::NEG_INFINITY, f64::max).max(f64::MIN) * 1e-3,
            mean_radial_um: mean(&|s| (s.1.y * s.1.y + s.1.z * s.1.z).sqrt()),
            mean_y_um: mean(&|s| s.1.y),
            mean_z_um: mean(&|s| s.1.z),
            evidence,
        };
        let fix = |v: f64| if v.is_finite() { v } else { 0.0 };
        let out = rbc_schema::results::RunSummary {
            min_velocity_mm_s: fix(out.min_velocity_mm_s),
            max_velocity_mm_s: fix(out.max_velocity_mm_s),
            ..out
        };
        // the checkpoint of the end state stays: a later end time continues the run from it
        // (`super::persist::reopen_to`)
        w.finish(&out).map_err(schema)
    }

    fn checkpoint_at_end(&mut self) -> bool {
        self.checkpoints.is_some()
    }

    fn checkpoint_due(&mut self, _t_s: f64) -> bool {
        let Some(c) = self.checkpoints.as_mut() else { return false };
        let due = c.due();
        self.suspend.as_mut().is_some_and(SuspendRequest::poll) || due
    }

    fn checkpoint(&mut self, state: &RunState) -> Result<(), SolverError> {
        let (Some(c), Some(w)) = (self.checkpoints.as_mut(), self.writer.as_mut()) else { return Ok(()) };
        let mut own = StateMap::new();
        self.rows.save(&mut own);
        c.write(w, state, &own)?;
        self.suspend.as_mut().map_or(Ok(()), SuspendRequest::after_checkpoint)
    }

    fn resume(&mut self) -> Result<Option<RunState>, SolverError> {
        Ok(self.resume_from.take())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn asphericity_of_sphere_points_is_zero_and_of_a_rod_is_one() {
        let cube: Vec<Vector3<f64>> = (0..8).map(|i| Vector3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)).collect();
        assert!(asphericity(&cube).abs() < 1e-14);
        let rod: Vec<Vector3<f64>> = (0..5).map(|i| Vector3::new(i as f64, 0.0, 0.0)).collect();
        assert!((asphericity(&rod) - 1.0).abs() < 1e-14);
        assert_eq!(extents(&rod), [4.0, 0.0, 0.0]);
    }
}
