//! `rbc-bench compare`: runs of the same scene made by different binaries or settings, against a reference run: cost and the science observables side by side.
//!
//! ```text
//! rbc-bench compare REF.h5@CPU_S NAME=RUN.h5@CPU_S [NAME=RUN.h5@CPU_S ...] [--from-s T] [--plot DIR/NAME] [--title T]
//! ```
//!
//! Each file holds one run (the last one is read); `CPU_S` is the process CPU time it took
//! (user + system, s; `scripts/bench_speed.sh` measures it). The observables are those the phase
//! diagram reads: the centroid's y and z (um), the asphericity and the centroid velocity along x
//! (mm/s, the backward difference between outputs as stored in the timeseries); the table gives
//! their largest deviation from the reference over the output times both runs share, the
//! core-seconds per simulated ms and the ratio of each run's cost to the first run's. The last
//! column is the drift of y from the reference (um/s, signed): the least-squares slope of
//! `y - y_ref` against time over the shared output times. A time-stepping error that biases the
//! lateral migration (penalty walls with long W-method steps, `solver/README.md` "Session 35")
//! grows linearly in time, so the slope is what it adds over a run's seconds; the largest
//! deviation of a short window mixes it with the offset of the first steps.
//!
//! `--from-s T` compares the runs from time `T` (s) on only: runs resumed from one checkpoint at
//! `T` (`scripts/bench_speed.sh --cases state:STUDY/RUN`) hold the same history before it, which
//! is neither simulated by them nor a deviation; their simulated ms are counted from `T` (a
//! checkpoint's time, not necessarily an output time).
//!
//! `--plot DIR/NAME` also draws the work-precision figure `DIR/NAME.png` (and `.svg`): each
//! deviation against the core-seconds per simulated ms, log-log, one panel per observable and one
//! line per scheme, a run's scheme being its label up to `@` (`bs23@4e-5`, `bs23@1e-4`, ... make
//! one line; a deviation of 0 is drawn at the panel's floor).

use anyhow::{bail, Context, Result};
use plotters::prelude::*;
use rbc_analysis::plot::{Figure, FONT_FAMILY};
use rbc_schema::results::{ResultsFile, TimeSample};
use std::path::{Path, PathBuf};

/// One run to compare: label, file, CPU seconds.
struct Entry {
    label: String,
    path: PathBuf,
    cpu_s: f64,
}

fn parse(arg: &str, label: Option<&str>) -> Result<Entry> {
    let (spec, label) = match (label, arg.split_once('=')) {
        (Some(l), _) => (arg, l.to_string()),
        (None, Some((l, rest))) => (rest, l.to_string()),
        (None, None) => bail!("`{arg}`: expected NAME=FILE.h5@CPU_S"),
    };
    let (file, cpu) = spec.rsplit_once('@').with_context(|| format!("`{arg}`: expected FILE.h5@CPU_S"))?;
    let cpu_s: f64 = cpu.parse().with_context(|| format!("`{arg}`: CPU seconds `{cpu}` is not a number"))?;
    if !(cpu_s >= 0.0 && cpu_s.is_finite()) {
        bail!("`{arg}`: CPU seconds must be finite and >= 0");
    }
    Ok(Entry { label, path: PathBuf::from(file), cpu_s })
}

fn rows(e: &Entry) -> Result<Vec<TimeSample>> {
    let f = ResultsFile::open(&e.path)?;
    let id = f.run_ids()?.pop().with_context(|| format!("{}: no run", e.path.display()))?;
    let rows = f.timeseries(&id)?;
    if rows.len() < 2 {
        bail!("{}: run {id} has {} rows", e.path.display(), rows.len());
    }
    Ok(rows)
}

/// The samples of `a` paired with the reference's at the same output time (to 1e-9 relative, or
/// 1e-15 s near 0; the first reference sample of a time when it repeats).
fn shared_times<'a>(a: &'a [TimeSample], reference: &'a [TimeSample]) -> impl Iterator<Item = (&'a TimeSample, &'a TimeSample)> {
    a.iter().filter_map(move |r| reference.iter().find(|q| (q.t_s - r.t_s).abs() <= 1e-9 * r.t_s.abs().max(1e-6)).map(|q| (r, q)))
}

