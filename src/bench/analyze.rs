//! `rbc-bench analyze`: frames per second of the whole analysis pipeline, next to trackpy, with centroid accuracy against truth.
//!
//! Usage: `rbc-bench analyze [--frames N] [--um-per-px P] [--velocity V] [--seed S] [--python PY]
//! [--trackpy-timeout SECONDS]` (defaults 400 frames, 0.25 um/px, 3 mm/s, trackpy stopped after 300 s:
//! at 12 mm/s its linking with a 30+ um search range does not finish in 15 min on this machine).
//!
//! A synthetic recording (`rbc_analysis::simulated::synth`) of N frames with a train of cells 50 um
//! apart is written to a temporary folder. Then, timed separately:
//! 1. `rbc-analyze`'s pipeline in this process: open + detect (background, channel,
//!    segmentation, measurement) + track + isolate + classify, on the current rayon pool;
//! 2. trackpy 0.7 (`scripts/trackpy_bench.py`: `tp.batch` locate + `tp.link`, one process),
//!    reading the same frames; its frame reading is excluded from its time.
//!
//! Printed: frames per second of each, their ratio (from this one run), and the centroid
//! error of each against the truth (every located object matched to the nearest truth centroid
//! of its frame within 3 um; only cells seen whole). trackpy is skipped with a note when it
//! is not installed (`pip install trackpy`).

use anyhow::{bail, Context};
use rbc_analysis::experiment::pipeline::{analyse_detections, detect_dir, StageConfig};
use rbc_analysis::simulated::synth::{random_spec, write_recording, Truth, TruthRow};
use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

/// Options of the benchmark.
struct Options {
    frames: usize,
    um_per_px: f64,
    velocity_mm_s: f64,
    seed: u64,
    python: String,
    trackpy_timeout_s: u64,
}

fn parse(args: &[String]) -> anyhow::Result<Options> {
    let mut o = Options {
        frames: 400,
        um_per_px: 0.25,
        velocity_mm_s: 3.0,
        seed: 7,
        python: "python3".into(),
        trackpy_timeout_s: 300,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a}: missing value"));
        match a.as_str() {
            "--frames" => o.frames = val()?.parse().context("--frames")?,
            "--um-per-px" => o.um_per_px = val()?.parse().context("--um-per-px")?,
            "--velocity" => o.velocity_mm_s = val()?.parse().context("--velocity")?,
            "--seed" => o.seed = val()?.parse().context("--seed")?,
            "--python" => o.python = val()?.clone(),
            "--trackpy-timeout" => o.trackpy_timeout_s = val()?.parse().context("--trackpy-timeout")?,
            other => bail!("unknown option {other} (options: --frames N --um-per-px P --velocity V --seed S --python PY --trackpy-timeout SECONDS)"),
        }
    }
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if o.frames < 10 || !positive(o.um_per_px) || !positive(o.velocity_mm_s) {
        bail!("--frames must be >= 10, --um-per-px and --velocity > 0");
    }
    Ok(o)
}

/// Median and 95th percentile.
fn quantiles(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let q = |p: f64| s[((s.len() - 1) as f64 * p).round() as usize];
    (q(0.5), q(0.95))
}

/// Errors (um) of located points `(frame, x_um, y_um)` against the visible truth centroids of
/// their frame (nearest within 3 um), and how many visible truth centroids were matched.
fn centroid_errors(points: &[(u64, f64, f64)], truth: &[TruthRow]) -> (Vec<f64>, usize, usize) {
    let mut by_frame: HashMap<u64, Vec<&TruthRow>> = HashMap::new();
    for r in truth.iter().filter(|r| r.visible) {
        by_frame.entry(r.frame).or_default().push(r);
    }
    let visible = by_frame.values().map(Vec::len).sum();
    let mut matched = std::collections::HashSet::new();
    let mut errs = Vec::new();
    for &(f, x, y) in points {
        if let Some(rows) = by_frame.get(&f) {
            let best = rows
                .iter()
                .map(|r| (r, ((r.x_um - x).powi(2) + (r.y_um - y).powi(2)).sqrt()))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((r, e)) = best {
                if e <= 3.0 {
                    errs.push(e);
                    matched.insert((r.frame, r.cell_id));
                }
            }
        }
    }
    (errs, matched.len(), visible)
}

/// Run `cmd` to completion, or kill it after `limit_s` seconds (then the status has no exit code).
fn run_with_timeout(
    cmd: &mut std::process::Command,
    limit_s: u64,
) -> std::io::Result<std::process::Output> {
    use std::process::Stdio;
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn()?;
    let start = Instant::now();
    while child.try_wait()?.is_none() {
        if start.elapsed().as_secs() >= limit_s {
            let _ = child.kill();
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(200));
    }
    child.wait_with_output()
}

/// A recording of `frames` frames with a train of cells 50 um apart entering from the left.
fn write_train(dir: &Path, o: &Options) -> anyhow::Result<Truth> {
    let mut spec = random_spec(o.seed, o.um_per_px, 0.01, o.velocity_mm_s);
    spec.n_frames = o.frames;
    let travel_um = o.velocity_mm_s * 1000.0 / spec.fps * o.frames as f64;
    let n_cells = ((travel_um / 50.0).ceil() as usize + 2).min(2000);
    let base = spec.cells.clone();
    spec.cells = (0..n_cells)
        .map(|k| {
            let mut c = base[k % base.len()];
            c.x0_um = base[0].x0_um - 50.0 * (k as f64 - 1.0);
            c.seed = c.seed.wrapping_add(k as u64);
            // One velocity for the whole train: cells at different speeds would run into each other.
            c.velocity_mm_s = o.velocity_mm_s;
            c
        })
        .collect();
    Ok(write_recording(dir, &spec, o.seed)?)
}

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let o = parse(args)?;
    // A scratch folder removed at the end (std only: tempfile is a dev-dependency of this package).
    let tmp = std::env::temp_dir().join(format!("rbc-bench-analyze-{}", std::process::id()));
    let result = bench(&o, &tmp);
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

