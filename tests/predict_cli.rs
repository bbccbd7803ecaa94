//! End-to-end tests of the `rbc-predict` binary on a results.h5 written through rbc-schema with a
//! synthetic phase diagram shaped like the paper's Fig. 5 (r_trans = 0.7 um at 6.5 mm/s, croissant-only
//! window 2-3 mm/s, no croissant below 0.25 mm/s), plus malformed inputs.

mod output_common;

use output_common::{files_in, hidden_entries};
use rbc_schema::results::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Simulated velocity columns, mm/s.
const COLUMNS: [f64; 12] = [0.2, 0.5, 1.0, 1.6, 2.2, 2.8, 3.5, 4.5, 5.5, 6.5, 8.0, 10.0];
/// True transition offset of discocyte starts per column (odd multiples of 0.1 um, i.e. midpoints of
/// the 0.2 um offset grid, so that the recovered r_trans equals it exactly); inf = croissant only.
const R_DISCOCYTE: [f64; 12] = [0.0, 0.3, 0.9, 1.3, f64::INFINITY, f64::INFINITY, 1.1, 0.9, 0.7, 0.7, 0.5, 0.5];

/// True r_trans per start shape: croissant starts favour croissants (+0.4 um), slipper starts slippers (-0.2 um).
fn r_true(start: &str, col: usize) -> f64 {
    let r = R_DISCOCYTE[col];
    let shifted = match start {
        "croissant" if col == 0 => 0.3,
        "croissant" => r + 0.4,
        "slipper" => r - 0.2,
        _ => r,
    };
    // an offset below the smallest simulated offset (0.2 um) means no croissant at all
    if shifted < 0.2 {
        0.0
    } else {
        shifted
    }
}

/// True r_trans of the runs as seen 10 mm downstream (their transit records): 0.2 um above the
/// steady one (cells near the switch have not become slippers yet), inf stays inf.
fn r_transit(start: &str, col: usize) -> f64 {
    let r = r_true(start, col);
    if r > 0.0 {
        r + 0.2
    } else {
        r
    }
}

/// Simulated slipper off-centre position, um: from 0.8 rising towards 1.5 (paper Fig. 6a).
fn slipper_y(u: f64) -> f64 {
    0.8 + 0.7 * (1.0 - (-u / 4.0).exp())
}

fn tetra() -> Vec<[u32; 3]> {
    vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
}

/// Write the synthetic sweep: 3 start shapes x 12 columns x 10 offsets (0.2..2.0 um), plus one failed
/// and one still-running run. Mean velocities vary by +-1 % with r_init (alternating, zero mean).
fn write_sims(path: &Path) {
    let mut f = ResultsFile::create_or_open(path).unwrap();
    for start in ["discocyte", "croissant", "slipper"] {
        for (c, &u_col) in COLUMNS.iter().enumerate() {
            let rt = r_true(start, c);
            for k in 0..10 {
                let r = 0.2 * (k + 1) as f64;
                let y0 = r * 9.0 / 106f64.sqrt();
                let attrs = RunAttrs { start_shape: start.into(), r_init_um: r, y_init_um: y0, z_init_um: 5.0 * y0 / 9.0, lambda: 5.0, scene: format!("u = {u_col}\n") };
                let id = format!("{start}_u{u_col}_r{r:.1}");
                let mut w = f.begin_run(&id, &attrs, &tetra()).unwrap();
                w.append_sample(&TimeSample { t_s: 0.0, centroid_um: [0.0, y0, 5.0 * y0 / 9.0], velocity_mm_s: [u_col, 0.0, 0.0], area_um2: 140.0, volume_um3: 100.0, asphericity: 0.2, extents_um: [8.0, 8.0, 2.0] }).unwrap();
                let croissant = r < rt;
                let u = u_col * if k % 2 == 0 { 1.01 } else { 0.99 };
                for (d, label) in [(0.0, FinalShape::Other), (10.0, if r < r_transit(start, c) { FinalShape::Croissant } else { FinalShape::Slipper })] {
                    let t_s = d / u;
                    w.set_transit(&Transit { distance_mm: d, t_s, x_um: d * 1e3, y_um: y0 * 0.9, z_um: 5.0 * y0 / 9.0 * 0.9, velocity_mm_s: u, shape: label, from_steady: false }).unwrap();
                }
                let (shape, spread, y, tt) = if croissant {
                    (FinalShape::Croissant, 0.001, 0.01, false)
                } else {
                    (FinalShape::Slipper, 0.03, slipper_y(u_col) * if k % 2 == 0 { 1.0 } else { -1.0 }, u_col > 0.7)
                };
                w.finish(&RunSummary {
                    status: if croissant { RunStatus::Steady } else { RunStatus::Periodic },
                    final_shape: shape,
                    tank_treading: tt,
                    tumbling: !croissant && !tt,
                    mean_velocity_mm_s: u,
                    min_velocity_mm_s: u * (1.0 - spread),
                    max_velocity_mm_s: u * (1.0 + spread),
                    mean_radial_um: y.abs(),
                    mean_y_um: y,
                    mean_z_um: 0.05,
                    evidence: BTreeMap::new(),
                })
                .unwrap();
            }
        }
    }
    let attrs = RunAttrs { start_shape: "discocyte".into(), r_init_um: 0.1, y_init_um: 0.09, z_init_um: 0.05, lambda: 5.0, scene: String::new() };
    let w = f.begin_run("blew_up", &attrs, &tetra()).unwrap();
    w.fail("inverted triangle 17 at t = 0.2 s").unwrap();
    let mut w = f.begin_run("still_running", &attrs, &tetra()).unwrap();
    w.flush().unwrap();
}

