//! Closed loop on shapes our solver produced: snapshots of free-space Poiseuille runs, each labelled by the solver's own 3D classifier, rendered in bright field and classified by the analysis.
//!
//! The fixture `fixtures/closedloop/solver_shapes.h5` holds one run per labelled shape:
//! the last snapshot of a 10 ms window (50 output samples, 0.2 ms apart) of a
//! simulation (windows ending every 20 ms and at the end of the run), with the label that `rbc_solver::classify` gives that window (the same
//! classifier and default thresholds that label a run's steady state) and the mean
//! velocity over the window. It was written by the ignored test below from the sweeps
//! `fixtures/closedloop/closedloop-sweep-l2.toml` (level 2, 128 triangles) and
//! `closedloop-sweep.toml` (level 3, 512 triangles; stopped after 14-30 ms of the 40 ms
//! for lack of time on this machine, read from its partial per-run files):
//!
//! ```text
//! cd analysis/tests/fixtures/closedloop
//! nice -n 10 rbc-sweep closedloop-sweep-l2.toml --out /tmp/sweep-l2.h5 --jobs 2
//! nice -n 10 rbc-sweep closedloop-sweep.toml --out /tmp/sweep.h5 --jobs 2
//! CLOSEDLOOP_RESULTS=/tmp/sweep-l2.h5,/tmp/sweep.h5 \
//!   cargo test -p rbc-analysis --test closedloop_solver write_fixture -- --ignored --nocapture
//! ```
//!
//! The same loop on any results.h5 (e.g. channel runs): `rbc-synth --closed-loop results.h5 --out DIR`.

use rbc_analysis::simulated::closedloop::{closed_loop, Agreement, LoopConfig, LoopRow};
use rbc_analysis::experiment::isolate::IsolationConfig;
use rbc_schema::results::{read_runs, read_snapshots, FinalShape, ResultsFile, RunStatus, RunSummary};
use rbc_solver::classify::{classify, volume_centroid, ClassifyConfig, Frame};
use std::path::{Path, PathBuf};

const FIXTURE: &str = "tests/fixtures/closedloop/solver_shapes.h5";
/// Output samples per classification window (10 ms at 0.2 ms).
const WINDOW: usize = 50;

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(FIXTURE)
}

fn run_loop(cfg: &LoopConfig) -> Vec<LoopRow> {
    let dir = tempfile::tempdir().unwrap();
    let (rows, skipped) = closed_loop(&fixture(), dir.path(), cfg).unwrap();
    assert!(skipped.is_empty(), "every fixture run is labelled: {skipped:?}");
    rows
}

/// `cargo test -p rbc-analysis --test closedloop_solver -- --nocapture` (about 10 s).
#[test]
fn analysis_agrees_with_the_solver_on_its_own_shapes() {
    let rows = run_loop(&LoopConfig::default());
    for r in &rows {
        println!(
            "{:24} solver {:9} pipeline {:9} classifier {:9} cluster {:5} y {:+.2} um asymmetry {:.3} solidity {:.3} notch {:.3} waist {:.3}",
            r.run_id, r.solver, r.pipeline, r.classifier, r.cluster, r.y_um, r.asymmetry, r.solidity, r.notch, r.waist
        );
    }
    let pipeline = Agreement::pipeline(&rows);
    let alone = Agreement::classifier(&rows);
    println!("\n{}", pipeline.render("rbc-analyze pipeline vs solver"));
    println!("{}", alone.render("shape classifier alone vs solver"));
    // the fixture's labels (written by write_fixture below)
    let n = |r| pipeline.class(r).1;
    assert_eq!([n(0), n(1), n(2)], EXPECTED_SOLVER, "solver labels in the fixture");
    // at most one single simulated cell is taken for merged touching cells: measured 1 of 24
    // (l2_discocyte_u6_r3.5_t20ms, whose in-focus section is pinched on both sides: waist
    // 0.23, notch 0.32-0.35; flagged with every seed tried); the rule before the notch/waist
    // evidence flagged 6 (old_cluster_rule_flags_six_single_cells_the_notch_rule_keeps)
    let clusters: Vec<&str> = rows.iter().filter(|r| r.cluster).map(|r| r.run_id.as_str()).collect();
    assert!(clusters.len() <= 1, "single cells flagged as clusters: {clusters:?}");
    for (k, min) in MIN_AGREEING.iter().enumerate() {
        assert!(pipeline.class(k).0 >= *min, "class {}: {}", k, pipeline.render("pipeline"));
    }
    assert!(pipeline.agreeing().0 >= 18 && alone.agreeing().0 >= 18, "{}", pipeline.render("pipeline"));
}

/// The fixture's solver labels (croissant, slipper, other): 24 shapes from the 12 level-2
/// runs and one level-3 run.
const EXPECTED_SOLVER: [usize; 3] = [7, 2, 15];
/// Agreeing cells per class required of the pipeline. Measured (seeded, deterministic; the
/// same with the noise seeds 100, 200, 300, 400 of `rbc-synth --closed-loop`):
/// croissant 6/7, slipper 2/2, other 12/15, in all 20/24, the classifier alone the same; a
/// margin of one cell for the croissants and the others. The disagreements: 3 off-centre,
/// asymmetric transients that do not (yet) tank-tread are `other` for the solver and
/// `slipper` from above (a top view cannot see the membrane's motion), and the level-3
/// croissant at 15 ms, still asymmetric in projection (0.21), is `other`.
const MIN_AGREEING: [usize; 3] = [5, 2, 11];

