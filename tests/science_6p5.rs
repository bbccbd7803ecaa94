//! The paper's shape bistability at ~6.5 mm/s: the committed runs of the study `examples/studies/science-6p5/` checked by default (issue 12), and an ignored study that runs (or reads) `examples/sweeps/science-6p5.toml` whole (issue 4, item 8).
//!
//! Guckenberger et al. (Fig. 4 and 5a): a discocyte started at ~6.5 mm/s ends as a centred
//! croissant when its initial offset `r_init` (along `z = 5 y / 9`) is below ~0.7 um, and as an
//! off-centre tank-treading slipper (steady offset 0.8 to 1.5 um, mostly along y) above it. The
//! sweep runs `r_init` = 0.4 and 1.2 um with the paper's 2048-triangle cell, lambda = 5 and
//! Krueger's Skalak convention (`examples/sweeps/science-6p5-scene.toml`).
//!
//! Cost: the paper's runs need 2 to 30 s of physical time (1 to 29 days per run on 28 cores in the
//! paper); ours 10-12 core-s per simulated ms late in a run (the study's ledger; README,
//! "Measured"), i.e. core-hours to days per run: run it where there are cores, e.g.
//!
//! ```text
//! rbc-sweep examples/sweeps/science-6p5.toml --slurm science      # then sbatch science/submit.sh
//! RBC_SCIENCE_RESULTS=science/results.h5 cargo test --test science_6p5 -- --ignored --nocapture
//! ```
//!
//! or locally (resumes from its checkpoints when run again; the results stay in
//! `target/tmp/science-6p5/`):
//!
//! ```text
//! nice cargo test --release --test science_6p5 -- --ignored --nocapture
//! ```

use rbc::sweep::stored_shapes::StoredShapes;
use rbc_analysis::simulated::orbit_events::{length_collapses, DEFAULT_FRACTION};
use rbc_schema::results::{read_runs, FinalShape, RunRecord};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The finished run started at `r_init` (um).
fn run_at(runs: &[RunRecord], r_init: f64) -> &RunRecord {
    runs.iter()
        .find(|r| r.attrs.as_ref().is_some_and(|a| (a.r_init_um - r_init).abs() < 1e-9))
        .unwrap_or_else(|| panic!("no run with r_init = {r_init} um"))
}

/// The study's (science-6p5, exact walls) ended run started at `r_init` (um): [`ended_run_of`].
fn ended_run(run_id: &str, r_init: f64) -> (PathBuf, RunRecord, rbc_schema::results::RunSummary) {
    ended_run_of("science-6p5", run_id, r_init)
}

/// The ended run `run_id` started at `r_init` (um) of study `study` from its state file
/// `examples/studies/STUDY/state/RUN.h5`: the file, the run and its summary (printed).
fn ended_run_of(study: &str, run_id: &str, r_init: f64) -> (PathBuf, RunRecord, rbc_schema::results::RunSummary) {
    let state = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/studies/{study}/state/{run_id}.h5"));
    let run = run_at(&read_runs(&state).unwrap(), r_init).clone();
    let s = run.summary.clone().unwrap_or_else(|| panic!("the r_init = {r_init} um run of study {study} has ended"));
    eprintln!("{} {} (tt {}), radial {:.3} um (y {:.3}, z {:.3}), u {:.2} mm/s, evidence {:?}", s.status.as_str(), s.final_shape.as_str(), s.tank_treading, s.mean_radial_um, s.mean_y_um, s.mean_z_um, s.mean_velocity_mm_s, s.evidence);
    (state, run, s)
}

/// The ended run `run_id` (started at `r_init` um), which ended as `shape` (the other side of a
/// switch: `why` says which).
fn ended_as(run_id: &str, r_init: f64, shape: FinalShape, why: &str) -> rbc_schema::results::RunSummary {
    let (_, _, s) = ended_run(run_id, r_init);
    assert_eq!(s.final_shape, shape, "{run_id}: {why}");
    s
}

/// A run that ended as the off-centre slipper of the ~6.3 mm/s column: `periodic` over the
/// study's 0.5 s window, no tumbling, 0.8-1.7 um off the axis mostly along y, at ~6.5 mm/s.
fn assert_off_centre_slipper(s: &rbc_schema::results::RunSummary) {
    assert_off_centre_slipper_at(s, 5.5..=7.5);
}

/// The ended run `run_id` (started at `r_init` um): an off-centre slipper at a cell velocity in
/// `mm_s` ([`assert_off_centre_slipper_at`]) that tank-treads.
fn ended_tank_treading_slipper(run_id: &str, r_init: f64, mm_s: std::ops::RangeInclusive<f64>) -> (PathBuf, RunRecord, rbc_schema::results::RunSummary) {
    let (state, run, s) = ended_run(run_id, r_init);
    assert_off_centre_slipper_at(&s, mm_s);
    assert!(s.tank_treading, "a tank-treading slipper");
    (state, run, s)
}

/// [`assert_off_centre_slipper`] at a cell velocity in `mm_s`.
fn assert_off_centre_slipper_at(s: &rbc_schema::results::RunSummary, mm_s: std::ops::RangeInclusive<f64>) {
    assert_eq!((s.status.as_str(), s.final_shape, s.tumbling), ("periodic", FinalShape::Slipper, false));
    assert!(s.evidence["steady_duration_s"] >= 0.5 - 1e-9, "the study's 0.5 s window");
    assert!((0.8..=1.7).contains(&s.mean_radial_um), "off-centre: {} um", s.mean_radial_um);
    assert!(s.mean_z_um.abs() < 0.1 * s.mean_y_um.abs(), "mostly along y: y {} z {}", s.mean_y_um, s.mean_z_um);
    assert!(mm_s.contains(&s.mean_velocity_mm_s), "cell velocity {} mm/s is not in {mm_s:?}", s.mean_velocity_mm_s);
}

/// A run that ended as the centred croissant of the ~6.3 mm/s column: `periodic` over the study's
/// 0.5 s window, centred (radial offset below 0.4 um, the paper's Fig. 5a "almost centered"),
/// nearly a rigid body (its non-rigid membrane speed under 2 % of the cell's) whose membrane
/// still circulates at 2-3 Hz, a tank-treading croissant (the flag since session 51, when
/// `min_tt_turns` went from 0.25 to 0.1 turn: the paper's tank-treading croissants, which it sees
/// above ~7 mm/s), not tumbling, at ~6.5 mm/s.
fn assert_centred_tank_treading_croissant(s: &rbc_schema::results::RunSummary) {
    assert_eq!((s.status.as_str(), s.final_shape, s.tank_treading, s.tumbling), ("periodic", FinalShape::Croissant, true, false));
    assert!(s.evidence["steady_duration_s"] >= 0.5 - 1e-9, "the study's 0.5 s window");
    assert!(s.mean_radial_um < 0.4 && s.evidence["radial_max_um"] < 0.41, "centred: {} um", s.mean_radial_um);
    assert!(s.evidence["nonrigid_ratio"] < 0.02, "nearly a rigid body: {}", s.evidence["nonrigid_ratio"]);
    assert!((2.0..3.0).contains(&s.evidence["tt_frequency_hz"]), "tank-treading at {} Hz", s.evidence["tt_frequency_hz"]);
    assert!((5.5..=7.5).contains(&s.mean_velocity_mm_s), "cell velocity {} mm/s", s.mean_velocity_mm_s);
}

/// A run that ended as a centred croissant moving as a rigid body ("a croissant shape (which moves
/// as a rigid body)": its non-rigid membrane speed under 2 % of the cell's), neither tank-treading
/// nor tumbling, centred (radial offset below 0.4 um), over the study's 0.5 s window, that ended `status` (`steady` or `periodic`) at a
/// cell velocity in `mm_s`.
fn assert_centred_rigid_croissant_at(s: &rbc_schema::results::RunSummary, status: &str, mm_s: std::ops::RangeInclusive<f64>) {
    assert_eq!((s.status.as_str(), s.final_shape, s.tank_treading, s.tumbling), (status, FinalShape::Croissant, false, false));
    assert!(s.evidence["steady_duration_s"] >= 0.5 - 1e-9, "the study's 0.5 s window");
    assert!(s.mean_radial_um < 0.4 && s.evidence["radial_max_um"] < 0.4, "centred: {} um", s.mean_radial_um);
    assert!(s.evidence["nonrigid_ratio"] < 0.02, "a rigid body: {}", s.evidence["nonrigid_ratio"]);
    assert!(mm_s.contains(&s.mean_velocity_mm_s), "cell velocity {} mm/s is not in {mm_s:?}", s.mean_velocity_mm_s);
}

/// The closed loop (`rbc-synth --closed-loop`) of a study's state file: its last shape rendered
/// as a bright-field recording (by the synthesiser, or with `wave` by the wave-optics renderer)
/// and analysed by `rbc-analyze`; the one row it gives (printed), whose shape the pipeline and
/// its image classifier both call `label`.
fn closed_loop_row(state: &Path, wave: bool, label: &str) -> rbc_analysis::simulated::closedloop::LoopRow {
    use rbc_analysis::simulated::closedloop::{closed_loop, LoopConfig};
    let dir = tempfile::tempdir().unwrap();
    let cfg = LoopConfig { wave: wave.then(Default::default), ..Default::default() };
    let (mut rows, skipped) = closed_loop(state, dir.path(), &cfg).unwrap();
    assert!(skipped.is_empty() && rows.len() == 1, "{skipped:?}");
    let row = rows.remove(0);
    eprintln!("closed loop (wave optics: {wave}): {row:?}");
    assert_eq!((row.pipeline.as_str(), row.classifier.as_str()), (label, label), "{row:?}");
    row
}

#[test]
#[ignore = "days of compute: see the module docs for the commands"]
fn discocyte_at_6p5_mm_s_ends_as_croissant_or_slipper_by_its_initial_offset() {
    let results = match std::env::var_os("RBC_SCIENCE_RESULTS") {
        Some(p) => PathBuf::from(p),
        None => {
            let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("science-6p5");
            std::fs::create_dir_all(&dir).unwrap();
            let sweep = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sweeps/science-6p5.toml");
            let out = dir.join("science.h5");
            let status = Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
                .arg(&sweep)
                .arg("--out")
                .arg(&out)
                .args(["--jobs", "2"])
                .status()
                .unwrap();
            assert!(status.success(), "rbc-sweep failed: {status}");
            out
        }
    };
    let runs = read_runs(&results).unwrap();
    for r in &runs {
        let a = r.attrs.as_ref().unwrap();
        match &r.summary {
            Some(s) => eprintln!(
                "r_init {:.2} um: {} {} (tank-treading {}), u = {:.2} mm/s, radial {:.3} um (y {:.3}, z {:.3})",
                a.r_init_um,
                s.status.as_str(),
                s.final_shape.as_str(),
                s.tank_treading,
                s.mean_velocity_mm_s,
                s.mean_radial_um,
                s.mean_y_um,
                s.mean_z_um
            ),
            None => eprintln!("r_init {:.2} um: {} {}", a.r_init_um, r.status.as_str(), r.failure.as_deref().unwrap_or("")),
        }
    }
    let small = run_at(&runs, 0.4).summary.as_ref().expect("the r_init = 0.4 um run has finished");
    let large = run_at(&runs, 1.2).summary.as_ref().expect("the r_init = 1.2 um run has finished");
    for s in [small, large] {
        assert!(matches!(s.status.as_str(), "steady" | "periodic"), "ended {}", s.status.as_str());
        assert!((5.5..=7.5).contains(&s.mean_velocity_mm_s), "cell velocity {} mm/s is not ~6.5", s.mean_velocity_mm_s);
    }
    // Small offset: a centred croissant.
    assert_eq!(small.final_shape, FinalShape::Croissant);
    assert!(small.mean_radial_um < 0.4, "croissant at {} um", small.mean_radial_um);
    // Large offset: an off-centre tank-treading slipper, displaced mostly along y.
    assert_eq!(large.final_shape, FinalShape::Slipper);
    assert!(large.tank_treading);
    assert!((0.8..=1.5).contains(&large.mean_radial_um), "slipper at {} um", large.mean_radial_um);
    assert!(large.mean_y_um.abs() > large.mean_z_um.abs(), "slipper displaced along z");
}

/// The study's committed result (issue 12, item 5), checked by default: the r_init = 0.4 um run of
/// `examples/studies/science-6p5/` (the paper's scene, 2048 triangles, lambda 5, exact walls),
/// which ended `periodic` at 1303.2 ms, is the paper's centred croissant: centred (radial offset
/// below 0.4 um, the paper's Fig. 5a "almost centered"), nearly a rigid body (its non-rigid
/// membrane speed under 2 % of the cell's) whose membrane circulates at 2.28 Hz: a
/// tank-treading croissant since session 51 (`assert_centred_tank_treading_croissant`), at the
/// paper's ~6.5 mm/s; and its transit record at 10 mm (the
/// experiments' window; it ended at 8.4 mm) is its steady state carried there; rendered and
/// analysed as an experiment would see it, it is a centred croissant too.
#[test]
fn the_studys_r_init_0p4_run_ended_a_centred_tank_treading_croissant() {
    let (state, run, s) = ended_run("discocyte_u3.8_r0.4", 0.4);
    assert_centred_tank_treading_croissant(&s);
    let ten = run.transits.iter().find(|t| t.distance_mm == 10.0).expect("a 10 mm transit record");
    assert!(ten.from_steady && ten.shape == FinalShape::Croissant && (1.5..1.6).contains(&ten.t_s), "{ten:?}");
    // the closed loop (`rbc-synth --closed-loop`): its last shape rendered as a bright-field
    // recording and analysed by rbc-analyze is a croissant there too, on the axis (measured
    // 2026-11-25: pipeline and classifier croissant, y +0.017 um)
    let row = closed_loop_row(&state, false, "croissant");
    assert!(row.y_um.abs() < 0.1, "the analysis sees it centred: {row:?}");
    // and drawn by the wave-optics renderer instead (`rbc-synth --closed-loop ... --renderer wave`:
    // the mesh's thickness as a thin phase-and-amplitude object, 1 um above focus, NA 0.8), which
    // shares no image formation with the one rbc-analyze was tuned on: a centred croissant too
    // (measured 2026-11-26: y +0.025 um)
    let row = closed_loop_row(&state, true, "croissant");
    assert!(row.y_um.abs() < 0.1, "the analysis sees it centred: {row:?}");
}

/// The study's r_init = 1.2 um run (issue 12, item 5): ended `periodic` at 998.6 ms over the
/// study's 0.5 s window (orbit period 49 ms, radial offset 1.44-1.72 um), an off-centre
/// tank-treading slipper: its mean offset lies along y (y 1.570, z 0.004 um), the membrane turns
/// about z (8.7 Hz), it does not tumble, at 6.28 mm/s. The paper's slippers sit 0.8 to 1.5 um off
/// the axis; this one sits 0.07 um beyond that range (mean radial 1.571 um; measured 2026-11-26),
/// so the bound below is 1.6 um and the excess is reported, not hidden. Its transit record at
/// 10 mm is its steady state carried there (it ended at 6.2 mm), and rendered and analysed as an
/// experiment would see it (both renderers: the synthesiser's 3D one and wave optics) it is an
/// off-centre slipper for `rbc-analyze` too (measured y 1.76 and 1.69 um from its last shape).
#[test]
fn the_studys_r_init_1p2_run_ended_an_off_centre_tank_treading_slipper() {
    let (state, run, s) = ended_run("discocyte_u3.8_r1.2", 1.2);
    assert_eq!((s.status.as_str(), s.final_shape, s.tank_treading, s.tumbling), ("periodic", FinalShape::Slipper, true, false));
    assert!(s.evidence["steady_duration_s"] >= 0.5 - 1e-9, "the study's 0.5 s window");
    assert!((0.8..=1.6).contains(&s.mean_radial_um), "off-centre as the paper's slippers (0.8-1.5 um): {} um", s.mean_radial_um);
    if s.mean_radial_um > 1.5 {
        eprintln!("note: mean offset {:.3} um, {:.3} um beyond the paper's 1.5 um", s.mean_radial_um, s.mean_radial_um - 1.5);
    }
    assert!(s.mean_z_um.abs() < 0.1 * s.mean_y_um.abs(), "mostly along y: y {} z {}", s.mean_y_um, s.mean_z_um);
    assert!(s.evidence["tt_axis_z"].abs() > 0.99, "the membrane turns about z (the vorticity of the y-offset flow)");
    assert!((5.5..=7.5).contains(&s.mean_velocity_mm_s), "cell velocity {} mm/s is not ~6.5", s.mean_velocity_mm_s);
    let ten = run.transits.iter().find(|t| t.distance_mm == 10.0).expect("a 10 mm transit record");
    assert!(ten.from_steady && ten.shape == FinalShape::Slipper && (1.5..1.7).contains(&ten.t_s), "{ten:?}");
    // the closed loop through both renderers
    for wave in [false, true] {
        let row = closed_loop_row(&state, wave, "slipper");
        assert!((1.2..=2.0).contains(&row.y_um.abs()), "the analysis sees it off-centre: {row:?}");
    }
}

/// The study's r_init = 0.6 um run: ended `periodic` at 852.2 ms (session 14) over the study's
/// 0.5 s window (orbit period 98 ms, radial offset 1.43-1.70 um), an off-centre tank-treading
/// slipper like the r_init = 1.2 um run (mean y 1.559, z 0.034 um; the membrane turns about z at
/// 8.3 Hz; 6.28 mm/s; measured 2026-11-26), not the paper's croissant: in this model
/// the switch from croissants to slippers at ~6.4 mm/s lies between r_init 0.4 and 0.6 um,
/// below the paper's ~0.7 um (its Fig. 4). Rendered and analysed as an experiment would see it,
/// it is an off-centre slipper for `rbc-analyze` too.
#[test]
fn the_studys_r_init_0p6_run_ended_an_off_centre_slipper() {
    let (state, _, s) = ended_run("discocyte_u3.8_r0.6", 0.6);
    assert_off_centre_slipper(&s);
    assert!(s.tank_treading, "a tank-treading slipper");
    closed_loop_row(&state, false, "slipper");
}

/// The study's r_init = 0.8 um run: ended `periodic` at 773.8 ms (session 14), an off-centre
/// tank-treading slipper as well (mean y 1.559, z 0.036 um, 6.28 mm/s; measured 2026-11-26):
/// every start at or above 0.6 um has become a slipper. Rendered and analysed as an experiment
/// would see it, `rbc-analyze` calls it a slipper too (y 1.71 um; session 22).
#[test]
fn the_studys_r_init_0p8_run_ended_an_off_centre_slipper() {
    let (state, _, s) = ended_run("discocyte_u3.8_r0.8", 0.8);
    assert_off_centre_slipper(&s);
    closed_loop_row(&state, false, "slipper");
}

/// `examples/results.h5`, which the README's `rbc-predict` example reads, is the study's ended
/// runs merged (issue 12, item 5): one run for each ended run in `state/` and no other, each with
/// the same summary, transit records, samples and snapshots as its state file. Stale when a run
/// has ended (or been reopened) since: `bash scripts/examples.sh results` merges them again.
#[test]
fn the_shipped_results_are_the_studys_ended_runs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut ended: Vec<RunRecord> = state_files("science-6p5").iter().flat_map(|f| read_runs(f).unwrap().into_iter().filter(|r| r.summary.is_some())).collect();
    ended.sort_by(|a, b| a.run_id.cmp(&b.run_id));
    assert!(ended.len() >= 2, "the study's first two runs have ended");
    let mut shipped = read_runs(&root.join("examples/results.h5")).unwrap();
    shipped.sort_by(|a, b| a.run_id.cmp(&b.run_id));
    let ids = |r: &[RunRecord]| r.iter().map(|r| r.run_id.clone()).collect::<Vec<_>>();
    let regenerate = "regenerate with `bash scripts/examples.sh results`";
    assert_eq!(ids(&shipped), ids(&ended), "examples/results.h5 holds other runs than the study's ended ones: {regenerate}");
    for (a, b) in shipped.iter().zip(&ended) {
        assert_eq!(a.summary, b.summary, "{}: another summary in examples/results.h5: {regenerate}", a.run_id);
        assert_eq!(a.transits, b.transits, "{}: other transit records: {regenerate}", a.run_id);
        assert_eq!((a.n_samples, a.n_snapshots), (b.n_samples, b.n_snapshots), "{}: other samples or snapshots: {regenerate}", a.run_id);
    }
}

/// The study's r_init = 0.4 um run at ~2.5 mm/s (session 15), in the paper's croissant-only
/// window: ended `steady` at 1460.2 ms over the study's 0.5 s window, a compact shape (extents
/// 6.5 x 6.8 x 6.3 um) centred at r 0.18 um and moving as a rigid body at 2.50 mm/s (its membrane
/// moves at 6e-5 of its speed), neither tank-treading nor tumbling: the paper's croissant, the
/// centred shape "which moves as a rigid body". Its most nearly symmetric plane containing the
/// flow axis (turned 16 degrees from the x-y plane) leaves 0.0506 R_eff, just beyond the mirror
/// test's bound of 0.05, so it was labelled `other` until session 21, when the classifier took
/// the paper's definition (a centred rigid body is a croissant whatever its mirror asymmetry;
/// `rigid_rel` 1e-3, measured 2026-11-27). Rendered and analysed as an experiment would see it,
/// it is a croissant for `rbc-analyze` too: centred (y 0.10 um), with a mirror asymmetry of
/// 0.1096 on the track's median mask, just below the image rule's 0.11.
#[test]
fn the_studys_u1p5_r_init_0p4_run_ended_a_centred_croissant_moving_as_a_rigid_body() {
    let (state, run, s) = ended_run("discocyte_u1.5_r0.4", 0.4);
    assert_eq!((s.status.as_str(), s.tank_treading, s.tumbling), ("steady", false, false));
    assert!(s.evidence["steady_duration_s"] >= 0.5 - 1e-9, "the study's 0.5 s window");
    assert!(s.mean_radial_um < 0.4, "centred: {} um", s.mean_radial_um);
    assert!((2.3..=2.7).contains(&s.mean_velocity_mm_s), "cell velocity {} mm/s is not ~2.5", s.mean_velocity_mm_s);
    assert!(s.evidence["nonrigid_ratio"] < 1e-3, "a rigid body: {}", s.evidence["nonrigid_ratio"]);
    let (fold, x_z, x_y) = (s.evidence["mirror_fold_rel"], s.evidence["mirror_y_rel"], s.evidence["mirror_z_rel"]);
    assert!(fold <= x_z.min(x_y), "the fold plane is searched: {fold} against {x_z} and {x_y}");
    assert!((0.05..0.052).contains(&fold), "just past the mirror test's bound: {fold}");
    assert_eq!(s.final_shape, FinalShape::Croissant, "centred and rigid: the paper's croissant");
    let ten = run.transits.iter().find(|t| t.distance_mm == 10.0).expect("a 10 mm transit record");
    assert!(ten.from_steady && ten.shape == FinalShape::Croissant, "{ten:?}");
    // the experiment's image classifier: at its own bound (0.11), just on the croissant side
    let row = closed_loop_row(&state, false, "croissant");
    assert!(row.y_um.abs() < 0.4, "the analysis sees it centred: {row:?}");
    assert!((0.10..0.11).contains(&row.asymmetry), "at the image rule's bound: {row:?}");
}

/// The study's r_init = 0.5 um run at ~6.3 mm/s (queued in session 15 to halve the bracket of
/// this model's switch): ended `periodic` at 935.4 ms (session 16) over the study's 0.5 s window
/// (period 109 ms, radial 0.30-0.33 um), a centred croissant like the r_init = 0.4 um run: mean
/// y 0.006, z 0.312 um, nearly rigid (non-rigid motion 0.006 of its speed; its membrane
/// circulating at 2.27 Hz, a tank-treading croissant since session 51), not tumbling,
/// mirror-symmetric to 0.006 R_eff about a plane 2 degrees from the x-y plane, at 6.44
/// mm/s (measured 2026-11-26). So at ~6.4 mm/s this model's switch from croissants to slippers
/// lies between r_init 0.5 and 0.6 um (the paper's: ~0.7 um). Rendered and analysed as an
/// experiment would see it, it is a centred croissant for `rbc-analyze` too (y -0.03 um).
#[test]
fn the_studys_r_init_0p5_run_ended_a_centred_croissant() {
    let (state, _, s) = ended_run("discocyte_u3.8_r0.5", 0.5);
    assert_centred_tank_treading_croissant(&s);
    let row = closed_loop_row(&state, false, "croissant");
    assert!(row.y_um.abs() < 0.1, "the analysis sees it centred: {row:?}");
}

/// The study's r_init = 1.2 um run at mean flow 2.4 mm/s (~4 mm/s cell velocity; sessions 16-17),
/// above the paper's croissant-only window (2-3 mm/s): ended `periodic` at 1061.8 ms over the
/// study's 0.5 s window, an off-centre tank-treading slipper mostly along y at ~4 mm/s (mean y
/// 1.333, z 0.010 um, radial 1.19-1.53 um with a period of 79 ms, tank-treading at 5.7 Hz, 3.98
/// mm/s; measured 2026-11-27), as the paper finds from large offsets at that velocity. Rendered
/// and analysed as an experiment would see it, `rbc-analyze` calls it a slipper too (y 1.28 um).
#[test]
fn the_studys_u2p4_r_init_1p2_run_ended_an_off_centre_slipper_at_4_mm_s() {
    let (state, _, _) = ended_tank_treading_slipper("discocyte_u2.4_r1.2", 1.2, 3.5..=4.5);
    closed_loop_row(&state, false, "slipper");
}

/// The study's r_init = 0.4 um run at mean flow 2.4 mm/s (run 8, sessions 17-19): ended `steady`
/// at 3160.2 ms over the study's 0.5 s window, a centred croissant (mean y 0.057, z 0.044 um,
/// radial 0.062-0.083 um), moving as a rigid body (non-rigid motion 1.2e-4 of its speed), neither
/// tank-treading nor tumbling, mirror-symmetric to 0.043 R_eff about its fold plane, at 4.05 mm/s
/// (measured 2026-11-27). With the r_init = 1.2 um run at the same flow (an off-centre slipper,
/// above) this is the paper's bistability above ~3 mm/s ("both shapes show coexistence at low
/// (< 1 mm/s) and high velocities (> 3 mm/s)", its abstract and Fig. 5a): the initial offset
/// decides the shape at ~4 mm/s as at ~6.4 mm/s. Rendered and analysed as an experiment would see
/// it, `rbc-analyze` calls it a centred croissant too (y 0.03 um).
#[test]
fn the_studys_u2p4_r_init_0p4_run_ended_a_centred_croissant_at_4_mm_s() {
    let (state, run, s) = ended_run("discocyte_u2.4_r0.4", 0.4);
    assert_centred_rigid_croissant_at(&s, "steady", 3.5..=4.5);
    assert!(s.evidence["mirror_fold_rel"] < 0.05, "mirror-symmetric: {}", s.evidence["mirror_fold_rel"]);
    let ten = run.transits.iter().find(|t| t.distance_mm == 10.0).expect("a 10 mm transit record");
    assert_eq!(ten.shape, FinalShape::Croissant, "{ten:?}");
    // the other shape at the same flow: bistable there
    let slipper = ended_as("discocyte_u2.4_r1.2", 1.2, FinalShape::Slipper, "the other shape at the same flow");
    assert!((s.mean_velocity_mm_s - slipper.mean_velocity_mm_s).abs() < 0.2, "the same cell velocity: {} and {} mm/s", s.mean_velocity_mm_s, slipper.mean_velocity_mm_s);
    let row = closed_loop_row(&state, false, "croissant");
    assert!(row.y_um.abs() < 0.1, "the analysis sees it centred: {row:?}");
}