/// Largest deviations (y, z, asphericity, x-velocity) of `a` from `reference` at shared output times.
pub fn deviations(a: &[TimeSample], reference: &[TimeSample]) -> Option<[f64; 4]> {
    let mut d = [0.0f64; 4];
    let mut shared = 0;
    for (r, q) in shared_times(a, reference) {
        shared += 1;
        d[0] = d[0].max((r.centroid_um[1] - q.centroid_um[1]).abs());
        d[1] = d[1].max((r.centroid_um[2] - q.centroid_um[2]).abs());
        d[2] = d[2].max((r.asphericity - q.asphericity).abs());
        d[3] = d[3].max((r.velocity_mm_s[0] - q.velocity_mm_s[0]).abs());
    }
    (shared > 1).then_some(d)
}

/// Least-squares slope of `y - y_ref` against time (um/s) at the output times `a` shares with
/// `reference`: `sum (t - t_mean) (d - d_mean) / sum (t - t_mean)^2`; `None` with fewer than two
/// shared times, or when they are all one time.
pub fn drift_y(a: &[TimeSample], reference: &[TimeSample]) -> Option<f64> {
    let pairs: Vec<(f64, f64)> = shared_times(a, reference).map(|(r, q)| (r.t_s, r.centroid_um[1] - q.centroid_um[1])).collect();
    if pairs.len() < 2 {
        return None;
    }
    let n = pairs.len() as f64;
    let (tm, dm) = pairs.iter().fold((0.0, 0.0), |(t, d), p| (t + p.0 / n, d + p.1 / n));
    let (num, den) = pairs.iter().fold((0.0, 0.0), |(u, v), (t, d)| (u + (t - tm) * (d - dm), v + (t - tm) * (t - tm)));
    (den > 0.0).then(|| num / den)
}

/// One compared run: its label, core-s per simulated ms and deviations (y, z, asphericity, u_x).
struct Point {
    label: String,
    rate: f64,
    deviations: [f64; 4],
}

/// The line a run belongs to: its label up to `@`.
fn scheme_of(label: &str) -> &str {
    label.split_once('@').map_or(label, |(s, _)| s)
}

/// The runs grouped into lines by scheme, in order of first appearance, each sorted by cost.
fn lines(points: &[Point]) -> Vec<(&str, Vec<&Point>)> {
    let mut out: Vec<(&str, Vec<&Point>)> = Vec::new();
    for p in points {
        let s = scheme_of(&p.label);
        match out.iter_mut().find(|(n, _)| *n == s) {
            Some((_, v)) => v.push(p),
            None => out.push((s, vec![p])),
        }
    }
    for (_, v) in &mut out {
        v.sort_by(|a, b| a.rate.total_cmp(&b.rate));
    }
    out
}

struct WorkPrecision<'a> {
    points: &'a [Point],
    title: &'a str,
}

impl Figure for WorkPrecision<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, plotters::coord::Shift>) -> rbc_analysis::plot::DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (title, panels) = root.split_vertically(36);
        title.titled(self.title, (FONT_FAMILY, 20))?;
        let names = ["max |dy| (um)", "max |dz| (um)", "max |d asphericity|", "max |d u_x| (mm/s)"];
        let colours = [RED, BLUE, GREEN, MAGENTA, CYAN, BLACK];
        let (rmin, rmax) = self.points.iter().fold((f64::MAX, 0.0f64), |(a, b), p| (a.min(p.rate), b.max(p.rate)));
        for (k, panel) in panels.split_evenly((2, 2)).iter().enumerate() {
            let positive: Vec<f64> = self.points.iter().map(|p| p.deviations[k]).filter(|&d| d > 0.0).collect();
            let dmax = positive.iter().copied().fold(0.0f64, f64::max).max(1e-12);
            let dmin = positive.iter().copied().fold(dmax, f64::min);
            let floor = dmin / 3.0;
            let mut chart = ChartBuilder::on(panel)
                .margin(10)
                .x_label_area_size(36)
                .y_label_area_size(64)
                .build_cartesian_2d((rmin / 1.5..rmax * 1.5).log_scale(), (floor..dmax * 3.0).log_scale())?;
            chart
                .configure_mesh()
                .x_desc("core-s per simulated ms")
                .y_desc(names[k])
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style((FONT_FAMILY, 13))
                .draw()?;
            for (i, (scheme, pts)) in lines(self.points).into_iter().enumerate() {
                let c = colours[i % colours.len()];
                let xy: Vec<(f64, f64)> = pts.iter().map(|p| (p.rate, p.deviations[k].max(floor))).collect();
                chart
                    .draw_series(LineSeries::new(xy.clone(), c.stroke_width(2)))?
                    .label(scheme.to_string())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
                chart.draw_series(xy.iter().map(|&q| Circle::new(q, 4, c.filled())))?;
            }
            if k == 0 {
                chart.configure_series_labels().position(SeriesLabelPosition::UpperRight).label_font((FONT_FAMILY, 13)).background_style(WHITE.mix(0.85)).border_style(BLACK).draw()?;
            }
        }
        Ok(())
    }
}