/// Pressure groups: (pressure, velocity at 10 mm, observed croissant fraction).
const GROUPS: [(f64, f64, f64); 6] = [(10.0, 0.15, 0.05), (50.0, 1.0, 0.6), (100.0, 2.5, 0.9), (200.0, 6.5, 0.35), (300.0, 9.5, 0.2), (250.0, 8.0, 0.25)];
/// Entering cells per group, evenly spaced on [-4, 4] um: phi = y_trans / 4 up to 1/N.
const N: usize = 400;

fn write_experiment(dir: &Path) -> (PathBuf, PathBuf) {
    let entry = dir.join("entry.csv");
    let mut s = String::from("pressure_mbar,y_um,velocity_mm_s\n");
    for (p, u, _) in GROUPS {
        for i in 0..N {
            let y = -4.0 + 8.0 * (i as f64 + 0.5) / N as f64;
            // entrance velocities: 0.6 u +- 10 % (alternating), mean exactly 0.6 u
            let v = 0.6 * u * if i % 2 == 0 { 1.1 } else { 0.9 };
            s += &format!("{p},{y},{v}\n");
        }
    }
    std::fs::write(&entry, s).unwrap();
    let summary = dir.join("summary.csv");
    let mut s = String::from("pressure_mbar,position_mm,n_cells,velocity_mean_mm_s,velocity_std_mm_s,frac_croissant,frac_slipper,frac_other\n");
    for (p, u, f) in GROUPS {
        s += &format!("{p},0,{N},{},{},0,0,1\n", 0.6 * u, 0.06 * u);
        s += &format!("{p},10,120,{u},{},{f},{},0\n", 0.1 * u, 1.0 - f);
    }
    std::fs::write(&summary, s).unwrap();
    // slipper-only densities at 10 mm: peaks at -+ (slipper_y(u) - 0.3) (the paper's ~0.3 um systematic gap)
    let mut s = String::from("pressure_mbar,position_mm,shape,y_um,density\n");
    for (p, u, _) in GROUPS {
        let m = slipper_y(u) - 0.3;
        for i in 0..100 {
            let y = -6.0 + 12.0 * i as f64 / 99.0;
            let d = ((-(y - m).powi(2) / 0.08).exp() + (-(y + m).powi(2) / 0.08).exp()) / (2.0 * (0.08 * std::f64::consts::PI).sqrt());
            s += &format!("{p},10,slipper,{y},{d}\n");
            s += &format!("{p},10,all,{y},{}\n", (-(y * y) / 2.0).exp());
        }
    }
    std::fs::write(dir.join("kde.csv"), s).unwrap();
    (entry, summary)
}

/// Tests in this file run one at a time: HDF5 opens files without close-on-exec, so a binary
/// spawned by one test would inherit (and keep locked) a file another test is writing.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

fn rbc_predict(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rbc-predict")).args(args).output().unwrap()
}

fn table(path: &Path) -> Vec<BTreeMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let h = r.headers().unwrap().clone();
    r.records().map(|rec| h.iter().zip(rec.unwrap().iter()).map(|(a, b)| (a.to_string(), b.to_string())).collect()).collect()
}

fn num(row: &BTreeMap<String, String>, col: &str) -> f64 {
    row[col].parse().unwrap_or_else(|_| panic!("{col} = {:?}", row[col]))
}

