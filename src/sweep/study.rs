//! Progress of the runs of a study (`scripts/study.sh status`, `rbc-sweep --study-status`): how far each run has come and what it looks like so far.
//!
//! An unfinished run is read from its checkpoint (`<results>.<run_id>.ckpt`, written atomically,
//! so it can be read while the run goes on; the results file itself is locked by the running
//! process): the state's time and vertices, and the observer's ring of classification frames
//! (the last `classify.frames` frames, `classify.frame_interval_s` apart). A finished or failed run, or one without a
//! checkpoint, is read from the results file: its last snapshot (time, shape, position; the
//! velocity of the row at that time) and the stored label of a finished run. The mesh topology of a checkpointed run comes from its scene
//! ([`rbc_solver::scene::initial_mesh`]), so the results file is not opened.
//!
//! Quantities (units in the names): the volume centroid `(y, z)` of the latest state (um from
//! the channel axis); the asphericity of [`rbc_solver::run::results::asphericity`]; the sharpest
//! fold, the largest angle between the normals of two triangles sharing an edge
//! ([`rbc_solver::integrate::check::sharpest_fold`], the resolution check of the runs); the
//! centroid velocity along x over the ring (mm/s); the label so far, the classifier
//! ([`rbc_solver::classify::classify`]) on the ring frames with the sweep's settings: this is a
//! snapshot of the current shape, not a steady-state verdict; and with it how the membrane and the
//! shape turn over those frames ([`Motion`]: the tank-treading frequency and the shape's rotation
//! about z, Hz; for a run that ended, as stored with its label). With the sweep's steady-state
//! criterion, the steady gap: over the last window of the stored time series, the largest range
//! of an observable over its tolerance ([`rbc_solver::steady::steady_gap`]; steady when `<= 1`),
//! read from the results file when it opens (a study's saved state opens); a running run's file
//! is locked, so its gap is the one its own detector computed at its checkpoint (the sweep's
//! criterion; `-` from a build before session 39, or while its samples span less than a window).
//! And the periodic gap ([`rbc_solver::steady::periodic_gap`]): over the candidate periods of the
//! periodic test, the smallest of the larger of the orbit's repetition and its mean drift over
//! their tolerances (periodic when `<= 1`), with the observable and the part that set it and the
//! candidate's period; read as the steady gap is (`-` from a build before session 42, or where
//! the lead observable, the one with the largest range over its tolerance, does not cross its
//! mean often enough to give a candidate period). A run on a slipper's orbit keeps
//! a steady gap of ~30 however settled its orbit is: the periodic gap says how far it is.
//! And the orbit's drift ([`rbc_solver::steady::radial_orbit_drift`]): the slope of the radial
//! position's means over whole periods of the periodic gap's candidate, over its last four
//! periods and the four before them (um/s): a cell settling onto its orbit slows, one
//! leaving it speeds up, however small its drift (the periodic test passes a slipper whose mean
//! moves by up to ~0.08 um/s at the study's tolerances). Read as the gaps are (a running run's
//! checkpoint keeps only the detector's last `WINDOW_STRETCH W` of samples, so there the earlier
//! rate of an orbit slower than 2 s is `-` (0.5 s before session 52); `-` from a build before session 46). A run with no
//! candidate period gets the same slopes of the means over quarters of the window
//! ([`rbc_solver::steady::drift_interval_s`]): its radial drift over the last window and the one
//! before (session 47), e.g. a croissant creeping off the axis by less than the position
//! tolerance per window; a swing with no period yet is not averaged out there.

use super::SweepError;
use nalgebra::Vector3;
use rbc_schema::checkpoint;
use rbc_schema::results::{ResultsFile, TimeSample};
use rbc_schema::scene::Scene;
use rbc_solver::classify::{classify, volume_centroid, ClassifyConfig, Frame};
use rbc_solver::integrate::check::sharpest_fold;
use rbc_solver::run::checkpoint::RunState;
use rbc_solver::run::results::asphericity;
use rbc_solver::steady::{drift_interval_s, periodic_gap, radial_orbit_drift, steady_gap, OrbitDrift, OrbitGap, SteadyCriterion, OBSERVABLE_NAMES};
use std::path::Path;

