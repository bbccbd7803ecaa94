//! Steady-state and periodic-orbit detection over a stream of sampled observables, with a maximum physical time.
//!
//! The paper ("Numerical results") runs each cell "until the RBC reaches the
//! steady state where the shape as well as the radial position does no longer
//! change, or alternatively until periodic motion is observed". This module
//! makes that decision reproducible: a [`SteadyDetector`] receives one sample
//! at a time (time in s and a few observables, each with its own absolute
//! tolerance) and returns a [`Verdict`].
//!
//! # Criterion
//!
//! Let `W` be the window length (s) and `tol_k` the tolerance of observable `k`.
//! At each sample time `t`, once samples cover `[t - W, t]`:
//!
//! 1. **Steady**: every observable varies by at most its tolerance over the window,
//!    `max_{[t-W,t]} x_k - min_{[t-W,t]} x_k <= tol_k` for all `k`.
//!    For `x(t) = a exp(-t/tau)` sampled from `t = 0` this first holds at
//!    `t* = W + tau ln(a (1 - exp(-W/tau)) / tol)` (tested).
//! 2. **Periodic** (when not steady): a period `P` is estimated from the upward
//!    crossings of the window mean by the observable with the largest
//!    `range_k / tol_k` (hysteresis 10 % of its range, at least `min_cycles`
//!    full cycles in the window); `P` is then refined (multiples 1, 2, 3 of the
//!    crossing estimate, for shapes with two humps per period) as the minimiser
//!    of the variance of the normalised lag differences
//!    `E(tau) = sum_k var_i((x_k(t_i) - x_k(t_i - tau)) / tol_k)` (a drift does not bias it)
//!    (grid over +-10 % of the estimate, then a parabola through the best three
//!    grid points). The orbit is accepted when it repeats within tolerance,
//!    `|x_k(t_i) - x_k(t_i - P)| <= tol_k` for all `k` and all samples `t_i` in
//!    `[t - W + P, t]`, the window holds at least `min_cycles + 1` periods
//!    (so the repetition is checked over `min_cycles` periods), and the orbit's
//!    mean does not drift across the window: the means over its first and its last
//!    period, `(1/P) int_{t-W}^{t-W+P} x_k` and `(1/P) int_{t-P}^{t} x_k` (of the
//!    piecewise linear interpolant, so that the oscillation averages out exactly),
//!    differ by at most `tol_k`. A drift or a decaying amplitude larger than `tol_k`
//!    per period fails the repetition; a slower drift that adds up to more than
//!    `tol_k` over the window fails the mean (a cell still migrating outwards by
//!    0.3 um/s while it oscillates with a 49 ms period repeats within 0.05 um per
//!    period, but is not at its steady orbit).
//!    `x_k(t_i - tau)` is linearly interpolated: sample at least ~30 times per
//!    period (interpolation error `A (2 pi dt / P)^2 / 8` for an amplitude `A`).
//!
//!    **An orbit too slow for the window** (`(min_cycles + 1) P > W`) is judged over a
//!    window stretched to `(min_cycles + 1) P`, the same repetition and drift tests, when
//!    the samples reach back that far: the detector keeps the last [`WINDOW_STRETCH`]` W`
//!    of samples, the period is estimated from the crossings over the last `4 W` of them and,
//!    for the periods those cannot hold, over the last `8 W`, `16 W` and all of them in turn
//!    (the shortest span that holds a period takes in the least transient), and only periods
//!    the window `W` cannot hold are tried there. `W` is then the shortest window,
//!    not a bound on the period: a fixed window would call a cell that swings with a period
//!    of more than `W / (min_cycles + 1)` undecided until `max_time_s` (at the study's
//!    `W` = 0.5 s that is 125 ms, which the slipper at ~2.5 mm/s exceeds: 135 ms). Periods
//!    above `WINDOW_STRETCH W / (min_cycles + 1)` are not detected (4 s at the study's `W`;
//!    the slipper at ~0.5 mm/s swings with ~0.77 s, the one at ~0.26 mm/s tumbles, turning
//!    over every ~1.2 s). This test runs once per
//!    `W / `[`SLOW_ORBITS_PER_WINDOW`] of sample time for the periods the first span adds and
//!    as much less often for the slower ones the longer spans add ([`slow_test_interval_s`]),
//!    at the first sample of each such interval, at a continued run's last sample and at
//!    `max_time_s`, not at every sample: its cost is `rbc-bench steady-detector`'s table
//!    (measured: ~10-20 ms of CPU per 10 ms of sample time with 16 s of samples kept at an
//!    output every 0.2 ms), against the 10-120 core-s a study run takes per 10 ms of sample
//!    time, and a verdict on an orbit of period `P > W / (min_cycles + 1)` comes at most
//!    `P / 12.5` later.
//! 3. **Unsteady**: neither holds by `max_time_s`.
//!
//! How far a run still is from these tests: the steady gap ([`steady_gap`], the largest range
//! over its tolerance, steady at `<= 1`) and the periodic gap ([`periodic_gap`], [`OrbitGap`]:
//! over the candidate periods of point 2, the smallest of the larger of the repetition and the
//! mean drift over their tolerances, periodic at `<= 1`). A run on a slipper's orbit keeps a
//! steady gap of ~30 whether or not its orbit has settled; its periodic gap says how close it is.
//!
//! Defaults ([`SteadyCriterion::paper_default`]) and why: see the constants below.