fn y_of(r: f64) -> f64 {
    r * 9.0 / 106f64.sqrt()
}

/// A temporary folder holding the synthetic sweep (`results.h5`), the experiment's tables and the
/// output folder `pred`; holds the [`serial`] lock for the test's lifetime.
struct Case {
    _guard: std::sync::MutexGuard<'static, ()>,
    dir: tempfile::TempDir,
    sims: PathBuf,
    entry: PathBuf,
    summary: PathBuf,
    out: PathBuf,
}

impl Case {
    fn new() -> Case {
        let _guard = serial();
        let dir = tempfile::tempdir().unwrap();
        let sims = dir.path().join("results.h5");
        write_sims(&sims);
        let (entry, summary) = write_experiment(dir.path());
        let out = dir.path().join("pred");
        Case { _guard, dir, sims, entry, summary, out }
    }

    /// `rbc-predict --sims .. --entry .. [--observed ..] --out ..`
    fn predict(&self, observed: bool) -> Output {
        let mut args: Vec<&std::ffi::OsStr> = vec!["--sims".as_ref(), self.sims.as_os_str(), "--entry".as_ref(), self.entry.as_os_str()];
        if observed {
            args.extend(["--observed".as_ref(), self.summary.as_os_str()]);
        }
        args.extend(["--out".as_ref(), self.out.as_os_str()]);
        rbc_predict(&args)
    }
}

