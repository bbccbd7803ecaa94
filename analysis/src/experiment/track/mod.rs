//! Frame-to-frame linking of detections along +x (the flow direction), and per-track velocities.
//!
//! Cells in the paper's channel move along +x at 0.1 to 12 mm/s, i.e. 0.25 to
//! 30 um per frame at 400 fps. The linker handles both ends of that range with
//! one motion model:
//!
//! 1. **Established tracks** (two or more points) predict their next position
//!    with their own least-squares velocity over the last
//!    [`TrackerConfig::history_frames`] points; the gate along x grows with the
//!    predicted displacement (`gate_x_um + gate_x_rel * |v| * frames_ahead`).
//! 2. **New tracks** (one point) have no velocity yet. The recording's typical
//!    displacement per frame is estimated first ([`displacement_prior`]: the
//!    densest cluster of the forward displacements between consecutive frames);
//!    a new track predicts with it, with a wide relative gate
//!    (`prior_rel`), inside the physical window `[-back_tolerance_um, v_max / fps]`.
//!    Without a prior (too few cells) the whole window is the gate and smaller
//!    forward steps are cheaper.
//! 3. Each frame, all active tracks and all detections are matched at once by a
//!    minimum-cost assignment ([`assign::assign`]) of the normalised squared
//!    distances `(e_x/g_x)^2 + (e_y/g_y)^2`, pairs outside the gate (cost > 1)
//!    forbidden; leaving a track unmatched costs 1. A global assignment with
//!    squared costs prefers equal displacements for all cells, which is what
//!    keeps two cells from swapping when both are in each other's gate.
//! 4. A track survives up to [`TrackerConfig::max_missed_frames`] frames without
//!    a detection (it is predicted further each missed frame).
//!
//! Objects touching the image border are never linked (their centroid is cut):
//! they only count as neighbours in [`crate::experiment::isolate`].

pub mod assign;
pub mod velocity;

use crate::types::Detection;

/// Parameters of the linker. Displacements are converted to um per frame with the recording's fps.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackerConfig {
    /// Slowest expected cell velocity, mm/s (paper: 0.14 mm/s at 20 mbar).
    pub v_min_mm_s: f64,
    /// Fastest expected cell velocity, mm/s (paper: 10.6 mm/s at 1000 mbar); the window has 15 % headroom.
    pub v_max_mm_s: f64,
    /// How far a new track may step backwards (centroid jitter, shape changes), um.
    pub back_tolerance_um: f64,
    /// Gate of an established track along x at zero velocity, um (centroid noise ~0.1 um, shape changes).
    pub gate_x_um: f64,
    /// Growth of the x gate with the predicted displacement (10 % velocity change per frame is far
    /// more than a cell in steady flow shows).
    pub gate_x_rel: f64,
    /// Relative half-width of a new track's gate around the prior displacement (cells of one
    /// recording differ in velocity by tens of percent: croissants vs slippers, cell size).
    pub prior_rel: f64,
    /// Gate across the channel, um (cells move across the 12 um channel slowly).
    pub gate_y_um: f64,
    /// Frames a track may miss in a row and still be continued.
    pub max_missed_frames: usize,
    /// Minimum number of linked detections for a track to be reported.
    pub min_frames: usize,
    /// Number of most recent points used for a track's predicting velocity.
    pub history_frames: usize,
    /// Tracks slower than this (least-squares velocity, mm/s) are objects stuck in the channel or
    /// dirt on the optics, not flowing cells; they are dropped (half the slowest expected velocity).
    pub stuck_velocity_mm_s: f64,
}

impl Default for TrackerConfig {
    fn default() -> Self {
        TrackerConfig {
            v_min_mm_s: 0.1,
            v_max_mm_s: 12.0,
            back_tolerance_um: 1.0,
            gate_x_um: 1.5,
            gate_x_rel: 0.1,
            prior_rel: 0.4,
            gate_y_um: 3.0,
            max_missed_frames: 2,
            min_frames: 3,
            history_frames: 10,
            stuck_velocity_mm_s: 0.05,
        }
    }
}

impl TrackerConfig {
    /// Largest forward displacement per frame considered, um (15 % above `v_max`).
    pub fn max_step_um(&self, fps: f64) -> f64 {
        1.15 * self.v_max_mm_s * 1000.0 / fps
    }
}

/// One linked cell: indices into the detection slice given to [`link`], in increasing frame order.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    /// 1-based id, in order of first frame then x.
    pub id: u64,
    pub detections: Vec<usize>,
}