/// The study's r_init = 1.2 um run at mean flow 1.5 mm/s (~2.5 mm/s cell velocity, sessions
/// 15-20), in the paper's croissant-only window (2-3 mm/s): an off-centre tank-treading slipper
/// that swings with a period of 132 ms (radial 0.98-1.41 um, mean y 1.15, z 0.005 um,
/// tank-treading at 3.7 Hz, 2.48 mm/s; measured 2026-11-27). The period is longer than the study's
/// 0.5 s window can hold four times (125 ms), so the run went on to 6413 ms undecided; since
/// session 20 the detector judges such an orbit over four of its periods
/// (`rbc_solver::steady::WINDOW_STRETCH`), and replaying the stored samples it found the orbit
/// repeating from 1.19 s on. The 5.2 s the run went on confirm it: the same orbit, its mean y
/// within 1.10-1.17 um. So, unlike the paper, this model keeps a slipper from a large offset at
/// ~2.5 mm/s (the paper: croissants "independently of the initial radial position", possibly
/// after an intermediate slipper state "that can last several seconds"; ours has lasted 5 s).
/// Rendered and analysed as an experiment would see it, `rbc-analyze` calls it a slipper too.
/// Would it still become a croissant by 30 s? Its mean y per swing drifts by -0.0051 um/s over
/// 3.0-4.4 s and -0.0016 um/s over 5.0-6.4 s (session 22): it settles into its orbit; at the last
/// rate 30 s would move it by 0.05 um, not the 1.1 um to the axis. Only a sudden change (none in
/// its 6.4 s) would make it one.
#[test]
fn the_studys_u1p5_r_init_1p2_run_ended_a_slipper_swinging_slower_than_the_window() {
    let (state, run, s) = ended_tank_treading_slipper("discocyte_u1.5_r1.2", 1.2, 2.3..=2.7);
    let period = s.evidence["period_s"];
    assert!((0.125..0.14).contains(&period), "a period the 0.5 s window cannot hold four times: {period} s");
    let (start, end) = (s.evidence["steady_start_s"], s.evidence["steady_end_s"]);
    assert!(((end - start) / (4.0 * period) - 1.0).abs() < 0.01, "judged over four periods: {start}..{end} s");
    assert!(end < 1.2, "periodic from {end} s on");
    // and the run went on in the same orbit for 5 s more (its last sample)
    let samples = rbc_schema::results::read_timeseries(&state, &run.run_id).unwrap();
    let last = samples.last().unwrap();
    assert!(last.t_s > 6.4, "run to {} s", last.t_s);
    let late: Vec<f64> = samples.iter().filter(|x| x.t_s > last.t_s - 4.0 * period).map(|x| x.centroid_um[1]).collect();
    let mean_y = late.iter().sum::<f64>() / late.len() as f64;
    assert!((mean_y - s.mean_y_um).abs() < 0.1, "the same orbit 5 s later: mean y {mean_y} against {}", s.mean_y_um);
    // converging to its orbit, not drifting to the axis (the paper's croissants here may come
    // "after an intermediate slipper state that can last several seconds"): the mean y of each
    // swing (maximum of y to the next) from 3 s on, its drift over the first and the last ten
    let after: Vec<&rbc_schema::results::TimeSample> = samples.iter().filter(|x| x.t_s >= 3.0).collect();
    let mut peaks: Vec<usize> = Vec::new();
    for i in 1..after.len() - 1 {
        let y = after[i].centroid_um[1];
        if y > s.mean_y_um && y > after[i - 1].centroid_um[1] && y >= after[i + 1].centroid_um[1] && peaks.last().is_none_or(|&j| after[i].t_s - after[j].t_s > period / 2.0) {
            peaks.push(i);
        }
    }
    let means: Vec<(f64, f64)> = peaks.windows(2).map(|w| (after[w[0]].t_s, after[w[0]..w[1]].iter().map(|x| x.centroid_um[1]).sum::<f64>() / (w[1] - w[0]) as f64)).collect();
    assert!(means.len() >= 20, "{} swings from 3 s on", means.len());
    let slope = |w: &[(f64, f64)]| {
        let (tm, ym) = (w.iter().map(|p| p.0).sum::<f64>() / w.len() as f64, w.iter().map(|p| p.1).sum::<f64>() / w.len() as f64);
        w.iter().map(|p| (p.0 - tm) * (p.1 - ym)).sum::<f64>() / w.iter().map(|p| (p.0 - tm).powi(2)).sum::<f64>()
    };
    let (early, late) = (slope(&means[..10]), slope(&means[means.len() - 10..]));
    eprintln!("mean y drift: {early:.5} um/s over {:.2}-{:.2} s, {late:.5} um/s over {:.2}-{:.2} s", means[0].0, means[10].0, means[means.len() - 10].0, last.t_s);
    assert!(late.abs() < 0.003 && late.abs() < early.abs() / 2.0, "the drift falls off: {early} then {late} um/s");
    assert!(late.abs() * 30.0 < 0.1, "30 s at the last drift would move the mean y by {} um", late.abs() * 30.0);
    closed_loop_row(&state, false, "slipper");
}

/// The study's r_init = 0.8 um run at mean flow 2.4 mm/s (run 9, sessions 19-20): ended
/// `periodic` at 1029.2 ms over the study's 0.5 s window (period 80 ms, radial 1.17-1.50 um), an
/// off-centre tank-treading slipper like the r_init = 1.2 um run at the same flow (mean y 1.317,
/// z 0.004 um, tank-treading at 5.6 Hz, 3.99 mm/s; measured 2026-11-27). With the croissant from
/// r_init = 0.4 um there, this model's switch at ~4 mm/s lies between r_init 0.4 and 0.8 um
/// (and between 0.6 and 0.8 um since run 14 ended a croissant, below). Rendered and analysed as an
/// experiment would see it, `rbc-analyze` calls it a slipper too.
#[test]
fn the_studys_u2p4_r_init_0p8_run_ended_an_off_centre_slipper_at_4_mm_s() {
    let (state, _, _) = ended_tank_treading_slipper("discocyte_u2.4_r0.8", 0.8, 3.5..=4.5);
    ended_as("discocyte_u2.4_r0.4", 0.4, FinalShape::Croissant, "the switch lies between 0.4 and 0.8 um");
    closed_loop_row(&state, false, "slipper");
}

/// The study's r_init = 1.2 um run at mean flow 0.63 mm/s (~1 mm/s cell velocity, the slow column
/// of session 20, the 100 mbar example recordings' velocity): ended `periodic` at 2410.6 ms
/// (session 21), judged over four of its own periods (0.308 s; window 1.18-2.41 s), an
/// off-centre tank-treading slipper (mean y 1.195, z 0.001 um, radial 0.95-1.59 um,
/// tank-treading at 1.3 Hz, 1.02 mm/s; measured 2026-11-27). Its classification frames are 15.8 ms
/// apart (`classify.frame_travel_um` = 10 um of the mean flow): 0.36 s, 0.47 turn; the study's
/// earlier 96 ms window would have seen 0.13 turn, short of the quarter turn the classifier asked
/// for then (since session 51 `min_tt_turns` is 0.1 turn, and the new frames hold 4x that).
#[test]
fn the_studys_u0p63_r_init_1p2_run_ended_a_slowly_tank_treading_slipper_at_1_mm_s() {
    let (state, _, s) = ended_tank_treading_slipper("discocyte_u0.63_r1.2", 1.2, 0.9..=1.15);
    let (window, f_tt) = (s.evidence["classify_window_s"], s.evidence["tt_frequency_hz"]);
    assert!((1.0..1.6).contains(&f_tt), "tank-treading at {f_tt} Hz");
    assert!(f_tt * window >= 0.25 && f_tt * 0.096 < 0.25, "{window} s holds a quarter turn, 96 ms would not: {f_tt} Hz");
    assert!(f_tt * window >= 4.0 * rbc_solver::classify::ClassifyConfig::default().min_tt_turns, "{window} s holds 4x the classifier's least turn: {f_tt} Hz");
    let period = s.evidence["period_s"];
    assert!((0.28..0.34).contains(&period), "period {period} s");
    closed_loop_row(&state, false, "slipper");
}

/// The study's r_init = 0.4 um run at mean flow 0.63 mm/s (~1 mm/s): ended `periodic` at 3660.0
/// ms (session 21) in the orbit of its r_init = 1.2 um partner (mean y 1.198, z 0.003 um, radial
/// 0.96-1.59 um, period 0.308 s, tank-treading at 1.37 Hz, 1.02 mm/s; measured 2026-11-27): it
/// stayed near its start for 0.3 s, then left the axis. Both starts end the same off-centre
/// slipper, so at ~1 mm/s this model's switch lies below 0.4 um (and above 0.2 um since run 13
/// ended a croissant, below).
#[test]
fn the_studys_u0p63_r_init_0p4_run_ended_the_same_slipper_as_r_init_1p2() {
    let (state, _, s) = ended_tank_treading_slipper("discocyte_u0.63_r0.4", 0.4, 0.9..=1.15);
    let (_, _, partner) = ended_run("discocyte_u0.63_r1.2", 1.2);
    assert!((s.mean_y_um - partner.mean_y_um).abs() < 0.05, "one orbit: y {} and {}", s.mean_y_um, partner.mean_y_um);
    assert!((s.evidence["period_s"] / partner.evidence["period_s"] - 1.0).abs() < 0.02, "one period");
    closed_loop_row(&state, false, "slipper");
}

/// The study's r_init = 0.8 um run at mean flow 1.5 mm/s (~2.5 mm/s, run 12, session 21): ended
/// `periodic` at 2000.4 ms, an off-centre tank-treading slipper like the r_init = 1.2 um run there
/// (mean y 1.132, z 0.000 um, radial 0.97-1.38 um, period 133 ms, judged over four of them,
/// tank-treading at 3.5 Hz, 2.49 mm/s; measured 2026-11-27). With the croissant from r_init = 0.4
/// um, this model's switch at ~2.5 mm/s lies between 0.4 and 0.8 um (and between 0.4 and 0.6 um
/// since run 15, below), where the paper finds croissants from every offset.
#[test]
fn the_studys_u1p5_r_init_0p8_run_ended_an_off_centre_slipper_at_2p5_mm_s() {
    let (state, _, s) = ended_tank_treading_slipper("discocyte_u1.5_r0.8", 0.8, 2.3..=2.7);
    let (_, _, partner) = ended_run("discocyte_u1.5_r1.2", 1.2);
    assert!((s.evidence["period_s"] / partner.evidence["period_s"] - 1.0).abs() < 0.05, "the r_init 1.2 um run's orbit: {} s", s.evidence["period_s"]);
    ended_as("discocyte_u1.5_r0.4", 0.4, FinalShape::Croissant, "the switch lies between 0.4 and 0.8 um");
    closed_loop_row(&state, false, "slipper");
}

/// The study's r_init = 0.2 um run at mean flow 0.63 mm/s (~1 mm/s, run 13, session 21): ended
/// `steady` at 5424.8 ms over the study's 0.5 s window (steady from 4.92 s), a centred croissant
/// (mean y -0.039, z 0.032 um, radial 0.05 um), moving as a rigid body (non-rigid motion 4.8e-4 of
/// its speed), neither tank-treading nor tumbling, mirror-symmetric to 0.039 R_eff about its fold
/// plane, at 1.05 mm/s (measured 2026-11-27). With the slippers from r_init 0.4 and 1.2 um at the
/// same flow, ~1 mm/s is bistable in this model, as in the paper ("both shapes show coexistence at
/// low (< 1 mm/s) and high velocities (> 3 mm/s)"); the switch lies between r_init 0.2 and 0.4 um
/// (`rbc-predict`'s column: r_trans 0.3 um, bracket [0.2, 0.4]). Rendered and analysed as an
/// experiment would see it, `rbc-analyze` calls it a centred croissant too.
#[test]
fn the_studys_u0p63_r_init_0p2_run_ended_a_centred_croissant_at_1_mm_s() {
    let (state, run, s) = ended_run("discocyte_u0.63_r0.2", 0.2);
    assert_centred_rigid_croissant_at(&s, "steady", 0.9..=1.15);
    assert!(s.evidence["nonrigid_ratio"] < 1e-3, "rigid by the classifier's bound: {}", s.evidence["nonrigid_ratio"]);
    assert!(s.evidence["mirror_fold_rel"] < 0.05, "mirror-symmetric: {}", s.evidence["mirror_fold_rel"]);
    assert!(s.mean_radial_um < 0.1, "on the axis: {} um", s.mean_radial_um);
    let ten = run.transits.iter().find(|t| t.distance_mm == 10.0).expect("a 10 mm transit record");
    assert_eq!(ten.shape, FinalShape::Croissant, "{ten:?}");
    // the other shape at the same flow, from r_init 0.4 um: bistable there
    let slipper = ended_as("discocyte_u0.63_r0.4", 0.4, FinalShape::Slipper, "the switch lies between 0.2 and 0.4 um");
    assert!((s.mean_velocity_mm_s - slipper.mean_velocity_mm_s).abs() < 0.1, "the same cell velocity: {} and {} mm/s", s.mean_velocity_mm_s, slipper.mean_velocity_mm_s);
    let row = closed_loop_row(&state, false, "croissant");
    assert!(row.y_um.abs() < 0.1, "the analysis sees it centred: {row:?}");
}

/// The ~1 mm/s r_init 0.2 um croissant continued 2 s past its `steady` verdict (5424.8 ms), with
/// the position tolerance 5x tighter so that the detector does not end it again at once (check
/// `check-u0.63-r0.2-continued` beside study science-6p5, session 48). At the verdict it was
/// leaving the axis at a steady +0.039 um/s (session 47); it was already slowing then (radial
/// 0.0526, 0.0559, 0.0567 um at 5.2, 5.3, 5.4 s), turned at 5.4 s and came back to 0.016-0.020
/// um from the axis over 6.2-7.4 s, its asphericity 0.0273-0.0283 and its velocity 1.052 mm/s
/// throughout (measured 2026-12-01). The verdict's drift was a phase of a slow wander about the
/// axis (radial 0.011-0.066 um over 2-5.4 s), not a departure: a croissant stays.
#[test]
fn the_exact_wall_1_mm_s_r_init_0p2_croissant_continued_past_its_verdict_comes_back_to_the_axis() {
    let (state, check) = continued_past_its_verdict("science-6p5", "check-u0.63-r0.2-continued", "discocyte_u0.63_r0.2", 5.4248, 1.95);
    let a = after_verdict(&check[state.len()..], 6.2);
    assert!(a.max_radial < 0.057, "never further out than at the verdict: {} um", a.max_radial);
    assert!(a.late_radial.0 > 0.01 && a.late_radial.1 < 0.022, "back near the axis over 6.2-7.4 s: radial {:?} um", a.late_radial);
    assert!(a.asphericity.0 > 0.027 && a.asphericity.1 < 0.029, "the same croissant's shape: asphericity {:?}", a.asphericity);
    assert!(a.u_x.0 > 1.052 - 0.002 && a.u_x.1 < 1.052 + 0.002, "the same cell velocity: {:?} mm/s", a.u_x);
    // the radial drift over the last window and the one before: it no longer leaves
    let d = rbc_solver::steady::radial_orbit_drift(&check, rbc_solver::steady::drift_interval_s(None, 0.5)).unwrap();
    assert!(d.rate.abs() < 0.02 && d.earlier_rate.unwrap().abs() < 0.02, "{d:?}");
    // and before the verdict it had wandered about the axis, in and out
    let before: Vec<f64> = state.iter().filter(|s| s.t_s >= 2.0).map(radial_um).collect();
    let (b_min, b_max, _) = min_max_mean(&before);
    assert!(b_min < 0.012 && b_max > 0.06 && b_max < 0.07, "radial {b_min}-{b_max} um over 2-5.4 s");
}

/// The distance (um) of a sample's centroid from the channel's axis.
fn radial_um(s: &rbc_schema::results::TimeSample) -> f64 {
    s.centroid_um[1].hypot(s.centroid_um[2])
}

/// The committed state of run `run_id` of study `study` (ended at `verdict_s`) and the samples of
/// the check `check` beside it (`examples/studies/STUDY/CHECK.h5`) that continued the run more
/// than `past_s` beyond its verdict: the check holds the state's samples as they are, then its own.
fn continued_past_its_verdict(study: &str, check: &str, run_id: &str, verdict_s: f64, past_s: f64) -> (Vec<rbc_schema::results::TimeSample>, Vec<rbc_schema::results::TimeSample>) {
    let state = state_rows(study, run_id);
    let rows = study_file_rows(&format!("{study}/{check}.h5"), run_id);
    let verdict = state.last().unwrap().t_s;
    assert!((verdict - verdict_s).abs() < 1e-9, "{study}: {run_id}'s state ends at its verdict: {verdict} s");
    assert_eq!(&rows[..state.len()], &state[..], "{check} holds the study's samples to the verdict");
    assert!(rows.last().unwrap().t_s > verdict + past_s, "{check}: {past_s} s past the verdict: {} s", rows.last().unwrap().t_s);
    (state, rows)
}

/// What a run continued past its verdict did after it (its rows `after` the verdict): its largest
/// radial position, its radial range from `late_from_s` on, and the ranges of its asphericity and
/// its velocity along the flow (mm/s), each (min, max).
struct AfterVerdict {
    max_radial: f64,
    late_radial: (f64, f64),
    asphericity: (f64, f64),
    u_x: (f64, f64),
}

fn after_verdict(after: &[rbc_schema::results::TimeSample], late_from_s: f64) -> AfterVerdict {
    let range = |v: Vec<f64>| {
        let (min, max, _) = min_max_mean(&v);
        (min, max)
    };
    AfterVerdict {
        max_radial: range(after.iter().map(radial_um).collect()).1,
        late_radial: range(after.iter().filter(|s| s.t_s >= late_from_s).map(radial_um).collect()),
        asphericity: range(after.iter().map(|s| s.asphericity).collect()),
        u_x: range(after.iter().map(|s| s.velocity_mm_s[0]).collect()),
    }
}

/// The paper's-walls ~4 mm/s r_init 0.8 um croissant continued 0.43 s past its `periodic` verdict
/// (2535.4 ms), with the position tolerance 5x tighter (check `check-u2.4-r0.8-continued` beside
/// study science-6p5-penalty, session 48). At the verdict the mean of its radial position went out
/// at +0.073 um/s against -0.018 over the four periods before (session 46), 0.061 um off the axis.
/// Its radial position averaged over a period had peaked at 2.50 s (0.061 um), before the verdict,
/// and it came back to 0.016-0.024 um over 2.87-2.96 s (radial drift -0.107 um/s over the last
/// window, +0.103 over the one before), its asphericity 0.0177-0.0187 and its velocity 4.08 mm/s
/// throughout (measured 2026-12-01). As at ~1 mm/s with exact walls, the drift at the verdict was
/// a phase of a wander about the axis (radial 0.004-0.11 um since 1 s), not a departure.
#[test]
fn the_papers_walls_4_mm_s_r_init_0p8_croissant_continued_past_its_verdict_comes_back_to_the_axis() {
    let (state, check) = continued_past_its_verdict("science-6p5-penalty", "check-u2.4-r0.8-continued", "discocyte_u2.4_r0.8", 2.5354, 0.42);
    let a = after_verdict(&check[state.len()..], 2.87);
    assert!(a.max_radial < 0.062, "never further out than at the verdict: {} um", a.max_radial);
    assert!(a.late_radial.0 > 0.012 && a.late_radial.1 < 0.025, "back near the axis over 2.87-2.96 s: radial {:?} um", a.late_radial);
    assert!(a.asphericity.0 > 0.0175 && a.asphericity.1 < 0.019, "the same croissant's shape: asphericity {:?}", a.asphericity);
    assert!(a.u_x.0 > 4.08 - 0.006 && a.u_x.1 < 4.08 + 0.006, "the same cell velocity: {:?} mm/s", a.u_x);
    let d = rbc_solver::steady::radial_orbit_drift(&check, rbc_solver::steady::drift_interval_s(None, 0.5)).unwrap();
    assert!(d.rate < -0.08 && d.earlier_rate.unwrap() > 0.08, "turned: {d:?}");
    let before: Vec<f64> = state.iter().filter(|s| s.t_s >= 1.0).map(radial_um).collect();
    let (b_min, b_max, _) = min_max_mean(&before);
    assert!(b_min < 0.006 && b_max > 0.1 && b_max < 0.12, "radial {b_min}-{b_max} um over 1-2.54 s");
}

/// The paper's-walls ~0.5 mm/s croissant start (0.2 um; session 58) continued 1.06 s past its
/// `steady` verdict (587.0 ms), with the position tolerance 5x tighter (check
/// `check-croissant-u0.31-continued` beside study science-6p5-penalty). Judged 0.142 um off the
/// axis, it held there to ~0.75 s and then came in to the axis: radial 0.111 um over 0.8-1.0 s,
/// 0.051 over 1.2-1.4 s, 0.013-0.037 after 1.4 s; its asphericity 0.042-0.044 and its velocity
/// 0.515 mm/s throughout (measured 2026-12-02). So the verdict's label stands, and the croissant
/// this start holds at ~0.5 mm/s is a centred one (as the paper's below ~0.7 mm/s); the verdict's
/// position (0.142 um) was not yet its last: the steady test's 0.05 um passed a pause.
#[test]
fn the_papers_walls_0p5_mm_s_croissant_start_continued_past_its_verdict_comes_in_to_the_axis() {
    let (state, check) = continued_past_its_verdict("science-6p5-penalty", "check-croissant-u0.31-continued", "croissant_u0.31_r0.2", 0.587, 1.0);
    let a = after_verdict(&check[state.len()..], 1.4);
    assert!(a.max_radial < 0.145, "never further out than at the verdict: {} um", a.max_radial);
    assert!(a.late_radial.1 < 0.04, "at the axis from 1.4 s: radial {:?} um", a.late_radial);
    assert!(a.asphericity.0 > 0.041 && a.asphericity.1 < 0.045, "the same croissant's shape: asphericity {:?}", a.asphericity);
    assert!(a.u_x.0 > 0.515 - 0.003 && a.u_x.1 < 0.515 + 0.003, "the same cell velocity: {:?} mm/s", a.u_x);
}

/// The study's r_init = 0.6 um run at mean flow 1.5 mm/s (~2.5 mm/s, run 15, sessions 21-22):
/// ended `periodic` at 2984.4 ms (window 2.45-2.98 s, period 134 ms, radial 0.94-1.39 um), an
/// off-centre tank-treading slipper in the orbit of the r_init 0.8 and 1.2 um runs there (mean y
/// 1.121, z 0.000 um, tank-treading at 3.1 Hz, 2.48 mm/s; measured 2026-11-27). Its z first
/// alternated by +-0.04 um from one swing to the next (a period-doubled orbit that decayed by
/// 2.2 s) before the orbit repeated. With the croissant from r_init = 0.4 um, this model's switch
/// at ~2.5 mm/s lies between 0.4 and 0.6 um (`rbc-predict`'s column: r_trans 0.5 um, bracket
/// [0.4, 0.6]), where the paper finds croissants from every offset.
#[test]
fn the_studys_u1p5_r_init_0p6_run_ended_the_same_slipper_at_2p5_mm_s() {
    let (state, _, s) = ended_tank_treading_slipper("discocyte_u1.5_r0.6", 0.6, 2.3..=2.7);
    let (_, _, partner) = ended_run("discocyte_u1.5_r0.8", 0.8);
    assert!((s.mean_y_um - partner.mean_y_um).abs() < 0.05, "one orbit: y {} and {}", s.mean_y_um, partner.mean_y_um);
    assert!((s.evidence["period_s"] / partner.evidence["period_s"] - 1.0).abs() < 0.03, "one period: {} s", s.evidence["period_s"]);
    ended_as("discocyte_u1.5_r0.4", 0.4, FinalShape::Croissant, "the switch lies between 0.4 and 0.6 um");
    closed_loop_row(&state, false, "slipper");
}

/// The study's r_init = 0.6 um run at mean flow 2.4 mm/s (~4 mm/s, run 14, sessions 21-22): ended
/// `steady` at 7178.2 ms over the study's 0.5 s window, a centred croissant (mean y -0.058, z
/// -0.055 um, radial at most 0.087 um), moving as a rigid body (non-rigid motion 3.7e-5 of its
/// speed), mirror-symmetric to 0.046 R_eff about its fold plane, at 4.05 mm/s (measured
/// 2026-11-27). It stayed centred from the start but changed shape slowly for seconds (its
/// asphericity fell from 0.028 to 0.016 between 3 and 6.5 s, the paper's "minuscule periodic
/// shape deformations" of croissants at 2-4 mm/s) before it settled. With the slipper from r_init
/// 0.8 um there, this model's switch at ~4 mm/s lies between 0.6 and 0.8 um (`rbc-predict`'s
/// column: r_trans 0.7 um, bracket [0.6, 0.8]). Rendered and analysed as an experiment would see
/// it, `rbc-analyze` calls it a centred croissant too.
#[test]
fn the_studys_u2p4_r_init_0p6_run_ended_a_centred_croissant_at_4_mm_s() {
    let (state, _, s) = ended_run("discocyte_u2.4_r0.6", 0.6);
    assert_centred_rigid_croissant_at(&s, "steady", 3.5..=4.5);
    assert!(s.evidence["nonrigid_ratio"] < 1e-3, "rigid by the classifier's bound: {}", s.evidence["nonrigid_ratio"]);
    assert!(s.evidence["steady_end_s"] > 7.0, "settled late: {} s", s.evidence["steady_end_s"]);
    ended_as("discocyte_u2.4_r0.8", 0.8, FinalShape::Slipper, "the switch lies between 0.6 and 0.8 um");
    let row = closed_loop_row(&state, false, "croissant");
    assert!(row.y_um.abs() < 0.15, "the analysis sees it centred: {row:?}");
}

/// The paper's other start shapes (Fig. 5 b, c; `examples/sweeps/starts.h5`, this study's settled
/// croissant and slipper at ~4 mm/s) at mean flow 1.5 mm/s (~2.5 mm/s, grids 16-17, session 22).
/// The slipper started 0.4 um off the axis ended `steady` at 2884.8 ms, a centred croissant moving
/// as a rigid body (radial 0.11-0.12 um, non-rigid motion 2e-4 of its speed, 2.52 mm/s), as the
/// discocyte from 0.4 um there; the croissant started 1.2 um off the axis ended `periodic` at
/// 1391.8 ms, an off-centre tank-treading slipper in the discocytes' orbit there (mean y 1.117
/// um, radial 0.94-1.38 um, period 134 ms, 3.1 Hz, 2.48 mm/s; measured 2026-11-27). So from every
/// start shape this model keeps both shapes at ~2.5 mm/s, where the paper's croissant-only
/// window holds "unscathed" for all three.
#[test]
fn the_studys_croissant_and_slipper_starts_at_2p5_mm_s_end_as_the_discocyte_does() {
    let (_, run, s) = ended_run("slipper_u1.5_r0.4", 0.4);
    assert_eq!(run.attrs.as_ref().map(|a| a.start_shape.as_str()), Some("slipper"));
    assert_centred_rigid_croissant_at(&s, "steady", 2.3..=2.7);
    assert!(s.evidence["nonrigid_ratio"] < 1e-3, "rigid: {}", s.evidence["nonrigid_ratio"]);
    let (state, run, s) = ended_tank_treading_slipper("croissant_u1.5_r1.2", 1.2, 2.3..=2.7);
    assert_eq!(run.attrs.as_ref().map(|a| a.start_shape.as_str()), Some("croissant"));
    let (_, _, discocyte) = ended_run("discocyte_u1.5_r1.2", 1.2);
    assert!((s.mean_y_um - discocyte.mean_y_um).abs() < 0.05 && (s.evidence["period_s"] / discocyte.evidence["period_s"] - 1.0).abs() < 0.03, "the discocyte's orbit: y {} period {}", s.mean_y_um, s.evidence["period_s"]);
    closed_loop_row(&state, false, "slipper");
}

/// A start-shape run of the ~6.3 mm/s column (start shape `start`) that ended as a tank-treading
/// slipper in the orbit of the discocyte started 1.2 um off the axis there: mean y within 0.05 um
/// of it, its radial extremes within `radial_tol` um. Returns the run's state file.
fn start_shape_in_the_6p3_discocytes_orbit(run_id: &str, r_init: f64, start: &str, radial_tol: f64) -> PathBuf {
    let (state, run, s) = ended_tank_treading_slipper(run_id, r_init, 6.0..=6.6);
    assert_eq!(run.attrs.as_ref().map(|a| a.start_shape.as_str()), Some(start));
    let (_, _, discocyte) = ended_run("discocyte_u3.8_r1.2", 1.2);
    assert!((s.mean_y_um - discocyte.mean_y_um).abs() < 0.05, "the discocyte's orbit: y {} against {}", s.mean_y_um, discocyte.mean_y_um);
    for k in ["radial_min_um", "radial_max_um"] {
        assert!((s.evidence[k] - discocyte.evidence[k]).abs() < radial_tol, "{k}: {} against {}", s.evidence[k], discocyte.evidence[k]);
    }
    state
}

/// The slipper start (`examples/sweeps/starts.h5`) 0.4 um off the axis at mean flow 3.8 mm/s
/// (~6.3 mm/s, grid 19, sessions 22-24) ended `periodic` at 1003.8 ms, an off-centre
/// tank-treading slipper in the discocyte's orbit from 1.2 um there (mean y 1.561 against 1.570
/// um, radial 1.44-1.70 against 1.44-1.72 um, 6.28 mm/s, 8.6 Hz; measured 2026-11-27), where the
/// discocyte started from the same 0.4 um ended a centred croissant: at ~6.3 mm/s the start shape
/// decides which of the two states a cell reaches from one position, the paper's bistability.
#[test]
fn the_studys_slipper_start_at_6p3_mm_s_from_0p4_um_ends_a_slipper_where_the_discocyte_ends_a_croissant() {
    let state = start_shape_in_the_6p3_discocytes_orbit("slipper_u3.8_r0.4", 0.4, "slipper", 0.03);
    let (_, from_same_place, _) = ended_run("discocyte_u3.8_r0.4", 0.4);
    assert_eq!(from_same_place.summary.map(|c| c.final_shape), Some(FinalShape::Croissant), "the discocyte from the same 0.4 um");
    closed_loop_row(&state, false, "slipper");
}