use rbc_schema::results::TimeSample;
use std::collections::VecDeque;

mod orbit;
mod orbit_drift;
mod window_stats;

use orbit::{slow_orbit, slow_orbits, window_orbits};
pub use orbit::{OrbitGap, OrbitPart};
pub use orbit_drift::{drift_interval_s, orbit_drift, OrbitDrift, ORBIT_DRIFT_PERIODS};
pub use window_stats::{window_stats, WindowStats};

/// Errors of the detector (bad input samples).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SteadyError {
    #[error("sample at t = {t_s} s has {found} observables, the criterion has {expected}")]
    Channels {
        t_s: f64,
        expected: usize,
        found: usize,
    },
    #[error("sample at t = {t_s} s: observable {channel} is not finite ({value})")]
    NonFinite {
        t_s: f64,
        channel: usize,
        value: f64,
    },
    #[error("sample time {t_s} s is not after the previous sample ({previous_s} s)")]
    TimeOrder { t_s: f64, previous_s: f64 },
    #[error("sample time {t_s} s is not a finite number")]
    NonFiniteTime { t_s: f64 },
    #[error("invalid criterion: {0}")]
    Criterion(String),
}

/// Outcome of the detection after a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict {
    /// Not decided yet (window not full, or still changing before `max_time_s`).
    Pending,
    /// Every observable constant within tolerance over `[window_start_s, t_s]`.
    Steady { t_s: f64, window_start_s: f64 },
    /// A periodic orbit of period `period_s` repeating within tolerance over `[window_start_s, t_s]`.
    Periodic {
        t_s: f64,
        window_start_s: f64,
        period_s: f64,
    },
    /// `max_time_s` reached without a steady or periodic state; the last window is `[window_start_s, t_s]`.
    Unsteady { t_s: f64, window_start_s: f64 },
}

impl Verdict {
    /// True for every verdict except [`Verdict::Pending`].
    pub fn is_decided(&self) -> bool {
        !matches!(self, Verdict::Pending)
    }

    /// The window `(start, end)` (s) the verdict was made on, if decided.
    pub fn window(&self) -> Option<(f64, f64)> {
        match *self {
            Verdict::Pending => None,
            Verdict::Steady {
                t_s,
                window_start_s,
            }
            | Verdict::Unsteady {
                t_s,
                window_start_s,
            } => Some((window_start_s, t_s)),
            Verdict::Periodic {
                t_s,
                window_start_s,
                ..
            } => Some((window_start_s, t_s)),
        }
    }