/// One run's progress (see the module documentation for the definitions).
#[derive(Debug, Clone, PartialEq)]
pub struct RunProgress {
    pub run_id: String,
    /// `running` (unfinished), `steady`, `periodic`, `unsteady` or `failed`.
    pub status: String,
    /// Simulated time reached (s).
    pub t_s: f64,
    pub y_um: f64,
    pub z_um: f64,
    pub asphericity: f64,
    pub sharpest_fold_deg: f64,
    /// Centroid velocity along x over the last frames (mm/s); NaN when unknown.
    pub velocity_mm_s: f64,
    /// Label of the current shape (croissant, slipper, other), or `-` with fewer than 3 frames.
    pub shape: String,
    /// The membrane's motion over the same frames (or, for a run that ended, over the frames its
    /// label was decided on): `None` where there is no label.
    pub motion: Option<Motion>,
    /// Accepted steps so far (unknown for runs read from the results file: 0).
    pub steps: usize,
    /// The steady gap and the observable that sets it (see the module documentation); `None`
    /// without a criterion, with less than a window stored, or when the results file is locked
    /// and the checkpoint holds no gap.
    pub steady_gap: Option<(f64, &'static str)>,
    /// The periodic gap (see the module documentation); `None` as the steady gap, or without a
    /// candidate period.
    pub periodic_gap: Option<OrbitGap>,
    /// The drift of the orbit's radial mean over the periodic gap's period (see the module
    /// documentation, um/s); `None` as the periodic gap, or with fewer whole periods than a span.
    pub orbit_drift: Option<OrbitDrift>,
}

/// How the membrane and the shape turn ([`rbc_solver::classify::Evidence`]): the paper's
/// slippers tank-tread (the membrane circulates around a steady or periodic shape), its slow
/// ones tumble (the whole shape rotates about z, below ~0.7 mm/s), its fastest croissants
/// tank-tread a little.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// The membrane's circulation relative to the shape, `|labels rate - shape rate| / 2 pi` (Hz).
    pub tank_treading_hz: f64,
    /// The shape's rotation about z (Hz, signed: positive from x towards y).
    pub tumbling_hz: f64,
}

impl Motion {
    /// The motion stored with a run's label (`evidence_tt_frequency_hz`,
    /// `evidence_tumbling_frequency_hz`), `None` when either is missing.
    pub fn from_evidence(e: &std::collections::BTreeMap<String, f64>) -> Option<Motion> {
        Some(Motion { tank_treading_hz: *e.get("tt_frequency_hz")?, tumbling_hz: *e.get("tumbling_frequency_hz")? })
    }
}

fn err(path: &Path, message: impl std::fmt::Display) -> SweepError {
    SweepError::Io { path: path.into(), message: message.to_string() }
}

fn v3(v: &[Vector3<f64>]) -> Vec<[f64; 3]> {
    v.iter().map(|p| [p.x, p.y, p.z]).collect()
}

fn centroid_velocity_mm_s(frames: &[(f64, Vec<[f64; 3]>)], triangles: &[[usize; 3]]) -> f64 {
    match (frames.first(), frames.last()) {
        (Some(a), Some(b)) if b.0 > a.0 => {
            let xa = volume_centroid(&a.1, triangles).1[0];
            let xb = volume_centroid(&b.1, triangles).1[0];
            (xb - xa) / (b.0 - a.0) * 1e-3
        }
        _ => f64::NAN,
    }
}

/// The label of `frames` and the membrane's motion over them (`-` and `None` with fewer than 3
/// frames; `other` and `None` when the classifier refuses them).
fn label(frames: &[(f64, Vec<[f64; 3]>)], triangles: &[[usize; 3]], cfg: &ClassifyConfig) -> (String, Option<Motion>) {
    if frames.len() < 3 {
        return ("-".into(), None);
    }
    let fr: Vec<Frame<'_>> = frames.iter().map(|(t, v)| Frame { t_s: *t, vertices: v }).collect();
    match classify(&fr, triangles, cfg) {
        Ok(c) => {
            let motion = Motion { tank_treading_hz: c.evidence.tt_frequency_hz, tumbling_hz: c.evidence.tumbling_frequency_hz };
            (c.shape.as_str().to_string(), Some(motion))
        }
        Err(_) => ("other".into(), None),
    }
}

/// What a run's progress is computed from: its latest state and the frames before it.
struct Latest<'a> {
    t_s: f64,
    vertices: &'a [[f64; 3]],
    triangles: &'a [[usize; 3]],
    frames: &'a [(f64, Vec<[f64; 3]>)],
    steps: usize,
}