/// The croissant start (`examples/sweeps/starts.h5`) 1.2 um off the axis at mean flow 3.8 mm/s
/// (~6.3 mm/s, grid 18, session 22-23) ended `periodic` at 741.2 ms, an off-centre tank-treading
/// slipper in the discocyte's orbit from 1.2 um there (mean y 1.564 against 1.570 um, radial
/// 1.44-1.72 um both, 6.28 mm/s, 9.1 Hz; its detected period 97.7 ms is two of the discocyte's
/// 49.1 ms swings; measured 2026-11-27): the paper's croissant start "favors croissants" at this
/// velocity, but not from 1.2 um in this model.
#[test]
fn the_studys_croissant_start_at_6p3_mm_s_from_1p2_um_ends_in_the_discocytes_slipper_orbit() {
    let state = start_shape_in_the_6p3_discocytes_orbit("croissant_u3.8_r1.2", 1.2, "croissant", 0.02);
    closed_loop_row(&state, false, "slipper");
}

/// The samples of run `run_id` in the committed state of study `study` (`examples/studies`).
fn state_rows(study: &str, run_id: &str) -> Vec<rbc_schema::results::TimeSample> {
    study_file_rows(&format!("{study}/state/{run_id}.h5"), run_id)
}

/// The samples of run `run_id` in study `study`'s committed state over `[from_s, to_s]`; panics
/// unless the state reaches `to_s` (the samples before it stay as the run goes on).
fn state_window(study: &str, run_id: &str, from_s: f64, to_s: f64) -> Vec<rbc_schema::results::TimeSample> {
    let rows = state_rows(study, run_id);
    assert!(rows.last().unwrap().t_s >= to_s - 1e-9, "{study}: {run_id} only to {} s", rows.last().unwrap().t_s);
    rows.into_iter().filter(|s| (from_s - 1e-9..=to_s + 1e-9).contains(&s.t_s)).collect()
}

/// The smallest, largest and mean value of `v`.
fn min_max_mean(v: &[f64]) -> (f64, f64, f64) {
    (v.iter().copied().fold(f64::INFINITY, f64::min), v.iter().copied().fold(f64::NEG_INFINITY, f64::max), v.iter().sum::<f64>() / v.len() as f64)
}

/// The samples of run `run_id` in `file` (a path under `examples/studies`: a study's state or a
/// check beside it); a file that does not read panics naming it.
fn study_file_rows(file: &str, run_id: &str) -> Vec<rbc_schema::results::TimeSample> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies").join(file);
    rbc_schema::results::read_timeseries(&path, run_id).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The samples of the ~2.5 mm/s r_init 0.8 um run in `file` (a path under `examples/studies`):
/// the two studies' runs and the checks beside them hold the same start.
fn u1p5_r0p8_rows(file: &str) -> Vec<rbc_schema::results::TimeSample> {
    study_file_rows(file, "discocyte_u1.5_r0.8")
}

/// The largest distances (um) in y and in z between a check run from rest and the study's run of
/// the same start, sample by sample over the check's samples (the same output times, the same start).
fn largest_apart_yz(check: &[rbc_schema::results::TimeSample], study: &[rbc_schema::results::TimeSample]) -> (f64, f64) {
    assert_eq!(check[0].centroid_um, study[0].centroid_um, "the same start");
    check.iter().zip(study).fold((0.0, 0.0), |(dy, dz): (f64, f64), (c, s)| {
        assert_eq!(c.t_s, s.t_s);
        (dy.max((c.centroid_um[1] - s.centroid_um[1]).abs()), dz.max((c.centroid_um[2] - s.centroid_um[2]).abs()))
    })
}

/// The ~2.5 mm/s column with the paper's penalty walls (study `science-6p5-penalty`): the r_init
/// 0.8 um discocyte swings out only to y 0.60 um (at 163 ms) and then heads for the axis (y 0.16
/// um at 300 ms), where exact no-slip walls swing the same start out to 0.99 um and on to its
/// slipper orbit (y 1.18 um at 300 ms). The walls' stepping errs towards the axis (solver
/// README, "Session 25"), so session 25 ran the same 300 ms again with the walls held 5x tighter
/// (`check-walls-2e-5.h5`): it turns at 0.63 um (162 ms) and follows the study's path within
/// 0.04 um (measured 0.0400 at most, 0.20 um at 300 ms). The turn is the walls', not the stepping's.
#[test]
fn with_the_papers_walls_the_2p5_mm_s_r_init_0p8_cell_heads_for_the_axis_also_with_the_walls_5x_tighter() {
    use rbc_schema::results::TimeSample;
    let exact = u1p5_r0p8_rows("science-6p5/state/discocyte_u1.5_r0.8.h5");
    // (the study's live state: every save appends to it and keeps its first 300 ms as they are)
    let study = u1p5_r0p8_rows("science-6p5-penalty/state/discocyte_u1.5_r0.8.h5");
    let check = u1p5_r0p8_rows("science-6p5-penalty/check-walls-2e-5.h5");
    assert!((check.last().unwrap().t_s - 0.3).abs() < 1e-12, "the check runs to 300 ms");
    let at = |r: &[TimeSample], t: f64| r.iter().find(|s| (s.t_s - t).abs() < 1e-9).unwrap_or_else(|| panic!("a row at {t} s")).centroid_um[1];
    // the largest y of the first swing (100-250 ms)
    let peak = |r: &[TimeSample]| r.iter().filter(|s| (0.1..=0.25).contains(&s.t_s)).map(|s| s.centroid_um[1]).fold(f64::NEG_INFINITY, f64::max);
    let (p_exact, p_study, p_check) = (peak(&exact), peak(&study), peak(&check));
    eprintln!("first swing's peak y: exact walls {p_exact:.3}, penalty {p_study:.3}, penalty 5x tighter {p_check:.3} um; at 300 ms {:.3}, {:.3}, {:.3}", at(&exact, 0.3), at(&study, 0.3), at(&check, 0.3));
    assert!(p_exact > 0.95 && p_study < 0.65 && p_check < 0.65, "{p_exact} {p_study} {p_check}");
    assert!(at(&exact, 0.3) > 1.1 && at(&study, 0.3) < 0.25 && at(&check, 0.3) < 0.25);
    let (apart, _) = largest_apart_yz(&check, &study);
    assert!(apart < 0.045, "the check follows the study within {apart} um");
}

/// The paper's wall springs decide the ~2.5 mm/s r_init 0.8 um cell's path: with them 4x and
/// 16x stiffer (checks `check-kappa-x4`, `check-kappa-x16` beside study `science-6p5-penalty`,
/// session 26, the walls at the study's 1e-4 um) the path lies between the paper's walls' (the
/// study) and the exact no-slip walls', the nearer the exact walls the stiffer the springs, at
/// every output time from 40 ms on. Measured centroid y (um) at 100 / 125 / 150 ms: the study
/// 0.515 / 0.550 / 0.590, x4 0.613 / 0.697 / 0.777, x16 0.653 / 0.756 / 0.837, exact walls 0.770
/// / 0.932 / 0.960.
#[test]
fn stiffer_penalty_walls_move_the_u1p5_r_init_0p8_path_towards_the_exact_walls() {
    let y = |file: &str| -> Vec<(f64, f64)> { u1p5_r0p8_rows(file).iter().map(|s| (s.t_s, s.centroid_um[1])).collect() };
    let exact = y("science-6p5/state/discocyte_u1.5_r0.8.h5");
    let study = y("science-6p5-penalty/state/discocyte_u1.5_r0.8.h5");
    let x4 = y("science-6p5-penalty/check-kappa-x4.h5");
    let x16 = y("science-6p5-penalty/check-kappa-x16.h5");
    assert!((x4.last().unwrap().0 - 0.15).abs() < 1e-12, "the 4x check runs to 150 ms");
    assert!(x16.last().unwrap().0 >= 0.15, "the 16x check runs past 150 ms");
    let at = |r: &[(f64, f64)], t: f64| r.iter().find(|s| (s.0 - t).abs() < 1e-9).unwrap_or_else(|| panic!("a row at {t} s")).1;
    let mut checked = 0;
    for &(t, _) in x16.iter().filter(|s| s.0 >= 0.04 - 1e-9 && s.0 <= 0.15 + 1e-9) {
        let (a, b, c, d) = (at(&study, t), at(&x4, t), at(&x16, t), at(&exact, t));
        assert!(a < b && b < c && c < d, "at {t} s: study {a}, x4 {b}, x16 {c}, exact {d}");
        checked += 1;
    }
    assert!(checked >= 500, "{checked} output times");
    let (a, b, c, d) = (at(&study, 0.15), at(&x4, 0.15), at(&x16, 0.15), at(&exact, 0.15));
    eprintln!("y at 150 ms: study {a:.3}, x4 {b:.3}, x16 {c:.3}, exact walls {d:.3} um");
    // each 4x of kappa_W closes about a third to a half of what is left to the exact walls
    assert!(d - b < 0.6 * (d - a) && d - c < 0.75 * (d - b) && d - c > 0.08, "{a} {b} {c} {d}");
}

/// With the wall springs 16x stiffer than the paper's (`check-kappa-x16`, run on from rest to 1 s
/// in session 27) the ~2.5 mm/s r_init 0.8 um cell swings back out once where the paper's springs
/// take it straight in (a trough of y 0.513 um at 258 ms, a peak of 0.749 at 354 ms; the study's
/// run is at y < 0.1 um from 331 ms on), but then it heads for the axis too: at 1 s it is 0.17 um off
/// the axis with the asphericity of the study's centred croissant (0.020 against 0.017), while
/// exact no-slip walls keep the same start swinging between y 0.85 and 1.36 um (a slipper). So
/// 16x stiffer springs delay the croissant by ~0.4 s but do not change it: at ~2.5 mm/s the
/// outcome is that of compliant walls versus rigid ones, not of the paper's spring constant.
#[test]
fn sixteen_times_stiffer_wall_springs_delay_the_u1p5_r_init_0p8_croissant_but_keep_it() {
    use rbc_schema::results::TimeSample;
    let exact = u1p5_r0p8_rows("science-6p5/state/discocyte_u1.5_r0.8.h5");
    let study = u1p5_r0p8_rows("science-6p5-penalty/state/discocyte_u1.5_r0.8.h5");
    let x16 = u1p5_r0p8_rows("science-6p5-penalty/check-kappa-x16.h5");
    assert!((x16.last().unwrap().t_s - 1.0).abs() < 1e-12, "the 16x check runs to 1 s");
    let y = |r: &[TimeSample], a: f64, b: f64| r.iter().filter(|s| s.t_s >= a - 1e-9 && s.t_s <= b + 1e-9).map(|s| s.centroid_um[1]).collect::<Vec<_>>();
    let min = |v: Vec<f64>| v.into_iter().fold(f64::INFINITY, f64::min);
    let max = |v: Vec<f64>| v.into_iter().fold(f64::NEG_INFINITY, f64::max);
    // the swing back out that the paper's springs do not make
    let (trough, peak) = (min(y(&x16, 0.2, 0.3)), max(y(&x16, 0.3, 0.4)));
    assert!(trough < 0.55 && peak > 0.7 && peak - trough > 0.2, "x16: trough {trough}, peak {peak}");
    assert!(max(y(&study, 0.35, 1.0)) < 0.1, "the paper's springs: within 0.1 um of the axis from 350 ms on");
    // ... and then the axis as well
    let end = x16.last().unwrap();
    let r_end = radial_um(end);
    let study_end = study.iter().find(|s| (s.t_s - 1.0).abs() < 1e-9).unwrap();
    eprintln!(
        "x16: trough y {trough:.3} um, peak {peak:.3}; at 1 s {r_end:.3} um off the axis, asphericity {:.4} (the study's {:.4}); exact walls y {:.3}-{:.3} over 0.3-1 s",
        end.asphericity,
        study_end.asphericity,
        min(y(&exact, 0.3, 1.0)),
        max(y(&exact, 0.3, 1.0))
    );
    assert!(r_end < 0.25 && max(y(&x16, 0.9, 1.0)) < 0.15, "x16 at 1 s: {r_end} um off the axis");
    assert!((end.asphericity - study_end.asphericity).abs() < 0.005, "x16 {} against the study's croissant {}", end.asphericity, study_end.asphericity);
    assert!(min(y(&exact, 0.3, 1.0)) > 0.8, "exact walls: a slipper swinging far off the axis");
}

/// The two wall models' paths of the ~2.5 mm/s r_init 0.8 um start do not rest on the walls'
/// mesh: meshed at 1.4 um (2160 wall triangles, the paper's 2166) instead of the studies' 2 um
/// (1008), the first 100 ms from rest stay within 0.027 um (exact walls) and 0.015 um (penalty
/// walls) in y (measured; growing from 0.003 at 20 ms) and 0.010 / 0.005 um in z, while the two
/// models stay 0.24 um apart at 100 ms on either mesh (checks `check-exact-walls-1p4` and
/// `check-penalty-walls-1p4` beside study `science-6p5-penalty`, session 26).
#[test]
fn the_wall_models_differ_by_the_same_on_the_papers_wall_mesh() {
    use rbc_schema::results::TimeSample;
    let exact = u1p5_r0p8_rows("science-6p5/state/discocyte_u1.5_r0.8.h5");
    let exact_fine = u1p5_r0p8_rows("science-6p5-penalty/check-exact-walls-1p4.h5");
    let penalty = u1p5_r0p8_rows("science-6p5-penalty/state/discocyte_u1.5_r0.8.h5");
    let penalty_fine = u1p5_r0p8_rows("science-6p5-penalty/check-penalty-walls-1p4.h5");
    let apart = |fine: &[TimeSample], coarse: &[TimeSample]| {
        assert!((fine.last().unwrap().t_s - 0.1).abs() < 1e-12, "the check runs to 100 ms");
        fine.iter().zip(coarse).fold((0.0f64, 0.0f64), |(dy, dz), (f, c)| {
            assert_eq!(f.t_s, c.t_s);
            (dy.max((f.centroid_um[1] - c.centroid_um[1]).abs()), dz.max((f.centroid_um[2] - c.centroid_um[2]).abs()))
        })
    };
    let (ey, ez) = apart(&exact_fine, &exact);
    let (py, pz) = apart(&penalty_fine, &penalty);
    let at = |r: &[TimeSample], t: f64| r.iter().find(|s| (s.t_s - t).abs() < 1e-9).unwrap().centroid_um[1];
    let (gap, gap_fine) = (at(&exact, 0.1) - at(&penalty, 0.1), at(&exact_fine, 0.1) - at(&penalty_fine, 0.1));
    eprintln!("wall edge 1.4 against 2 um over 100 ms: exact dy {ey:.4} dz {ez:.4}, penalty dy {py:.4} dz {pz:.4} um; the models {gap:.3} / {gap_fine:.3} um apart at 100 ms");
    assert!(ey < 0.035 && ez < 0.015 && py < 0.02 && pz < 0.01, "{ey} {ez} {py} {pz}");
    assert!(gap > 0.2 && gap_fine > 0.2 && (gap - gap_fine).abs() < 0.03, "{gap} {gap_fine}");
}

/// The ~2.5 mm/s r_init 0.8 um discocyte with the paper's penalty walls (study
/// `science-6p5-penalty`) ended a steady centred croissant moving as a rigid body at 2.04 s,
/// where exact no-slip walls keep the same start an off-centre slipper
/// (`the_studys_u1p5_r_init_0p8_run_ended_an_off_centre_slipper_at_2p5_mm_s`).
#[test]
fn with_the_papers_walls_the_u1p5_r_init_0p8_run_ended_a_centred_croissant() {
    assert_penalty_u1p5_run_ended_a_steady_centred_croissant("discocyte_u1.5_r0.8", 0.8);
}

/// The ~2.5 mm/s column's run `run_id` (r_init `r_init_um`) with the paper's penalty walls ended
/// a steady centred croissant moving as a rigid body at 2.4-2.7 mm/s.
fn assert_penalty_u1p5_run_ended_a_steady_centred_croissant(run_id: &str, r_init_um: f64) {
    let (_, _, s) = ended_run_of("science-6p5-penalty", run_id, r_init_um);
    assert_centred_rigid_croissant_at(&s, "steady", 2.4..=2.7);
}

/// The ~2.5 mm/s r_init 0.6 um discocyte with the paper's penalty walls ended a steady centred
/// croissant moving as a rigid body at 1.84 s (session 27), where exact no-slip walls keep the
/// same start a slipper (`the_studys_u1p5_r_init_0p6_run_ended_the_same_slipper_at_2p5_mm_s`).
#[test]
fn with_the_papers_walls_the_u1p5_r_init_0p6_run_ended_a_centred_croissant() {
    assert_penalty_u1p5_run_ended_a_steady_centred_croissant("discocyte_u1.5_r0.6", 0.6);
}

/// The ~2.5 mm/s r_init 1.2 um discocyte with the paper's penalty walls ended a steady centred
/// croissant moving as a rigid body at 3.26 s (session 56; its radial drift -0.025 um/s, -0.017
/// before: coming in), where exact no-slip walls keep the same start a slipper swinging at y
/// 0.9-1.5 um (`the_studys_u1p5_r_init_1p2_run_ended_a_slipper_swinging_slower_than_the_window`):
/// with the paper's walls every start of the ~2.5 mm/s column tried, 0.4 to 1.2 um, ends a
/// croissant (0.4 um ended in session 57). On its way it passed through the paper's "intermediate slipper
/// state": over 0.05-0.5 s it swung 0.54-1.04 um off the axis, its asphericity 0.081 on average
/// (0.028-0.17; the croissant's 0.020), reached the axis at 0.79 s and stayed within 0.1 um of it
/// from then on, while its shape relaxed to the croissant's for ~2.5 s (asphericity 0.012 at 0.75
/// s, 0.020-0.021 from 2 s).
#[test]
fn with_the_papers_walls_the_u1p5_r_init_1p2_run_ended_a_centred_croissant() {
    assert_penalty_u1p5_run_ended_a_steady_centred_croissant("discocyte_u1.5_r1.2", 1.2);
    let rows = state_rows("science-6p5-penalty", "discocyte_u1.5_r1.2");
    let swing: Vec<&rbc_schema::results::TimeSample> = rows.iter().filter(|r| (0.05..=0.5).contains(&r.t_s)).collect();
    let (near, far, _) = min_max_mean(&swing.iter().map(|r| radial_um(r)).collect::<Vec<_>>());
    let (_, _, mean) = min_max_mean(&swing.iter().map(|r| r.asphericity).collect::<Vec<_>>());
    assert!(near > 0.5 && far > 1.0 && mean > 0.07, "0.05-0.5 s: radial {near}-{far} um, mean asphericity {mean}");
    let arrived = rows.iter().find(|r| radial_um(r) < 0.1).unwrap().t_s;
    assert!((0.75..0.85).contains(&arrived), "on the axis at {arrived} s");
    assert!(rows.iter().filter(|r| r.t_s >= arrived).all(|r| radial_um(r) < 0.1), "within 0.1 um of the axis from {arrived} s on");
}

/// The ~2.5 mm/s r_init 0.4 um discocyte with the paper's penalty walls ended a steady centred
/// croissant moving as a rigid body at 2.73 s (session 57; 0.036 um off the axis, its radial drift
/// -0.015 um/s, +0.003 before: the slow outward creep of 2.4-2.6 s, +0.010-0.011 um/s, stopped),
/// as exact no-slip walls end the same start (a croissant there too). So with the paper's walls
/// every start of the ~2.5 mm/s column, 0.4 to 1.2 um, ends a croissant: the paper's finding at
/// this velocity.
#[test]
fn with_the_papers_walls_the_u1p5_r_init_0p4_run_ended_a_centred_croissant() {
    assert_penalty_u1p5_run_ended_a_steady_centred_croissant("discocyte_u1.5_r0.4", 0.4);
    let rows = state_rows("science-6p5-penalty", "discocyte_u1.5_r0.4");
    // within 0.1 um of the axis and at a croissant's asphericity over its last 0.5 s
    let t_end = rows.last().unwrap().t_s;
    let window: Vec<_> = rows.iter().filter(|r| r.t_s >= t_end - 0.5).collect();
    let radial = window.iter().map(|r| radial_um(r)).fold(0.0f64, f64::max);
    let asphericity = window.iter().map(|r| r.asphericity).fold(0.0f64, f64::max);
    assert!(radial <= 0.1 && asphericity <= 0.025, "over its last 0.5 s: radial <= {radial} um, asphericity <= {asphericity}");
}

/// The ~0.5 mm/s croissant start with the paper's penalty walls (session 58: this study's ~1 mm/s
/// r_init 0.4 um croissant at its end, 4.06 s, started 0.2 um off the axis; the paper's Fig. 5 b
/// start shape) ended `steady` at 587.0 ms: a rigid croissant 0.142 um off the axis at 0.515 mm/s,
/// never further out than it started, where every discocyte started at ~0.5 mm/s (0.2, 0.4 and
/// 1.2 um) leaves the axis for one slipper orbit (the discocyte from the same 0.2 um: 0.333 um off
/// it at 0.45 s, 1.0 um at 1.0 s). So with the paper's walls ~0.5 mm/s is bistable, as the paper
/// finds when its cells start as croissants below ~0.7 mm/s ("stable croissants emerge at very
/// low velocities"). Judged 0.5 s after a start from a settled shape; the study's README, "A check:
/// the ~0.5 mm/s croissant start continued", follows it past the verdict.
#[test]
fn with_the_papers_walls_the_u0p31_croissant_start_held_a_croissant_where_discocytes_leave_the_axis() {
    let (_, _, s) = ended_run_of("science-6p5-penalty", "croissant_u0.31_r0.2", 0.2);
    assert_centred_rigid_croissant_at(&s, "steady", 0.45..=0.55);
    let rows = state_rows("science-6p5-penalty", "croissant_u0.31_r0.2");
    assert!(rows.iter().all(|r| radial_um(r) <= 0.2 + 1e-3), "further out than its start");
    let t_end = rows.last().unwrap().t_s;
    let (near, far, _) = min_max_mean(&rows.iter().filter(|r| r.t_s >= t_end - 0.3).map(radial_um).collect::<Vec<_>>());
    assert!(near > 0.13 && far < 0.15, "over its last 0.3 s: radial {near}-{far} um");
    let disc = state_rows("science-6p5-penalty", "discocyte_u0.31_r0.2");
    let at = |t: f64| disc.iter().find(|r| r.t_s >= t).map(radial_um).unwrap();
    assert!(at(0.45) > 0.3 && at(1.0) > 0.9, "the discocyte from 0.2 um: {} um at 0.45 s, {} at 1.0 s", at(0.45), at(1.0));
}

/// The ~6.5 mm/s column with the paper's penalty walls (study `science-6p5-penalty`, sessions
/// 28-31) in its committed state (both runs have ended since: r_init 1.2 um `periodic` at 984.8 ms
/// and 0.4 um at 896.6 ms, the tests below): both of the paper's shapes from the two starts
/// that give both with exact no-slip walls. Over each run's last 100 ms (two swings of the
/// slipper's ~50 ms orbit), against the exact-wall run of the same start (science-6p5) at the
/// same times:
/// - r_init 1.2 um swings as an off-centre slipper: y 1.1-1.6 um (the paper's slippers: 0.8-1.5),
///   |z| < 0.15 um, its asphericity swinging by more than 0.1 (0.06-0.22), and its mean y at
///   least 0.15 um nearer the axis than the exact-wall slipper's (measured over 884.8-984.8 ms:
///   1.321 against 1.571 um);
/// - r_init 0.4 um is a croissant off the axis by less than 0.4 um on average and 0.45 um at
///   most (measured over 796.6-896.6 ms: 0.383 and 0.402; the exact-wall
///   croissant of the same start 0.312 at those times, settling at 0.31), its asphericity steady
///   within 0.03 at 0.06-0.10 (measured 0.075-0.089; the exact-wall one settled at 0.072);
///
/// each at 6.2-6.7 mm/s.
#[test]
fn with_the_papers_walls_the_u3p8_runs_keep_both_shapes_over_their_last_100_ms() {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let range = |v: &[f64]| (v.iter().copied().fold(f64::INFINITY, f64::min), v.iter().copied().fold(f64::NEG_INFINITY, f64::max));
    for (run_id, slipper) in [("discocyte_u3.8_r1.2", true), ("discocyte_u3.8_r0.4", false)] {
        let penalty = state_rows("science-6p5-penalty", run_id);
        let exact = state_rows("science-6p5", run_id);
        let t_end = penalty.last().unwrap().t_s;
        assert!(t_end >= 0.5 && exact.last().unwrap().t_s >= t_end, "{run_id}: penalty to {t_end} s, exact walls to {} s", exact.last().unwrap().t_s);
        let last = |r: &[rbc_schema::results::TimeSample]| -> Vec<rbc_schema::results::TimeSample> { r.iter().filter(|s| s.t_s >= t_end - 0.1 && s.t_s <= t_end).cloned().collect() };
        let (p, e) = (last(&penalty), last(&exact));
        let radial = |w: &[rbc_schema::results::TimeSample]| w.iter().map(radial_um).collect::<Vec<_>>();
        let (y, z): (Vec<f64>, Vec<f64>) = p.iter().map(|s| (s.centroid_um[1], s.centroid_um[2])).unzip();
        let asphericity: Vec<f64> = p.iter().map(|s| s.asphericity).collect();
        let u: Vec<f64> = p.iter().map(|s| s.velocity_mm_s[0]).collect();
        let (r_p, r_e) = (radial(&p), radial(&e));
        eprintln!(
            "{run_id} to {:.1} ms, last 100 ms: y {:.3?} z {:.3?} radial mean {:.3} (exact walls {:.3}) asphericity {:.3?} u {:.2?} mm/s",
            t_end * 1e3, range(&y), range(&z), mean(&r_p), mean(&r_e), range(&asphericity), range(&u)
        );
        let (u_lo, u_hi) = range(&u);
        assert!(u_lo >= 6.2 && u_hi <= 6.7, "{run_id}: {u_lo}-{u_hi} mm/s");
        let (a_lo, a_hi) = range(&asphericity);
        if slipper {
            let (y_lo, y_hi) = range(&y);
            assert!(y_lo >= 1.1 && y_hi <= 1.6, "{run_id}: y {y_lo}-{y_hi} um");
            assert!(z.iter().all(|z| z.abs() < 0.15), "{run_id}: z {:?}", range(&z));
            assert!(a_hi - a_lo > 0.1, "{run_id}: a slipper's swing, asphericity {a_lo}-{a_hi}");
            assert!(mean(&r_e) - mean(&r_p) >= 0.15, "{run_id}: radial {} against exact walls' {}", mean(&r_p), mean(&r_e));
        } else {
            assert!(mean(&r_p) < 0.4 && range(&r_p).1 < 0.45, "{run_id}: radial mean {} max {}", mean(&r_p), range(&r_p).1);
            assert!(a_hi - a_lo < 0.03 && (0.06..=0.1).contains(&a_lo) && a_hi <= 0.1, "{run_id}: asphericity {a_lo}-{a_hi}");
        }
    }
}

/// A run with the paper's walls that ended as their ~6.5 mm/s croissant: `periodic` over the
/// study's 0.5 s window, not tumbling, nearly a rigid body (non-rigid membrane speed under 2 % of
/// the cell's) whose membrane circulates at 2-3 Hz (a tank-treading croissant since session 51,
/// as the exact-wall ones: `assert_centred_tank_treading_croissant`), off the axis along z
/// (|mean y| < 0.05 um).
fn assert_tank_treading_croissant_along_z(s: &rbc_schema::results::RunSummary) {
    assert_eq!((s.status.as_str(), s.final_shape, s.tank_treading, s.tumbling), ("periodic", FinalShape::Croissant, true, false));
    assert!(s.evidence["steady_duration_s"] >= 0.5 - 1e-9, "the study's 0.5 s window");
    assert!(s.evidence["nonrigid_ratio"] < 0.02, "nearly a rigid body: {}", s.evidence["nonrigid_ratio"]);
    assert!((2.0..3.0).contains(&s.evidence["tt_frequency_hz"]), "tank-treading at {} Hz", s.evidence["tt_frequency_hz"]);
    assert!(s.mean_y_um.abs() < 0.05, "along z: y {} z {}", s.mean_y_um, s.mean_z_um);
}

