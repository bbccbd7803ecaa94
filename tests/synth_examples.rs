//! `rbc-synth --examples DIR` replaces the example recordings as one set: every example folder is
//! written anew (a file left in an old one is gone), files that are not examples stay, and no
//! staging folder is left behind. `rbc-synth --random` with imaging conditions writes them into
//! the recording's spec and refuses values out of range.

mod output_common;

use output_common::{files_in, hidden_entries};
use rbc_analysis::simulated::synth::examples::examples;
use std::process::Command;

#[test]
fn examples_are_replaced_as_a_set() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("frames");
    let first = examples().into_iter().next().unwrap().name;
    std::fs::create_dir_all(root.join(&first)).unwrap();
    std::fs::write(root.join(&first).join("frame_00099.png"), "from an older synthesiser").unwrap();
    std::fs::write(root.join("README.md"), "mine").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-synth")).arg("--examples").arg(&root).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let files = files_in(&root);
    assert_eq!(files[std::path::Path::new("README.md")], b"mine");
    assert!(!root.join(&first).join("frame_00099.png").exists(), "an example folder is replaced as a whole");
    for ex in examples() {
        let n = files.keys().filter(|p| p.starts_with(&ex.name) && p.extension().is_some_and(|e| e == "png")).count();
        assert_eq!(n, ex.spec.n_frames, "{}", ex.name);
        assert!(files.contains_key(&std::path::Path::new(&ex.name).join("truth.csv")), "{}", ex.name);
    }
    assert_eq!(hidden_entries(dir.path()), Vec::<String>::new());
}

/// `--defocus -1.5 --debris 3 --bits 16 --spacing 20` reach the spec (below focus the rim is
/// bright: a negative `optics.rim`, which the edge profile subtracts), the truth has the three cells and no debris; `--na 0` is refused
/// naming the flag.
#[test]
fn random_recording_takes_imaging_conditions() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rec");
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-synth"))
        .args(["--random", "--seed", "4", "--defocus", "-1.5", "--debris", "3", "--bits", "16", "--spacing", "20", "--velocity", "2"])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let truth = rbc_analysis::simulated::synth::Truth::read(&out).unwrap();
    let spec = &truth.spec;
    assert!(spec.optics.rim < 0.0 && spec.optics.halo < 0.0, "below focus the rim is bright and the halo dark: {:?}", spec.optics);
    assert_eq!(spec.debris.len(), 3);
    assert!(spec.format.sixteen_bit());
    assert!((spec.cells[0].x0_um - spec.cells[1].x0_um - 20.0).abs() <= 3.0);
    assert!(truth.rows.iter().all(|r| r.cell_id < 3));
    let bad = Command::new(env!("CARGO_BIN_EXE_rbc-synth")).args(["--random", "--na", "0"]).arg("--out").arg(dir.path().join("bad")).output().unwrap();
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("--na") && err.lines().count() == 1, "{err}");
    // a pixel size out of range is named as the flag it came from, not as the spec written from it
    let bad = Command::new(env!("CARGO_BIN_EXE_rbc-synth")).args(["--random", "--um-per-px", "1e-9"]).arg("--out").arg(dir.path().join("bad")).output().unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("--um-per-px must be in [0.01, 10], got 0.000000001") && !err.contains("spec.toml") && err.lines().count() == 1, "{err}");
    assert!(!dir.path().join("bad").exists(), "nothing written");
}