/// The progress of `l`; its label and motion are `stored` (a run that ended: those it ended
/// with), else the classifier's on its frames.
fn describe(run_id: &str, status: &str, l: Latest<'_>, cfg: &ClassifyConfig, stored: Option<(String, Option<Motion>)>) -> RunProgress {
    let Latest { t_s, vertices, triangles, frames, steps } = l;
    let c = volume_centroid(vertices, triangles).1;
    let x: Vec<Vector3<f64>> = vertices.iter().map(|p| Vector3::from(*p)).collect();
    let (shape, motion) = stored.unwrap_or_else(|| label(frames, triangles, cfg));
    RunProgress {
        run_id: run_id.into(),
        status: status.into(),
        t_s,
        y_um: c[1],
        z_um: c[2],
        asphericity: asphericity(&x),
        sharpest_fold_deg: sharpest_fold(&x, triangles).0.to_degrees(),
        velocity_mm_s: centroid_velocity_mm_s(frames, triangles),
        shape,
        motion,
        steps,
        steady_gap: None,
        periodic_gap: None,
        orbit_drift: None,
    }
}

/// The progress of run `run_id` of results file `path` (see the module documentation).
pub fn run_progress(path: &Path, run_id: &str, cfg: &ClassifyConfig, steady: Option<&SteadyCriterion>) -> Result<RunProgress, SweepError> {
    let (mut p, rows) = latest_progress(path, run_id, cfg)?;
    if let Some(c) = steady {
        // The gaps come from the rows when they read, up to the table's time (a killed run may
        // have rows past its checkpoint). A running run's file is locked by its process: then
        // the gaps its checkpoint holds, not an error (so for any other failure to read the
        // rows, which the table's other columns do not need). `None` is an answer either way:
        // less than a window, no candidate period.
        if let Some(rows) = rows.or_else(|| ResultsFile::open(path).and_then(|f| f.timeseries(run_id)).ok()) {
            let upto = rows.partition_point(|r| r.t_s <= p.t_s);
            p.steady_gap = steady_gap(&rows[..upto], c);
            p.periodic_gap = periodic_gap(&rows[..upto], c);
            p.orbit_drift = radial_orbit_drift(&rows[..upto], drift_interval_s(p.periodic_gap.as_ref(), c.window_s));
        }
    } else {
        p.steady_gap = None;
        p.periodic_gap = None;
        p.orbit_drift = None;
    }
    Ok(p)
}