/// The ~6.5 mm/s r_init 0.4 um discocyte with the paper's penalty walls ended `periodic` at 896.6
/// ms (session 31) over the study's 0.5 s window: a croissant moving nearly as a rigid body (its
/// non-rigid membrane speed 0.7 % of the cell's, its membrane circulating at 2.76 Hz: a
/// tank-treading croissant since session 51), not tumbling, off the axis
/// along z by 0.38 um on average (0.365-0.402 um on a 91 ms beat), at 6.45 mm/s (measured
/// 2026-11-29). The exact-wall run of the same start ended the same shape at 0.31 um
/// (`the_studys_r_init_0p4_run_ended_a_centred_tank_treading_croissant`, at most 0.33): the paper's walls
/// hold it ~0.07 um further out, so its largest offset reaches 0.4 um (the classifier's
/// `centred_um` was 0.4 um until session 60, now 0.6: `a_croissant_held_further_out_stays_a_croissant_and_a_slipper_nearer_the_axis_a_slipper`). With r_init 1.2 um a slipper (below), the paper's walls keep both
/// of the paper's shapes at ~6.5 mm/s.
#[test]
fn with_the_papers_walls_the_u3p8_r_init_0p4_run_ended_a_tank_treading_croissant_further_off_the_axis() {
    let (_, _, s) = ended_run_of("science-6p5-penalty", "discocyte_u3.8_r0.4", 0.4);
    let (_, _, exact) = ended_run_of("science-6p5", "discocyte_u3.8_r0.4", 0.4);
    assert_tank_treading_croissant_along_z(&s);
    assert!((0.35..0.4).contains(&s.mean_radial_um) && s.evidence["radial_max_um"] < 0.42, "off the axis by {} um, at most {}", s.mean_radial_um, s.evidence["radial_max_um"]);
    assert!((6.2..=6.7).contains(&s.mean_velocity_mm_s), "{} mm/s", s.mean_velocity_mm_s);
    assert!(s.mean_radial_um - exact.mean_radial_um >= 0.05, "{} um against exact walls' {}", s.mean_radial_um, exact.mean_radial_um);
}

/// `rbc-predict` on the paper's-walls study: it reads the study's state files as they are
/// (`--sims` repeated; a run still going has no steady state and is skipped) and finds the start
/// that divides croissants from slippers in each velocity column from the ended runs (session 33:
/// r_trans 0.9 um in [0.8, 1.0] at ~6.4 mm/s, croissants from 0.4 and 0.8 um and slippers from
/// 1.0 and 1.2; at ~2.5 mm/s croissants from every ended start, 0.6 and 0.8 um, so no slipper
/// bounds it and r_trans is infinite; session 38: at ~4 mm/s the croissant from 0.8 um and the
/// slipper from 1.2 um, r_trans 1.0 in [0.8, 1.2], and since session 41 the croissant from 1.0 um,
/// 1.1 in [1.0, 1.2]; at ~1 mm/s the croissant from 0.4 um and the slipper from 1.2 um, r_trans
/// 0.8 in [0.4, 1.2], since session 42 the slipper from 0.8 um, 0.6 in [0.4, 0.8], and since
/// session 48 the slipper from 0.6 um, 0.5 in [0.4, 0.6]; session 46:
/// at ~0.5 mm/s the slipper from 1.2 um, the column's one ended run, r_trans 0 in [0, 1.2]; session
/// 49: at ~3.6 mm/s the croissant from 1.2 um, the column's one run, so r_trans is infinite). The one
/// run still going in the ~6.5 mm/s
/// column, from 0.6 um, lies inside the croissants' starts: a croissant leaves the bracket as it is (a slipper would cross
/// the croissant from 0.8 um, a second switch this test would then report).
#[test]
fn rbc_predict_reads_the_papers_walls_study_and_brackets_the_switch_at_6p5_mm_s() {
    let dir = tempfile::tempdir().unwrap();
    let entry = dir.path().join("entry.csv");
    std::fs::write(&entry, "pressure_mbar,y_um,velocity_mm_s\n600.0,0.3,6.3\n600.0,1.0,6.3\n").unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_rbc-predict"));
    for f in &state_files("science-6p5-penalty") {
        cmd.arg("--sims").arg(f);
    }
    let out = cmd.arg("--entry").arg(&entry).arg("--out").arg(dir.path().join("prediction")).output().unwrap();
    assert!(out.status.success(), "rbc-predict failed: {}", String::from_utf8_lossy(&out.stderr));
    let csv = std::fs::read_to_string(dir.path().join("prediction/thresholds.csv")).unwrap();
    eprintln!("{csv}");
    let rows: Vec<Vec<f64>> = csv.lines().skip(1).map(|l| l.split(',').skip(1).map(|v| v.parse::<f64>().unwrap()).collect()).collect();
    let column = |lo: f64, hi: f64| rows.iter().find(|r| (lo..hi).contains(&r[0])).unwrap_or_else(|| panic!("no column at {lo}-{hi} mm/s in\n{csv}"));
    // the column between `lo` and `hi` mm/s has r_trans `r_trans` in the bracket [`r_lo`, `r_hi`]
    let assert_bracket = |lo: f64, hi: f64, r_trans: f64, r_lo: f64, r_hi: f64| {
        let c = column(lo, hi);
        let (a, b) = (c[2].min(c[3]), c[2].max(c[3]));
        assert!((a - r_lo).abs() < 1e-9 && (b - r_hi).abs() < 1e-9 && (c[1] - r_trans).abs() < 1e-9, "{lo}-{hi} mm/s: r_trans {} in [{}, {}]", c[1], c[2], c[3]);
    };
    assert_bracket(6.2, 6.7, 0.9, 0.8, 1.0);
    let slow = column(2.4, 2.7);
    assert!(slow[2] >= 0.8 && slow[1] > 0.8, "~2.5 mm/s: croissants from every ended start up to 0.8 um, r_trans {} in [{}, {}]", slow[1], slow[2], slow[3]);
    // ~3.2 mm/s (session 43): the one start, 1.2 um, ended a croissant: croissants only up to 1.2 um
    let band = column(3.1, 3.35);
    assert!(band[2] >= 1.2 && band[1].is_infinite(), "~3.2 mm/s: croissants from 1.2 um, r_trans {} in [{}, {}]", band[1], band[2], band[3]);
    // ~3.6 mm/s (session 49): the one start, 1.2 um, ended a croissant: croissants only up to 1.2 um
    let upper = column(3.5, 3.8);
    assert!(upper[2] >= 1.2 && upper[1].is_infinite(), "~3.6 mm/s: croissants from 1.2 um, r_trans {} in [{}, {}]", upper[1], upper[2], upper[3]);
    // ~4 mm/s (session 41): the croissant from 1.0 um (0.8 um before it) and the slipper from 1.2 um
    assert_bracket(3.9, 4.2, 1.1, 1.0, 1.2);
    // ~1 mm/s (session 48): the croissant from 0.4 um and the slipper from 0.6 um (0.8 um before
    // it, session 42, and 1.2 um before that)
    assert_bracket(0.9, 1.15, 0.5, 0.4, 0.6);
    // ~0.5 mm/s (session 46): the slipper from 1.2 um alone, so slippers from every ended start
    assert_bracket(0.45, 0.55, 0.0, 0.0, 1.2);
}

/// The ~6.5 mm/s r_init 0.6 um discocyte with the paper's penalty walls (study
/// `science-6p5-penalty`, session 31) comes in to the axis where the exact-wall run of the same
/// start (science-6p5) swings out to its slipper orbit: over 120-150 ms the penalty-wall cell
/// stays within 0.1 um of the axis in y and 0.3 um in all (measured y 0.020 and 0.013 um at 120
/// and 150 ms, z 0.19), while the exact-wall cell is at y 0.5 um or more and passes 0.9 um by
/// 150 ms (measured 0.578 at 120 ms, 0.965 at 150). With exact walls the divide between the two
/// shapes' starts lies between 0.5 and 0.6 um (the paper's: ~0.7 um); where this run ends will say
/// whether the paper's walls move it. The samples before 150 ms stay as the run goes on.
#[test]
fn with_the_papers_walls_the_u3p8_r_init_0p6_run_comes_in_where_the_exact_wall_run_swings_out() {
    let w = both_walls_window("discocyte_u3.8_r0.6", 0.12, 0.15);
    assert!(w.penalty_y_max < 0.1 && w.penalty_radial_max < 0.3, "paper's walls: |y| up to {}, radial up to {}", w.penalty_y_max, w.penalty_radial_max);
    assert!(w.exact_y_min >= 0.5 && w.exact_y_end > 0.9, "exact walls: y from {}, {} at 150 ms", w.exact_y_min, w.exact_y_end);
}

/// The ~6.5 mm/s r_init 0.8 um discocyte with the paper's penalty walls (session 31) comes in as
/// the 0.6 um one does: its y (0.70 um at the start; r_init is the distance from the axis) falls
/// after a brief rise to 0.76 um in the first 3 ms, without swinging out (0.47 um at 50 ms, 0.15
/// at 150), and over 150-200 ms it stays within 0.16 um of the axis in y and 0.3 um in all, ending the
/// window at y 0.01 (measured |y| <= 0.152, radial <= 0.298, y 0.009 um at 200 ms), while the
/// exact-wall cell of the same start has swung out to its slipper orbit, y 1.27-1.57 um over the
/// same window (it ended a slipper). So with the paper's walls the divide between the two shapes'
/// starts lies above 0.8 um, unless this run swings out later. The samples before 200 ms stay as
/// the run goes on.
#[test]
fn with_the_papers_walls_the_u3p8_r_init_0p8_run_comes_in_where_the_exact_wall_run_is_a_slipper() {
    let w = both_walls_window("discocyte_u3.8_r0.8", 0.15, 0.2);
    assert!(w.penalty_y_max < 0.16 && w.penalty_radial_max < 0.3 && w.penalty_y_end.abs() < 0.05, "paper's walls: |y| up to {}, radial up to {}, y {} at 200 ms", w.penalty_y_max, w.penalty_radial_max, w.penalty_y_end);
    assert!(w.exact_y_min >= 1.2, "exact walls: y from {}", w.exact_y_min);
}

/// The ~4 mm/s r_init 1.2 um discocyte with the paper's penalty walls (session 32, from rest)
/// ended `periodic` at 1631.2 ms (session 35) over the study's 0.5 s window, an off-centre
/// tank-treading slipper (orbit period 91 ms, y 0.87-1.18 um, mean y 0.999, z 0.005 um, 4.05
/// mm/s, tank-treading at 4.8 Hz; measured 2026-11-29): the same shape as with exact no-slip walls
/// (`the_studys_u2p4_r_init_1p2_run_ended_an_off_centre_slipper_at_4_mm_s`: mean y 1.32 um),
/// 0.3 um nearer the axis and inside the paper's 0.8-1.5 um. With the paper's walls croissants only
/// at ~2.5 mm/s, and a slipper again at ~4 mm/s: the paper's "both shapes above ~3 mm/s".
#[test]
fn with_the_papers_walls_the_u2p4_r_init_1p2_run_ended_an_off_centre_tank_treading_slipper() {
    assert_penalty_slipper_nearer_the_axis("discocyte_u2.4_r1.2", 3.9..=4.2, 0.2);
}

/// The ~1 mm/s r_init 1.2 um discocyte with the paper's penalty walls (from rest in session 35,
/// stepped with ROS34PRw) ended `periodic` at 2545.4 ms (session 38), judged over four of its own
/// periods (0.332 s; window 1.22-2.55 s): an off-centre tank-treading slipper (mean y 1.083, z
/// 0.000 um, radial 0.86-1.45 um, tank-treading at 1.31 Hz, 1.03 mm/s; measured 2026-11-29), the
/// same shape as with exact no-slip walls
/// (`the_studys_u0p63_r_init_1p2_run_ended_a_slowly_tank_treading_slipper_at_1_mm_s`: mean y 1.195
/// um, period 0.308 s), 0.11 um nearer the axis and inside the paper's 0.8-1.5 um: the paper's
/// walls keep the paper's slipper below ~1 mm/s. Rendered as an experiment would see it, its last
/// shape is a slipper to `rbc-analyze` too.
#[test]
fn with_the_papers_walls_the_u0p63_r_init_1p2_run_ended_an_off_centre_tank_treading_slipper() {
    let (state, s) = assert_penalty_slipper_nearer_the_axis("discocyte_u0.63_r1.2", 0.95..=1.1, 0.1);
    let (period, f_tt) = (s.evidence["period_s"], s.evidence["tt_frequency_hz"]);
    assert!((0.3..0.36).contains(&period), "period {period} s");
    assert!((1.0..1.6).contains(&f_tt), "tank-treading at {f_tt} Hz");
    closed_loop_row(&state, false, "slipper");
}

/// The ~1 mm/s r_init 0.8 um discocyte with the paper's penalty walls (from rest in session 39,
/// stepped with ROS34PRw) ended `periodic` at 4019.6 ms (session 42), judged over four of its own
/// periods (0.331 s; window 2.69-4.02 s): the 1.2 um run's tank-treading slipper
/// (`with_the_papers_walls_the_u0p63_r_init_1p2_run_ended_an_off_centre_tank_treading_slipper`):
/// mean y 1.085 against 1.083 um, radial 0.87-1.45 against 0.86-1.45 um, period 0.3312 against
/// 0.3318 s, 1.028 mm/s both (measured 2026-11-30). With the croissant from 0.4 um the paper's
/// walls put the ~1 mm/s switch between 0.4 and 0.8 um (rbc-predict: r_trans 0.6 um; exact walls:
/// between 0.2 and 0.4).
#[test]
fn with_the_papers_walls_the_u0p63_r_init_0p8_run_ended_the_1p2_runs_slipper() {
    assert_ended_on_the_u0p63_r_init_1p2_slipper_orbit("discocyte_u0.63_r0.8", 0.8);
}

/// Run `run_id` (from `r_init` um) of the paper's-walls study ended the ~1 mm/s r_init 1.2 um
/// run's tank-treading slipper: its mean y within 0.01 um, its radial range within 0.02 um and its
/// period within 1 % of that run's.
fn assert_ended_on_the_u0p63_r_init_1p2_slipper_orbit(run_id: &str, r_init: f64) {
    let (_, _, s) = ended_run_of("science-6p5-penalty", run_id, r_init);
    let (_, _, orbit) = ended_run_of("science-6p5-penalty", "discocyte_u0.63_r1.2", 1.2);
    assert_off_centre_slipper_at(&s, 0.95..=1.1);
    assert!(s.tank_treading, "a tank-treading slipper");
    assert!((s.mean_y_um - orbit.mean_y_um).abs() < 0.01, "mean y {} against {} um", s.mean_y_um, orbit.mean_y_um);
    for k in ["radial_min_um", "radial_max_um"] {
        assert!((s.evidence[k] - orbit.evidence[k]).abs() < 0.02, "{k}: {} against {} um", s.evidence[k], orbit.evidence[k]);
    }
    assert!((s.evidence["period_s"] / orbit.evidence["period_s"] - 1.0).abs() < 0.01, "period {} against {} s", s.evidence["period_s"], orbit.evidence["period_s"]);
}

/// The ~1 mm/s r_init 0.6 um discocyte with the paper's penalty walls (from rest in session 46,
/// stepped with ROS34PRw) ended `periodic` at 4110.0 ms (session 48), judged over four of its own
/// periods (0.3312 s; window 2.79-4.11 s): the 0.8 and 1.2 um runs' tank-treading slipper (mean y
/// 1.086 against 1.085 and 1.083 um, radial 0.87-1.45 um, tank-treading at 1.21 Hz, 1.028 mm/s;
/// measured 2026-12-01). Its z at the top of each swing alternated in sign from one swing to the
/// next, decaying by ~0.72 a swing from 0.047 um at 1.8 s to 0.006 at 3.8 s (a period-doubled
/// orbit that decays, as the exact-wall ~2.5 mm/s r_init 0.6 um one did).
/// With the croissant from 0.4 um the paper's walls put the ~1 mm/s switch between 0.4 and 0.6 um
/// (rbc-predict: r_trans 0.5 um; exact walls: between 0.2 and 0.4).
#[test]
fn with_the_papers_walls_the_u0p63_r_init_0p6_run_ended_the_1p2_runs_slipper() {
    assert_ended_on_the_u0p63_r_init_1p2_slipper_orbit("discocyte_u0.63_r0.6", 0.6);
    let (_, _, croissant) = ended_run_of("science-6p5-penalty", "discocyte_u0.63_r0.4", 0.4);
    assert_eq!(croissant.final_shape, FinalShape::Croissant, "the switch lies between 0.4 and 0.6 um");
}

/// The ~4 mm/s r_init 0.8 um discocyte with the paper's penalty walls (from rest in session 33)
/// ended `periodic` at 2535.4 ms (session 38): a croissant on the axis (mean radial offset 0.047
/// um, at most 0.062, along z), a rigid body (non-rigid speed 0.06 % of the cell's) beating with
/// a period of 0.110 s, 4.08 mm/s (measured 2026-11-29), where the exact-wall run of the same start
/// ended a slipper. With the slipper from 1.2 um
/// (`with_the_papers_walls_the_u2p4_r_init_1p2_run_ended_an_off_centre_tank_treading_slipper`) the
/// paper's walls put the ~4 mm/s switch between 0.8 and 1.2 um (exact walls: 0.6-0.8), and keep
/// both shapes there, the paper's "both shapes above ~3 mm/s".
#[test]
fn with_the_papers_walls_the_u2p4_r_init_0p8_run_ended_a_croissant_on_the_axis_where_the_exact_wall_run_is_a_slipper() {
    assert_penalty_croissant_near_the_axis_where_exact_walls_give_a_slipper("discocyte_u2.4_r0.8", 0.8, "periodic", 3.9..=4.2);
}

/// The ~4 mm/s r_init 0.8 um start goes in to the axis also without the stepping's drift
/// (`check-u2.4-r0.8-coupled`, session 39): the study's run (stepped without the walls' answer to
/// the cell in its stages, which drifts the cell towards the axis, ~0.085 um/s on the ~4 mm/s
/// slipper's orbit, `solver/README.md` "Session 36") left its fast start at y ~0.46 um by 50 ms
/// and lingered there until ~100 ms, moving sideways slower than that drift. The same 300 ms from
/// rest with the walls coupled (`integrator.wall_coupling`, "Session 37") linger 0.01-0.02 um
/// farther out (y 0.466-0.481 um against 0.458-0.466 from 50 to 100 ms; measured: the coupled
/// run moves out against the study's at 0.17 um/s over the first 100 ms), then go in on the same
/// path: at most 0.030 um from the study's in y (0.0296 at 185 ms) and 0.020 in z, across the
/// axis in y by 250 ms and within 0.13 um of it at 300 ms (0.128; the study's 0.121). The croissant
/// is the walls', not the stepping's.
#[test]
fn with_the_papers_walls_the_u2p4_r_init_0p8_start_goes_in_also_with_the_walls_coupled() {
    let run = "discocyte_u2.4_r0.8";
    let study = state_rows("science-6p5-penalty", run);
    let coupled = study_file_rows("science-6p5-penalty/check-u2.4-r0.8-coupled.h5", run);
    assert!(coupled.len() == 1501 && (coupled[1500].t_s - 0.3).abs() < 1e-9, "300 ms at 0.2 ms: {} rows", coupled.len());
    let (dy, dz) = largest_apart_yz(&coupled, &study);
    assert!(dy < 0.035 && dz < 0.025, "the same path: at most {dy:.4} um in y and {dz:.4} in z from the study's");
    let y = |lo: f64, hi: f64| coupled.iter().filter(move |c| (lo..=hi).contains(&c.t_s)).map(|c| c.centroid_um[1]);
    let (ymin, ymax) = (y(0.05, 0.1).fold(f64::INFINITY, f64::min), y(0.05, 0.1).fold(f64::NEG_INFINITY, f64::max));
    assert!(ymin > 0.46 && ymax < 0.49, "the linger: y {ymin:.3}-{ymax:.3} um from 50 to 100 ms");
    assert!(y(0.25, 0.3).all(|v| v < 0.0), "across the axis in y by 250 ms");
    let end = coupled[1500].centroid_um;
    assert!(end[1].hypot(end[2]) < 0.13, "within 0.13 um of the axis at 300 ms: {end:?}");
}

/// The ~1 mm/s r_init 0.4 um discocyte with the paper's penalty walls (from rest in session 35,
/// stepped with ROS34PRw) ended `steady` at 4064.4 ms (session 38): a centred croissant (mean
/// radial offset 0.077 um, at most 0.081, along y), a rigid body (non-rigid speed 0.08 % of the
/// cell's), neither tank-treading nor tumbling, 1.06 mm/s (measured 2026-11-29). The exact-wall
/// run of the same start left the axis and ended the slipper of r_init 1.2 um. With the slipper
/// from 1.2 um (`with_the_papers_walls_the_u0p63_r_init_1p2_run_ended_an_off_centre_tank_treading_slipper`)
/// the paper's walls keep both shapes at ~1 mm/s, as the paper finds below ~1 mm/s, with the switch
/// between 0.4 and 1.2 um (exact walls: 0.2-0.4).
#[test]
fn with_the_papers_walls_the_u0p63_r_init_0p4_run_ended_a_centred_croissant_where_the_exact_wall_run_is_a_slipper() {
    assert_penalty_croissant_near_the_axis_where_exact_walls_give_a_slipper("discocyte_u0.63_r0.4", 0.4, "steady", 0.95..=1.15);
}

/// Run `run_id` (started at `r_init` um) with the paper's penalty walls ended `status`, a centred
/// rigid croissant at a cell velocity in `mm_s` ([`assert_centred_rigid_croissant_at`]) within 0.1
/// um of the axis, where the exact-wall run of the same start ended a slipper.
fn assert_penalty_croissant_near_the_axis_where_exact_walls_give_a_slipper(run_id: &str, r_init: f64, status: &str, mm_s: std::ops::RangeInclusive<f64>) {
    assert_penalty_croissant_near_the_axis(run_id, r_init, status, mm_s);
    let (_, _, exact) = ended_run(run_id, r_init);
    assert_eq!(exact.final_shape, FinalShape::Slipper, "the exact-wall run of the same start");
}

/// Run `run_id` (r_init 1.2 um) with the paper's penalty walls ended `periodic`, an off-centre
/// tank-treading slipper at a cell velocity in `mm_s`, inside the paper's slipper offsets (0.8-1.5
/// um), and at least `nearer_um` nearer the axis than the exact-wall run of the same start; its
/// state file and summary.
fn assert_penalty_slipper_nearer_the_axis(run_id: &str, mm_s: std::ops::RangeInclusive<f64>, nearer_um: f64) -> (PathBuf, rbc_schema::results::RunSummary) {
    let (state, _, s) = ended_run_of("science-6p5-penalty", run_id, 1.2);
    assert_off_centre_slipper_at(&s, mm_s);
    assert!(s.tank_treading, "a tank-treading slipper");
    assert!((0.8..=1.5).contains(&s.mean_radial_um), "inside the paper's slipper offsets: {} um", s.mean_radial_um);
    let (_, _, exact) = ended_run(run_id, 1.2);
    assert!(exact.mean_radial_um - s.mean_radial_um >= nearer_um, "nearer the axis than with exact walls: {} against {} um", s.mean_radial_um, exact.mean_radial_um);
    (state, s)
}