    /// `steady`, `periodic`, `unsteady` (the results.h5 status) or `pending`.
    pub fn name(&self) -> &'static str {
        match self {
            Verdict::Pending => "pending",
            Verdict::Steady { .. } => "steady",
            Verdict::Periodic { .. } => "periodic",
            Verdict::Unsteady { .. } => "unsteady",
        }
    }
}

/// Default window length (s): 1 s holds 4 periods (`min_cycles + 1`) of a cell that
/// swings or tumbles with a period of up to 0.25 s, and is short against the 2 to 30 s
/// the paper's runs need to settle. (Until session 52 this said that it held the tumbling
/// of slippers at ~0.13 mm/s, half a turn being `pi 4 um / 0.13 mm/s ~ 0.1 s`; the study's
/// slipper at ~0.26 mm/s turns over every ~1.2 s, 25x that estimate: such orbits are judged
/// over a stretched window, [`WINDOW_STRETCH`].)
pub const DEFAULT_WINDOW_S: f64 = 1.0;
/// Default maximal physical time (s): the paper reports croissants settling
/// only after 10 to 30 s; 40 s leaves one window of margin.
pub const DEFAULT_MAX_TIME_S: f64 = 40.0;
/// Default tolerance on the radial centroid position and on the extents (um):
/// half the experiment's position uncertainty `s_P = 0.1 um` (physics.md),
/// 1/16 of the smallest slipper offset (0.8 um), 1/8 of a mesh edge at 2048 triangles (~0.4 um).
pub const DEFAULT_POSITION_TOL_UM: f64 = 0.05;
/// Default tolerance on the asphericity (dimensionless, 0 sphere .. 1 rod): the
/// discocyte has ~0.1 and slippers/croissants differ by > 0.05; 0.005 is 1/10 of that.
pub const DEFAULT_ASPHERICITY_TOL: f64 = 0.005;
/// Default number of periods over which a periodic orbit must repeat.
pub const DEFAULT_MIN_CYCLES: usize = 3;
/// How far back (in windows `W`) the detector keeps samples to judge an orbit whose
/// `min_cycles + 1` periods do not fit in `W` (see the module documentation): periods up to
/// `32 W / (min_cycles + 1)`, `8 W` for the default three cycles. 4 until session 46, then 8:
/// the study's slipper at ~0.5 mm/s swings with a period of ~0.77 s, more than the 0.5 s that
/// 4 let its `W` = 0.5 s judge. 32 since session 52: the study's slipper at ~0.26 mm/s
/// (science-6p5-penalty, r_init 1.2 um) tumbles, turning over at ~0.75 s and ~1.9 s, so its
/// orbit's period is ~1.2 s (or ~2.4 s if the two halves of a turn differ), more than the 1 s
/// that 8 let the study judge; 32 judges up to 4 s there (a tumbling period scales as the
/// inverse velocity: down to ~0.15 mm/s), from 16 s of samples kept (~80k at an output every
/// 0.2 ms, ~6 MB). A longer stretch only adds candidates: multiples of a shorter
/// crossing period are judged over their own `(min_cycles + 1)` periods, with the same tests.
pub const WINDOW_STRETCH: f64 = 32.0;
/// The spans (in windows `W`) over which the detector estimates the period of an orbit too slow
/// for `W` from the crossings, each for the periods the spans before could not hold: over
/// `4 W` the periods up to `4 W / (min_cycles + 1)` (all of them until session 46), over
/// `8 W` those up to `2 W` (until session 52 the last span), then `16 W` and `WINDOW_STRETCH W`.
/// One estimate over all the kept samples instead would take in a transient up to
/// `WINDOW_STRETCH W` back, and lose orbits whose last spans repeat.
const SLOW_ORBIT_SPANS: [f64; 4] = [4.0, 8.0, 16.0, WINDOW_STRETCH];
/// How often per window `W` of sample time the detector judges the orbits too slow for `W`
/// (see the module documentation): every 10 ms at the study's `W` = 0.5 s, 1/12 of the
/// shortest such period (`W / (min_cycles + 1)` = 125 ms). The longer spans of
/// [`SLOW_ORBIT_SPANS`] add slower orbits only and are judged as much less often
/// ([`slow_test_interval_s`]).
pub const SLOW_ORBITS_PER_WINDOW: f64 = 50.0;