/// The latest state's progress, and the run's stored rows when they were read for it (a run
/// read from its results file), so that the steady gap does not read them again.
fn latest_progress(path: &Path, run_id: &str, cfg: &ClassifyConfig) -> Result<(RunProgress, Option<Vec<TimeSample>>), SweepError> {
    let ck_path = checkpoint::checkpoint_path(path, run_id);
    // a run that ended keeps the checkpoint of its end state (for `reopen`): its results file,
    // readable then, says so; a running one's file is locked, a suspended one says `running`
    // (opened once: the results branch below reads it)
    let opened = ResultsFile::open(path);
    let ended = opened.as_ref().ok().and_then(|f| f.run(run_id).ok()).is_some_and(|r| r.status != rbc_schema::results::RunStatus::Running);
    if ck_path.exists() && !ended {
        let ck = checkpoint::read(&ck_path)?;
        let state = RunState::from_fields(&ck.fields, "").map_err(|e| err(&ck_path, e))?;
        let scene = Scene::parse(&ck.scene, &ck_path)?;
        let mesh = rbc_solver::scene::initial_mesh(&scene).map_err(|e| err(&ck_path, e))?;
        let triangles = mesh.triangles.clone();
        // the state is the cell's vertices, followed by the walls' displacements with penalty walls
        let nv = mesh.vertices.len();
        // a state its run could not continue from (`rbc-simulate --resume` refuses it too) is an
        // error, not a row of NaN
        if let Some(why) = state.unusable(nv) {
            return Err(err(&ck_path, why));
        }
        let penalty = scene.walls.has_penalty_walls();
        let n_state = state.vertices.len();
        if n_state != nv && !(penalty && n_state > nv) {
            return Err(err(&ck_path, format!("field `runner.vertices_um`: {n_state} vertices, but the run's scene has {nv}")));
        }
        let own = rbc_solver::run::persist::observer_fields(&ck.fields);
        // the ring also holds the snapshot samples between its frames; a checkpoint without a
        // readable ring is shown without its frames
        let ring = super::observer_state::stored_ring(&own, nv).unwrap_or_default();
        let frames: Vec<(f64, Vec<[f64; 3]>)> = ring.into_iter().filter(|e| e.frame).map(|e| (e.t_s, e.vertices)).collect();
        let latest = Latest { t_s: state.t_s, vertices: &v3(&state.vertices[..nv]), triangles: &triangles, frames: &frames, steps: state.summary.accepted };
        let mut p = describe(run_id, "running", latest, cfg, None);
        p.steady_gap = super::observer_state::stored_gap(&own);
        p.periodic_gap = super::observer_state::stored_periodic_gap(&own);
        p.orbit_drift = super::observer_state::stored_orbit_drift(&own);
        return Ok((p, None));
    }
    let file = opened?;
    let rec = file.run(run_id)?;
    if rec.status == rbc_schema::results::RunStatus::OverlapsWall {
        // never run: where it would have started, nothing else
        let (y_um, z_um) = rec.attrs.as_ref().map_or((f64::NAN, f64::NAN), |a| (a.y_init_um, a.z_init_um));
        // (no rows: it never ran)
        let p = RunProgress {
            run_id: run_id.into(),
            status: rec.status.as_str().into(),
            t_s: 0.0,
            y_um,
            z_um,
            asphericity: f64::NAN,
            sharpest_fold_deg: f64::NAN,
            velocity_mm_s: f64::NAN,
            shape: "-".into(),
            motion: None,
            steps: 0,
            steady_gap: None,
            periodic_gap: None,
            orbit_drift: None,
        };
        return Ok((p, Some(Vec::new())));
    }
    let snaps = file.snapshots(run_id)?;
    let triangles: Vec<[usize; 3]> = snaps.triangles.iter().map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
    let rows = file.timeseries(run_id)?;
    let n = snaps.times_s.len();
    let frames: Vec<(f64, Vec<[f64; 3]>)> = (n.saturating_sub(25)..n).map(|k| (snaps.times_s[k], snaps.vertices_um[k].clone())).collect();
    let Some((t_s, last)) = frames.last() else {
        return Err(err(path, format!("run {run_id} has no snapshot yet")));
    };
    let t_s = *t_s;
    let stored = rec.summary.as_ref().map(|s| (s.final_shape.as_str().to_string(), Motion::from_evidence(&s.evidence)));
    let mut p = describe(run_id, rec.status.as_str(), Latest { t_s, vertices: last, triangles: &triangles, frames: &frames, steps: 0 }, cfg, stored);
    if let Some(r) = rows.iter().find(|r| r.t_s == t_s) {
        p.velocity_mm_s = r.velocity_mm_s[0];
    }
    Ok((p, Some(rows)))
}

/// The progress of every run in each results file of `paths`.
pub fn progress(paths: &[&Path], cfg: &ClassifyConfig, steady: Option<&SteadyCriterion>) -> Result<Vec<RunProgress>, SweepError> {
    let mut out = Vec::new();
    for path in paths {
        let ids = match ResultsFile::open(path) {
            Ok(f) => f.run_ids()?,
            // locked by the running process: the run ids from the checkpoints beside it; without
            // any, the file's own error (missing, cut short, not HDF5) is the answer
            Err(e) => {
                let ids = checkpoint_ids(path);
                if ids.is_empty() {
                    return Err(e.into());
                }
                ids
            }
        };
        if ids.is_empty() {
            return Err(err(path, "no run and no checkpoint"));
        }
        for id in ids {
            out.push(run_progress(path, &id, cfg, steady)?);
        }
    }
    Ok(out)
}

/// Run ids of the checkpoints `<results>.<run_id>.ckpt` beside `path`.
fn checkpoint_ids(path: &Path) -> Vec<String> {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else { return Vec::new() };
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut ids: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let f = e.file_name().to_string_lossy().into_owned();
            f.strip_prefix(&format!("{name}.")).and_then(|r| r.strip_suffix(".ckpt")).map(str::to_string)
        })
        .collect();
    ids.sort();
    ids
}