#[test]
fn predicts_the_synthetic_phase_diagram() {
    let case = Case::new();
    let out = &case.out;
    let o = case.predict(true);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("run blew_up skipped: failed (inverted triangle 17"), "{stderr}");
    assert!(stderr.contains("run still_running skipped: still running"), "{stderr}");
    assert!(stderr.contains("10 mbar") && stderr.contains("outside the simulated range"), "0.15 mm/s is below the 0.2 column: {stderr}");

    // thresholds: every column recovered exactly, with the grid's bracket
    let th = table(&out.join("thresholds.csv"));
    assert_eq!(th.len(), 3 * COLUMNS.len());
    for row in &th {
        let start = row["start_shape"].as_str();
        let u = num(row, "velocity_mm_s");
        let c = COLUMNS.iter().position(|&x| (x - u).abs() < 1e-9 * x).unwrap_or_else(|| panic!("column {u}"));
        let rt = r_true(start, c);
        let (r, lo, hi) = (num(row, "r_trans_um"), num(row, "r_lo_um"), num(row, "r_hi_um"));
        if rt.is_infinite() {
            assert_eq!((row["r_trans_um"].as_str(), lo, row["r_hi_um"].as_str()), ("inf", 2.0, "inf"), "{row:?}");
        } else if rt == 0.0 {
            assert_eq!((r, lo, hi), (0.0, 0.0, 0.2), "{row:?}");
        } else {
            assert!((r - rt).abs() < 1e-9 && (lo - (rt - 0.1)).abs() < 1e-9 && (hi - (rt + 0.1)).abs() < 1e-9, "{row:?}");
        }
    }
    let disc65 = th.iter().find(|r| r["start_shape"] == "discocyte" && (num(r, "velocity_mm_s") - 6.5).abs() < 1e-9).unwrap();
    assert!((num(disc65, "r_trans_um") - 0.7).abs() < 1e-9, "the paper's 0.7 um at 6.5 mm/s");

    // predictions
    let pr = table(&out.join("prediction.csv"));
    assert_eq!(pr.len(), 3 * GROUPS.len());
    let get = |start: &str, p: f64| pr.iter().find(|r| r["start_shape"] == start && num(r, "pressure_mbar") == p).unwrap();
    for row in &pr {
        let (phi, lo, hi) = (num(row, "phi"), num(row, "phi_lo"), num(row, "phi_hi"));
        assert!((0.0..=1.0).contains(&lo) && lo <= phi && phi <= hi && hi <= 1.0, "{row:?}");
        let (p, _, f) = GROUPS.iter().copied().find(|g| g.0 == num(row, "pressure_mbar")).unwrap();
        assert_eq!(num(row, "phi_observed"), f, "{p} mbar");
        let yt = num(row, "y_trans_um");
        if yt.is_finite() {
            assert!((phi - yt / 4.0).abs() <= 1.0 / N as f64, "uniform entrance: phi = y_trans / 4: {row:?}");
        }
    }
    // 6.5 mm/s, discocyte: r_trans 0.7; velocity 6.5 +- 0.65 from summary.csv at 10 mm
    let r = get("discocyte", 200.0);
    assert_eq!((num(r, "velocity_mm_s"), num(r, "velocity_std_mm_s")), (6.5, 0.65));
    assert!((num(r, "r_trans_um") - 0.7).abs() < 1e-9 && (num(r, "y_trans_um") - y_of(0.7)).abs() < 1e-9);
    // phi_lo: bracket lower end over [5.85, 7.15] is 0.6 - 0.2 * 0.65 / 1.5 (towards the 8.0 column), minus s_P,
    // then the lower 1-sigma Wilson end; phi_hi: 0.8 + s_P, upper Wilson end
    let wilson = |p: f64, lower: bool| {
        let n = N as f64;
        let c = p + 0.5 / n;
        let h = (p * (1.0 - p) / n + 0.25 / (n * n)).sqrt();
        (if lower { c - h } else { c + h }) / (1.0 + 1.0 / n)
    };
    let lo = wilson((y_of(0.6 - 0.2 * 0.65 / 1.5) - 0.1) / 4.0, true);
    let hi = wilson((y_of(0.8) + 0.1) / 4.0, false);
    assert!((num(r, "phi_lo") - lo).abs() < 2.0 / N as f64 && (num(r, "phi_hi") - hi).abs() < 2.0 / N as f64, "{r:?} {lo} {hi}");
    assert_eq!(r["status"], "bracketed", "{r:?}");
    assert_eq!(get("discocyte", 10.0)["status"], "extrapolated", "0.15 mm/s is below the 0.2 column");
    assert!(!stderr.contains("unbracketed"), "every group here is bracketed or extrapolated: {stderr}");
    // croissant-only window (2.5 +- 0.25 within [2.2, 2.8]): phi = 1 for every start shape
    for s in ["discocyte", "croissant", "slipper"] {
        let r = get(s, 100.0);
        assert_eq!((r["r_trans_um"].as_str(), num(r, "phi"), num(r, "phi_hi")), ("inf", 1.0, 1.0), "{r:?}");
    }
    // below every croissant (0.15 mm/s, nearest column 0.2): discocyte and slipper starts give 0
    assert_eq!(num(get("discocyte", 10.0), "phi"), 0.0);
    assert_eq!(num(get("slipper", 10.0), "phi"), 0.0);
    // start shape order of the bias: croissant starts predict more croissants than discocyte, slipper starts fewer
    for p in [50.0, 200.0, 300.0] {
        let (c, d, s) = (num(get("croissant", p), "phi"), num(get("discocyte", p), "phi"), num(get("slipper", p), "phi"));
        assert!(c > d && d > s, "{p} mbar: {c} {d} {s}");
    }

    // next runs: at 6.5 mm/s the discocyte column's bracket [0.6, 0.8] um leaves the entering
    // cells with y(0.6) < |y| < y(0.8) undecided; on the even entrance their median |y| is the
    // middle of that range, so the run joins the column at the bracket's middle, 0.70 um: the
    // true r_trans
    let next = table(&out.join("next_runs.csv"));
    let n65 = next.iter().find(|r| r["start_shape"] == "discocyte" && num(r, "pressure_mbar") == 200.0).unwrap();
    let undecided = (0..N).map(|i| (-4.0 + 8.0 * (i as f64 + 0.5) / N as f64).abs()).filter(|&y| y > y_of(0.6) && y < y_of(0.8)).count();
    assert!(undecided > 10, "{undecided}");
    assert_eq!((num(n65, "r_init_um"), n65["column"].as_str(), num(n65, "undecided") as usize, num(n65, "cells") as usize), (0.7, "joins", undecided, N), "{n65:?}");
    assert!((num(n65, "velocity_mm_s") - 6.5).abs() < 1e-9 && (num(n65, "r_lo_um") - 0.6).abs() < 1e-9 && (num(n65, "r_hi_um") - 0.8).abs() < 1e-9, "{n65:?}");
    // these scenes have no channel: no mean flow to impose, an empty cell (never a NaN)
    assert_eq!(n65["mean_flow_mm_s"], "");
    assert!(!std::fs::read_to_string(out.join("next_runs.csv")).unwrap().contains("NaN"));
    // 2.5 mm/s lies between the 2.2 and 2.8 columns (more than 5 % from each): a new column, where
    // r_trans is anywhere in [0, inf) until both shapes end there, so every cell is undecided and
    // the run starts at their median |y| (2 um, 2.29 um on the offset line), no farther out than
    // the grid's largest start, 2.0 um; the rows are ordered by undecided cells, most first
    let n25 = next.iter().find(|r| r["start_shape"] == "discocyte" && num(r, "pressure_mbar") == 100.0).unwrap();
    assert_eq!((num(n25, "velocity_mm_s"), num(n25, "r_init_um"), n25["column"].as_str(), n25["r_hi_um"].as_str(), num(n25, "undecided") as usize), (2.5, 2.0, "new", "inf", N), "{n25:?}");
    let counts: Vec<f64> = next.iter().map(|r| num(r, "undecided")).collect();
    assert!(!counts.is_empty() && counts.windows(2).all(|w| w[0] >= w[1]), "{counts:?}");

    // slipper offsets: experiment (y_r - y_l)/2 = slipper_y(u) - 0.3; simulation |y| = slipper_y(u)
    let off = table(&out.join("slipper_offsets.csv"));
    let exp: Vec<_> = off.iter().filter(|r| r["source"] == "experiment").collect();
    assert_eq!(exp.len(), GROUPS.len());
    for r in exp {
        let u = num(r, "velocity_mm_s");
        // peaks 5 sigma apart or more: the other Gaussian's tail moves a peak by < 1e-5 um
        assert!((num(r, "offset_um") - (slipper_y(u) - 0.3)).abs() < 1e-4, "{r:?}");
    }
    let sim: Vec<_> = off.iter().filter(|r| r["source"] == "simulation").collect();
    // tank-treading slippers: columns above 0.7 mm/s outside the croissant-only window (1.0, 1.6, 3.5 ... 10)
    assert_eq!(sim.len(), 8);
    for r in sim {
        let u = num(r, "velocity_mm_s");
        let c = COLUMNS.iter().position(|&x| (x - u).abs() < 0.011 * x).unwrap();
        assert!((num(r, "offset_um") - slipper_y(COLUMNS[c])).abs() < 1e-12 && (num(r, "abs_z_um") - 0.05).abs() < 1e-12, "{r:?}");
    }

    // figures: PNG + SVG each, non-trivial PNGs of the requested size
    for name in ["phase_discocyte", "phase_croissant", "phase_slipper", "phi_discocyte", "phi_croissant", "phi_slipper", "slipper_offset"] {
        let png = out.join("figures").join(format!("{name}.png"));
        let svg = out.join("figures").join(format!("{name}.svg"));
        assert!(svg.exists() && std::fs::metadata(&png).unwrap().len() > 10_000, "{name}");
    }
    // to look at the figures: RBC_PREDICT_KEEP=/some/dir cargo test --test predict_cli
    if let Some(keep) = std::env::var_os("RBC_PREDICT_KEEP") {
        let keep = PathBuf::from(keep);
        std::fs::create_dir_all(keep.join("figures")).unwrap();
        for e in std::fs::read_dir(out.join("figures")).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), keep.join("figures").join(e.file_name())).unwrap();
        }
        for f in ["thresholds.csv", "prediction.csv", "slipper_offsets.csv", "next_runs.csv"] {
            std::fs::copy(out.join(f), keep.join(f)).unwrap();
        }
        std::fs::copy(&case.sims, keep.join("results.h5")).unwrap();
        std::fs::copy(&case.entry, keep.join("entry.csv")).unwrap();
        std::fs::copy(&case.summary, keep.join("summary.csv")).unwrap();
    }
    // nothing else left behind (no temporary files)
    let leftovers: Vec<_> = std::fs::read_dir(out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).filter(|n| n.starts_with('.')).collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// `--transit-mm 10`: the runs as they were 10 mm downstream give their own thresholds (the