/// The ~6.5 mm/s r_init 1.0 um discocyte with the paper's penalty walls (session 32, from rest)
/// swings out where the 0.8 um one comes in: its y dips from 0.87 to 0.59 um (26 ms), swings out
/// again, and over 150-190 ms stays at y >= 0.85 um, reaching 1.19 (measured 0.874-1.186 um), as
/// the exact-wall runs do on their way to their slipper orbits, while the 0.8 um run of the same
/// study stays within 0.16 um of the axis in y over the same window. So with the paper's walls
/// the start that divides the two shapes lies between 0.8 and 1.0 um, unless the 1.0 um run comes
/// back in (the walls' stepping bias points towards the axis, solver README "Session 25": a run
/// that swings out against it is not its artefact). The samples before 190 ms stay as the runs go
/// on.
#[test]
fn with_the_papers_walls_the_u3p8_r_init_1p0_run_swings_out_where_0p8_comes_in() {
    let window = |run_id: &str| penalty_window(run_id, 0.15, 0.19).iter().map(|s| s.centroid_um[1]).collect::<Vec<f64>>();
    let (out, r#in) = (window("discocyte_u3.8_r1"), window("discocyte_u3.8_r0.8"));
    assert!(out.len() >= 100 && r#in.len() >= 100, "samples: {} and {}", out.len(), r#in.len());
    let (lo, hi, _) = min_max_mean(&out);
    let in_max = r#in.iter().map(|y| y.abs()).fold(0.0, f64::max);
    eprintln!("150-190 ms: r_init 1.0 um y {lo:.3}-{hi:.3} um, r_init 0.8 um |y| <= {in_max:.3}");
    assert!(lo >= 0.85 && hi > 1.1, "r_init 1.0 um: y {lo}-{hi}");
    assert!(in_max < 0.16, "r_init 0.8 um: |y| up to {in_max}");
}

/// The ~4 mm/s column with the paper's penalty walls (sessions 33-34, from rest), where the
/// exact-wall runs of both starts ended slippers. Over 300-750 ms the r_init 0.8 um cell stays
/// near the axis, |y| <= 0.074 um and radial <= 0.157 (off it along z, 0.10-0.14 um: a croissant so
/// far), while the exact-wall cell of the same start swings at y 1.08-1.50 um; the r_init 1.2 um
/// cell swings at y 0.62-1.02 um, inside the exact-wall run's 1.17-1.52 (measured 2026-11-29).
/// The samples before 750 ms stay as the runs go on; where the 1.2 um run ends says whether the
/// paper's walls keep both shapes at ~4 mm/s (the paper: both above ~3 mm/s).
#[test]
fn with_the_papers_walls_the_u2p4_r_init_0p8_run_stays_near_the_axis_and_1p2_swings_inside_the_exact_walls_slipper() {
    let w = both_walls_window("discocyte_u2.4_r0.8", 0.3, 0.75);
    assert!(w.penalty_y_max < 0.1 && w.penalty_radial_max < 0.2, "paper's walls: |y| up to {}, radial up to {}", w.penalty_y_max, w.penalty_radial_max);
    assert!(w.exact_y_min >= 1.0, "exact walls: y from {}", w.exact_y_min);
    let y_range = |study: &str| {
        let y: Vec<f64> = state_window(study, "discocyte_u2.4_r1.2", 0.3, 0.75).iter().map(|s| s.centroid_um[1]).collect();
        assert!(y.len() >= 2000, "{study}: {} samples", y.len());
        let (lo, hi, _) = min_max_mean(&y);
        (lo, hi)
    };
    let ((p_lo, p_hi), (e_lo, e_hi)) = (y_range("science-6p5-penalty"), y_range("science-6p5"));
    eprintln!("discocyte_u2.4_r1.2, 300-750 ms: paper's walls y {p_lo:.3}-{p_hi:.3} um, exact walls {e_lo:.3}-{e_hi:.3}");
    assert!(p_lo > 0.5 && p_hi < e_lo, "r_init 1.2 um: y {p_lo}-{p_hi} against the exact walls' {e_lo}-{e_hi} um");
}

/// With the paper's walls the ~6.5 mm/s runs from r_init 0.8 and 1.0 um (sessions 31-33; both
/// ended in session 33) sit on the states of the ended runs either side of them. Over 600-830 ms the 0.8 um
/// run is on the 0.4 um run's croissant: radial 0.366-0.402 um, mean 0.3822 against 0.3820 over
/// the same window, |y| <= 0.03 um (off the axis along z), 6.456 against 6.457 mm/s. The 1.0 um
/// run swings on the 1.2 um run's slipper orbit: y 1.202-1.441 against 1.212-1.457 um, mean 1.308
/// against 1.317 (measured 2026-11-29). So the start that divides croissant from slipper lies
/// between 0.8 and 1.0 um, as their ends say (the tests below).
#[test]
fn with_the_papers_walls_the_u3p8_runs_from_0p8_and_1p0_sit_on_the_states_of_0p4_and_1p2() {
    // (radial min, max, mean; y min, max, mean) over 600-830 ms
    let stats = |run_id: &str| {
        let w = penalty_window(run_id, 0.6, 0.83);
        assert!(w.len() >= 1000, "{run_id}: {} samples", w.len());
        let r: Vec<f64> = w.iter().map(radial_um).collect();
        let y: Vec<f64> = w.iter().map(|s| s.centroid_um[1]).collect();
        let s = (min_max_mean(&r), min_max_mean(&y));
        eprintln!("{run_id}, 600-830 ms: radial {:.4}-{:.4} (mean {:.4}), y {:.4}-{:.4} (mean {:.4}) um", s.0 .0, s.0 .1, s.0 .2, s.1 .0, s.1 .1, s.1 .2);
        s
    };
    let ((r08_lo, r08_hi, r08_mean), (y08_lo, y08_hi, _)) = stats("discocyte_u3.8_r0.8");
    let ((r04_lo, r04_hi, r04_mean), _) = stats("discocyte_u3.8_r0.4");
    assert!((r08_mean - r04_mean).abs() < 0.005, "croissant: radial mean {r08_mean} against {r04_mean} um");
    assert!((r08_lo - r04_lo).abs() < 0.01 && (r08_hi - r04_hi).abs() < 0.01, "croissant: radial {r08_lo}-{r08_hi} against {r04_lo}-{r04_hi} um");
    assert!(y08_lo > -0.05 && y08_hi < 0.05, "off the axis along z: y {y08_lo}-{y08_hi} um");
    let (_, (y1_lo, y1_hi, y1_mean)) = stats("discocyte_u3.8_r1");
    let (_, (y12_lo, y12_hi, y12_mean)) = stats("discocyte_u3.8_r1.2");
    assert!((y1_mean - y12_mean).abs() < 0.02, "slipper: mean y {y1_mean} against {y12_mean} um");
    assert!((y1_lo - y12_lo).abs() < 0.03 && (y1_hi - y12_hi).abs() < 0.03, "slipper: y {y1_lo}-{y1_hi} against {y12_lo}-{y12_hi} um");
}

/// The lateral position over `t0..=t1` (s) of run `run_id` in the two ~6.5 mm/s studies: the
/// paper's penalty walls (`science-6p5-penalty`) and exact no-slip walls (`science-6p5`).
struct BothWallsWindow {
    /// Largest |y| (um) with the paper's walls.
    penalty_y_max: f64,
    /// Largest distance from the axis, hypot(y, z) (um), with the paper's walls.
    penalty_radial_max: f64,
    /// y (um) at `t1` with the paper's walls.
    penalty_y_end: f64,
    /// Smallest y (um) with exact walls.
    exact_y_min: f64,
    /// y (um) at `t1` with exact walls.
    exact_y_end: f64,
}

fn both_walls_window(run_id: &str, t0: f64, t1: f64) -> BothWallsWindow {
    let (penalty, exact) = (state_window("science-6p5-penalty", run_id, t0, t1), state_window("science-6p5", run_id, t0, t1));
    assert!(penalty.len() >= 100 && exact.len() >= 100, "samples: {} and {}", penalty.len(), exact.len());
    let w = BothWallsWindow {
        penalty_y_max: penalty.iter().map(|s| s.centroid_um[1].abs()).fold(0.0, f64::max),
        penalty_radial_max: penalty.iter().map(radial_um).fold(0.0, f64::max),
        penalty_y_end: penalty.last().unwrap().centroid_um[1],
        exact_y_min: exact.iter().map(|s| s.centroid_um[1]).fold(f64::INFINITY, f64::min),
        exact_y_end: exact.last().unwrap().centroid_um[1],
    };
    eprintln!(
        "{run_id}, {:.0}-{:.0} ms: paper's walls |y| <= {:.3} um, radial <= {:.3}, y {:.3} at the end; exact walls y >= {:.3}, {:.3} at the end",
        t0 * 1e3, t1 * 1e3, w.penalty_y_max, w.penalty_radial_max, w.penalty_y_end, w.exact_y_min, w.exact_y_end
    );
    w
}

/// The ~6.5 mm/s r_init 1.2 um discocyte with the paper's penalty walls ended `periodic` at 984.8 ms
/// (session 30) over the study's 0.5 s window, an off-centre tank-treading slipper (orbit period
/// 51 ms, mean y 1.317, z 0.026 um, 6.39 mm/s; measured 2026-11-28): the same shape as with exact
/// no-slip walls (`the_studys_r_init_1p2_run_ended_an_off_centre_tank_treading_slipper`: mean y
/// 1.570 um, 6.28 mm/s), 0.25 um nearer the axis and inside the paper's 0.8-1.5 um.
#[test]
fn with_the_papers_walls_the_u3p8_r_init_1p2_run_ended_an_off_centre_tank_treading_slipper() {
    assert_penalty_slipper_nearer_the_axis("discocyte_u3.8_r1.2", 6.2..=6.6, 0.15);
}

/// The ~6.5 mm/s r_init 1.0 um discocyte with the paper's penalty walls (session 32, from rest)
/// ended `periodic` at 951.2 ms (session 33) on the 1.2 um run's slipper orbit: an off-centre
/// tank-treading slipper, mean y 1.305 against 1.317 um, 6.40 against 6.39 mm/s (measured
/// 2026-11-29). With exact walls the start that divides croissant from slipper lies between 0.5
/// and 0.6 um; with the paper's walls a slipper from 1.0 um and the croissants from 0.4 and 0.8 um
/// (`with_the_papers_walls_the_u3p8_r_init_0p8_run_ended_the_0p4_runs_croissant`) put it between
/// 0.8 and 1.0 um.
#[test]
fn with_the_papers_walls_the_u3p8_r_init_1p0_run_ended_the_1p2_runs_slipper() {
    let (_, _, s) = ended_run_of("science-6p5-penalty", "discocyte_u3.8_r1", 1.0);
    assert_off_centre_slipper_at(&s, 6.2..=6.6);
    assert!(s.tank_treading, "a tank-treading slipper");
    let (_, _, s12) = ended_run_of("science-6p5-penalty", "discocyte_u3.8_r1.2", 1.2);
    assert!((s.mean_radial_um - s12.mean_radial_um).abs() < 0.03, "the 1.2 um run's orbit: {} against {} um", s.mean_radial_um, s12.mean_radial_um);
    assert!((s.mean_velocity_mm_s - s12.mean_velocity_mm_s).abs() < 0.05, "{} against {} mm/s", s.mean_velocity_mm_s, s12.mean_velocity_mm_s);
}

/// The ~6.5 mm/s r_init 0.8 um discocyte with the paper's penalty walls (session 31, from rest)
/// ended `periodic` at 1003.6 ms (session 33) on the 0.4 um run's croissant: nearly a rigid body
/// (non-rigid speed 0.7 % of the cell's) whose membrane circulates at 2.69 Hz (a tank-treading
/// croissant since session 51), not tumbling, along z, mean radial offset
/// 0.3823 um against 0.3819, 6.455 against 6.454 mm/s, the same 91 ms beat (measured 2026-11-29).
/// The exact-wall run of the same start ended a slipper. With the 1.0 um run a
/// slipper, the paper's walls put the ~6.5 mm/s switch between 0.8 and 1.0 um (exact walls: 0.5-0.6).
#[test]
fn with_the_papers_walls_the_u3p8_r_init_0p8_run_ended_the_0p4_runs_croissant() {
    assert_ended_on_the_0p4_runs_croissant_where_exact_walls_give_a_slipper("discocyte_u3.8_r0.8", 0.8);
}

/// The ~6.5 mm/s run `run_id` (r_init `r_init_um`) with the paper's walls ended the r_init 0.4 um
/// run's tank-treading croissant along z (mean radial within 0.01 um, velocity within 0.02 mm/s of
/// it), where the exact-wall run of the same start ended a slipper.
fn assert_ended_on_the_0p4_runs_croissant_where_exact_walls_give_a_slipper(run_id: &str, r_init_um: f64) {
    let (_, _, s) = ended_run_of("science-6p5-penalty", run_id, r_init_um);
    let (_, _, s04) = ended_run_of("science-6p5-penalty", "discocyte_u3.8_r0.4", 0.4);
    assert_tank_treading_croissant_along_z(&s);
    assert!((s.mean_radial_um - s04.mean_radial_um).abs() < 0.01, "the 0.4 um run's croissant: {} against {} um", s.mean_radial_um, s04.mean_radial_um);
    assert!((s.mean_velocity_mm_s - s04.mean_velocity_mm_s).abs() < 0.02, "{} against {} mm/s", s.mean_velocity_mm_s, s04.mean_velocity_mm_s);
    let (_, _, exact) = ended_run_of("science-6p5", run_id, r_init_um);
    assert_eq!(exact.final_shape, FinalShape::Slipper, "exact walls: a slipper from the same start");
}

/// The ~6.5 mm/s r_init 0.6 um discocyte with the paper's penalty walls (session 31, from rest)
/// ended `periodic` at 1040.4 ms (session 57) on the 0.4 and 0.8 um runs' croissant: a
/// tank-treading croissant along z (its membrane circulating at 2.73 Hz), 0.383 um off the axis on
/// average (the 0.4 um run's 0.382), at 6.46 mm/s, the same 91 ms beat, where the exact-wall run
/// of the same start ended a slipper. It was the ~6.5 mm/s column's last run: with the paper's
/// walls croissants from 0.4, 0.6 and 0.8 um, slippers from 1.0 and 1.2 um.
#[test]
fn with_the_papers_walls_the_u3p8_r_init_0p6_run_ended_the_0p4_runs_croissant() {
    assert_ended_on_the_0p4_runs_croissant_where_exact_walls_give_a_slipper("discocyte_u3.8_r0.6", 0.6);
}

/// The paper's Fig. 4 (steady radial position against r_init at ~6.5 mm/s) from both studies'
/// state, as `rbc-sweep offsets` draws it (README, `docs/radial_offset.png`). With exact walls:
/// croissants 0.31 um off the axis from 0.4 and 0.5 um, slippers at 1.56-1.57 um from 0.6, 0.8 and
/// 1.2 um, one sharp switch between 0.5 and 0.6 um (the paper's: ~0.7 um). With the paper's walls
/// (every run ended since session 57): croissants at 0.37-0.39 um from 0.4, 0.6 and 0.8 um,
/// slippers at 1.3 um from 1.0 and 1.2 um, one switch between 0.8 and 1.0 um.
#[test]
fn the_papers_fig_4_column_from_both_studies_has_one_switch_each() {
    use rbc_analysis::plot::offset::OffsetFigure;
    let files = both_studies_state();
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = OffsetFigure::read(&refs, "discocyte", 6.5, 0.05, Some(0.7)).unwrap();
    assert_eq!(fig.series.iter().map(|s| s.label.as_str()).collect::<Vec<_>>(), ["science-6p5", "science-6p5-penalty"]);
    for s in &fig.series {
        let ended: Vec<(f64, FinalShape, f64)> = s.points.iter().map(|p| (p.r_init_um, p.final_shape, p.mean_radial_um)).collect();
        let going: Vec<(f64, f64, f64)> = s.running.iter().map(|p| (p.r_init_um, p.tail.t_s, p.tail.radial_um)).collect();
        eprintln!("{}: ended {ended:?}, still going {going:?}", s.label);
        let top_croissant = ended.iter().filter(|p| p.1 == FinalShape::Croissant).map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
        let low_slipper = ended.iter().filter(|p| p.1 == FinalShape::Slipper).map(|p| p.0).fold(f64::INFINITY, f64::min);
        assert!(top_croissant < low_slipper, "{}: croissant from {top_croissant} um, slipper from {low_slipper} um", s.label);
        assert!(ended.iter().all(|p| p.1 != FinalShape::Other), "{}: {ended:?}", s.label);
        for p in &ended {
            let band = if p.1 == FinalShape::Croissant { 0.3..0.4 } else { 1.25..1.6 };
            assert!(band.contains(&p.2), "{}: r_init {} um ended a {:?} at {} um", s.label, p.0, p.1, p.2);
        }
    }
    let starts = |k: usize| {
        let s = &fig.series[k];
        let mut r: Vec<f64> = s.points.iter().map(|p| p.r_init_um).chain(s.running.iter().map(|p| p.r_init_um)).collect();
        r.sort_by(f64::total_cmp);
        r
    };
    assert_eq!(starts(0), [0.4, 0.5, 0.6, 0.8, 1.2], "the exact-wall column, all ended");
    assert!(fig.series[0].running.is_empty());
    let (exact, penalty) = (&fig.series[0].points, &fig.series[1].points);
    assert_eq!(exact.iter().map(|p| p.final_shape).collect::<Vec<_>>(), [FinalShape::Croissant, FinalShape::Croissant, FinalShape::Slipper, FinalShape::Slipper, FinalShape::Slipper]);
    assert_eq!(starts(1), [0.4, 0.6, 0.8, 1.0, 1.2], "the paper's-walls column, all ended");
    assert!(fig.series[1].running.is_empty());
    assert_eq!(penalty.iter().map(|p| p.final_shape).collect::<Vec<_>>(), [FinalShape::Croissant, FinalShape::Croissant, FinalShape::Croissant, FinalShape::Slipper, FinalShape::Slipper]);
}

/// `docs/radial_offset.svg` (and its PNG, drawn with it; the README's figure) is what `rbc-sweep
/// offsets` draws from the two studies' committed state (`scripts/study.sh save
/// science-6p5-penalty` draws both again; by hand: `rbc-sweep offsets
/// examples/studies/science-6p5/state/*.h5 examples/studies/science-6p5-penalty/state/*.h5
/// --mark-um 0.7 --out docs`).
#[test]
fn the_readmes_fig_4_column_is_drawn_from_the_studies_state() {
    shipped_figure_is_drawn_from_the_state("offsets", &["--mark-um", "0.7"], "radial_offset");
}

/// `docs/NAME.svg` is what `rbc-sweep COMMAND` (with `extra` arguments) draws from the two
/// studies' committed state into a fresh folder.
fn shipped_figure_is_drawn_from_the_state(command: &str, extra: &[&str], name: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).arg(command).args(both_studies_state()).args(extra).arg("--out").arg(dir.path()).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // `name` may sit in a folder of docs/ (`croissant-start/phase_studies`); the command writes its file
    let (folder, file) = name.rsplit_once('/').map_or(("", name), |(f, n)| (f, n));
    let drawn = std::fs::read_to_string(dir.path().join(format!("{file}.svg"))).unwrap();
    let shipped = std::fs::read_to_string(root.join(format!("docs/{name}.svg"))).unwrap();
    let out = if folder.is_empty() { "docs".to_string() } else { format!("docs/{folder}") };
    let again = format!("rbc-sweep {command} examples/studies/science-6p5/state/*.h5 examples/studies/science-6p5-penalty/state/*.h5 {}--out {out}", extra.iter().map(|a| format!("{a} ")).collect::<String>());
    assert!(drawn == shipped, "docs/{name}.svg is stale: draw it again with `{again}` (the study's save does)");
}

/// `docs/steady_studies.svg` (its PNG is drawn with it; the README's Fig. 6) is what `rbc-sweep
/// steady` draws from the two studies' committed state (`scripts/study.sh save` draws it again; by
/// hand: `rbc-sweep steady examples/studies/science-6p5/state/*.h5
/// examples/studies/science-6p5-penalty/state/*.h5 --out docs`), and the two studies show what the
/// paper's Fig. 6 says of the steady states (session 50, on the runs ended by then):
/// - croissants sit near the axis: every column's mean within 0.4 um (the paper: "always almost
///   centered"; ours at ~6.5 mm/s 0.31-0.38 um, tank-treading croissants further off the axis, one
///   window's largest 0.402 um);
/// - slippers 0.8-1.6 um off the axis (the paper: 0.8-1.5 um), furthest out in the fastest column
///   (the paper: the offset grows with the velocity towards ~1.5 um);
/// - slippers get longer (x) and flatter (z) as the velocity grows, column after column (the
///   paper: "more elongated and thinner at higher velocities"); along x from ~0.5 mm/s up: the
///   ~0.32 mm/s slipper with the paper's walls, which folds once a period (session 57), is 7.35 um
///   long against the ~0.5 mm/s one's 7.19;
/// - with exact walls a slipper sits further out than with the paper's penalty walls in every
///   velocity column where both have one (new: the walls' slip lets it come 0.11-0.33 um closer).
#[test]
fn the_readmes_fig_6_is_drawn_from_the_studies_state_and_shows_the_papers_trends() {
    shipped_figure_is_drawn_from_the_state("steady", &[], "steady_studies");
    let files = both_studies_state();
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = rbc_analysis::plot::steady_studies::SteadyStudiesFigure::read(&refs, "discocyte", 0.05).unwrap();
    assert_eq!(fig.studies().iter().map(|s| s.label.as_str()).collect::<Vec<_>>(), ["science-6p5", "science-6p5-penalty"]);
    use rbc_analysis::plot::simulation::SteadyClass;
    let slippers = |k: usize| fig.studies()[k].radial.iter().filter(|c| c.class == SteadyClass::Slipper).map(|c| (c.velocity_mm_s, c.value)).collect::<Vec<_>>();
    for s in fig.studies() {
        for c in &s.radial {
            eprintln!("{}: {} at {:.2} mm/s: {:.3} um ({} runs)", s.label, c.class.label(), c.velocity_mm_s, c.value, c.n_runs);
            match c.class {
                SteadyClass::Slipper => assert!((0.8..=1.6).contains(&c.value), "{}: a slipper at {} um", s.label, c.value),
                _ => assert!(c.value < 0.4, "{}: a croissant at {} um", s.label, c.value),
            }
        }
    }
    for k in 0..2 {
        let sl = slippers(k);
        assert!(sl.len() >= 3, "slipper columns: {sl:?}");
        let fastest = sl.last().unwrap().1;
        assert!(sl.iter().all(|c| c.1 <= fastest), "{}: the fastest slippers furthest out: {sl:?}", fig.studies()[k].label);
        let axis = |j: usize| fig.studies()[k].extents[j].iter().map(|c| c.value).collect::<Vec<f64>>();
        // longer along x from ~0.5 mm/s up; the ~0.32 mm/s folding slipper (the paper's walls,
        // session 57) is the exception below: 7.35 um against the ~0.5 mm/s one's 7.19
        let x_from_0p45: Vec<f64> = fig.studies()[k].extents[0].iter().filter(|c| c.velocity_mm_s >= 0.45).map(|c| c.value).collect();
        assert!(x_from_0p45.windows(2).all(|w| w[1] > w[0]), "{}: longer with the velocity: {:?}", fig.studies()[k].label, axis(0));
        if let [slow, next, ..] = fig.studies()[k].extents[0].as_slice() {
            if slow.velocity_mm_s < 0.45 {
                assert!(slow.value > next.value && (7.3..7.4).contains(&slow.value), "{}: the folding slipper {slow:?} against {next:?}", fig.studies()[k].label);
            }
        }
        assert!(axis(2).windows(2).all(|w| w[1] < w[0]), "{}: flatter with the velocity: {:?}", fig.studies()[k].label, axis(2));
    }
    let shared = shared_columns(&slippers(0), &slippers(1));
    assert!(shared.len() >= 3, "velocity columns with a slipper in both studies: {shared:?}");
    for (u, exact, penalty) in shared {
        assert!(exact > penalty, "at {u} mm/s: exact walls {exact} um, the paper's {penalty} um");
    }
}

/// The velocity columns two studies share (within 5 % of the first's velocity): `(velocity,
/// first's value, second's value)` from `(velocity, value)` columns.
fn shared_columns(a: &[(f64, f64)], b: &[(f64, f64)]) -> Vec<(f64, f64, f64)> {
    a.iter().filter_map(|&(u, x)| b.iter().find(|c| (c.0 - u).abs() < 0.05 * u).map(|&(_, y)| (u, x, y))).collect()
}

/// Panel (c) of `docs/steady_studies.png`, the membrane's motion in the steady states of both
/// studies (session 51, on the runs ended by then), against what the paper says in words:
/// - every slipper tank-treads, 1.0-1.5 membrane turns per mm the cell travels (the fewest at
///   ~0.5 mm/s, 1.02), at a frequency that grows with the velocity column after column from ~0.5
///   mm/s up (ours: 0.51 Hz at ~0.5 mm/s to 8.3-8.5 Hz at ~6.3 mm/s); below, the two slippers
///   with the paper's walls that fold once a period (~0.32 and ~0.37 mm/s, ended in sessions 57
///   and 60) tank-tread at 0.41-0.43 Hz, the slower cell the faster (1.38 against 1.14 turns per
///   mm), both slower than the ~0.5 mm/s one;
/// - with the paper's walls a slipper tank-treads slower than with exact walls in every column
///   both hold (it sits closer to the axis, where the flow shears less);
/// - the croissants at 1-4.1 mm/s are rigid (below 0.2 Hz), those at ~6.45 mm/s tank-tread at
///   2-3 Hz (the paper sees tank-treading croissants above ~7 mm/s) and carry the flag
///   (`ClassifyConfig::min_tt_turns`, 0.1 turn since session 51): the paper's "non-tank-treading
///   croissants are always almost centered" then holds, every rigid croissant column within
///   0.18 um of the axis and the tank-treading ones at 0.31-0.38 um;
/// - no steady state tumbles: the shape turns about z by less than 0.05 turns over its window
///   (0.1 for the ~0.32 mm/s slipper, whose shape turns back and forth at its folds: -0.08).
///   The paper's slippers tumble below ~0.7 mm/s; the ~0.5 and ~0.32 mm/s slippers here
///   tank-tread (`discocyte_u0.16_r1.2`, ~0.26 mm/s, tumbles so far).
///
/// `rbc-sweep status --field tank_treading_hz,tumbling_hz` gives an ended run's stored motion.
#[test]
fn the_steady_slippers_tank_tread_faster_with_the_velocity_and_none_tumbles() {
    let files = both_studies_state();
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = rbc_analysis::plot::steady_studies::SteadyStudiesFigure::read(&refs, "discocyte", 0.05).unwrap();
    use rbc_analysis::plot::simulation::SteadyClass;
    let slippers = |k: usize| fig.studies()[k].tank_treading.iter().filter(|c| c.class == SteadyClass::Slipper).map(|c| (c.velocity_mm_s, c.value)).collect::<Vec<_>>();
    for k in 0..2 {
        let sl = slippers(k);
        eprintln!("{}: slippers' tank-treading {sl:?}", fig.studies()[k].label);
        assert!(sl.len() >= 4, "slipper columns: {sl:?}");
        let (folding, swinging): (Vec<(f64, f64)>, Vec<(f64, f64)>) = sl.iter().partition(|&&(u, _)| u < 0.4);
        assert!(swinging.windows(2).all(|w| w[1].1 > w[0].1), "faster with the velocity from ~0.5 mm/s up: {sl:?}");
        assert!(folding.iter().all(|&(_, f)| (0.4..0.45).contains(&f) && f < swinging[0].1), "the folding slippers: {sl:?}");
        assert!(sl.iter().all(|&(u, f)| (1.0..=1.5).contains(&(f / u))), "turns per mm travelled: {sl:?}");
        for c in fig.studies()[k].tank_treading.iter().filter(|c| c.class != SteadyClass::Slipper) {
            if c.velocity_mm_s < 4.2 {
                assert!(c.class == SteadyClass::Croissant && c.max < 0.2, "a rigid croissant at {} mm/s: {} Hz", c.velocity_mm_s, c.max);
            } else {
                assert!(c.class == SteadyClass::TankTreadingCroissant && c.min > 2.0 && c.max < 3.0, "a tank-treading croissant at {} mm/s: {}-{} Hz", c.velocity_mm_s, c.min, c.max);
            }
        }
        for c in fig.studies()[k].radial.iter() {
            match c.class {
                SteadyClass::Croissant => assert!(c.max < 0.18, "a rigid croissant {} um off the axis at {} mm/s", c.max, c.velocity_mm_s),
                SteadyClass::TankTreadingCroissant => assert!((0.3..0.41).contains(&c.value), "a tank-treading croissant {} um off the axis", c.value),
                SteadyClass::Slipper => {}
            }
        }
    }
    let shared = shared_columns(&slippers(0), &slippers(1));
    assert!(shared.len() >= 3, "velocity columns with a slipper in both studies: {shared:?}");
    for (u, exact, penalty) in shared {
        assert!(exact > penalty, "at {u} mm/s: exact walls {exact} Hz, the paper's {penalty} Hz");
    }
    // no ended run tumbles, and `status` gives the motion its label was decided on
    let mut ended = 0;
    for f in &files {
        for run in read_runs(f).unwrap() {
            let (id, Some(s)) = (run.run_id, run.summary) else { continue };
            let Some(turns) = s.evidence.get("tumbling_turns") else { continue };
            // (the ~0.32 mm/s slipper's shape turns back and forth by up to 0.08 turn at its folds)
            let limit = if id == "discocyte_u0.2_r1.2" { 0.1 } else { 0.05 };
            assert!(turns.abs() < limit && !s.tumbling, "{id} in {}: the shape turned {turns} about z", f.display());
            ended += 1;
        }
    }
    assert!(ended >= 36, "ended runs with their motion: {ended}");
    assert!(fig.studies().iter().all(|s| s.tumbling.is_empty()), "panel (c) has no tumbling column yet");
    let study = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies/science-6p5-penalty");
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
        .arg("status")
        .arg(study.join("state/discocyte_u0.31_r1.2.h5"))
        .args(["--run", "discocyte_u0.31_r1.2", "--field", "shape,tank_treading_hz,tumbling_hz"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Vec<String> = String::from_utf8(o.stdout).unwrap().split_whitespace().map(str::to_string).collect();
    let (tt, tumbling): (f64, f64) = (v[1].parse().unwrap(), v[2].parse().unwrap());
    assert!(v[0] == "slipper" && (0.45..0.55).contains(&tt) && tumbling.abs() < 0.05, "the ~0.5 mm/s slipper tank-treads: {v:?}");
}

/// The paper's Fig. 6 (a): "the final radial positions are independent of the initial starting
/// shape, i.e. a particular steady state shape at a certain velocity is always located at the
/// same position". With exact walls (the study with croissant and slipper starts as well,
/// `examples/sweeps/starts.h5`), every steady state of another start shape lies in the
/// same place as the discocytes' of its class and velocity column: its mean radial position
/// within 0.06 um of theirs (session 51: the croissant-started slippers at 2.48 and 6.28 mm/s at
/// 1.117 and 1.565 um against the discocytes' 1.135 and 1.564; the slipper-started slipper at
/// 6.28 mm/s at 1.562; the slipper-started croissant at 2.52 mm/s 0.121 um off the axis against
/// 0.176, the largest difference, 0.055 um, both "almost centered"), and its slippers' extents
/// within 0.1 um of theirs.
#[test]
fn with_exact_walls_a_steady_state_sits_where_the_discocytes_do_whatever_the_start_shape() {
    let files = state_files("science-6p5");
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let read = |start: &str| rbc_analysis::plot::steady_studies::SteadyStudiesFigure::read(&refs, start, 0.05).unwrap().studies()[0].clone();
    let disc = read("discocyte");
    let mut compared = 0;
    for start in ["croissant", "slipper"] {
        let other = read(start);
        for c in &other.radial {
            let d = disc.radial.iter().find(|d| d.class == c.class && (d.velocity_mm_s - c.velocity_mm_s).abs() < 0.05 * d.velocity_mm_s).unwrap_or_else(|| panic!("no discocyte {} column at {} mm/s", c.class.label(), c.velocity_mm_s));
            eprintln!("{start} start: {} at {:.2} mm/s: {:.3} um; discocytes {:.3} ({:.3}-{:.3})", c.class.label(), c.velocity_mm_s, c.value, d.value, d.min, d.max);
            assert!((c.value - d.value).abs() < 0.06, "{start} start: {} at {} mm/s: {} um, discocytes {} um", c.class.label(), c.velocity_mm_s, c.value, d.value);
            compared += 1;
        }
        for (j, axis) in other.extents.iter().enumerate() {
            for c in axis {
                let d = disc.extents[j].iter().find(|d| (d.velocity_mm_s - c.velocity_mm_s).abs() < 0.05 * d.velocity_mm_s).unwrap();
                assert!((c.value - d.value).abs() < 0.1, "{start} start: extent {j} at {} mm/s: {} um, discocytes {} um", c.velocity_mm_s, c.value, d.value);
            }
        }
    }
    assert!(compared >= 4, "steady states of other start shapes: {compared}");
}

/// `docs/phase_studies.svg` (its PNG is drawn with it; the README's phase diagrams, one panel per
/// wall model) is what `rbc-sweep phase` draws from the two studies' committed state (`scripts/study.sh save
/// science-6p5-penalty` draws it again; by hand: `rbc-sweep phase
/// examples/studies/science-6p5/state/*.h5 examples/studies/science-6p5-penalty/state/*.h5 --out
/// docs`), and it shows what the README says of it: with exact walls both shapes in every
/// column; with the paper's walls croissants only at ~2.5 mm/s and both shapes at ~6.5 mm/s.
#[test]
fn the_readmes_phase_diagrams_are_drawn_from_the_studies_state() {
    shipped_figure_is_drawn_from_the_state("phase", &[], "phase_studies");
    let files = both_studies_state();
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = rbc_analysis::plot::phase_studies::PhaseStudiesFigure::read(&refs, "discocyte", 0.05).unwrap();
    assert_eq!(fig.studies().iter().map(|s| s.label.as_str()).collect::<Vec<_>>(), ["science-6p5", "science-6p5-penalty"]);
    // each column's shapes: (its velocity, whether a croissant and whether a slipper ended there)
    let shapes = |k: usize| {
        let th = &fig.studies()[k].thresholds;
        th.iter().map(|t| (t.velocity_mm_s, t.n_croissant > 0, t.n_slipper > 0)).collect::<Vec<_>>()
    };
    assert!(shapes(0).len() >= 4 && shapes(0).iter().all(|&(_, croissant, slipper)| croissant && slipper), "exact walls: both shapes in every column: {:?}", shapes(0));
    let penalty = shapes(1);
    let near = |u: f64| penalty.iter().find(|c| (c.0 - u).abs() < 0.3).unwrap_or_else(|| panic!("no column at ~{u} mm/s: {penalty:?}"));
    assert_eq!((near(2.5).1, near(2.5).2), (true, false), "the paper's walls at ~2.5 mm/s: croissants only");
    assert_eq!((near(6.4).1, near(6.4).2), (true, true), "the paper's walls at ~6.5 mm/s: both shapes");
}

/// `docs/croissant-start/phase_studies.svg` (the README's phase diagrams of the croissant starts,
/// the paper's Fig. 5 b; `scripts/study.sh save` draws it again; by hand: `rbc-sweep phase
/// examples/studies/science-6p5/state/*.h5 examples/studies/science-6p5-penalty/state/*.h5
/// --start croissant --out docs/croissant-start`) is what `rbc-sweep phase --start croissant`
/// draws from the two studies' committed state, and it shows what the README says of it: with
/// exact walls the settled croissant started 1.2 um off the axis ends a slipper at ~2.5 and ~6.3
/// mm/s (no croissant there); with the paper's walls a croissant started 0.2 um off the axis at
/// ~0.5 mm/s stays one, where every discocyte of that column ends a slipper.
#[test]
fn the_readmes_croissant_start_phase_diagrams_are_drawn_from_the_studies_state() {
    shipped_figure_is_drawn_from_the_state("phase", &["--start", "croissant"], "croissant-start/phase_studies");
    let files = both_studies_state();
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = rbc_analysis::plot::phase_studies::PhaseStudiesFigure::read(&refs, "croissant", 0.05).unwrap();
    assert_eq!(fig.studies().iter().map(|s| s.label.as_str()).collect::<Vec<_>>(), ["science-6p5", "science-6p5-penalty"]);
    let columns = |k: usize| fig.studies()[k].thresholds.iter().map(|t| (t.velocity_mm_s, t.n_croissant, t.n_slipper)).collect::<Vec<_>>();
    let exact = columns(0);
    for u in [2.5, 6.3] {
        let c = exact.iter().find(|c| (c.0 - u).abs() < 0.3).unwrap_or_else(|| panic!("exact walls: no croissant-start column at ~{u} mm/s: {exact:?}"));
        assert_eq!((c.1, c.2), (0, 1), "exact walls, croissant start at ~{u} mm/s: {c:?}");
    }
    let penalty = columns(1);
    let slow = penalty.iter().find(|c| (c.0 - 0.51).abs() < 0.05).unwrap_or_else(|| panic!("the paper's walls: no croissant-start column at ~0.5 mm/s: {penalty:?}"));
    assert!(slow.1 >= 1, "the paper's walls at ~0.5 mm/s: a croissant start held a croissant: {slow:?}");
    let discocytes = rbc_analysis::plot::phase_studies::PhaseStudiesFigure::read(&refs, "discocyte", 0.05).unwrap();
    let d = discocytes.studies()[1].thresholds.iter().find(|t| (t.velocity_mm_s - 0.51).abs() < 0.05).expect("the paper's walls: a discocyte column at ~0.5 mm/s");
    assert_eq!((d.n_croissant, d.n_slipper > 0), (0, true), "the paper's walls at ~0.5 mm/s: discocytes end slippers only");
}

/// The state files of the ~6.5 mm/s studies, exact walls (`science-6p5`) first, then the paper's
/// walls (`science-6p5-penalty`), each folder's files by name.
fn both_studies_state() -> Vec<PathBuf> {
    ["science-6p5", "science-6p5-penalty"].iter().flat_map(|s| state_files(s)).collect()
}

/// The results files (`*.h5`) of study `study`'s committed state (`examples/studies`), by name.
fn state_files(study: &str) -> Vec<PathBuf> {
    let state = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies").join(study).join("state");
    let mut f: Vec<PathBuf> = std::fs::read_dir(&state).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "h5")).collect();
    f.sort();
    f
}

/// The extremes of y (um) of a swinging slipper's half orbits in `rows` over `t0..t1` (s): the
/// samples split where y crosses `level` (um), and each whole half orbit between two crossings
/// gives its largest y (above `level`) or its smallest (below it): `(t_s, y_um, is_peak)`.
fn half_orbit_extremes(rows: &[rbc_schema::results::TimeSample], t0: f64, t1: f64, level: f64) -> Vec<(f64, f64, bool)> {
    let w: Vec<(f64, f64)> = rows.iter().filter(|s| s.t_s >= t0 && s.t_s <= t1).map(|s| (s.t_s, s.centroid_um[1])).collect();
    let crossings: Vec<usize> = (1..w.len()).filter(|&i| (w[i].1 > level) != (w[i - 1].1 > level)).collect();
    crossings
        .windows(2)
        .map(|c| {
            let seg = &w[c[0]..c[1]];
            let peak = seg[0].1 > level;
            let pick = |a: &&(f64, f64), b: &&(f64, f64)| if peak { a.1.total_cmp(&b.1) } else { b.1.total_cmp(&a.1) };
            let e = seg.iter().max_by(pick).expect("a crossing pair spans a sample");
            (e.0, e.1, peak)
        })
        .collect()
}

/// The ~2.5 mm/s r_init 0.8 um start with the paper's walls turns at y ~0.6 um and heads for the
/// axis (a croissant; exact walls swing it out to its slipper) also without the stepping's drift
/// (`check-u1.5-r0.8-coupled`, session 39: the same 300 ms from rest with the walls coupled,
/// RosW6S4). The study's run, stepped without the coupling (drift -0.091 um/s at ~2.5 mm/s,
/// `solver/README.md` "Session 36"), turned at 0.599 um (163 ms); the coupled run turns 0.04 um
/// farther out, at 0.637 um (162 ms), and goes in on the same path: at most 0.054 um from it in y
/// over the 300 ms, y 0.215 um at 300 ms (the study's 0.162; measured).
#[test]
fn with_the_papers_walls_the_2p5_mm_s_r_init_0p8_start_turns_in_also_with_the_walls_coupled() {
    let study = u1p5_r0p8_rows("science-6p5-penalty/state/discocyte_u1.5_r0.8.h5");
    let coupled = u1p5_r0p8_rows("science-6p5-penalty/check-u1.5-r0.8-coupled.h5");
    assert!(coupled.len() == 1501 && (coupled[1500].t_s - 0.3).abs() < 1e-9, "300 ms at 0.2 ms: {} rows", coupled.len());
    let (dy, _) = largest_apart_yz(&coupled, &study);
    assert!(dy < 0.06, "the same path: at most {dy:.4} um in y from the study's");
    let turn = coupled.iter().filter(|c| c.t_s > 0.1 && c.t_s < 0.25).max_by(|a, b| a.centroid_um[1].total_cmp(&b.centroid_um[1])).unwrap();
    assert!((0.15..0.18).contains(&turn.t_s) && turn.centroid_um[1] < 0.66, "the turn: y {:.3} um at {:.4} s", turn.centroid_um[1], turn.t_s);
    assert!(coupled[1500].centroid_um[1] < 0.25, "heading for the axis: y {:.3} um at 300 ms", coupled[1500].centroid_um[1]);
}

/// The ~6.5 mm/s r_init 1.2 um slipper with the paper's walls ended `periodic` at 984.8 ms,
/// stepped with ROS34PW2, which drifts the cell towards the axis at -0.23 um/s against bs23 on
/// this orbit (`solver/README.md`, "Session 39"). Continued from its end with the walls coupled
/// (`check-u3.8-r1.2-coupled`, session 39: +0.017 um/s against bs23), its orbit moves out: the
/// peaks of y, at most 1.4579 um over the study's last eight orbits (creeping out by ~0.001 um an
/// orbit), are 1.4651, 1.4662 and 1.4663 um on the first three coupled orbits (to 1.1607 s), each
/// step out smaller than the one before (measured: the orbits' mean y 1.3223 on the last
/// uncoupled orbit, 1.3296, 1.3315 and 1.3317 on the coupled ones). The drift's share of the 0.25
/// um between the penalty and the exact-wall slippers' mean y is therefore ~0.01 um.
#[test]
fn without_the_stepping_drift_the_6p3_mm_s_penalty_slipper_orbit_moves_out_a_little() {
    let run = "discocyte_u3.8_r1.2";
    let study = state_rows("science-6p5-penalty", run);
    let coupled = study_file_rows("science-6p5-penalty/check-u3.8-r1.2-coupled.h5", run);
    let end = study.last().unwrap().t_s;
    assert!((end - 0.9848).abs() < 1e-9, "the study's run ended at {end} s");
    assert!(coupled.len() > study.len() && shared_history(&coupled, &study, end) == study.len(), "the check continues the study's run");
    let peaks = |rows: &[rbc_schema::results::TimeSample], t0: f64, t1: f64| -> Vec<(f64, f64)> { half_orbit_extremes(rows, t0, t1, 1.33).into_iter().filter(|e| e.2).map(|e| (e.0, e.1)).collect() };
    let before = peaks(&study, 0.55, end);
    assert!(before.len() >= 7 && before.iter().all(|p| p.1 <= 1.458), "the uncoupled peaks {before:?}");
    let after = peaks(&coupled, end + 0.02, coupled.last().unwrap().t_s);
    eprintln!("peaks of y before {before:?}\nand with the walls coupled {after:?}");
    assert!(after.len() >= 3 && after.iter().all(|p| p.1 > 1.464), "the coupled peaks {after:?}");
    let steps: Vec<f64> = after.windows(2).map(|w| w[1].1 - w[0].1).collect();
    assert!(steps.windows(2).all(|w| w[1] < w[0] + 2e-4) && steps.iter().all(|d| *d < 0.005), "each step out smaller: {steps:?}");
}

/// The time (s) of the ~4 mm/s r_init 1.2 um run's state (committed in 1372b8e) from which the
/// checks `check-u2.4-r1.2-*` beside study science-6p5-penalty continue it.
const U2P4_CHECKS_START_S: f64 = 1.6084691415;

/// `check` holds the samples of `run` up to `U2P4_CHECKS_START_S` exactly as `run` does (more than
/// 7000 of them): it continues that run's state.
fn assert_continues_from_the_u2p4_state(check: &[rbc_schema::results::TimeSample], run: &[rbc_schema::results::TimeSample]) {
    assert!(shared_history(check, run, U2P4_CHECKS_START_S - 1e-6) > 7000, "the shared history");
}

/// How many samples `check` holds up to `until_s` (s), asserted equal to `run`'s (times and
/// centroids): a check that continues a run's state holds its history as it was.
fn shared_history(check: &[rbc_schema::results::TimeSample], run: &[rbc_schema::results::TimeSample], until_s: f64) -> usize {
    let shared = check.iter().filter(|s| s.t_s <= until_s).count();
    assert!(check.iter().zip(run).take(shared).all(|(a, b)| a.t_s == b.t_s && a.centroid_um == b.centroid_um), "the shared history");
    shared
}

/// The ~4 mm/s r_init 1.2 um slipper with the paper's walls, continued from the study's state at
/// 1608.5 ms with ROS34PRw (`check-u2.4-r1.2-ros34prw`, session 36), whose drift towards the axis
/// against bs23 on this orbit is 16x smaller than RosW6S4's (0.0054 against 0.085 um/s over 20 ms;
/// `solver/README.md`, "Session 36"): its orbit moves out. The study's RosW6S4 run crept out by
/// 0.0013-0.0029 um an orbit over its last four (91 ms; peaks of y 1.1731 to 1.1792 um, troughs
/// 0.8726 to 0.8768); with ROS34PRw the next peak is at 1.1851 um (1.670 s) and the next trough at
/// 0.8855 (1.709 s), 0.0059 and 0.0087 um beyond the last ones, 4-6x the creep (measured
/// 2026-11-29), and the cell stays a slipper (y > 0.8 um). The samples of its first orbit stay as
/// the check runs on.
#[test]
fn without_the_stepping_drift_the_u2p4_r_init_1p2_slippers_orbit_moves_out() {
    let study = state_rows("science-6p5-penalty", "discocyte_u2.4_r1.2");
    let check = study_file_rows("science-6p5-penalty/check-u2.4-r1.2-ros34prw.h5", "discocyte_u2.4_r1.2");
    let start = U2P4_CHECKS_START_S;
    assert_continues_from_the_u2p4_state(&check, &study);
    let rosw = half_orbit_extremes(&study, 1.25, 1.6312, 1.03);
    let (peaks, troughs): (Vec<_>, Vec<_>) = rosw.iter().partition(|e| e.2);
    let creep = |v: &[&(f64, f64, bool)]| v.windows(2).map(|w| w[1].1 - w[0].1).collect::<Vec<_>>();
    let (cp, ct) = (creep(&peaks), creep(&troughs));
    eprintln!("RosW6S4 half orbits {rosw:?}: creep of peaks {cp:?}, troughs {ct:?}");
    assert!(peaks.len() >= 4 && troughs.len() >= 3, "{rosw:?}");
    assert!(cp.iter().chain(&ct).all(|d| (0.0..0.003).contains(d)), "RosW6S4 creeps out by under 0.003 um an orbit: {cp:?} {ct:?}");
    let prw = half_orbit_extremes(&check, start, f64::INFINITY, 1.03);
    eprintln!("ROS34PRw half orbits {prw:?}");
    let first = |peak: bool| prw.iter().find(|e| e.2 == peak).unwrap_or_else(|| panic!("a whole half orbit in the check: {prw:?}"));
    // RosW6S4's last peak, and its last trough (at 1.618 s, in the study's run after the check's start)
    let (last_peak, last_trough) = (peaks.last().unwrap().1, study.iter().filter(|s| s.t_s > 1.6).map(|s| s.centroid_um[1]).fold(f64::INFINITY, f64::min));
    let (p, t) = (first(true), first(false));
    assert!(p.1 - last_peak > 0.004, "ROS34PRw's first peak {p:?} against RosW6S4's last {last_peak}");
    assert!(t.1 - last_trough > 0.006, "ROS34PRw's first trough {t:?} against RosW6S4's last {last_trough}");
    let lowest = check.iter().filter(|s| s.t_s > start).map(|s| s.centroid_um[1]).fold(f64::INFINITY, f64::min);
    assert!(lowest > 0.8, "still a slipper off the axis: y down to {lowest} um");
}

/// The same slipper continued from the same state with the other scheme without the drift:
/// RosW6S4 with the walls' answer to the cell in its stages (`check-u2.4-r1.2-coupled`, session
/// 37, `integrator.wall_coupling`; 0.011 um/s against bs23 over 20 ms where RosW6S4 alone drifts
/// -0.085, at half ROS34PRw's cost; `solver/README.md`, "Session 37"). Its half orbits' extremes
/// of y agree with ROS34PRw's to 1e-3 um (measured: 1e-4 to 7e-4 um over its first five half
/// orbits, to 1.8755 s, the coupled one's peaks 0.0003, 0.0005, 0.0007 um lower),
/// where RosW6S4 alone fell 0.006-0.009 um behind within one orbit: the orbit is the walls', not
/// the stepping's. The samples of these orbits stay as the check runs on.
#[test]
fn two_schemes_without_the_drift_put_the_u2p4_r_init_1p2_slipper_on_one_orbit() {
    let run = "discocyte_u2.4_r1.2";
    let prw = study_file_rows("science-6p5-penalty/check-u2.4-r1.2-ros34prw.h5", run);
    let coupled = study_file_rows("science-6p5-penalty/check-u2.4-r1.2-coupled.h5", run);
    let (start, end) = (U2P4_CHECKS_START_S, 1.8755);
    assert_continues_from_the_u2p4_state(&coupled, &prw);
    let a = half_orbit_extremes(&prw, start, end, 1.03);
    let b = half_orbit_extremes(&coupled, start, end, 1.03);
    eprintln!("ROS34PRw {a:?}\ncoupled RosW6S4 {b:?}");
    assert!(b.len() >= 5 && a.len() == b.len(), "whole half orbits to {end} s: {a:?} {b:?}");
    for (x, y) in a.iter().zip(&b) {
        assert!(x.2 == y.2 && (x.0 - y.0).abs() < 2e-3, "the same half orbit: {x:?} {y:?}");
        assert!((x.1 - y.1).abs() < 1e-3, "y {:.4} against ROS34PRw's {:.4} at {:.3} s", y.1, x.1, y.0);
    }
}

/// The samples of run `run_id` of science-6p5-penalty's committed state over `[from_s, to_s]`;
/// panics unless the state reaches `to_s` (the samples before it stay as the run goes on).
fn penalty_window(run_id: &str, from_s: f64, to_s: f64) -> Vec<rbc_schema::results::TimeSample> {
    state_window("science-6p5-penalty", run_id, from_s, to_s)
}

/// The ~4 mm/s r_init 1.0 um discocyte with the paper's penalty walls (session 39, from rest with
/// the walls coupled into the stages, `integrator.wall_coupling`, so that the stepping does not
/// drift it towards the axis) is, over 1.4-1.9 s, the croissant the 0.8 um run ended on the axis:
/// within 0.06 um of the axis (measured at most 0.0565, mean 0.044 um; the 0.8 um run's mean 0.047),
/// asphericity 0.0178-0.0187, 4.08 mm/s. So the ~4 mm/s switch lies between 1.0 and 1.2 um
/// (r_init 1.2 um ended a slipper) unless this run leaves the axis; rbc-predict takes it when it
/// ends. The samples before 1.9 s stay as the run goes on.
#[test]
fn with_the_papers_walls_the_u2p4_r_init_1p0_run_is_the_0p8_runs_croissant_on_the_axis_so_far() {
    let w = penalty_window("discocyte_u2.4_r1", 1.4, 1.9);
    assert!(w.len() >= 2500, "{} samples", w.len());
    let radial: Vec<f64> = w.iter().map(radial_um).collect();
    let (max, mean) = (radial.iter().copied().fold(0.0, f64::max), radial.iter().sum::<f64>() / radial.len() as f64);
    let (_, _, croissant) = ended_run_of("science-6p5-penalty", "discocyte_u2.4_r0.8", 0.8);
    assert!(max < 0.06 && (mean - croissant.mean_radial_um).abs() < 0.01, "radial up to {max:.4} um, mean {mean:.4} (the 0.8 um croissant's {:.4})", croissant.mean_radial_um);
    assert!(w.iter().all(|s| (0.017..0.02).contains(&s.asphericity) && (4.0..4.2).contains(&s.velocity_mm_s[0])), "a croissant's asphericity at ~4 mm/s");
}

/// The ~1 mm/s r_init 0.8 um discocyte with the paper's penalty walls (session 39, from rest,
/// ROS34PRw as its column) swings, over 1.6-2.5 s, on the orbit of the 1.2 um run's slipper: y
/// 0.838-1.436 um (the 1.2 um run over the same times: 0.869-1.453), mean 1.079 (1.082), off the
/// axis throughout; its swings still grow slowly towards the 1.2 um run's (the troughs by ~0.01
/// um a period of ~0.34 s), so it has no periodic verdict yet. With the croissant from 0.4 um the
/// ~1 mm/s switch lies between 0.4 and 0.8 um unless this run comes in. The samples before 2.5 s
/// stay as the run goes on.
#[test]
fn with_the_papers_walls_the_u0p63_r_init_0p8_run_swings_on_the_1p2_runs_slipper_orbit_so_far() {
    let y = |run_id: &str| -> Vec<f64> { penalty_window(run_id, 1.6, 2.5).iter().map(|s| s.centroid_um[1]).collect() };
    let (own, orbit) = (y("discocyte_u0.63_r0.8"), y("discocyte_u0.63_r1.2"));
    assert!(own.len() >= 4500 && own.len() == orbit.len(), "{} and {} samples", own.len(), orbit.len());
    let ((lo, hi, mean), (olo, ohi, omean)) = (min_max_mean(&own), min_max_mean(&orbit));
    eprintln!("1.6-2.5 s: y {lo:.3}-{hi:.3} um, mean {mean:.4}; the 1.2 um run's {olo:.3}-{ohi:.3}, mean {omean:.4}");
    assert!(lo > 0.8, "off the axis throughout: y down to {lo:.3} um");
    assert!((lo - olo).abs() < 0.04 && (hi - ohi).abs() < 0.04 && (mean - omean).abs() < 0.01, "the 1.2 um run's orbit");
}

/// The ~4 mm/s r_init 1.0 um discocyte with the paper's penalty walls (from rest in session 39,
/// the walls coupled into the stages) ended `steady` at 2406.6 ms (session 41): a centred rigid
/// croissant within 0.1 um of the axis at ~4.08 mm/s, as the 0.8 um run ended. With the slipper
/// from 1.2 um the paper's walls put the ~4 mm/s switch between 1.0 and 1.2 um (rbc-predict:
/// r_trans 1.1 um), where exact walls put it between 0.6 and 0.8.
#[test]
fn with_the_papers_walls_the_u2p4_r_init_1p0_run_ended_a_centred_croissant() {
    assert_penalty_croissant_near_the_axis("discocyte_u2.4_r1", 1.0, "steady", 3.9..=4.2);
}

/// Run `run_id` (started at `r_init` um) with the paper's penalty walls ended `status`, a centred
/// rigid croissant at a cell velocity in `mm_s` ([`assert_centred_rigid_croissant_at`]) within 0.1
/// um of the axis. Returns the run's summary for further checks.
fn assert_penalty_croissant_near_the_axis(run_id: &str, r_init: f64, status: &str, mm_s: std::ops::RangeInclusive<f64>) -> rbc_schema::results::RunSummary {
    let (_, _, s) = ended_run_of("science-6p5-penalty", run_id, r_init);
    assert_centred_rigid_croissant_at(&s, status, mm_s);
    assert!(s.evidence["radial_max_um"] < 0.1, "near the axis: at most {} um off it", s.evidence["radial_max_um"]);
    s
}

/// Every ended run of both studies ends so again under today's detector (since session 42 it
/// scores its periodic candidates in one place for the verdict and for the status table's
/// periodic gap): handed a run's stored samples up to the end of its verdict's window (its
/// last sample, but for a run relabelled from an earlier window, as the ~2.5 mm/s r_init 1.2 um
/// exact-wall slipper), the detector with the study's criterion judges that window, every
/// slow-orbit span tested (`judge_at_the_last`: a run that ended at a resume before session 59,
/// or under an earlier cadence of the slow tests, may have ended at a sample where today's
/// cadence tests none), as the run
/// ended, `steady` or `periodic` (at the stored period within 1 %), and that verdict's gap is
/// `<= 1` (the steady gap of a steady run, the periodic gap of a periodic one); the steady gap of
/// a periodic run is not.
#[test]
fn the_studies_ended_runs_end_so_again_and_their_gaps_say_so() {
    use rbc_solver::steady::{observables, periodic_gap, steady_gap, SteadyDetector, Verdict};
    let mut checked = 0;
    for Ended { study, criterion: c, run: r, summary: s, mut rows } in ended_runs_of_both_studies(&["steady", "periodic"]) {
        rows.truncate(rows.partition_point(|row| row.t_s <= s.evidence["steady_end_s"] + 1e-9));
        let obs: Vec<[f64; 5]> = rows.iter().map(observables).collect();
        let mut d = SteadyDetector::new(c.clone()).unwrap();
        let v = d.judge_at_the_last(rows.iter().zip(&obs).map(|(row, o)| (row.t_s, &o[..]))).unwrap();
        let (steady, periodic) = (steady_gap(&rows, &c).map(|g| g.0), periodic_gap(&rows, &c).map(|g| g.gap));
        eprintln!("{study} {}: {} -> {v:?}, steady gap {steady:?}, periodic gap {periodic:?}", r.run_id, s.status.as_str());
        match v {
            Verdict::Steady { .. } => assert!(s.status.as_str() == "steady" && steady.is_some_and(|g| g <= 1.0), "{}", r.run_id),
            Verdict::Periodic { period_s, .. } => {
                assert_eq!(s.status.as_str(), "periodic", "{}", r.run_id);
                assert!((period_s / s.evidence["period_s"] - 1.0).abs() < 0.01, "{}: period {period_s} against {}", r.run_id, s.evidence["period_s"]);
                assert!(periodic.is_some_and(|g| g <= 1.0) && steady.is_some_and(|g| g > 1.0), "{}", r.run_id);
            }
            other => panic!("{}: ended {} but judged {other:?}", r.run_id, s.status.as_str()),
        }
        checked += 1;
    }
    assert!(checked >= 25, "{checked} ended runs");
}

/// An ended run of one of the two studies, with its study's steady-state criterion and its rows.
struct Ended {
    study: &'static str,
    criterion: rbc_solver::steady::SteadyCriterion,
    run: RunRecord,
    summary: rbc_schema::results::RunSummary,
    rows: Vec<rbc_schema::results::TimeSample>,
}

/// The runs of both studies' committed states that ended with one of `statuses`.
fn ended_runs_of_both_studies(statuses: &[&str]) -> Vec<Ended> {
    let mut ended = Vec::new();
    for study in ["science-6p5", "science-6p5-penalty"] {
        let sweep = rbc_schema::sweep::Sweep::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies").join(study).join("sweep.toml")).unwrap();
        let criterion = rbc::sweep::verdict::criterion(&sweep.steady, f64::INFINITY);
        for f in state_files(study) {
            for run in read_runs(&f).unwrap() {
                let Some(summary) = run.summary.clone().filter(|s| statuses.contains(&s.status.as_str())) else { continue };
                let rows = rbc_schema::results::read_timeseries(&f, &run.run_id).unwrap();
                ended.push(Ended { study, criterion: criterion.clone(), run, summary, rows });
            }
        }
    }
    ended
}

/// A tank-treading slipper judged over four of its own periods (in `period`, s), swinging from
/// nearer than `swing.0` to further than `swing.1` um off the axis, its shape turning by less than
/// `turns` about z over the classification window; returns its period (s).
fn assert_tank_treading_slipper_over_four_periods(s: &rbc_schema::results::RunSummary, period: std::ops::Range<f64>, swing: (f64, f64), turns: f64) -> f64 {
    assert!(s.tank_treading, "a tank-treading slipper");
    let p = s.evidence["period_s"];
    assert!(period.contains(&p), "a period of {p} s, not in {period:?}");
    let window = s.evidence["steady_end_s"] - s.evidence["steady_start_s"];
    assert!((window / (4.0 * p) - 1.0).abs() < 1e-3, "judged over four periods: {window} s");
    assert!(s.evidence["radial_min_um"] < swing.0 && s.evidence["radial_max_um"] > swing.1, "a wide swing: {:?}", (s.evidence["radial_min_um"], s.evidence["radial_max_um"]));
    assert!(s.evidence["tumbling_turns"].abs() < turns, "its shape does not turn over: {} turns", s.evidence["tumbling_turns"]);
    p
}

/// The ~0.5 mm/s r_init 1.2 um discocyte with the paper's penalty walls (from rest in session 43,
/// ROS34PRw; the mean flow 0.31 mm/s of the example recordings' 50 mbar group) ended `periodic` at
/// 5620.0 ms (session 46), judged over four of its own periods of 0.7245 s (window 2.722-5.620 s),
/// which the detector holds since session 46 (`WINDOW_STRETCH` 8: periods up to 1 s at the study's
/// 0.5 s window; 32 since session 52, up to 4 s). A tank-treading slipper (0.51 Hz about z) swinging widely, y 0.57-1.67 um (mean
/// 0.953), slowly out and quickly back: its disc's normal swings between ~60 and ~78 degrees in
/// the x-y plane and never turns over (0.016 turns over the classification window), 0.498 mm/s
/// (measured 2026-11-30). Its orbit's radial mean had settled: +0.0003 um/s over its last four
/// periods. The paper finds slippers below ~0.7 mm/s tumbling ("the cell rotates around the
/// z-axis while approximately preserving its shape"); this one, from 1.2 um, does not.
#[test]
fn with_the_papers_walls_the_u0p31_r_init_1p2_run_ended_a_tank_treading_slipper_swinging_with_0p72_s() {
    let (state, _, s) = ended_run_of("science-6p5-penalty", "discocyte_u0.31_r1.2", 1.2);
    assert_off_centre_slipper_at(&s, 0.47..=0.53);
    // (a period more than the 0.5 s the detector held before session 46)
    let period = assert_tank_treading_slipper_over_four_periods(&s, 0.7..0.75, (0.65, 1.6), 0.05);
    let rows = rbc_schema::results::read_timeseries(&state, "discocyte_u0.31_r1.2").unwrap();
    let d = rbc_solver::steady::radial_orbit_drift(&rows, period).unwrap();
    assert!(d.rate.abs() < 0.002, "its orbit's mean settled: {d:?}");
    closed_loop_row(&state, false, "slipper");
}

/// The ~0.32 mm/s r_init 1.2 um discocyte with the paper's penalty walls (from rest in session
/// 53, ROS34PRw; mean flow 0.2 mm/s) ended `periodic` at 7400.0 ms (session 57), judged over four
/// of its own periods of 0.960 s (window 3.560-7.400 s): a tank-treading slipper (0.43 Hz) swinging
/// widely, 0.78-2.04 um off the axis (mean y 1.27 um), 0.312 mm/s, its shape turning -0.08 turn
/// about z over the classification window: it does not tumble. Once a period it folds (two
/// shortest axes nearly equal) and comes out lying flat
/// (`at_0p32_mm_s_the_cell_folds_as_at_0p37_mm_s_where_at_0p26_mm_s_it_turns_over_as_a_disc`): the
/// detector's period is the folds' interval, which had settled to 0.9608 s (+0.0008 s on the one
/// before) at the last fold the samples hold. With the ~0.26 mm/s run tumbling, this model's switch
/// from tank-treading to tumbling slippers lies between ~0.26 and ~0.32 mm/s (the paper's: ~0.7).
#[test]
fn with_the_papers_walls_the_u0p2_r_init_1p2_run_ended_a_tank_treading_slipper_folding_every_0p96_s() {
    assert_ended_slipper_folding_once_a_period("discocyte_u0.2_r1.2", 0.29..=0.33, 0.955..0.965, (0.8, 2.0), 7);
}

/// The paper's-walls run `run_id` (started at 1.2 um) ended an off-centre slipper at a cell
/// velocity in `mm_s`, tank-treading over four of its own periods (in `period`, s) while swinging
/// from nearer than `swing.0` to further than `swing.1` um off the axis, its shape turning by less
/// than 0.1 turn about z; its length along the flow collapsed at least `folds` times, the first an
/// overturn from its start (`across` above 0.9), every later one a fold (below 0.85), the last
/// interval between them the detector's period within 2 ms.
fn assert_ended_slipper_folding_once_a_period(run_id: &str, mm_s: std::ops::RangeInclusive<f64>, period: std::ops::Range<f64>, swing: (f64, f64), folds: usize) {
    let (state, _, s) = ended_run_of("science-6p5-penalty", run_id, 1.2);
    assert_off_centre_slipper_at(&s, mm_s);
    let period = assert_tank_treading_slipper_over_four_periods(&s, period, swing, 0.1);
    let rows = rbc_schema::results::read_timeseries(&state, run_id).unwrap();
    let c = length_collapses(&rows, DEFAULT_FRACTION);
    let last = c.last().and_then(|c| c.interval_s).unwrap();
    assert!(c.len() >= folds && (last - period).abs() < 2e-3, "{run_id}: the folds' last interval {last} s against the period {period} s");
    assert!(c[0].across > 0.9 && c[1..].iter().all(|e| e.across < 0.85), "{run_id}: one overturn, then folds: {c:?}");
}

/// The ~0.37 mm/s r_init 1.2 um discocyte with the paper's penalty walls (from rest in session
/// 52, ROS34PRw; mean flow 0.23 mm/s) ended `periodic` at 7720.0 ms (session 60), judged over four
/// of its own periods of 0.890 s (window 4.159-7.720 s): a tank-treading slipper (0.41 Hz)
/// swinging widely, 0.65-1.89 um off the axis (mean y 1.11 um), 0.363 mm/s, its shape turning
/// -0.04 turn about z over the classification window: it does not tumble. As the ~0.32 mm/s run,
/// it overturned once from its start (0.58 s) and then folds once a period (nine folds, the
/// intervals settling from 0.926 and 0.816 s to 0.8904 s, +0.01 % at the last): the detector's
/// period is the folds' interval. So at ~0.37 mm/s this model's slipper still tank-treads and
/// folds; the switch to tumbling lies between ~0.26 and ~0.32 mm/s.
#[test]
fn with_the_papers_walls_the_u0p23_r_init_1p2_run_ended_a_tank_treading_slipper_folding_every_0p89_s() {
    assert_ended_slipper_folding_once_a_period("discocyte_u0.23_r1.2", 0.34..=0.39, 0.885..0.895, (0.7, 1.8), 9);
}

/// The ~0.5 mm/s croissant start from 1.2 um with the paper's walls (session 59's last save, its
/// samples up to 1614.4 ms; the run goes on), the same settled ~1 mm/s croissant as the 0.2 um
/// start, which held a croissant 0.14 um off the axis and came in to it: this one swings off the
/// axis as the discocytes of its column do (y 0.57-1.67 um), 0.57-1.45 um from the axis after 0.4
/// s, never nearer. So at ~0.5 mm/s a croissant start holds from 0.2 um and not from 1.2 um: the
/// croissant starts' switch lies in [0.2, 1.2] um there (its verdict will say whether it ends a
/// slipper).
#[test]
fn the_u0p31_croissant_start_from_1p2_um_swings_off_the_axis_where_the_0p2_um_one_held() {
    let mut rows = study_file_rows("science-6p5-penalty/state/croissant_u0.31_r1.2.h5", "croissant_u0.31_r1.2");
    rows.truncate(rows.partition_point(|r| r.t_s <= 1.6145));
    assert!((rows[rows.len() - 1].t_s - 1.6144).abs() < 1e-3, "the samples of session 59's last save");
    let radial: Vec<f64> = rows.iter().filter(|r| r.t_s >= 0.4).map(|r| r.centroid_um[1].hypot(r.centroid_um[2])).collect();
    let (lo, hi) = radial.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| (lo.min(r), hi.max(r)));
    assert!(lo > 0.5 && hi > 1.4, "off the axis and swinging after 0.4 s: {lo}-{hi} um");
    let (_, _, held) = ended_run_of("science-6p5-penalty", "croissant_u0.31_r0.2", 0.2);
    assert!(held.evidence["radial_max_um"] < 0.2, "the 0.2 um start held near the axis: {}", held.evidence["radial_max_um"]);
}