fn bench(o: &Options, tmp: &Path) -> anyhow::Result<()> {
    let rec = tmp.join("rec");
    eprintln!(
        "writing {} synthetic frames ({} um/px, {} mm/s) ...",
        o.frames, o.um_per_px, o.velocity_mm_s
    );
    let truth = write_train(&rec, o)?;
    let (axis_row_px, _) = truth.channel_rows();

    // 1. Our pipeline, in process.
    let t0 = Instant::now();
    let detected = detect_dir(&rec, tmp)?;
    let detect_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let tables = analyse_detections(
        &detected.name,
        &detected.config,
        &detected.detections,
        &StageConfig::default(),
    );
    let track_s = t1.elapsed().as_secs_f64();
    let ours_s = t0.elapsed().as_secs_f64();
    let ours_pts: Vec<(u64, f64, f64)> = detected
        .detections
        .iter()
        .filter(|d| !d.touches_border)
        .map(|d| (d.frame as u64, d.x_um, d.y_um))
        .collect();
    let (ours_err, ours_matched, visible) = centroid_errors(&ours_pts, &truth.rows);

    // 2. trackpy, as a separate Python process.
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/trackpy_bench.py");
    let csv_out = tmp.join("trackpy.csv");
    let tp = run_with_timeout(
        std::process::Command::new(&o.python)
            .arg(&script)
            .arg(&rec)
            .arg(&csv_out)
            .arg("--search-um")
            .arg(format!(
                "{}",
                (o.velocity_mm_s * 1000.0 / truth.spec.fps * 1.5).max(5.0)
            )),
        o.trackpy_timeout_s,
    );
    let threads = rayon::current_num_threads();
    println!("rbc-bench analyze: {} frames of {} x {} px, {} cells, {} um/px, {} mm/s, {threads} threads", o.frames, truth.spec.width_px, truth.spec.height_px, truth.spec.cells.len(), o.um_per_px, o.velocity_mm_s);
    println!("| method | frames/s | centroid error median (um) | p95 (um) | whole cells located |");
    println!("| --- | --- | --- | --- | --- |");
    let (m, p) = quantiles(&ours_err);
    let ours_fps = o.frames as f64 / ours_s;
    println!("| rbc-analyze pipeline (detect+track+isolate+classify) | {ours_fps:.1} | {m:.4} | {p:.4} | {ours_matched}/{visible} |");
    println!(
        "  ({} tracks; stages: read+detect {:.3} s, track+isolate+classify {:.4} s)",
        tables.tracks.len(),
        detect_s,
        track_s
    );
    match tp {
        Ok(out) if out.status.success() => {
            let stdout = String::from_utf8_lossy(&out.stdout);
            let line = stdout.lines().last().unwrap_or("");
            let num = |key: &str| -> f64 {
                line.split(&format!("\"{key}\": "))
                    .nth(1)
                    .and_then(|s| s.split([',', '}']).next())
                    .and_then(|s| s.trim().parse().ok())
                    .unwrap_or(f64::NAN)
            };
            let tp_s = num("locate_s") + num("link_s");
            // Plain numeric columns frame,x_px,y_px,particle: split by hand.
            let text = std::fs::read_to_string(&csv_out)
                .with_context(|| format!("{}", csv_out.display()))?;
            let mut pts = Vec::new();
            for line in text.lines().skip(1) {
                let v: Vec<f64> = line
                    .split(',')
                    .map(|c| c.trim().parse().unwrap_or(f64::NAN))
                    .collect();
                let (f, x, y) = (
                    v.first().copied().unwrap_or(f64::NAN),
                    v.get(1).copied().unwrap_or(f64::NAN),
                    v.get(2).copied().unwrap_or(f64::NAN),
                );
                if f.is_finite() && x.is_finite() && y.is_finite() {
                    pts.push((
                        f as u64,
                        (x + 0.5) * o.um_per_px,
                        (y - axis_row_px) * o.um_per_px,
                    ));
                }
            }
            let (err, matched, _) = centroid_errors(&pts, &truth.rows);
            let (m, p) = quantiles(&err);
            let tp_fps = o.frames as f64 / tp_s;
            println!("| trackpy 0.7 locate+link (1 process) | {tp_fps:.1} | {m:.4} | {p:.4} | {matched}/{visible} |");
            println!(
                "  ({} tracks; frame reading {:.2} s not counted)",
                num("tracks"),
                num("read_s")
            );
            println!(
                "speed ratio rbc-analyze / trackpy (one run): {:.2}",
                ours_fps / tp_fps
            );
        }
        Ok(out) if out.status.code().is_none() => {
            println!(
                "trackpy: stopped after {} s (--trackpy-timeout)",
                o.trackpy_timeout_s
            )
        }
        Ok(out) => println!(
            "trackpy: not run ({})",
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .last()
                .unwrap_or("failed")
        ),
        Err(e) => println!("trackpy: not run ({}: {e})", o.python),
    }
    Ok(())
}