/// Writes the fixture from the runs of the results files in `CLOSEDLOOP_RESULTS` (comma
/// separated): for every run, windows of [`WINDOW`] snapshots ending every 20 ms and at the
/// run's end, each classified by the solver's classifier; the window's last snapshot is stored.
#[test]
#[ignore]
fn write_fixture() {
    let sources = std::env::var("CLOSEDLOOP_RESULTS").expect("set CLOSEDLOOP_RESULTS=a.h5,b.h5");
    let out = fixture();
    let _ = std::fs::remove_file(&out);
    let mut f = ResultsFile::create_or_open(&out).unwrap();
    let cfg = ClassifyConfig::default();
    for src in sources.split(',') {
        let src = Path::new(src);
        for run in read_runs(src).unwrap() {
            let Some(attrs) = run.attrs.clone() else { continue };
            let snaps = read_snapshots(src, &run.run_id).unwrap();
            let tri: Vec<[usize; 3]> = snaps.triangles.iter().map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
            let n = snaps.vertices_um.len();
            // windows ending every 20 ms, and the run's last full window when it does not
            // overlap the previous one (a run cut short)
            let mut ends: Vec<usize> = (1..).map(|k| 2 * k * WINDOW - 1).take_while(|&e| e < n).collect();
            if n >= WINDOW && ends.last().is_none_or(|&l| n > l + WINDOW) {
                ends.push(n - 1);
            }
            for end in ends {
                let w = (end + 1 - WINDOW)..=end;
                let frames: Vec<Frame> = w.clone().map(|k| Frame { t_s: snaps.times_s[k], vertices: &snaps.vertices_um[k] }).collect();
                let c = classify(&frames, &tri, &cfg).unwrap();
                let (_, c0) = volume_centroid(&snaps.vertices_um[*w.start()], &tri);
                let (_, c1) = volume_centroid(&snaps.vertices_um[end], &tri);
                let dt = snaps.times_s[end] - snaps.times_s[*w.start()];
                let ev = &c.evidence;
                // mesh level from the triangle count (8 4^level) keeps level 2 and 3 runs apart
                let level = (tri.len() as f64 / 8.0).log(4.0).round();
                let id = format!("l{level}_{}_t{:.0}ms", run.run_id, 1000.0 * snaps.times_s[end]);
                println!("{id}: {} (tank-treading {}, offset {:.2} um)", c.shape.as_str(), c.tank_treading, ev.offset_r_um);
                let mut wr = f.begin_run(&id, &attrs, &snaps.triangles).unwrap();
                wr.append_snapshot(snaps.times_s[end], &snaps.vertices_um[end]).unwrap();
                let v = (c1[0] - c0[0]) / dt / 1000.0;
                wr.finish(&RunSummary {
                    status: RunStatus::Unsteady,
                    final_shape: c.shape,
                    tank_treading: c.tank_treading,
                    tumbling: c.tumbling,
                    mean_velocity_mm_s: v,
                    min_velocity_mm_s: v,
                    max_velocity_mm_s: v,
                    mean_radial_um: ev.offset_r_um,
                    mean_y_um: ev.offset_y_um,
                    mean_z_um: ev.offset_z_um,
                    evidence: Default::default(),
                })
                .unwrap();
            }
        }
    }
    // what was written reads back with the labels the loop test expects of the fixture
    drop(f);
    let labels: Vec<FinalShape> = read_runs(&out).unwrap().iter().filter_map(|r| r.summary.as_ref().map(|s| s.final_shape)).collect();
    let count = |shape| labels.iter().filter(|&&l| l == shape).count();
    assert_eq!([count(FinalShape::Croissant), count(FinalShape::Slipper), count(FinalShape::Other)], EXPECTED_SOLVER, "the solver's labels of the windows written");
}

/// The loop with the cluster rule as it was before the notch/waist evidence (asymmetric and
/// solidity < 0.88 = merged cells): how many solver shapes it would have thrown out.
/// Measured: 6 of 24 flagged (not isolated, left out of every statistic), against at most 1
/// with the notch/waist evidence; the labels agree as often (20/24) because the 6 are solver
/// `other` and a cluster is reported `other`. Asserted (it passed in the suite of 2026-11-25:
/// 6 flagged, all solver `other`); ignored because it repeats the whole loop for a rule no
/// longer used (as long as `analysis_agrees_with_the_solver_on_its_own_shapes`: 10 s unloaded,
/// 90 s beside other builds).
/// `cargo nextest run -p rbc-analysis --run-ignored only -E 'test(old_cluster_rule)'`
#[test]
#[ignore = "study: the cluster rule before the notch/waist evidence, asserted"]
fn old_cluster_rule_flags_six_single_cells_the_notch_rule_keeps() {
    let mut cfg = LoopConfig::default();
    cfg.stages.isolation = IsolationConfig { cluster_min_notch: 0.0, ..IsolationConfig::default() };
    let rows = run_loop(&cfg);
    let pipeline = Agreement::pipeline(&rows);
    println!("{}", pipeline.render("pipeline, old cluster rule"));
    let clusters: Vec<&LoopRow> = rows.iter().filter(|r| r.cluster).collect();
    println!("clusters: {}", clusters.len());
    assert_eq!(clusters.len(), 6, "single cells flagged by the old rule: {:?}", clusters.iter().map(|r| &r.run_id).collect::<Vec<_>>());
    assert!(clusters.iter().all(|r| r.solver == "other"), "the flagged cells are solver `other`");
    assert!(pipeline.agreeing().0 >= 18, "{}", pipeline.render("pipeline, old cluster rule"));
}