/// The ~2.1 mm/s r_init 1.2 um run with the paper's walls (session 45's save, its samples up to
/// 5532.5 ms; the run goes on) swings as a tank-treading slipper at y 0.56-0.94 um whose orbit
/// mean comes in without slowing down. Over whole periods of the periodic gap's candidate (217
/// ms) the radial mean fell at 0.0251 um/s over its last span of four periods and at 0.0237 over
/// the span before (`rbc_solver::steady::orbit_drift`, the column `radial drift` of `rbc-sweep
/// status`; period by period 0.013-0.020 um/s over 1.5-2.4 s, 0.030-0.043 over 2.8-3.7 s,
/// 0.022 over 4.5-5.0 s and 0.028 at 5.4 s). A cell settling onto a stable orbit would slow
/// down; this one has not, so its slipper is not shown to be stable. At the same time its periodic gap is
/// 2.1 (the repetition of the extent along x), and the periodic test's drift part would pass a
/// mean moving at up to ~0.08 um/s at this period: the drift's trend is what a `periodic`
/// verdict on this run would need beside it.
#[test]
fn the_u1p25_r_init_1p2_slippers_orbit_mean_comes_in_without_slowing_so_far() {
    let mut rows = study_file_rows("science-6p5-penalty/state/discocyte_u1.25_r1.2.h5", "discocyte_u1.25_r1.2");
    rows.truncate(rows.partition_point(|r| r.t_s <= 5.5326));
    assert!((rows[rows.len() - 1].t_s - 5.5325).abs() < 1e-3, "the samples of session 45's save");
    let sweep = rbc_schema::sweep::Sweep::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies/science-6p5-penalty/sweep.toml")).unwrap();
    let c = rbc::sweep::verdict::criterion(&sweep.steady, f64::INFINITY);
    let orbit = rbc_solver::steady::periodic_gap(&rows, &c).unwrap();
    assert!((0.21..0.22).contains(&orbit.period_s) && (1.5..3.0).contains(&orbit.gap), "{orbit:?}");
    let d = rbc_solver::steady::radial_orbit_drift(&rows, orbit.period_s).unwrap();
    let e = d.earlier_rate.unwrap();
    assert!((d.span_s / orbit.period_s - 4.0).abs() < 1e-9, "{d:?}");
    assert!((-0.03..-0.02).contains(&d.rate) && (-0.03..-0.02).contains(&e), "{d:?}");
    assert!(d.rate <= e, "not slowing down: {d:?}");
}