/// The periodic gap's cell: `1.84 (extent_y_um drift, P 341 ms)`.
fn orbit_gap_cell(o: OrbitGap) -> String {
    let name = OBSERVABLE_NAMES.get(o.observable).map_or_else(|| format!("observable {}", o.observable), |n| n.to_string());
    format!("{:.2} ({name} {}, P {:.0} ms)", o.gap, o.part.name(), o.period_s * 1e3)
}

/// The radial drift's cell: `-0.0327 (-0.0212 before)`, um/s over spans of four periods (or, with no
/// candidate period, of one window).
fn orbit_drift_cell(d: OrbitDrift) -> String {
    match d.earlier_rate {
        Some(e) => format!("{:+.4} ({e:+.4} before)", d.rate),
        None => format!("{:+.4}", d.rate),
    }
}

/// A Markdown table of `rows`, one line per run.
pub fn table(rows: &[RunProgress]) -> String {
    let mut s = String::from("| run | status | t (ms) | y (um) | z (um) | asphericity | sharpest fold (deg) | velocity (mm/s) | shape so far | tank-treading, tumbling (Hz) | steps | steady gap (x tol) | periodic gap (x tol) | radial drift (um/s) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {:.2} | {:.3} | {:.3} | {:.4} | {:.0} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.run_id,
            r.status,
            r.t_s * 1e3,
            r.y_um,
            r.z_um,
            r.asphericity,
            r.sharpest_fold_deg,
            // unknown before a run has two frames to take it from (a run just started)
            if r.velocity_mm_s.is_finite() { format!("{:.2}", r.velocity_mm_s) } else { "-".into() },
            r.shape,
            r.motion.map_or("-".into(), |m| format!("{:.2}, {:+.2}", m.tank_treading_hz, m.tumbling_hz)),
            r.steps,
            r.steady_gap.map_or("-".into(), |(g, name)| format!("{g:.2} ({name})")),
            r.periodic_gap.map_or("-".into(), orbit_gap_cell),
            r.orbit_drift.map_or("-".into(), orbit_drift_cell)
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run just started has no velocity yet: the table says `-`, as for its shape, not NaN;
    /// so for the gaps it has not got.
    #[test]
    fn the_table_shows_an_unknown_velocity_as_a_dash() {
        use rbc_solver::steady::OrbitPart;
        let row = |v: f64, gap, orbit, drift| RunProgress { run_id: "r".into(), status: "running".into(), t_s: 0.0, y_um: 0.35, z_um: 0.19, asphericity: 0.2, sharpest_fold_deg: 40.0, velocity_mm_s: v, shape: "-".into(), motion: None, steps: 0, steady_gap: gap, periodic_gap: orbit, orbit_drift: drift };
        let orbit = OrbitGap { gap: 1.836, part: OrbitPart::Drift, observable: 3, period_s: 0.3414, window_start_s: 2.1 };
        let drift = OrbitDrift { period_s: 0.3414, span_s: 1.3656, rate: -0.03271, earlier_rate: Some(-0.02119) };
        let young = OrbitDrift { earlier_rate: None, rate: 0.00412, ..drift };
        let turning = RunProgress { shape: "slipper".into(), motion: Some(Motion { tank_treading_hz: 0.5137, tumbling_hz: -0.0261 }), ..row(0.498, None, None, None) };
        let t = table(&[row(f64::NAN, None, None, None), row(2.456, Some((3.816, "extent_x_um")), Some(orbit), Some(drift)), row(2.456, None, Some(orbit), Some(young)), turning]);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines[2], "| r | running | 0.00 | 0.350 | 0.190 | 0.2000 | 40 | - | - | - | 0 | - | - | - |");
        assert_eq!(lines[3], "| r | running | 0.00 | 0.350 | 0.190 | 0.2000 | 40 | 2.46 | - | - | 0 | 3.82 (extent_x_um) | 1.84 (extent_y_um drift, P 341 ms) | -0.0327 (-0.0212 before) |");
        assert_eq!(lines[5], "| r | running | 0.00 | 0.350 | 0.190 | 0.2000 | 40 | 0.50 | slipper | 0.51, -0.03 | 0 | - | - | - |");
        assert!(lines[4].ends_with("| 1.84 (extent_y_um drift, P 341 ms) | +0.0041 |"), "{}", lines[4]);
        assert!(!t.contains("NaN"));
    }
}