/// How often (s of sample time) the detector judges the periods that span `k` of
/// [`SLOW_ORBIT_SPANS`] adds: their shortest period over 12.5, `held / SLOW_ORBITS_PER_WINDOW`
/// with `held` the time the spans before hold (`W` before the first): every 10, 40, 80 and 160 ms
/// at the study's `W` = 0.5 s, for periods from 125 ms, 0.5, 1 and 2 s. The last span alone,
/// tried every 10 ms, would cost ~75 ms of CPU per 10 ms of sample time over its 80k samples
/// (`rbc-bench steady-detector`).
pub fn slow_test_interval_s(k: usize, window_s: f64) -> f64 {
    let held = if k == 0 { 1.0 } else { SLOW_ORBIT_SPANS[k - 1] };
    held * window_s / SLOW_ORBITS_PER_WINDOW
}

/// The criterion: window, maximal time, tolerances (one per observable).
#[derive(Debug, Clone, PartialEq)]
pub struct SteadyCriterion {
    /// Window length `W` (s).
    pub window_s: f64,
    /// Physical time at which an undecided run is declared unsteady (s).
    pub max_time_s: f64,
    /// Periods that must repeat within tolerance for a periodic verdict.
    pub min_cycles: usize,
    /// Minimal number of samples in a window before any decision.
    pub min_samples: usize,
    /// Absolute tolerance of each observable (its own unit).
    pub tolerances: Vec<f64>,
}

impl SteadyCriterion {
    /// Criterion on the observables of [`observables`] (radial position, asphericity,
    /// extents x, y, z) with the documented default window, maximal time and tolerances.
    pub fn paper_default() -> Self {
        let p = DEFAULT_POSITION_TOL_UM;
        SteadyCriterion {
            window_s: DEFAULT_WINDOW_S,
            max_time_s: DEFAULT_MAX_TIME_S,
            min_cycles: DEFAULT_MIN_CYCLES,
            min_samples: 20,
            tolerances: vec![p, DEFAULT_ASPHERICITY_TOL, p, p, p],
        }
    }

    /// Check the parameters (positive finite window and end, tolerances, at least one cycle, at
    /// least 3 samples a window).
    pub fn validate(&self) -> Result<(), SteadyError> {
        let bad = |m: String| Err(SteadyError::Criterion(m));
        if !(self.window_s.is_finite() && self.window_s > 0.0) {
            return bad(format!(
                "window_s = {} must be a finite number > 0",
                self.window_s
            ));
        }
        if !(self.max_time_s.is_finite() && self.max_time_s > 0.0) {
            return bad(format!(
                "max_time_s = {} must be a finite number > 0",
                self.max_time_s
            ));
        }
        if self.min_cycles == 0 {
            return bad("min_cycles must be at least 1".into());
        }
        // the count of a window includes one sample before it (`judged_window`): 3 keep at least
        // two samples inside the window, so that max - min measures a change
        if self.min_samples < 3 {
            return bad(format!("min_samples = {} must be at least 3", self.min_samples));
        }
        if self.tolerances.is_empty() {
            return bad("needs at least one observable tolerance".into());
        }
        if let Some(t) = self
            .tolerances
            .iter()
            .find(|t| !(t.is_finite() && **t > 0.0))
        {
            return bad(format!("tolerance {t} must be a finite number > 0"));
        }
        Ok(())
    }
}

/// Names of the observables returned by [`observables`], in order.
pub const OBSERVABLE_NAMES: [&str; 5] = [
    "radial_um",
    "asphericity",
    "extent_x_um",
    "extent_y_um",
    "extent_z_um",
];