/// `rbc-sweep status` reads the gaps of an ended run for scripts: the ~1 mm/s r_init 0.8 um
/// slipper with the paper's walls ended `periodic`, so its periodic gap is at most 1 and its steady
/// gap (the swinging slipper's extents range ~30x their tolerance) is not; its orbit's radial
/// mean was still moving out, but settling: 0.012 um/s over its last span of four ~331 ms
/// periods against 0.047 over the span before. Without the sweep's criterion there is no gap and
/// no period to give.
#[test]
fn the_status_fields_give_an_ended_slippers_gaps() {
    let study = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies/science-6p5-penalty");
    let status = |with_sweep: bool| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_rbc-sweep"));
        cmd.arg("status").arg(study.join("state/discocyte_u0.63_r0.8.h5")).args(["--run", "discocyte_u0.63_r0.8", "--field", "status,steady_gap,periodic_gap,orbit_drift_um_s,orbit_drift_before_um_s"]);
        if with_sweep {
            cmd.arg("--sweep").arg(study.join("sweep.toml"));
        }
        let o = cmd.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap().split_whitespace().map(str::to_string).collect::<Vec<_>>()
    };
    let v = status(true);
    assert_eq!(v[0], "periodic", "{v:?}");
    let (steady, periodic): (f64, f64) = (v[1].parse().unwrap(), v[2].parse().unwrap());
    assert!(steady > 20.0 && periodic <= 1.0 && periodic > 0.5, "{v:?}");
    let (rate, earlier): (f64, f64) = (v[3].parse().unwrap(), v[4].parse().unwrap());
    assert!(0.0 < rate && rate < 0.02 && rate < 0.5 * earlier && earlier < 0.06, "settling: {v:?}");
    assert_eq!(status(false), ["periodic", "-", "-", "-", "-"]);
}

/// The ~3.2 mm/s r_init 1.2 um discocyte with the paper's penalty walls (from rest in session 41,
/// the walls coupled into the stages) comes in to the axis where the ~4 mm/s run of the same start
/// swings as a slipper: its swings shrank and moved in (y 0.28-0.66 um over 400-600 ms), it
/// crossed the axis at ~680 ms, and over 800-1100 ms it stays 0.13-0.16 um off the axis (mostly
/// along z; measured 2026-11-30), while the ~4 mm/s r_init 1.2 um slipper swings at y 0.87-1.18
/// um. It ended a croissant (the next test).
#[test]
fn with_the_papers_walls_the_u1p9_r_init_1p2_run_comes_in_to_the_axis_so_far() {
    let w = penalty_window("discocyte_u1.9_r1.2", 0.8, 1.1);
    assert!(w.len() >= 1500, "{} samples", w.len());
    let radial: Vec<f64> = w.iter().map(radial_um).collect();
    let (min, max, _) = min_max_mean(&radial);
    eprintln!("800-1100 ms: radial {min:.3}-{max:.3} um");
    assert!(max < 0.2, "near the axis: radial up to {max} um");
    let slipper: Vec<f64> = penalty_window("discocyte_u2.4_r1.2", 1.1, 1.6).iter().map(|s| s.centroid_um[1]).collect();
    assert!(min_max_mean(&slipper).0 > 0.8, "the ~4 mm/s slipper swings off the axis");
}

/// The ~3.2 mm/s r_init 1.2 um discocyte with the paper's penalty walls ended `steady` at 2297.8 ms
/// (session 43; window 1.80-2.30 s): a centred rigid croissant, mean radial offset 0.061 um (at
/// most 0.076, mostly along z), non-rigid speed 0.02 % of the cell's, 3.22 mm/s (measured
/// 2026-11-30), where the ~4 mm/s run of the same start ended a tank-treading slipper
/// (`with_the_papers_walls_the_u2p4_r_init_1p2_run_ended_an_off_centre_tank_treading_slipper`).
/// So with the paper's walls every start at ~2.5 and ~3.2 mm/s ends a croissant (the paper:
/// croissants only "from around 2 to 3 mm/s"), and the band's upper edge lies between 3.22 and
/// 4.07 mm/s.
#[test]
fn with_the_papers_walls_the_u1p9_r_init_1p2_run_ended_a_centred_croissant_where_4_mm_s_gives_a_slipper() {
    assert_penalty_croissant_near_the_axis("discocyte_u1.9_r1.2", 1.2, "steady", 3.1..=3.35);
    let (_, _, slipper) = ended_run_of("science-6p5-penalty", "discocyte_u2.4_r1.2", 1.2);
    assert_eq!((slipper.final_shape, slipper.tank_treading), (FinalShape::Slipper, true), "the ~4 mm/s run of the same start");
}

/// The ~3.6 mm/s r_init 1.2 um discocyte with the paper's penalty walls (the walls coupled; queued
/// in session 43, from rest since session 46) ended `steady` at 3643.0 ms (session 49; window
/// 3.143-3.643 s): a centred rigid croissant, mean radial offset 0.013 um (at most 0.023),
/// non-rigid speed 0.003 % of the cell's, 3.658 mm/s (measured 2026-12-01). It came in to the axis
/// by ~0.8 s and then held a croissant whose extents relaxed for ~2.5 s more (x 6.85 -> 6.63 um).
/// So with the paper's walls the croissant-only band reaches ~3.66 mm/s: its upper edge lies
/// between 3.66 and 4.07 mm/s, where the run of the same start ended a slipper.
#[test]
fn with_the_papers_walls_the_u2p15_r_init_1p2_run_ended_a_centred_croissant() {
    let s = assert_penalty_croissant_near_the_axis("discocyte_u2.15_r1.2", 1.2, "steady", 3.6..=3.7);
    assert!(s.evidence["radial_max_um"] < 0.03, "on the axis: at most {} um off it", s.evidence["radial_max_um"]);
}

/// The radial drift at each ended `steady` run's verdict (`rbc-sweep status`'s last column: with
/// no orbit, the slope of the radial position's means over quarters of the window, over the last
/// window and the one before; session 47). The steady test passes a centroid that moves by less
/// than its 0.05 um tolerance per 0.5 s window, i.e. up to ~0.1 um/s. Of the paper's-walls
/// study's eight steady croissants (the ~3.6 mm/s one since session 49, the ~2.5 mm/s r_init 1.2 um
/// one since session 56, its r_init 0.4 um one since session 57) none was leaving the axis: each
/// came in (rates -0.015 to -0.066 um/s; the r_init 0.4 um one after creeping out at +0.010 um/s
/// over 2.4-2.6 s) or went out slowing (the ~2.5 mm/s r_init 0.8 um one, +0.020 against -0.106
/// before).
/// Of the exact-wall study's five, the ~1 mm/s r_init 0.2 um croissant was leaving it at a steady
/// +0.039 um/s (+0.039 before): radial 0.012 um at 3.5 s, 0.055 at 5.25 s, its asphericity rising
/// 0.024 -> 0.028 and its extents still changing, when it was judged steady at 5.42 s; continued
/// 2 s past its verdict (session 48) it turned there and came back to ~0.02 um, a slow wander
/// about the axis (`the_exact_wall_1_mm_s_r_init_0p2_croissant_continued_past_its_verdict_comes_back_to_the_axis`).
/// The ~4 mm/s r_init 0.6 um one went out too, but slowing (+0.036 against +0.088).
/// The ~0.5 mm/s croissant start (session 58), judged within its first two windows (at 0.587 s,
/// started from a settled croissant), has no earlier rate: it came in at 0.029 um/s.
#[test]
fn the_steady_croissants_radial_drift_at_their_verdicts() {
    use rbc_solver::steady::{drift_interval_s, radial_orbit_drift};
    let mut leaving = Vec::new();
    let mut first_window = Vec::new();
    let mut checked = 0;
    for Ended { study, criterion: c, run: r, summary: s, rows } in ended_runs_of_both_studies(&["steady"]) {
        assert!((rows[rows.len() - 1].t_s - s.evidence["steady_end_s"]).abs() < 1e-6, "{study} {}: rows end at the verdict", r.run_id);
        let d = radial_orbit_drift(&rows, drift_interval_s(None, c.window_s)).unwrap();
        assert!(d.rate.abs() < 0.1, "{study} {}: {d:?}", r.run_id);
        checked += 1;
        // a run judged within its first two windows has no window before its last
        let Some(e) = d.earlier_rate else {
            first_window.push(format!("{study} {} {:+.3}", r.run_id, d.rate));
            continue;
        };
        eprintln!("{study} {}: {:+.4} um/s ({e:+.4} before)", r.run_id, d.rate);
        if d.rate > 0.0 && d.rate.abs() >= 0.9 * e.abs() {
            leaving.push(format!("{study} {} {:.3} {:.3}", r.run_id, d.rate, e));
        }
    }
    assert_eq!(checked, 14);
    assert_eq!(leaving, ["science-6p5 discocyte_u0.63_r0.2 0.039 0.039"]);
    assert_eq!(first_window, ["science-6p5-penalty croissant_u0.31_r0.2 -0.029"]);
}

/// The ~0.5 mm/s r_init 0.4 um run (ROS34PRw, from rest since session 48) on the samples before
/// session 49's first save (they stay as the run goes on): it left the axis at ~0.5 um/s (y 0.68
/// um at 0.5 s, 1.06 at 0.7 s) and swings on the 1.2 um run's slipper orbit (that run's y
/// 0.57-1.67 um, mean 0.95): y up to 1.36 um over 0.7-0.9 s, down to 0.55 over 0.9-1.1 s (measured
/// 1.359 and 0.553). A slipper so far: so the r_init 0.2 um run was queued.
#[test]
fn with_the_papers_walls_the_0p5_mm_s_r_init_0p4_run_left_the_axis_for_the_slipper_orbit_so_far() {
    let y = |t0: f64, t1: f64| min_max_mean(&state_window("science-6p5-penalty", "discocyte_u0.31_r0.4", t0, t1).iter().map(|s| s.centroid_um[1]).collect::<Vec<f64>>());
    let (_, out, _) = y(0.7, 0.9);
    let (back, _, _) = y(0.9, 1.1);
    assert!(out > 1.3 && out < 1.67, "out to y {out} um");
    assert!(back > 0.5 && back < 0.6, "back to y {back} um");
}

/// ~0.26 mm/s (mean flow 0.16 mm/s) from 1.2 um (ROS34PRw, from rest since session 51, ahead of
/// the ~0.5 mm/s r_init 0.2 um run), on the samples before session 51's save (they stay as the run
/// goes on): its discocyte flipped to face the flow as every start does (x extent 2.6 -> 8.2 um by
/// 0.2 s), then turned on about z: its x extent fell to 4.85 um at ~0.75 s, broadside to the flow
/// again (y extent 8.0 um), its shape's orientation in the x-y plane turning past 180 degrees with
/// its membrane turning along (`rbc-sweep status` at 777 ms: tank-treading 0.04 Hz, the shape
/// turning about z at 0.52 Hz over its last 0.8 s: a tumbling slipper so far; at the save, 1160.5
/// ms, 0.64 Hz and 0.02 Hz). After that flip it lies flat in the x-z plane (x 8.1, y 3.9, z 7.8 um
/// at 1.14 s), thinnest along the shear's gradient, as a tumbling disc lies between its flips,
/// its shape's orientation 258 degrees on from the start and its membrane 209. No slipper at ~0.5
/// or ~1 mm/s does so: from 0.2 s on their x extents stay above 6 um (6.17 at least; they
/// tank-tread and swing). So this model's slipper tumbles at ~0.26 mm/s, as the paper's do below
/// ~0.7 mm/s, where at ~0.5 mm/s it does not: its switch to tumbling lies in [0.26, 0.5] mm/s.
/// Session 52 (samples to 2.0 s of its save at 2099.9 ms): it turned over again, its x extent
/// down to 4.51 um at 1.90 s (4.80 at 0.74 s), 1.16 s after the first turn, having lain flat in
/// the x-z plane for ~0.9 s between (x extent above 7.9 um over 1.0-1.6 s): it tumbles, so the
/// ~0.37 mm/s run (mean flow 0.23) was queued to halve the bracket. And a third time, x extent
/// 4.52 um at 2.89 s, 0.99 s after the second (session 52's second save, 2946.7 ms).
/// Session 53 (its first save, 3992.8 ms): a fourth time, 4.47 um at 3.93 s, 1.04 s after the
/// third; and (its second save, 5084.5 ms) a fifth, 4.41 um at 4.98 s, 1.05 s after the fourth:
/// the intervals (1.160, 0.991, 1.037, 1.054 s) settle, the last change 0.37x the one before,
/// towards ~1.06 s, a limit cycle of one turn-over (half a turn of its disc's normal about z).
/// Session 54 (its last save, 6266.9 ms): a sixth, 4.38 um at 6.05 s, 1.068 s after the fifth:
/// the intervals still lengthen, by 0.014 s where the last change was 0.017 (0.85x, not 0.37x),
/// and the cell comes out further before each turn-over (y up to 1.78, 1.80, 1.85, 1.89 um over
/// the four lying-flat phases from 2.0 s): its orbit drifts outwards at ~0.04 um a turn-over.
#[test]
fn at_0p26_mm_s_the_cell_turned_broadside_to_the_flow_again_so_far() {
    let rows = state_window("science-6p5-penalty", "discocyte_u0.16_r1.2", 0.0, 6.1);
    let x = |t0: f64, t1: f64| min_max_mean(&rows.iter().filter(|s| (t0..=t1).contains(&s.t_s)).map(|s| s.extents_um[0]).collect::<Vec<_>>());
    assert!(x(0.0, 0.0).0 < 3.0, "edge-on to the flow at the start: {:?}", x(0.0, 0.0));
    assert!(x(0.15, 0.45).0 > 8.0, "face-on after its first flip: {:?}", x(0.15, 0.45));
    assert!(x(0.6, 0.8).0 < 5.0, "broadside again: {:?}", x(0.6, 0.8));
    assert!(x(1.0, 1.6).0 > 7.9, "face-on again, lying flat: {:?}", x(1.0, 1.6));
    assert!(x(1.8, 2.0).0 < 5.0, "and broadside again: {:?}", x(1.8, 2.0));
    let at_least = |t0: f64, t1: f64| rows.iter().filter(|s| (t0..=t1).contains(&s.t_s)).min_by(|a, b| a.extents_um[0].total_cmp(&b.extents_um[0])).unwrap().t_s;
    let between = at_least(1.8, 2.0) - at_least(0.6, 0.8);
    assert!((1.1..1.25).contains(&between), "{between} s between the turns");
    assert!(x(2.1, 2.6).0 > 7.9 && x(2.8, 2.94).0 < 5.0, "face-on, then broadside a third time: {:?} {:?}", x(2.1, 2.6), x(2.8, 2.94));
    let third = at_least(2.8, 2.94) - at_least(1.8, 2.0);
    assert!((0.9..1.1).contains(&third), "{third} s between the second and third turns");
    assert!(x(3.1, 3.6).0 > 7.9 && x(3.85, 3.99).0 < 5.0, "face-on, then broadside a fourth time: {:?} {:?}", x(3.1, 3.6), x(3.85, 3.99));
    let fourth = at_least(3.85, 3.99) - at_least(2.8, 2.94);
    assert!((1.0..1.07).contains(&fourth), "{fourth} s between the third and fourth turns");
    assert!((fourth - third).abs() < 0.5 * (third - between).abs(), "the intervals settle: {between} {third} {fourth} s");
    assert!(x(4.1, 4.6).0 > 7.9 && x(4.9, 5.05).0 < 5.0, "face-on, then broadside a fifth time: {:?} {:?}", x(4.1, 4.6), x(4.9, 5.05));
    let fifth = at_least(4.9, 5.05) - at_least(3.85, 3.99);
    assert!((fifth - fourth).abs() < 0.5 * (fourth - third).abs() && fifth > fourth, "the intervals settle: {third} {fourth} {fifth} s");
    assert!(x(5.2, 5.7).0 > 7.9 && x(5.95, 6.1).0 < 4.4, "face-on, then broadside a sixth time: {:?} {:?}", x(5.2, 5.7), x(5.95, 6.1));
    let sixth = at_least(5.95, 6.1) - at_least(4.9, 5.05);
    assert!(sixth > fifth && sixth - fifth < 0.9 * (fifth - fourth), "the intervals lengthen by less each time: {fourth} {fifth} {sixth} s");
    // and the cell comes out further before each turn-over
    let y_out: Vec<f64> = [(2.0, 2.8), (3.0, 3.85), (4.0, 4.9), (5.0, 5.95)].iter().map(|&(t0, t1)| rows.iter().filter(|s| (t0..=t1).contains(&s.t_s)).map(|s| s.centroid_um[1]).fold(f64::NEG_INFINITY, f64::max)).collect();
    assert!(y_out.windows(2).all(|w| w[1] > w[0] + 0.02) && y_out[3] < 1.95, "y before the turn-overs: {y_out:?} um");
    for id in ["discocyte_u0.31_r1.2", "discocyte_u0.31_r0.4", "discocyte_u0.31_r0.2", "discocyte_u0.63_r0.6", "discocyte_u0.63_r0.8", "discocyte_u0.63_r1.2"] {
        let least = state_rows("science-6p5-penalty", id).iter().filter(|s| s.t_s >= 0.2).map(|s| s.extents_um[0]).fold(f64::INFINITY, f64::min);
        assert!(least > 6.0, "{id}: x extent down to {least} um after 0.2 s");
    }
}

/// The shapes of the run `run_id` in study `study`'s committed state, every `snapshot_every`-th
/// sample: the results file's snapshots and, for a run still open, the later ones its
/// checkpoint's ring holds (the ring reaches the checkpoint).
fn state_shapes(study: &str, run_id: &str) -> StoredShapes {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies").join(study).join("state").join(format!("{run_id}.h5"));
    rbc::sweep::stored_shapes::stored_shapes(&path, run_id).unwrap_or_else(|e| panic!("{study} {run_id}: {e}"))
}

/// Wherever in its orbit the ~0.26 mm/s run is judged, the classifier calls it a tumbling
/// slipper: over the windows of 25 shapes 60 ms apart (1.44 s; the run's ring holds 25 frames
/// one per 10 um of mean-flow travel, 62.4 ms apart, 1.50 s) ending every 0.15 s from 1.5 s to
/// 3.9 s (session 53's first save: three turn-overs and the lying flat between them), each is
/// an off-centre, asymmetric slipper whose shape turns at least half a turn about z (measured
/// 0.53-0.94 turns, against the 0.25 of `min_tumble_turns`), its membrane turning with it
/// (tank-treading at most 0.03 Hz relative to it, below the 0.1 turn of `min_tt_turns`). The
/// window is a distance of travel and the tumbling rate scales with the shear rate, so the turns
/// a window holds hardly depend on the velocity: slower tumbling slippers keep the label too.
#[test]
fn at_0p26_mm_s_every_classifier_window_of_the_orbit_is_a_tumbling_slipper() {
    use rbc_solver::classify::{classify, ClassifyConfig, Frame};
    let StoredShapes { times_s: times, vertices_um: shapes, triangles } = state_shapes("science-6p5-penalty", "discocyte_u0.16_r1.2");
    assert!(times.windows(2).all(|w| (w[1] - w[0] - 0.02).abs() < 1e-9), "a shape every 20 ms");
    let cfg = ClassifyConfig::default();
    assert_eq!((cfg.centred_um, cfg.symmetric_rel), (0.6, 0.05), "the study's [classify] settings");
    let mut turns = Vec::new();
    for k in 0..=16 {
        let end = times.partition_point(|&t| t < 1.5 + 0.15 * k as f64 - 1e-9);
        let frames: Vec<Frame<'_>> = (0..25).map(|j| end - 3 * (24 - j)).map(|i| Frame { t_s: times[i], vertices: &shapes[i] }).collect();
        let c = classify(&frames, &triangles, &cfg).unwrap();
        let e = &c.evidence;
        assert_eq!(c.shape, FinalShape::Slipper, "window ending {:.2} s: {e:?}", times[end]);
        assert!(c.tumbling && !c.tank_treading, "window ending {:.2} s: {e:?}", times[end]);
        assert!(e.offset_r_um > 1.2 && e.tumbling_turns.abs() > 0.5 && e.tt_frequency_hz < 0.035, "window ending {:.2} s: {e:?}", times[end]);
        turns.push(e.tumbling_turns.abs());
    }
    eprintln!("turns about z per window: {turns:.2?}");
}

/// The covariance of a shape's vertex cloud about its mean (um^2).
fn vertex_covariance(v: &[[f64; 3]]) -> nalgebra::Matrix3<f64> {
    let n = v.len() as f64;
    let c = v.iter().fold(nalgebra::Vector3::zeros(), |a, p| a + nalgebra::Vector3::from(*p)) / n;
    v.iter().fold(nalgebra::Matrix3::zeros(), |a, p| {
        let d = nalgebra::Vector3::from(*p) - c;
        a + d * d.transpose()
    }) / n
}

/// The azimuth in the x-y plane (degrees, unwrapped from the first shape on, the sign of the
/// normal kept continuous) of the normal of each shape: the principal axis of least extent of
/// its vertex cloud (the disc's normal).
fn normal_azimuths_deg(shapes: &[Vec<[f64; 3]>]) -> Vec<f64> {
    let mut prev: Option<nalgebra::Vector3<f64>> = None;
    let mut out: Vec<f64> = Vec::new();
    for v in shapes {
        let e = vertex_covariance(v).symmetric_eigen();
        let k = (0..3).min_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j])).unwrap();
        let mut normal: nalgebra::Vector3<f64> = e.eigenvectors.column(k).into();
        if prev.is_some_and(|p| p.dot(&normal) < 0.0) {
            normal = -normal;
        }
        prev = Some(normal);
        let a = normal.y.atan2(normal.x).to_degrees();
        let a = match out.last() {
            Some(&b) => b + (a - b + 180.0).rem_euclid(360.0) - 180.0,
            None => a,
        };
        out.push(a);
    }
    out
}