pub fn run(args: &[String]) -> Result<()> {
    let mut plot: Option<PathBuf> = None;
    let mut title = String::from("Work-precision against the reference");
    let mut from_s = f64::NEG_INFINITY;
    let mut runs: Vec<&String> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--plot" => plot = Some(PathBuf::from(it.next().context("--plot needs DIR/NAME")?)),
            "--title" => title = it.next().context("--title needs a text")?.clone(),
            "--from-s" => {
                let v = it.next().context("--from-s needs a time (s)")?;
                from_s = v.parse().ok().filter(|t: &f64| t.is_finite()).with_context(|| format!("--from-s `{v}`: not a finite time (s)"))?;
            }
            _ => runs.push(a),
        }
    }
    let Some((first, rest)) = runs.split_first() else {
        bail!("usage: rbc-bench compare REF.h5@CPU_S NAME=RUN.h5@CPU_S [...] [--from-s T] [--plot DIR/NAME] [--title T]");
    };
    let reference = parse(first, Some("reference"))?;
    let entries: Vec<Entry> = rest.iter().map(|a| parse(a, None)).collect::<Result<_>>()?;
    // the rows from `from_s` on (a sample at `from_s` itself, the shared start, is kept)
    let rows_from = |e: &Entry| -> Result<Vec<TimeSample>> {
        let r: Vec<TimeSample> = rows(e)?.into_iter().filter(|s| s.t_s >= from_s - 1e-9 * from_s.abs().max(1e-6)).collect();
        if r.len() < 2 {
            bail!("{}: {} rows from --from-s {from_s} s on", e.path.display(), r.len());
        }
        Ok(r)
    };
    let ref_rows = rows_from(&reference)?;
    println!("| run | core-s | simulated ms | core-s per simulated ms | cost vs first | max dy (um) | max dz (um) | max d asphericity | max d u_x (mm/s) | drift of y (um/s) |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    // (from `from_s` when given: a resumed run simulates from its checkpoint, which need not be an output time)
    let span = |r: &[TimeSample]| (r[r.len() - 1].t_s - if from_s.is_finite() { from_s } else { r[0].t_s }) * 1e3;
    let ms = span(&ref_rows);
    println!("| {} | {:.0} | {:.2} | {:.1} | | 0 | 0 | 0 | 0 | 0 |", reference.label, reference.cpu_s, ms, reference.cpu_s / ms);
    let mut first_rate = None;
    let mut points = Vec::new();
    for e in &entries {
        let r = rows_from(e)?;
        let ms = span(&r);
        let rate = e.cpu_s / ms;
        let ratio = rate / *first_rate.get_or_insert(rate);
        let d = deviations(&r, &ref_rows).with_context(|| format!("{}: no output time shared with the reference", e.path.display()))?;
        // (`-` when the shared times do not span an interval)
        let drift = drift_y(&r, &ref_rows).map_or("-".to_string(), |v| format!("{v:.1e}"));
        println!(
            "| {} | {:.0} | {:.2} | {:.1} | {:.2} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {drift} |",
            e.label, e.cpu_s, ms, rate, ratio, d[0], d[1], d[2], d[3]
        );
        points.push(Point { label: e.label.clone(), rate, deviations: d });
    }
    if let Some(stem) = plot {
        if points.is_empty() {
            bail!("--plot: no run to draw beside the reference");
        }
        let dir = stem.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let name = stem.file_name().and_then(|n| n.to_str()).with_context(|| format!("--plot {}: expected DIR/NAME", stem.display()))?;
        let paths = WorkPrecision { points: &points, title: &title }.save(dir, name, (1100, 800))?;
        println!("\nplot: {}", paths[0].display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(label: &str, rate: f64) -> Point {
        Point { label: label.into(), rate, deviations: [rate; 4] }
    }

    fn sample(t_s: f64, y: f64) -> TimeSample {
        TimeSample { t_s, centroid_um: [0.0, y, 0.3], velocity_mm_s: [1.0, 0.0, 0.0], area_um2: 135.0, volume_um3: 94.0, asphericity: 0.1, extents_um: [8.0, 3.0, 8.0] }
    }

    /// `y - y_ref = 0.2 - 0.05 t` (um, t in s) on the shared times gives the slope -0.05 um/s,
    /// whatever the reference's own path; an offset alone drifts by 0; a time the reference lacks
    /// is left out, and one shared time gives none.
    #[test]
    fn drift_is_the_least_squares_slope_of_the_y_deviation_at_shared_times() {
        let reference: Vec<TimeSample> = (0..21).map(|k| sample(1.0 + 1e-3 * k as f64, 1.0 + (k as f64).sin())).collect();
        let shifted = |f: &dyn Fn(f64) -> f64| -> Vec<TimeSample> { reference.iter().map(|q| sample(q.t_s, q.centroid_um[1] + f(q.t_s))).collect() };
        let d = drift_y(&shifted(&|t| 0.2 - 0.05 * t), &reference).unwrap();
        assert!((d + 0.05).abs() < 1e-9, "{d}");
        assert!(drift_y(&shifted(&|_| 0.7), &reference).unwrap().abs() < 1e-9);
        let mut extra = shifted(&|t| 3.0 * t);
        extra.push(sample(5.0, 100.0));
        assert!((drift_y(&extra, &reference).unwrap() - 3.0).abs() < 1e-6);
        assert_eq!(drift_y(&[sample(1.0, 0.0), sample(9.0, 1.0)], &reference), None);
        assert_eq!(drift_y(&[sample(1.0, 0.0), sample(1.0, 1.0)], &reference), None, "one time twice spans no interval");
        // times matched to 1e-9 relative, as the deviations match them
        let jittered: Vec<TimeSample> = reference.iter().map(|q| sample(q.t_s * (1.0 + 5e-10), q.centroid_um[1] + 2.0 * q.t_s)).collect();
        assert!((drift_y(&jittered, &reference).unwrap() - 2.0).abs() < 1e-6);
    }

    /// Known shifts of y, z, asphericity and u_x, largest at different samples: each column is
    /// the largest absolute shift of its own quantity (by sign too), a time the reference lacks
    /// is left out, and fewer than two shared times give none.
    #[test]
    fn deviations_are_the_largest_shift_of_each_quantity_at_shared_times() {
        let reference: Vec<TimeSample> = (0..5).map(|k| sample(1.0 + 1e-3 * k as f64, 1.0 + 0.1 * k as f64)).collect();
        let shifts = [[0.3, 0.0, 0.0, 0.0], [0.0, -0.1, 0.0, 0.0], [0.0, 0.0, 0.02, 0.0], [-0.1, 0.05, 0.0, -0.5], [0.0, 0.0, -0.01, 0.2]];
        let mut a: Vec<TimeSample> = reference
            .iter()
            .zip(shifts)
            .map(|(q, [dy, dz, da, du])| {
                let mut s = *q;
                s.centroid_um[1] += dy;
                s.centroid_um[2] += dz;
                s.asphericity += da;
                s.velocity_mm_s[0] += du;
                s
            })
            .collect();
        let mut far = sample(7.0, 50.0);
        far.asphericity = 9.0;
        a.push(far);
        let d = deviations(&a, &reference).unwrap();
        for (got, want) in d.iter().zip([0.3, 0.1, 0.02, 0.5]) {
            assert!((got - want).abs() < 1e-12, "{d:?}");
        }
        assert_eq!(deviations(&a[..1], &reference), None);
    }

    #[test]
    fn runs_group_into_lines_by_the_label_up_to_the_at_sign_each_sorted_by_cost() {
        let pts = [point("bs23@1e-4", 30.0), point("ros@2e-3", 5.0), point("bs23@4e-5", 40.0), point("bs23@2e-4", 20.0), point("ros@1e-3", 6.0), point("old", 9.0)];
        let got: Vec<(&str, Vec<&str>)> = lines(&pts).into_iter().map(|(s, v)| (s, v.iter().map(|p| p.label.as_str()).collect())).collect();
        assert_eq!(got, [("bs23", vec!["bs23@2e-4", "bs23@1e-4", "bs23@4e-5"]), ("ros", vec!["ros@2e-3", "ros@1e-3"]), ("old", vec!["old"])]);
    }
}