/// The observables watched by default: radial centroid position `sqrt(y^2 + z^2)` (um),
/// asphericity, and the bounding-box extents along x, y, z (um).
pub fn observables(s: &TimeSample) -> [f64; 5] {
    let [_, y, z] = s.centroid_um;
    [
        (y * y + z * z).sqrt(),
        s.asphericity,
        s.extents_um[0],
        s.extents_um[1],
        s.extents_um[2],
    ]
}

/// Incremental detector: push samples in time order, read the verdict.
#[derive(Debug, Clone)]
pub struct SteadyDetector {
    criterion: SteadyCriterion,
    times: VecDeque<f64>,
    rows: VecDeque<Vec<f64>>,
    verdict: Verdict,
    /// Per span of [`SLOW_ORBIT_SPANS`], the last interval `floor(t / slow_test_interval_s)`
    /// whose slow orbits were judged.
    slow_judged: [f64; SLOW_ORBIT_SPANS.len()],
}

impl SteadyDetector {
    /// A detector with a validated criterion.
    pub fn new(criterion: SteadyCriterion) -> Result<Self, SteadyError> {
        criterion.validate()?;
        Ok(SteadyDetector {
            criterion,
            times: VecDeque::new(),
            rows: VecDeque::new(),
            verdict: Verdict::Pending,
            slow_judged: [f64::NEG_INFINITY; SLOW_ORBIT_SPANS.len()],
        })
    }

    /// The criterion in use.
    pub fn criterion(&self) -> &SteadyCriterion {
        &self.criterion
    }

    /// The current verdict (the first decided verdict is kept).
    pub fn verdict(&self) -> Verdict {
        self.verdict
    }

    /// Add the sample `(t_s, values)` and return the verdict. Once decided, the
    /// verdict no longer changes (further samples are checked but ignored).
    pub fn push(&mut self, t_s: f64, values: &[f64]) -> Result<Verdict, SteadyError> {
        if self.record(t_s, values)? {
            self.judge(t_s, false);
        }
        Ok(self.verdict)
    }

