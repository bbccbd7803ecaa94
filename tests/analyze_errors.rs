//! `rbc-analyze` on bad input, end to end through the binary: a one-line error naming the
//! file and a non-zero exit (or a warning and an empty group), never a panic, and never a
//! replaced or half-written output.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Run rbc-analyze with `args`; returns (exit code, stderr).
fn analyze(args: &[&Path], out: &Path) -> (i32, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_rbc-analyze"));
    cmd.args(args).arg("--out").arg(out).arg("--no-figures").arg("--jobs").arg("1");
    let o = cmd.output().expect("run rbc-analyze");
    (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// Asserts the failure contract: exit code 1 (not a panic's 101), no "panicked", and an
/// error line naming `names`.
fn assert_clean_failure(code: i32, stderr: &str, names: &[&str]) {
    assert_eq!(code, 1, "exit code; stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let line = stderr.lines().find(|l| l.starts_with("rbc-analyze: ")).unwrap_or_else(|| panic!("no error line in {stderr}"));
    for n in names {
        assert!(line.contains(n), "error line {line:?} should name {n:?}");
    }
}

/// An output folder with old results: a failing run must leave it byte for byte as it was.
fn old_outputs(dir: &Path) -> (PathBuf, Vec<(PathBuf, String)>) {
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let files: Vec<(PathBuf, String)> = ["detections.csv", "tracks.csv", "summary.csv", "kde.csv", "entry.csv"]
        .iter()
        .map(|f| (out.join(f), format!("old {f}\n")))
        .collect();
    for (p, c) in &files {
        std::fs::write(p, c).unwrap();
    }
    (out, files)
}

fn assert_untouched(out: &Path, files: &[(PathBuf, String)]) {
    for (p, c) in files {
        assert_eq!(&std::fs::read_to_string(p).unwrap(), c, "{} replaced", p.display());
    }
    let extra: Vec<String> = std::fs::read_dir(out)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !files.iter().any(|(p, _)| p.file_name().unwrap().to_string_lossy() == *n))
        .collect();
    assert!(extra.is_empty(), "left behind: {extra:?}");
}

#[test]
fn missing_path_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (out, files) = old_outputs(dir.path());
    let missing = dir.path().join("no-such-folder");
    let (code, err) = analyze(&[&missing], &out);
    assert_clean_failure(code, &err, &["no-such-folder"]);
    assert_untouched(&out, &files);
}

#[test]
fn empty_folder_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (out, files) = old_outputs(dir.path());
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let (code, err) = analyze(&[&empty], &out);
    assert_clean_failure(code, &err, &["empty", "no recording"]);
    assert_untouched(&out, &files);
}

#[test]
fn invalid_recording_toml_names_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let (out, files) = old_outputs(dir.path());
    let rec = dir.path().join("rec");
    std::fs::create_dir(&rec).unwrap();
    std::fs::write(rec.join("recording.toml"), "fps = -400.0\num_per_px = 0.2\npressure_mbar = 100.0\nposition_mm = 10.0\n").unwrap();
    let (code, err) = analyze(&[&rec], &out);
    assert_clean_failure(code, &err, &["recording.toml", "fps"]);
    assert_untouched(&out, &files);
    std::fs::write(rec.join("recording.toml"), "fps = 400.0\num_per_px = 0.2\npressure_mbar = 100.0\n").unwrap();
    let (code, err) = analyze(&[&rec], &out);
    assert_clean_failure(code, &err, &["recording.toml", "position_mm"]);
    std::fs::write(rec.join("recording.toml"), "fps = [oops\n").unwrap();
    let (code, err) = analyze(&[&rec], &out);
    assert_clean_failure(code, &err, &["recording.toml"]);
    assert_untouched(&out, &files);
}

#[test]
fn usage_errors_exit_2_and_jobs_0_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-analyze")).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-analyze")).arg(dir.path()).args(["--jobs", "0"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_clean_failure(o.status.code().unwrap(), &err, &["--jobs"]);
}