/// Per-track measurements (um, s).
#[derive(Debug, Clone, PartialEq)]
pub struct TrackMotion {
    pub n_frames: usize,
    pub first_frame: usize,
    pub last_frame: usize,
    pub x_first_um: f64,
    pub y_mean_um: f64,
    /// Sample standard deviation of y (n - 1 in the denominator), um.
    pub y_std_um: f64,
    /// Least-squares slope of x(t), um/s.
    pub velocity_um_s: f64,
    /// Its standard error, um/s (0 for an exact two-point track never reported: `min_frames >= 3`).
    pub velocity_se_um_s: f64,
}

/// Least-squares motion of a track (see [`velocity::fit_line`]). `None` when fewer than 2 points.
pub fn motion(track: &Track, dets: &[Detection]) -> Option<TrackMotion> {
    let pts: Vec<&Detection> = track.detections.iter().map(|&i| &dets[i]).collect();
    let first = pts.first()?;
    let last = pts.last()?;
    let xt: Vec<(f64, f64)> = pts.iter().map(|d| (d.t_s, d.x_um)).collect();
    let fit = velocity::fit_line(&xt)?;
    let n = pts.len() as f64;
    let y_mean = pts.iter().map(|d| d.y_um).sum::<f64>() / n;
    let y_std = if pts.len() > 1 {
        (pts.iter().map(|d| (d.y_um - y_mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    Some(TrackMotion {
        n_frames: pts.len(),
        first_frame: first.frame,
        last_frame: last.frame,
        x_first_um: first.x_um,
        y_mean_um: y_mean,
        y_std_um: y_std,
        velocity_um_s: fit.slope,
        velocity_se_um_s: fit.slope_se.unwrap_or(0.0),
    })
}

/// Typical forward displacement per frame (um) of the cells of a recording, from all pairs of
/// non-border detections in consecutive frames with `dx` in `[-back, max_step]` and
/// `|dy| <= gate_y`: the `dx` with the most other pairs within `+-max(0.5 um, 10 %)` of it.
/// True pairs of every cell pile up at its displacement, while pairs of two different cells
/// scatter with their spacing. `None` with fewer than 3 pairs in the densest cluster.
pub fn displacement_prior(dets: &[Detection], fps: f64, cfg: &TrackerConfig) -> Option<f64> {
    let by_frame = frames_of(dets);
    let max_step = cfg.max_step_um(fps);
    let mut dx = Vec::new();
    for f in 1..by_frame.len() {
        for &i in &by_frame[f - 1] {
            for &j in &by_frame[f] {
                let (a, b) = (&dets[i], &dets[j]);
                let d = b.x_um - a.x_um;
                if d >= -cfg.back_tolerance_um
                    && d <= max_step
                    && (b.y_um - a.y_um).abs() <= cfg.gate_y_um
                {
                    dx.push(d);
                }
            }
        }
    }
    dx.sort_by(f64::total_cmp);
    let mut best: Option<(usize, f64)> = None;
    for &d in &dx {
        let h = (0.1 * d.abs()).max(0.5);
        let lo = dx.partition_point(|&v| v < d - h);
        let hi = dx.partition_point(|&v| v <= d + h);
        let count = hi - lo;
        if best.is_none_or(|(c, _)| count > c) {
            // Centre of the cluster: its mean, not the first member.
            let mean = dx[lo..hi].iter().sum::<f64>() / count as f64;
            best = Some((count, mean));
        }
    }
    best.filter(|(c, _)| *c >= 3).map(|(_, m)| m)
}

/// Indices of the linkable (non-border) detections per frame; index = frame number.
fn frames_of(dets: &[Detection]) -> Vec<Vec<usize>> {
    let n_frames = dets.iter().map(|d| d.frame + 1).max().unwrap_or(0);
    let mut by_frame = vec![Vec::new(); n_frames];
    for (i, d) in dets.iter().enumerate() {
        if !d.touches_border && d.x_um.is_finite() && d.y_um.is_finite() {
            by_frame[d.frame].push(i);
        }
    }
    by_frame
}

/// A track being built.
struct Active {
    detections: Vec<usize>,
    last_frame: usize,
}

/// Where an active track expects its cell in frame `f`, and how far it may be from there.
struct Prediction {
    x: f64,
    y: f64,
    gate_x: f64,
    gate_y: f64,
    /// Allowed absolute displacement window along x, relative to the last point (new tracks only).
    window: Option<(f64, f64)>,
    x_last: f64,
}

fn predict(
    t: &Active,
    f: usize,
    dets: &[Detection],
    prior: Option<f64>,
    max_step: f64,
    cfg: &TrackerConfig,
) -> Prediction {
    let ahead = (f - t.last_frame) as f64;
    let last = &dets[*t.detections.last().expect("tracks are never empty")];
    let k = t.detections.len().min(cfg.history_frames.max(2));
    let recent = &t.detections[t.detections.len() - k..];
    let y = recent.iter().map(|&i| dets[i].y_um).sum::<f64>() / k as f64;
    if t.detections.len() >= 2 {
        let pts: Vec<(f64, f64)> = recent
            .iter()
            .map(|&i| (dets[i].frame as f64, dets[i].x_um))
            .collect();
        if let Some(fit) = velocity::fit_line(&pts) {
            let x = fit.intercept + fit.slope * f as f64;
            let gate_x = cfg.gate_x_um + cfg.gate_x_rel * fit.slope.abs() * ahead;
            return Prediction {
                x,
                y,
                gate_x,
                gate_y: cfg.gate_y_um,
                window: None,
                x_last: last.x_um,
            };
        }
    }
    let window = (-cfg.back_tolerance_um, max_step * ahead);
    match prior {
        Some(p) => Prediction {
            x: last.x_um + p * ahead,
            y,
            gate_x: cfg.gate_x_um + cfg.prior_rel * p.abs() * ahead,
            gate_y: cfg.gate_y_um,
            window: Some(window),
            x_last: last.x_um,
        },
        // No prior: cost grows with the step from the window's back edge, so smaller forward steps win.
        None => Prediction {
            x: last.x_um + window.0,
            y,
            gate_x: window.1 - window.0,
            gate_y: cfg.gate_y_um,
            window: Some(window),
            x_last: last.x_um,
        },
    }
}

fn cost(p: &Prediction, d: &Detection) -> f64 {
    if let Some((lo, hi)) = p.window {
        let step = d.x_um - p.x_last;
        if step < lo || step > hi {
            return f64::INFINITY;
        }
    }
    let c = ((d.x_um - p.x) / p.gate_x).powi(2) + ((d.y_um - p.y) / p.gate_y).powi(2);
    if c <= 1.0 {
        c
    } else {
        f64::INFINITY
    }
}

/// Link the detections of one recording (frames `0..`, `fps` frames per second) into tracks.
///
/// Detections touching the image border are not linked. Tracks shorter than
/// [`TrackerConfig::min_frames`] or slower than [`TrackerConfig::stuck_velocity_mm_s`] are
/// dropped (their detections stay unlinked, and still count as neighbours in [`crate::experiment::isolate`]).
pub fn link(dets: &[Detection], fps: f64, cfg: &TrackerConfig) -> Vec<Track> {
    let by_frame = frames_of(dets);
    let prior = displacement_prior(dets, fps, cfg);
    let max_step = cfg.max_step_um(fps);
    let mut active: Vec<Active> = Vec::new();
    let mut done: Vec<Active> = Vec::new();
    for (f, here) in by_frame.iter().enumerate() {
        // Retire tracks that have missed too many frames.
        let (keep, retire): (Vec<Active>, Vec<Active>) = active
            .into_iter()
            .partition(|t| f - t.last_frame <= cfg.max_missed_frames + 1);
        done.extend(retire);
        active = keep;
        let preds: Vec<Prediction> = active
            .iter()
            .map(|t| predict(t, f, dets, prior, max_step, cfg))
            .collect();
        let costs: Vec<Vec<f64>> = preds
            .iter()
            .map(|p| here.iter().map(|&j| cost(p, &dets[j])).collect())
            .collect();
        let matched = assign::assign(&costs, here.len(), 1.0, 0.0);
        let mut used = vec![false; here.len()];
        for (t, m) in active.iter_mut().zip(&matched) {
            if let Some(j) = *m {
                t.detections.push(here[j]);
                t.last_frame = f;
                used[j] = true;
            }
        }
        for (j, &d) in here.iter().enumerate() {
            if !used[j] {
                active.push(Active {
                    detections: vec![d],
                    last_frame: f,
                });
            }
        }
    }
    done.extend(active);
    let stuck_um_s = cfg.stuck_velocity_mm_s * 1000.0;
    let moving = |d: &Vec<usize>| {
        let pts: Vec<(f64, f64)> = d.iter().map(|&i| (dets[i].t_s, dets[i].x_um)).collect();
        velocity::fit_line(&pts).is_some_and(|f| f.slope >= stuck_um_s)
    };
    let mut tracks: Vec<Vec<usize>> = done
        .into_iter()
        .map(|t| t.detections)
        .filter(|d| d.len() >= cfg.min_frames.max(2) && moving(d))
        .collect();
    tracks.sort_by(|a, b| {
        let (da, db) = (&dets[a[0]], &dets[b[0]]);
        da.frame.cmp(&db.frame).then(da.x_um.total_cmp(&db.x_um))
    });
    tracks
        .into_iter()
        .enumerate()
        .map(|(k, d)| Track {
            id: k as u64 + 1,
            detections: d,
        })
        .collect()
}