/// synthetic ground truth r_transit), written beside the steady ones; a distance no run has
/// travelled is refused with nothing written.
#[test]
fn transit_matched_prediction_beside_the_steady_one() {
    let case = Case::new();
    let out = &case.out;
    let o = rbc_predict(&["--sims".as_ref(), case.sims.as_os_str(), "--entry".as_ref(), case.entry.as_os_str(), "--observed".as_ref(), case.summary.as_os_str(), "--transit-mm".as_ref(), "10".as_ref(), "--out".as_ref(), out.as_os_str()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("run blew_up has no transit record at 10 mm"), "{stderr}");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("steady states:") && stdout.contains("after 10 mm:"), "{stdout}");
    let th = table(&out.join("thresholds_transit_10mm.csv"));
    assert_eq!(th.len(), 3 * COLUMNS.len());
    for row in &th {
        let start = row["start_shape"].as_str();
        let c = COLUMNS.iter().position(|u| (u - num(row, "velocity_mm_s")).abs() < 1e-9).unwrap();
        let rt = r_transit(start, c);
        if rt.is_infinite() {
            assert_eq!(row["r_trans_um"], "inf", "{row:?}");
        } else if rt > 0.0 && rt < 2.0 {
            assert!((num(row, "r_trans_um") - rt).abs() < 1e-9, "{start} {}: {row:?} against {rt}", COLUMNS[c]);
        }
    }
    // steady thresholds unchanged beside them; phi at 10 mm is larger (0.9 against 0.7 um at 6.5 mm/s)
    let steady = table(&out.join("prediction.csv"));
    let at10 = table(&out.join("prediction_transit_10mm.csv"));
    let get = |t: &[BTreeMap<String, String>], p: f64| t.iter().find(|r| r["start_shape"] == "discocyte" && num(r, "pressure_mbar") == p).unwrap().clone();
    assert!((num(&get(&steady, 200.0), "r_trans_um") - 0.7).abs() < 1e-9);
    let r10 = get(&at10, 200.0);
    assert!((num(&r10, "r_trans_um") - 0.9).abs() < 1e-9, "{r10:?}");
    assert!((num(&r10, "phi") - y_of(0.9) / 4.0).abs() <= 1.0 / N as f64, "{r10:?}");
    assert_eq!(num(&r10, "phi_observed"), 0.35, "the observed fraction at 10 mm beside it");

    let out5 = case.dir.path().join("pred5");
    let o = rbc_predict(&["--sims".as_ref(), case.sims.as_os_str(), "--entry".as_ref(), case.entry.as_os_str(), "--transit-mm".as_ref(), "5".as_ref(), "--out".as_ref(), out5.as_os_str()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("--transit-mm 5: no run of") && stderr.contains("has travelled 5 mm yet"), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(!out5.exists(), "nothing written");
}

/// The outputs are replaced as a set: a second run without `--transit-mm` leaves no transit table
/// of the first beside its own, replaces the figure folder as a whole, keeps files that are not
/// rbc-predict's, and leaves no staging folder behind; a refused run changes no byte.
#[test]
fn outputs_are_replaced_as_a_set() {
    let case = Case::new();
    let out = &case.out;
    let base: Vec<&std::ffi::OsStr> = vec!["--sims".as_ref(), case.sims.as_os_str(), "--entry".as_ref(), case.entry.as_os_str(), "--out".as_ref(), out.as_os_str()];
    let o = rbc_predict(&[base.clone(), vec!["--transit-mm".as_ref(), "10".as_ref()]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::write(out.join("figures/stale.png"), "from an older run").unwrap();
    let first = files_in(out);
    assert!(first.contains_key(Path::new("prediction_transit_10mm.csv")));

    // refused late (a row of entry.csv out of range): nothing changes
    let bad = case.dir.path().join("entry_bad.csv");
    let mut text = std::fs::read_to_string(&case.entry).unwrap();
    text.push_str("100,0.5,-3\n");
    std::fs::write(&bad, text).unwrap();
    let o = rbc_predict(&["--sims".as_ref(), case.sims.as_os_str(), "--entry".as_ref(), bad.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    assert!(!o.status.success());
    assert_eq!(files_in(out), first, "a refused run changes nothing");

    let o = rbc_predict(&base);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let second = files_in(out);
    let names: Vec<String> = second.keys().map(|p| p.display().to_string()).filter(|n| !n.starts_with("figures/")).collect();
    assert_eq!(names, ["next_runs.csv", "notes.txt", "prediction.csv", "slipper_offsets.csv", "thresholds.csv"]);
    assert_eq!(second[Path::new("notes.txt")], b"mine");
    assert!(!second.contains_key(Path::new("figures/stale.png")), "the figure folder is replaced as a whole");
    assert!(second.keys().any(|p| p.starts_with("figures") && p.extension().is_some_and(|e| e == "png")));
    assert_eq!(hidden_entries(case.dir.path()), Vec::<String>::new(), "temporary folders left");
}

#[test]
fn without_observed_velocities_come_from_the_entry_table() {
    let case = Case::new();
    let out = &case.out;
    let o = case.predict(false);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let pr = table(&out.join("prediction.csv"));
    for row in &pr {
        let (_, u, _) = GROUPS.iter().copied().find(|g| g.0 == num(row, "pressure_mbar")).unwrap();
        // mean 0.6 u; sample std of +-10 % alternating values: 0.06 u sqrt(N / (N - 1))
        assert!((num(row, "velocity_mm_s") - 0.6 * u).abs() < 1e-9 * u, "{row:?}");
        assert!((num(row, "velocity_std_mm_s") - 0.06 * u * (N as f64 / (N as f64 - 1.0)).sqrt()).abs() < 1e-9 * u, "{row:?}");
        assert_eq!(row["phi_observed"], "", "empty without --observed");
    }
}

/// Run with bad inputs: non-zero exit, a single stderr line containing every `needles`, no output folder.
fn assert_fails(args: &[&std::ffi::OsStr], out: &Path, needles: &[&str]) {
    let o = rbc_predict(args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "should fail: {stderr}");
    let lines: Vec<_> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "one line: {stderr}");
    for n in needles {
        assert!(lines[0].contains(n), "`{n}` missing in: {}", lines[0]);
    }
    assert!(!stderr.contains("panicked"));
    assert!(!out.join("prediction.csv").exists() || std::fs::read_to_string(out.join("prediction.csv")).unwrap() == "old\n");
}

#[test]
fn malformed_inputs_give_one_line_errors_and_no_output() {
    let case = Case::new();
    let Case { dir, sims, entry, summary, out, .. } = &case;
    std::fs::create_dir(out).unwrap();
    std::fs::write(out.join("prediction.csv"), "old\n").unwrap();
    let d = dir.path();
    let args = |s: &Path, e: &Path, extra: &[&Path]| -> Vec<std::ffi::OsString> {
        let mut v: Vec<std::ffi::OsString> = vec!["--sims".into(), s.into(), "--entry".into(), e.into(), "--out".into(), out.clone().into()];
        if let Some(x) = extra.first() {
            v.push("--observed".into());
            v.push(x.into());
        }
        v
    };
    let run = |v: Vec<std::ffi::OsString>, needles: &[&str]| {
        let refs: Vec<&std::ffi::OsStr> = v.iter().map(|s| s.as_os_str()).collect();
        assert_fails(&refs, out, needles);
    };

    // entry.csv without the y_um column
    let e1 = d.join("entry_nocol.csv");
    std::fs::write(&e1, "pressure_mbar,velocity_mm_s\n100,3\n").unwrap();
    run(args(sims, &e1, &[]), &["entry_nocol.csv", "y_um"]);
    // NaN and non-numeric cells, named with their row
    let e2 = d.join("entry_nan.csv");
    std::fs::write(&e2, "pressure_mbar,y_um,velocity_mm_s\n100,0.5,3\n100,NaN,3\n").unwrap();
    run(args(sims, &e2, &[]), &["entry_nan.csv", "row 2", "y_um"]);
    // implausible values (1e155 mm/s hung the plot's axis search; negative velocities passed)
    for (name, row, col) in [("entry_fast.csv", "100,0.5,1e155", "velocity_mm_s"), ("entry_back.csv", "100,0.5,-3", "velocity_mm_s"), ("entry_far.csv", "100,5e4,3", "y_um")] {
        let e = d.join(name);
        std::fs::write(&e, format!("pressure_mbar,y_um,velocity_mm_s\n100,0.5,3\n{row}\n")).unwrap();
        run(args(sims, &e, &[]), &[name, "row 2", col, "plausible range"]);
    }
    // the message shows the value and the range briefly (not 156 digits)
    run(args(sims, &d.join("entry_fast.csv"), &[]), &["1e155 is outside the plausible range (0, 1000] mm/s"]);
    // the observed summary's velocities too, named with their row and column
    for (name, row, col) in [("summary_fast.csv", "100,10,40,1e155,0.5,0.5,0.5,0", "velocity_mean_mm_s"), ("summary_back.csv", "100,10,40,-2.5,0.5,0.5,0.5,0", "velocity_mean_mm_s"), ("summary_spread.csv", "100,10,40,3,-1,0.5,0.5,0", "velocity_std_mm_s")] {
        let f = d.join(name);
        std::fs::write(&f, format!("pressure_mbar,position_mm,n_cells,velocity_mean_mm_s,velocity_std_mm_s,frac_croissant,frac_slipper,frac_other\n{row}\n")).unwrap();
        run(args(sims, entry, &[&f]), &[name, "row 1", col, "plausible range"]);
    }
    // one (pressure, position) group twice, disagreeing: refused naming both rows
    let twice = d.join("summary_twice.csv");
    std::fs::write(&twice, "pressure_mbar,position_mm,n_cells,velocity_mean_mm_s,velocity_std_mm_s,frac_croissant,frac_slipper,frac_other\n100,10,40,3,0.5,0.5,0.5,0\n100,10,40,3,0.5,0.9,0.1,0\n").unwrap();
    run(args(sims, entry, &[&twice]), &["summary_twice.csv", "row 2", "row 1 has it", "100 mbar, 10 mm"]);
    let e3 = d.join("entry_text.csv");
    std::fs::write(&e3, "pressure_mbar,y_um,velocity_mm_s\n100,abc,3\n").unwrap();
    run(args(sims, &e3, &[]), &["entry_text.csv", "row 1", "y_um"]);
    // summary.csv without frac_croissant
    let s1 = d.join("summary_nocol.csv");
    std::fs::write(&s1, "pressure_mbar,position_mm,n_cells,velocity_mean_mm_s,velocity_std_mm_s,frac_slipper,frac_other\n").unwrap();
    run(args(sims, entry, &[&s1]), &["summary_nocol.csv", "frac_croissant"]);
    // results.h5 of an unknown schema version
    let future = d.join("future.h5");
    {
        let f = hdf5::File::create(&future).unwrap();
        f.new_attr::<u32>().shape(()).create("schema_version").unwrap().write_scalar(&99u32).unwrap();
    }
    run(args(&future, entry, &[summary]), &["future.h5", "schema_version 99"]);
    // missing file
    run(args(&d.join("nope.h5"), entry, &[]), &["nope.h5"]);
    // the same runs twice
    let mut twice = args(sims, entry, &[]);
    twice.extend(["--sims".into(), sims.clone().into()]);
    run(twice, &["results.h5", "also occurs in an earlier --sims file"]);
    // only failed / running runs
    let empty = d.join("unfinished.h5");
    {
        let mut f = ResultsFile::create_or_open(&empty).unwrap();
        let attrs = RunAttrs { start_shape: "discocyte".into(), r_init_um: 0.1, y_init_um: 0.09, z_init_um: 0.05, lambda: 5.0, scene: String::new() };
        f.begin_run("x", &attrs, &tetra()).unwrap().fail("diverged").unwrap();
    }
    run(args(&empty, entry, &[]), &["unfinished.h5", "no finished run"]);
    assert_eq!(std::fs::read_to_string(out.join("prediction.csv")).unwrap(), "old\n", "old output untouched");
    assert!(!out.join("thresholds.csv").exists());
}

#[test]
fn without_kde_csv_slipper_densities_come_from_tracks_csv() {
    let case = Case::new();
    let dir = &case.dir;
    std::fs::remove_file(dir.path().join("kde.csv")).unwrap();
    // 200 mbar at 10 mm: 60 isolated slippers in two symmetric clusters at -+0.9 um (+-0.15), 40 croissants at 0
    let track = |i: usize, y: f64, shape: &str| rbc_schema::tables::TrackRow {
        recording: "r200".into(), pressure_mbar: 200.0, position_mm: 10.0, track_id: i as u64, n_frames: 20, x_first_um: 0.0,
        y_mean_um: y, y_std_um: 0.05, velocity_mm_s: 6.5, velocity_se_mm_s: 0.01, isolated: true, gap_um: 80.0,
        shape: shape.into(), shape_score: 0.0, p_croissant: None,
    };
    let mut rows: Vec<_> = (0..60).map(|i| track(i, if i % 2 == 0 { 1.0 } else { -1.0 } * (0.9 + 0.15 * ((i / 2) as f64 / 29.0 * 2.0 - 1.0)), "slipper")).collect();
    rows.extend((60..100).map(|i| track(i, 0.0, "croissant")));
    rbc_schema::tables::write_table(&dir.path().join("tracks.csv"), &rows, rbc_schema::tables::columns::TRACKS).unwrap();
    let out = &case.out;
    let o = case.predict(true);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && stderr.contains("tracks.csv"), "{stderr}");
    let exp: Vec<_> = table(&out.join("slipper_offsets.csv")).into_iter().filter(|r| r["source"] == "experiment").collect();
    assert_eq!(exp.len(), 1, "only 200 mbar has slippers");
    // symmetric clusters: peaks symmetric, within the clusters' +-0.15 um
    let (l, r) = (num(&exp[0], "y_l_um"), num(&exp[0], "y_r_um"));
    assert!((l + r).abs() < 1e-6 && (num(&exp[0], "offset_um") - 0.9).abs() < 0.15, "{:?}", exp[0]);
    assert_eq!(num(&exp[0], "velocity_mm_s"), 6.5);
}