/// At ~0.37 mm/s (mean flow 0.23 mm/s, from 1.2 um, ROS34PRw) the cell overturned once and then
/// swung back instead of turning over again, on the shapes stored every 20 ms up to session 53's
/// second save (2329.5 ms). Its disc's normal (azimuth in the x-y plane from x) turned from along x (the
/// start, edge-on to the flow) to ~90 degrees by 0.4 s (facing the flow, as every start does),
/// and on through ~120 degrees more by 0.7 s, tilted out of the x-y plane (z component up to
/// 0.75): one overturn. After lying flat it crept back to ~89 degrees by 1.46 s, where the
/// ~0.26 mm/s run's normal goes on and turns over (180 degrees a turn-over, every ~1.03 s), but
/// swung back by ~40 degrees, to ~226, within 60 ms, and came back towards ~266 by 2.26 s, to
/// swing back again (by ~27 degrees by 2.32 s, the save). Its membrane turned on the while
/// (`rbc-sweep status` at 1.91 s: a slipper, tank-treading 0.57 Hz, its shape turning -0.01 Hz):
/// a swinging, tank-treading slipper after one overturn, where the
/// ~0.26 mm/s one tumbles. So far this model's switch to tumbling lies between ~0.26 and ~0.37
/// mm/s (the paper's: ~0.7).
#[test]
fn at_0p37_mm_s_the_cell_overturned_once_then_swung_back_so_far() {
    let StoredShapes { times_s: times, vertices_um: shapes, .. } = state_shapes("science-6p5-penalty", "discocyte_u0.23_r1.2");
    let az = normal_azimuths_deg(&shapes);
    let at = |t: f64| az[times.partition_point(|&s| s < t - 1e-9)];
    eprintln!("{:?}", times.iter().zip(&az).step_by(5).map(|(t, a)| format!("{t:.2}: {a:.0}")).collect::<Vec<_>>());
    let (start, faced, overturned) = (at(0.0), at(0.42), at(0.72));
    assert!(start.rem_euclid(180.0) < 10.0 || start.rem_euclid(180.0) > 170.0, "edge-on at the start: {start}");
    assert!(((faced - start).abs() - 90.0).abs() < 15.0, "faced the flow: {start} -> {faced}");
    assert!(((overturned - faced).abs() - 125.0).abs() < 20.0, "overturned once: {faced} -> {overturned}");
    let sense = (overturned - faced).signum();
    let creep = at(1.46);
    assert!(sense * (creep - overturned) > 20.0, "crept on in the same sense: {overturned} -> {creep}");
    assert!((creep - overturned).abs() < 60.0, "but not over again: {overturned} -> {creep}");
    let (lo, _, _) = min_max_mean(&(0..times.len()).filter(|&i| (1.46..=1.9).contains(&times[i])).map(|i| sense * (az[i] - creep)).collect::<Vec<_>>());
    assert!(lo < -30.0, "swung back by {lo} degrees");
    let again = at(2.26);
    assert!(sense * (again - creep) > -15.0 && sense * (again - creep) < 10.0, "back near the same azimuth: {creep} -> {again}");
    let swung = sense * (at(2.32) - again);
    assert!(swung < -20.0, "and swung back again, by {swung} degrees at 2.32 s");
    // the ~0.26 mm/s run's normal, in contrast, turns on in one sense, 180 degrees a turn-over
    let StoredShapes { times_s: t16, vertices_um: s16, .. } = state_shapes("science-6p5-penalty", "discocyte_u0.16_r1.2");
    let a16 = normal_azimuths_deg(&s16);
    let at16 = |t: f64| a16[t16.partition_point(|&s| s < t - 1e-9)];
    let turned = at16(3.98) - at16(1.0);
    assert!((turned.abs() - 540.0).abs() < 40.0, "~0.26 mm/s: {turned} degrees over 1.0-3.98 s, three turn-overs");
    let back = (0..t16.len()).filter(|&i| t16[i] >= 1.0).map(|i| turned.signum() * (a16[i] - a16[i.saturating_sub(1)])).fold(f64::INFINITY, f64::min);
    assert!(back > -3.0, "~0.26 mm/s: never back by more than {back} degrees between two shapes");
}

/// The in-plane anisotropy `sqrt((g_xx - g_yy)^2 + 4 g_xy^2) / (g_xx + g_yy)` of a shape's vertex
/// cloud (0: round seen along z), the ratio of its two least principal moments (a disc: ~0.15-0.3;
/// 1: its two shortest axes equal, no disc) and its extents (um).
fn disc_measures(v: &[[f64; 3]]) -> (f64, f64, [f64; 3]) {
    let g = vertex_covariance(v);
    let anisotropy = ((g[(0, 0)] - g[(1, 1)]).powi(2) + 4.0 * g[(0, 1)].powi(2)).sqrt() / (g[(0, 0)] + g[(1, 1)]);
    let mut w: Vec<f64> = g.symmetric_eigen().eigenvalues.iter().copied().collect();
    w.sort_by(f64::total_cmp);
    let extent = |k: usize| v.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max) - v.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
    (anisotropy, w[0] / w[1], [extent(0), extent(1), extent(2)])
}

/// At ~0.32 mm/s (mean flow 0.2 mm/s, from 1.2 um, ROS34PRw; queued in session 53) the cell does
/// what the ~0.37 mm/s one does, not what the ~0.26 mm/s one does. The events are the collapses of
/// each cell's length along the flow that `rbc-sweep events` lists (`length_collapses`, at the
/// times below within 2 ms; each run's first is its overturn from the start, broadside). Over
/// +-0.12 s around each event on the shapes stored every 20 ms (session 54's second save, 1786 ms):
/// - ~0.26 mm/s, its turn-overs at 1.90, 2.89, 3.93, 4.98 and 6.05 s: it turns over as a disc,
///   the shape kept (in-plane anisotropy at least 0.50, the two least principal moments at most
///   0.29 apart in ratio), broadside to the flow on the way (x extent down to 4.41-4.60 um, y up
///   to 7.71-7.86): the paper's tumbling, "while approximately preserving its shape";
/// - ~0.37 mm/s at 1.49 s and ~0.32 mm/s at 1.70 s (after lying flat since their one overturn at
///   0.5-0.73 s): the cell folds instead, its two shortest axes nearly equal (ratio 0.84 and 0.91),
///   round seen along z (anisotropy 0.067 and 0.039), x extent no lower than 6.01 and 5.89 um, y
///   no higher than 6.21 and 6.34, and comes out lying flat again; the ~0.32 mm/s one folded
///   again at 2.58 s, 0.88 s later (ratio 0.89, anisotropy 0.058, x extent >= 5.82 um, y <= 6.16),
///   a third time at 3.53 s, 0.94 s later (0.90, 0.055, 5.82, 6.17), and a fourth at 4.48 s, 0.96
///   s later (0.87, 0.068, 5.83, 6.14; its shapes to 4.64 s, session 56's first save), and a fifth
///   at 5.44 s (session 56's last save, 5.82 s), and a sixth at 6.40 s (session 57): the intervals
///   0.88, 0.94, 0.958, 0.960, 0.961 s lengthen by less each time (+0.062, +0.016, +0.0023,
///   +0.0008 s). Its membrane turns through the
///   event as the ~0.26 mm/s run's does through a turn-over (a rigid fit of the labelled vertices:
///   +80, +82 and +93 degrees about z over 0.18 s), but the shape does not turn with it.
///
/// So this model's switch to tumbling lies between ~0.26 and ~0.32 mm/s (the paper's: ~0.7). The
/// 20 ms frames do not tell which way the ~0.32 mm/s shape's long axis turned through its round
/// moment (21 -> -66 degrees from x between 1.68 and 1.70 s); over whole windows the classifier
/// finds the shape turning at most 0.18 turn about z
/// (`at_0p32_mm_s_every_classifier_window_so_far_is_a_tank_treading_slipper`).
#[test]
fn at_0p32_mm_s_the_cell_folds_as_at_0p37_mm_s_where_at_0p26_mm_s_it_turns_over_as_a_disc() {
    let event = |run: &str, s: &StoredShapes, at_s: f64| {
        assert!(*s.times_s.last().unwrap() >= at_s + 0.06, "{run}: shapes to {} s", s.times_s.last().unwrap());
        let m: Vec<_> = (0..s.times_s.len()).filter(|&i| (s.times_s[i] - at_s).abs() <= 0.12 + 1e-9).map(|i| disc_measures(&s.vertices_um[i])).collect();
        assert!(m.len() >= 9, "{run} at {at_s} s: {} shapes", m.len());
        let least_anisotropy = m.iter().map(|x| x.0).fold(f64::INFINITY, f64::min);
        let most_round = m.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max);
        let least_x = m.iter().map(|x| x.2[0]).fold(f64::INFINITY, f64::min);
        let most_y = m.iter().map(|x| x.2[1]).fold(f64::NEG_INFINITY, f64::max);
        eprintln!("{run} at {at_s} s: anisotropy >= {least_anisotropy:.3}, least moments' ratio <= {most_round:.2}, x extent >= {least_x:.2} um, y extent <= {most_y:.2} um");
        (least_anisotropy, most_round, least_x, most_y)
    };
    // the moments each run's length along the flow collapsed (`rbc-sweep events`), at the times
    // this test was written from: the first an overturn from the start (broadside, `across` ~1),
    // then turn-overs (~0.26 mm/s) or folds
    let collapses = |run: &str, at: &[f64]| {
        let c = length_collapses(&state_rows("science-6p5-penalty", run), DEFAULT_FRACTION);
        let times: Vec<f64> = c.iter().map(|e| e.t_s).collect();
        assert!(times.len() >= at.len() && times.iter().zip(at).all(|(t, a)| (t - a).abs() < 2e-3), "{run}: collapses at {times:?} s, expected {at:?}");
        assert!(c[0].across > 0.9, "{run}: the first, an overturn: {:?}", c[0]);
        c[1..at.len()].to_vec()
    };
    // each run's shapes read once
    let tumbling = state_shapes("science-6p5-penalty", "discocyte_u0.16_r1.2");
    for e in collapses("discocyte_u0.16_r1.2", &[0.740, 1.900, 2.890, 3.927, 4.981, 6.049]) {
        assert!(e.across > 0.95 && e.x_min_rel < 0.6, "~0.26 mm/s: broadside {e:?}");
        let (an, ratio, x, y) = event("discocyte_u0.16_r1.2", &tumbling, e.t_s);
        assert!(an > 0.45 && ratio < 0.32 && x < 4.7 && y > 7.6, "~0.26 mm/s at {} s: a disc turning over", e.t_s);
    }
    for (run, at) in [("discocyte_u0.23_r1.2", &[0.582, 1.508][..]), ("discocyte_u0.2_r1.2", &[0.667, 1.704, 2.584, 3.526, 4.484, 5.444, 6.405][..])] {
        let shapes = state_shapes("science-6p5-penalty", run);
        for e in collapses(run, at) {
            assert!(e.across < 0.85 && (0.74..0.8).contains(&e.x_min_rel), "{run}: folded {e:?}");
            let (an, ratio, x, y) = event(run, &shapes, e.t_s);
            assert!(an < 0.1 && ratio > 0.75 && x > 5.8 && y < 6.5, "{run} at {} s: folded, not a disc turning over", e.t_s);
        }
    }
}

/// `rbc-sweep events` on every ended run of both studies: the tank-treading orbits' swings never
/// take a cell's length along the flow below the default threshold (0.82 of its median), but for
/// three: the exact-wall ~6.5 mm/s r_init 0.6 um run's start transient at 0.07 s (0.80, the cell
/// bending, not turning: `across` 0.66), and the ~0.32 and ~0.37 mm/s slippers with the paper's
/// walls (ended in sessions 57 and 60), which overturn once from their start and then fold once a
/// period, never turning over again (`across` below 0.85 at each fold).
#[test]
fn no_ended_run_of_either_study_turns_over_and_two_fold() {
    let mut early = Vec::new();
    let mut folding = Vec::new();
    let mut checked = 0;
    for Ended { study, run: r, rows, .. } in ended_runs_of_both_studies(&["steady", "periodic"]) {
        let c = length_collapses(&rows, DEFAULT_FRACTION);
        if study == "science-6p5-penalty" && ["discocyte_u0.2_r1.2", "discocyte_u0.23_r1.2"].contains(&r.run_id.as_str()) {
            assert!(c.len() >= 7 && c[0].across > 0.9 && c[1..].iter().all(|e| e.across < 0.85), "{}: {c:?}", r.run_id);
            folding.push(c.len());
        } else {
            for e in c {
                assert!(e.t_s < 0.1, "{study} {} collapses at {} s: {e:?}", r.run_id, e.t_s);
                early.push(format!("{study} {} {:.2}", r.run_id, e.t_s));
            }
        }
        checked += 1;
    }
    assert!(checked >= 30, "{checked} ended runs");
    assert_eq!(early, ["science-6p5 discocyte_u3.8_r0.6 0.07"]);
    assert_eq!(folding.len(), 2, "the ~0.32 and ~0.37 mm/s runs have ended");
}

/// The ~0.5 mm/s r_init 0.2 um run (ROS34PRw, from rest since session 49) on the samples before
/// session 50's save (they stay as the run goes on): after its first 0.2 s near 0.23 um it moved
/// out faster and faster, radial 0.236 um at 0.25 s, 0.305 at 0.4, 0.454 at 0.65 and 0.492 at 0.7
/// (0.59 um/s over 0.4-0.65 s), its z going to 0, then y 0.74 um at 0.9 s and 1.36 at 1.1 s: the
/// 0.4 um run's way out, 0.4 s later (that run: 0.35-0.51 um over 0.3 s, 1.06 um at 0.7 s, 1.36 at
/// 0.8 s, then the 1.2 um run's slipper orbit). So the axis repels the cell at ~0.5 mm/s from
/// 0.2 um too: with the paper's walls this model's switch there seems to lie below 0.2 um (the
/// paper's Fig. 5 a has croissants near the axis down to ~0.25 mm/s; how near, its text does not
/// say).
#[test]
fn with_the_papers_walls_the_0p5_mm_s_r_init_0p2_run_left_the_axis_as_the_0p4_run_did_so_far() {
    let rows = state_window("science-6p5-penalty", "discocyte_u0.31_r0.2", 0.25, 1.1);
    let near = |t: f64| rows.iter().min_by(|a, b| (a.t_s - t).abs().total_cmp(&(b.t_s - t).abs())).unwrap();
    let at = |t: f64| radial_um(near(t));
    let radial: Vec<f64> = (0..18).map(|k| at(0.25 + 0.05 * k as f64)).collect();
    assert!(radial.windows(2).all(|w| w[1] > w[0]), "moving out: {radial:?}");
    let speed = |t0: f64, t1: f64| (at(t1) - at(t0)) / (t1 - t0);
    assert!((0.5..0.7).contains(&speed(0.4, 0.65)), "{} um/s over 0.4-0.65 s", speed(0.4, 0.65));
    assert!(speed(0.6, 0.7) > 1.2 * speed(0.4, 0.5), "faster and faster: {} then {} um/s", speed(0.4, 0.5), speed(0.6, 0.7));
    let y = near(1.1).centroid_um[1];
    assert!(y > 1.3 && y < 1.67, "out to y {y} um at 1.1 s, the slipper orbit's range (the 1.2 um run: 0.57-1.67 um)");
}

/// The two runs still going at session 47's save, on the samples before it (they stay as the runs
/// go on). ~3.6 mm/s r_init 1.2 um (the walls coupled): on the axis since ~0.8 s, a croissant so
/// far; over 1.7-2.2 s its radial position held 0.052-0.057 um and its asphericity 0.0180-0.0185,
/// and its radial drift turned (-0.0095 um/s over the last window against +0.063 over the one
/// before: it crept out at ~0.06 um/s over 1.1-1.7 s, then stopped). ~1 mm/s r_init 0.6 um
/// (ROS34PRw): over 1.9-2.8 s it swings at y 0.85-1.44 um, the 0.8 and 1.2 um runs' slipper
/// orbit (mean y 1.08), with their ~0.34 s period.
#[test]
fn with_the_papers_walls_the_3p6_mm_s_run_is_a_croissant_and_the_1_mm_s_r_init_0p6_run_a_slipper_so_far() {
    let croissant: Vec<f64> = state_window("science-6p5-penalty", "discocyte_u2.15_r1.2", 1.7, 2.2186).iter().map(radial_um).collect();
    let (min, max, _) = min_max_mean(&croissant);
    assert!(min > 0.04 && max < 0.07, "~3.6 mm/s: radial {min}-{max} um");
    let mut rows = state_rows("science-6p5-penalty", "discocyte_u2.15_r1.2");
    rows.truncate(rows.partition_point(|r| r.t_s <= 2.2187));
    let d = rbc_solver::steady::radial_orbit_drift(&rows, rbc_solver::steady::drift_interval_s(None, 0.5)).unwrap();
    assert!(d.rate.abs() < 0.02 && d.earlier_rate.unwrap() > 0.05, "~3.6 mm/s: {d:?}");
    let slipper: Vec<f64> = state_window("science-6p5-penalty", "discocyte_u0.63_r0.6", 1.9, 2.8056).iter().map(|s| s.centroid_um[1]).collect();
    let (min, max, _) = min_max_mean(&slipper);
    assert!(min > 0.8 && max > 1.4 && max < 1.5, "~1 mm/s r_init 0.6 um: y {min}-{max} um");
}

/// Every run saved in the two studies' state holds its whole history (the study saves and
/// resumes runs session after session; `scripts/study.sh save` copies a results file and its
/// checkpoint together):
/// - its samples start at rest (t = 0) and follow one another at the scene's output interval,
///   without a gap or a repeat;
/// - its regular snapshots (every `snapshot_every`-th sample, the sweep's) are the samples 0,
///   `snapshot_every`, `2 snapshot_every`, ... without a gap; an ended run holds them up to its
///   last sample (the observer stores its ring at the end, plus the classification frames between);
///   an open run holds the rest in its checkpoint's ring (up to ~1 s at ~0.5 mm/s, where a frame
///   is taken every few ms), so its checkpoint, saved with it, counts the same samples and
///   snapshots, at the time of its last sample, and a state its run can continue from
///   (`RunState::unusable`).
#[test]
fn every_saved_run_of_both_studies_holds_its_history_from_rest() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies");
    let key = |file: &str, table: Option<&str>, name: &str| -> toml::Value {
        let v: toml::Value = toml::from_str(&std::fs::read_to_string(root.join(file)).unwrap()).unwrap();
        let t = match table {
            Some(t) => &v[t],
            None => &v,
        };
        t.get(name).unwrap_or_else(|| panic!("{file}: no {name}")).clone()
    };
    let mut checked = (0, 0);
    for study in ["science-6p5", "science-6p5-penalty"] {
        let dt = key(&format!("{study}/scene.toml"), Some("time"), "output_interval_s").as_float().unwrap();
        let every = key(&format!("{study}/sweep.toml"), None, "snapshot_every").as_integer().unwrap() as usize;
        for file in state_files(study) {
            for run in read_runs(&file).unwrap() {
                let id = &run.run_id;
                let t: Vec<f64> = rbc_schema::results::read_timeseries(&file, id).unwrap().iter().map(|s| s.t_s).collect();
                assert_eq!(t[0], 0.0, "{study} {id}: the samples start at rest");
                for (k, w) in t.windows(2).enumerate() {
                    assert!((w[1] - w[0] - dt).abs() < 1e-9 * dt.max(w[1]), "{study} {id}: samples {k} and {} at {} and {} s", k + 1, w[0], w[1]);
                }
                let layout = rbc_schema::results::ResultsFile::open(&file).unwrap().snapshot_layout(id).unwrap();
                let snaps = &layout.times_s;
                assert!(snaps.windows(2).all(|w| w[1] > w[0]), "{study} {id}: snapshots in time order");
                let regular: Vec<usize> = snaps.iter().map(|s| (s / dt).round() as usize).filter(|k| k % every == 0).collect();
                assert!(regular.iter().enumerate().all(|(j, &k)| k == j * every), "{study} {id}: a regular snapshot is missing before sample {:?}", regular.iter().enumerate().find(|(j, &k)| k != j * every));
                let ck = rbc_schema::checkpoint::checkpoint_path(&file, id);
                if run.summary.is_some() {
                    assert_eq!(regular.len(), (t.len() - 1) / every + 1, "{study} {id} ended: regular snapshots up to its last sample");
                    checked.0 += 1;
                } else {
                    let ck = rbc_schema::checkpoint::read(&ck).unwrap_or_else(|e| panic!("{study} {id} is open: its checkpoint: {e}"));
                    assert_eq!((ck.n_samples, ck.n_snapshots), (t.len(), snaps.len()), "{study} {id}: the checkpoint counts the file's samples and snapshots");
                    let last = *t.last().unwrap();
                    assert!(ck.t_s >= last - 1e-12 && ck.t_s < last + dt, "{study} {id}: checkpoint at {} s, last sample at {last} s", ck.t_s);
                    assert!(regular.len() <= (t.len() - 1) / every + 1, "{study} {id}: no snapshot beyond the samples");
                    let state = rbc_solver::run::checkpoint::RunState::from_fields(&ck.fields, "").unwrap();
                    assert_eq!(state.unusable(layout.n_vertices), None, "{study} {id}: a state its run can continue from");
                    checked.1 += 1;
                }
            }
        }
    }
    eprintln!("ended runs {}, open runs {}", checked.0, checked.1);
    assert!(checked.0 >= 30 && checked.1 >= 5, "ended and open runs checked: {checked:?}");
}

/// At ~0.32 mm/s the classifier calls every window of the orbit so far a tank-treading slipper,
/// where at ~0.26 mm/s it calls every one a tumbling slipper
/// (`at_0p26_mm_s_every_classifier_window_of_the_orbit_is_a_tumbling_slipper`): windows of 25
/// shapes 60 ms apart (1.44 s; the run's ring takes a frame per 10 um of mean-flow travel, 50 ms
/// apart) ending every 0.05 s from 2.0 s (the first holds its one overturn at 0.60-0.73 s) to its
/// last stored shape (session 56's first save, 4642 ms: the folds at 1.70, 2.58, 3.53 and 4.48 s
/// inside). Each of the 53 is an off-centre slipper (1.13-1.40 um) whose membrane turns about its
/// shape at 0.38-0.56 Hz while the shape turns at most 0.18 turn about z (the ~0.26 mm/s run's:
/// 0.53-0.94 turns; `min_tumble_turns` 0.25): the folds do not turn the shape over.
#[test]
fn at_0p32_mm_s_every_classifier_window_so_far_is_a_tank_treading_slipper() {
    use rbc_solver::classify::{classify, ClassifyConfig, Frame};
    let StoredShapes { times_s: all_times, vertices_um: all_shapes, triangles } = state_shapes("science-6p5-penalty", "discocyte_u0.2_r1.2");
    // the regular shapes, every 20 ms (the run, ended in session 57, also stored the frames its
    // label was decided on, between them)
    let regular: Vec<usize> = (0..all_times.len()).filter(|&i| ((all_times[i] / 0.02).round() * 0.02 - all_times[i]).abs() < 1e-9).collect();
    let times: Vec<f64> = regular.iter().map(|&i| all_times[i]).collect();
    let shapes: Vec<&Vec<[f64; 3]>> = regular.iter().map(|&i| &all_shapes[i]).collect();
    assert!(times.windows(2).all(|w| (w[1] - w[0] - 0.02).abs() < 1e-9), "a shape every 20 ms");
    let last = *times.last().unwrap();
    assert!(last >= 2.8, "shapes to {last} s");
    let cfg = ClassifyConfig::default();
    let mut turns = Vec::new();
    for t_end in (0..).map(|k| 2.0 + 0.05 * k as f64).take_while(|&t| t <= last + 1e-9) {
        let end = times.partition_point(|&t| t < t_end - 1e-9);
        let frames: Vec<Frame<'_>> = (0..25).map(|j| end - 3 * (24 - j)).map(|i| Frame { t_s: times[i], vertices: shapes[i] }).collect();
        let c = classify(&frames, &triangles, &cfg).unwrap();
        let e = &c.evidence;
        assert_eq!(c.shape, FinalShape::Slipper, "window ending {:.2} s: {e:?}", times[end]);
        assert!(c.tank_treading && !c.tumbling, "window ending {:.2} s: {e:?}", times[end]);
        assert!(e.offset_r_um > 1.1 && e.tumbling_turns.abs() < 0.2 && (0.35..0.6).contains(&e.tt_frequency_hz), "window ending {:.2} s: {e:?}", times[end]);
        turns.push((e.tumbling_turns, e.tt_frequency_hz, e.offset_r_um));
    }
    assert!(turns.len() >= 53, "{} windows", turns.len());
    let range = |f: fn(&(f64, f64, f64)) -> f64| min_max_mean(&turns.iter().map(f).collect::<Vec<_>>());
    eprintln!("{} windows: turns about z {:.2?}, tank-treading {:.3?} Hz, offset {:.2?} um", turns.len(), range(|w| w.0), range(|w| w.1), range(|w| w.2));
}

/// The classifier's `centred_um` (0.6 um since session 60, 0.4 before) against the evidence of
/// every run of both studies that ended a croissant or a slipper (`Evidence::from_map` of the
/// stored attributes): the croissants end at most 0.39 um off the axis (the paper's-walls
/// tank-treading croissants at ~6.45 mm/s, 0.386-0.387 um) and the slippers at least 0.94 um
/// (the ~0.5 mm/s slipper, 0.944 um; the paper's from 0.8 um), so the bound sits at least 0.2 um
/// from both, every label decided again under it is the stored one, and the outermost croissant
/// moved out to 0.59 um stays a tank-treading croissant while the innermost slipper moved in to
/// 0.61 um stays a slipper. Under the old 0.4 um the same croissant moved out by 0.02 um became
/// a slipper.
#[test]
fn a_croissant_held_further_out_stays_a_croissant_and_a_slipper_nearer_the_axis_a_slipper() {
    use rbc_solver::classify::{decide, ClassifyConfig, Evidence};
    let cfg = ClassifyConfig::default();
    assert_eq!(cfg.centred_um, 0.6);
    let (mut croissants, mut slippers) = (Vec::new(), Vec::new());
    for e in ended_runs_of_both_studies(&["steady", "periodic"]) {
        let s = &e.summary;
        let shapes = match s.final_shape {
            FinalShape::Croissant => &mut croissants,
            FinalShape::Slipper => &mut slippers,
            FinalShape::Other => continue,
        };
        let ev = Evidence::from_map(&s.evidence).unwrap_or_else(|name| panic!("{} {}: no evidence {name}", e.study, e.run.run_id));
        let c = decide(&ev, &cfg);
        assert_eq!((c.shape, c.tank_treading, c.tumbling), (s.final_shape, s.tank_treading, s.tumbling), "{} {} decided again", e.study, e.run.run_id);
        shapes.push(ev);
    }
    let decided = croissants.len() + slippers.len();
    let by_offset = |a: &&Evidence, b: &&Evidence| a.offset_r_um.total_cmp(&b.offset_r_um);
    let (c, s) = (croissants.iter().max_by(by_offset).unwrap().clone(), slippers.iter().min_by(by_offset).unwrap().clone());
    eprintln!("{decided} labels decided again; outermost croissant {:.3} um, innermost slipper {:.3} um", c.offset_r_um, s.offset_r_um);
    assert!(decided >= 40, "{decided} ended croissants and slippers");
    assert!((0.38..0.4).contains(&c.offset_r_um) && cfg.centred_um - c.offset_r_um >= 0.2, "outermost croissant {} um", c.offset_r_um);
    assert!((0.9..1.0).contains(&s.offset_r_um) && s.offset_r_um - cfg.centred_um >= 0.2, "innermost slipper {} um", s.offset_r_um);
    let moved = |e: &Evidence, r: f64| Evidence { offset_r_um: r, ..e.clone() };
    let out = decide(&moved(&c, 0.59), &cfg);
    assert_eq!((out.shape, out.tank_treading, out.tumbling), (FinalShape::Croissant, true, false), "the croissant at 0.59 um");
    let inn = decide(&moved(&s, 0.61), &cfg);
    assert_eq!(inn.shape, FinalShape::Slipper, "the slipper at 0.61 um");
    let old = ClassifyConfig { centred_um: 0.4, ..cfg };
    assert_eq!(decide(&moved(&c, c.offset_r_um + 0.02), &old).shape, FinalShape::Slipper, "under 0.4 um the croissant 0.02 um further out");
}