    /// Add the stored samples of a run that continues (a resumed or reopened run), checked and
    /// kept as [`SteadyDetector::push`] keeps them, and judge the window that ends at the last
    /// one only: the verdict describes where the run is, not the first earlier window that a
    /// criterion changed since would accept (the run's classification frames are its last ones
    /// too). The slow-orbit tests count as judged up to the sample before the last, so they fall
    /// due at the same samples as in a run that never stopped. For a run that went on undecided
    /// under the same criterion this is the state sample-by-sample pushes give (every earlier
    /// window was judged undecided then), in one judgement instead of one per sample.
    pub fn resume_with<'a>(&mut self, samples: impl IntoIterator<Item = (f64, &'a [f64])>) -> Result<Verdict, SteadyError> {
        self.take_and_judge_the_last(samples, false)
    }

    /// Add stored samples as [`SteadyDetector::resume_with`] does and judge the window that ends
    /// at the last one with every slow-orbit span, due or not: the verdict of that window itself,
    /// e.g. to check a run's stored verdict again at the end of its window (a run that reached it
    /// at a resume before session 59 had every span tested there).
    pub fn judge_at_the_last<'a>(&mut self, samples: impl IntoIterator<Item = (f64, &'a [f64])>) -> Result<Verdict, SteadyError> {
        self.take_and_judge_the_last(samples, true)
    }

    fn take_and_judge_the_last<'a>(&mut self, samples: impl IntoIterator<Item = (f64, &'a [f64])>, every_span: bool) -> Result<Verdict, SteadyError> {
        let (mut before, mut last) = (None, None);
        for (t_s, values) in samples {
            if self.record(t_s, values)? {
                (before, last) = (last, Some(t_s));
            }
        }
        if let Some(t_s) = last {
            if let Some(b) = before {
                let w = self.criterion.window_s;
                self.slow_judged = std::array::from_fn(|k| (b / slow_test_interval_s(k, w)).floor());
            }
            self.judge(t_s, every_span);
        }
        Ok(self.verdict)
    }

    /// The steady gap of the window ending at the latest sample kept ([`steady_gap`] of the same
    /// samples: the largest range of an observable over its tolerance, and its name), for a run
    /// still undecided; `None` while its samples span less than a window. Once a verdict is
    /// decided no sample is kept, so this is the gap of the last window judged before it.
    pub fn gap(&self) -> Option<(f64, &'static str)> {
        let first = judged_window(self.times.len(), |i| self.times[i], &self.criterion)?;
        let rows: Vec<&[f64]> = self.rows.iter().skip(first).map(|r| r.as_slice()).collect();
        gap_of(&rows, &self.criterion)
    }

    /// The closest candidate of the periodic test at the latest sample kept: over the window the
    /// detector judges and, for orbits too slow for it, over all the samples kept, the candidate
    /// period with the smallest [`OrbitGap`] (the verdict turns periodic when it is `<= 1`);
    /// `None` while the samples span less than a window, or where the lead observable (the one
    /// whose range is the largest over its tolerance, whose crossings give the candidate periods)
    /// does not cross its mean `min_cycles` times. As [`SteadyDetector::gap`], once a verdict is
    /// decided it is the candidate of the last window judged.
    pub fn periodic_gap(&self) -> Option<OrbitGap> {
        let first = judged_window(self.times.len(), |i| self.times[i], &self.criterion)?;
        let times: Vec<f64> = self.times.iter().copied().collect();
        let rows: Vec<&[f64]> = self.rows.iter().map(|r| r.as_slice()).collect();
        let mut all = window_orbits(&times[first..], &rows[first..], &self.criterion);
        all.extend(slow_orbits(&times, &rows, &self.criterion));
        all.into_iter().min_by(|a, b| a.gap.total_cmp(&b.gap))
    }

    /// The drift of the orbit mean of the first observable (the radial position under
    /// [`observables`]) over periods of `period_s`, from the samples kept ([`orbit_drift()`]; the
    /// samples kept are the last `WINDOW_STRETCH W`, so the earlier rate of an orbit slower than
    /// `WINDOW_STRETCH W / 8` (2 s at the study's `W`) is `None` here), for a run's checkpoint with the interval
    /// [`drift_interval_s`] of its [`SteadyDetector::periodic_gap`] (a quarter of the window
    /// when it has none).
    pub fn orbit_drift(&self, period_s: f64) -> Option<OrbitDrift> {
        let times: Vec<f64> = self.times.iter().copied().collect();
        let x: Vec<f64> = self.rows.iter().map(|r| r[0]).collect();
        orbit_drift(&times, &x, period_s)
    }

    /// Check the sample and keep it (the samples of the last `WINDOW_STRETCH` windows plus one
    /// older one); false when a verdict was decided before (the sample is checked, not kept).
    fn record(&mut self, t_s: f64, values: &[f64]) -> Result<bool, SteadyError> {
        let c = &self.criterion;
        if values.len() != c.tolerances.len() {
            return Err(SteadyError::Channels {
                t_s,
                expected: c.tolerances.len(),
                found: values.len(),
            });
        }
        if let Some((channel, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SteadyError::NonFinite {
                t_s,
                channel,
                value,
            });
        }
        if !t_s.is_finite() {
            return Err(SteadyError::NonFiniteTime { t_s });
        }
        if let Some(&prev) = self.times.back() {
            if t_s <= prev {
                return Err(SteadyError::TimeOrder {
                    t_s,
                    previous_s: prev,
                });
            }
        }
        if self.verdict.is_decided() {
            return Ok(false);
        }
        self.times.push_back(t_s);
        self.rows.push_back(values.to_vec());
        // keep the samples of [t - WINDOW_STRETCH W, t] plus one older sample (the window
        // [t - W, t] is "full" when the oldest kept sample is at or before t - W)
        let eps = 1e-9 * c.window_s;
        let keep_s = WINDOW_STRETCH * c.window_s;
        while self.times.len() >= 2 && self.times[1] <= t_s - keep_s + eps {
            self.times.pop_front();
            self.rows.pop_front();
        }
        Ok(true)
    }

    /// Judge the window ending at the latest kept sample `t_s` (and, at the first sample of each
    /// of a span's [`slow_test_interval_s`] intervals, at `max_time_s` or when `every_span`, the
    /// slow-orbit test of the spans due over the kept samples); sets the verdict when decided.
    fn judge(&mut self, t_s: f64, every_span: bool) {
        let c = &self.criterion;
        let t0 = self.times[0];
        let slots: [f64; SLOW_ORBIT_SPANS.len()] = std::array::from_fn(|k| (t_s / slow_test_interval_s(k, c.window_s)).floor());
        let due: [bool; SLOW_ORBIT_SPANS.len()] = std::array::from_fn(|k| every_span || t_s >= c.max_time_s || slots[k] > self.slow_judged[k]);
        let slow_due = due.iter().any(|&d| d);
        if let Some(first) = judged_window(self.times.len(), |i| self.times[i], c) {
            let times: Vec<f64> = self.times.iter().skip(first).copied().collect();
            let rows: Vec<&[f64]> = self.rows.iter().skip(first).map(|r| r.as_slice()).collect();
            let decided = classify_window(&times, &rows, c).or_else(|| {
                if !slow_due {
                    return None;
                }
                for k in (0..due.len()).filter(|&k| due[k]) {
                    self.slow_judged[k] = slots[k];
                }
                // an orbit too slow for W, over the kept samples of the spans due
                let times: Vec<f64> = self.times.iter().copied().collect();
                let rows: Vec<&[f64]> = self.rows.iter().map(|r| r.as_slice()).collect();
                slow_orbit(&times, &rows, c, &due)
            });
            if let Some(v) = decided {
                self.verdict = v;
                return;
            }
        }
        if t_s >= c.max_time_s {
            self.verdict = Verdict::Unsteady {
                t_s,
                window_start_s: (t_s - c.window_s).max(t0),
            };
        }
    }
}

/// Run the detector over a whole series (`rows[i]` holds the observables at `times[i]`);
/// returns the first decided verdict, or `Pending` if the series ends before `max_time_s` undecided.
pub fn detect(
    criterion: &SteadyCriterion,
    times: &[f64],
    rows: &[Vec<f64>],
) -> Result<Verdict, SteadyError> {
    let mut d = SteadyDetector::new(criterion.clone())?;
    for (t, r) in times.iter().zip(rows) {
        let v = d.push(*t, r)?;
        if v.is_decided() {
            return Ok(v);
        }
    }
    Ok(d.verdict())
}

/// The window `[t - W, t]` the detector judges at the latest of `len` samples (`time(i)` in
/// time order): the index of its first sample, the first one at or after `t - W` (within
/// `1e-9 W`). On output times whose step divides `W` (the sweeps': 0.2 ms into 0.5 s) that
/// sample is at `t - W`; otherwise the window judged is up to one step shorter than `W`. `None`
/// while the samples span less than `W` or the window holds fewer than `min_samples`, counted with
/// the sample before it when there is one (so `min_samples >= 3` keeps two inside).
fn judged_window(len: usize, time: impl Fn(usize) -> f64, c: &SteadyCriterion) -> Option<usize> {
    let t1 = time(len.checked_sub(1)?);
    let eps = 1e-9 * c.window_s;
    if t1 - time(0) < c.window_s - eps {
        return None;
    }
    // the first sample at or after t - W - eps (binary search: the times are ordered)
    let (mut lo, mut hi) = (0, len);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if time(mid) < t1 - c.window_s - eps {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    (len - lo + usize::from(lo > 0) >= c.min_samples).then_some(lo)
}

/// Each observable's range (max - min, its unit) over `rows` (`nk` observables a row).
fn ranges(rows: &[&[f64]], nk: usize) -> Vec<f64> {
    (0..nk)
        .map(|k| {
            let col = rows.iter().map(|r| r[k]);
            col.clone().fold(f64::NEG_INFINITY, f64::max) - col.fold(f64::INFINITY, f64::min)
        })
        .collect()
}

/// How far a run is from the steady test of `c` at its latest sample: over the last window
/// `[t - W, t]` of `samples` (in time order), the largest range of an observable
/// ([`observables`]) over its tolerance, and that observable's name ([`OBSERVABLE_NAMES`]).
/// The window is steady when the gap is `<= 1` (a periodic orbit keeps it above 1). `None`
/// while the samples span less than one window or hold fewer than `min_samples` in it (counted
/// as [`SteadyDetector`] counts them), i.e. where the detector does not judge yet.
pub fn steady_gap(samples: &[TimeSample], c: &SteadyCriterion) -> Option<(f64, &'static str)> {
    let first = judged_window(samples.len(), |i| samples[i].t_s, c)?;
    let rows: Vec<[f64; 5]> = samples[first..].iter().map(observables).collect();
    let rows: Vec<&[f64]> = rows.iter().map(|r| &r[..]).collect();
    gap_of(&rows, c)
}

/// The largest range of an observable over its tolerance in the judged window `rows`, and its name.
fn gap_of(rows: &[&[f64]], c: &SteadyCriterion) -> Option<(f64, &'static str)> {
    let nk = c.tolerances.len().min(OBSERVABLE_NAMES.len());
    ranges(rows, nk)
        .iter()
        .zip(&c.tolerances)
        .zip(OBSERVABLE_NAMES)
        .map(|((r, tol), name)| (r / tol, name))
        .max_by(|a, b| a.0.total_cmp(&b.0))
}

/// Steady or periodic verdict on one full window, or `None`.
fn classify_window(times: &[f64], rows: &[&[f64]], c: &SteadyCriterion) -> Option<Verdict> {
    let nk = c.tolerances.len();
    let (t0, t1) = (times[0], times[times.len() - 1]);
    if ranges(rows, nk).iter().zip(&c.tolerances).all(|(r, tol)| r <= tol) {
        return Some(Verdict::Steady {
            t_s: t1,
            window_start_s: t0,
        });
    }
    let g = window_orbits(times, rows, c).into_iter().find(|g| g.gap <= 1.0)?;
    Some(Verdict::Periodic {
        t_s: t1,
        window_start_s: g.window_start_s,
        period_s: g.period_s,
    })
}

/// The closest candidate of the periodic test at the latest of `samples` (in time order), as
/// [`SteadyDetector::periodic_gap`] gives it after the same samples while undecided (a detector
/// that decided keeps no later sample; this judges the window at the last sample regardless):
/// `None` where the detector does not judge yet, or where the lead observable does not cross its
/// mean `min_cycles` times; also for samples the detector refuses (a non-finite observable, a
/// time not after the previous one).
pub fn periodic_gap(samples: &[TimeSample], c: &SteadyCriterion) -> Option<OrbitGap> {
    let mut d = SteadyDetector::new(c.clone()).ok()?;
    for s in samples {
        d.record(s.t_s, &observables(s)).ok()?;
    }
    d.periodic_gap()
}

/// The drift of the orbit mean of the radial position (the first of [`observables`]) over
/// periods of `period_s` in `samples` (in time order): [`orbit_drift()`] of the samples' times and
/// radial positions, as `rbc-sweep status` reads it for a run whose rows it has.
pub fn radial_orbit_drift(samples: &[TimeSample], period_s: f64) -> Option<OrbitDrift> {
    let times: Vec<f64> = samples.iter().map(|s| s.t_s).collect();
    let radial: Vec<f64> = samples.iter().map(|s| observables(s)[0]).collect();
    orbit_drift(&times, &radial, period_s)
}
