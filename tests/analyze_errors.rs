//! `rbc-analyze` on bad input, end to end through the binary: a one-line error naming the
//! file and a non-zero exit (or a warning and an empty group), never a panic, and never a
//! replaced or half-written output.

use rbc_analysis::simulated::synth::{random_spec, write_recording};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A small valid synthetic recording (two cells at 3 mm/s, 0.3 um/px) in `dir`.
fn synth(dir: &Path, seed: u64, um_per_px: f64) {
    write_recording(dir, &random_spec(seed, um_per_px, 0.01, 3.0), seed).unwrap();
}

/// Frame files of a recording, in name order.
fn frames(dir: &Path) -> Vec<PathBuf> {
    let mut f: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| {
            p.extension()
                .is_some_and(|e| e == "png" || e == "tif" || e == "tiff")
        })
        .collect();
    f.sort();
    f
}

/// Run rbc-analyze with `args`; returns (exit code, stderr).
fn analyze(args: &[&Path], out: &Path) -> (i32, String) {
    let mut cmd = Command::new(bin());
    cmd.args(args)
        .arg("--out")
        .arg(out)
        .arg("--no-figures")
        .arg("--jobs")
        .arg("1");
    let o = cmd.output().expect("run rbc-analyze");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Asserts the failure contract: exit code 1 (not a panic's 101), no "panicked", and an
/// error line naming `names`.
fn assert_clean_failure(code: i32, stderr: &str, names: &[&str]) {
    assert_eq!(code, 1, "exit code; stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.starts_with("rbc-analyze: "))
        .unwrap_or_else(|| panic!("no error line in {stderr}"));
    for n in names {
        assert!(line.contains(n), "error line {line:?} should name {n:?}");
    }
}

/// An output folder with old results: a failing run must leave it byte for byte as it was.
fn old_outputs(dir: &Path) -> (PathBuf, Vec<(PathBuf, String)>) {
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let files: Vec<(PathBuf, String)> = [
        "detections.csv",
        "tracks.csv",
        "summary.csv",
        "kde.csv",
        "entry.csv",
    ]
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
        assert_eq!(
            &std::fs::read_to_string(p).unwrap(),
            c,
            "{} replaced",
            p.display()
        );
    }
    let extra: Vec<String> = std::fs::read_dir(out)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| {
            !files
                .iter()
                .any(|(p, _)| p.file_name().unwrap().to_string_lossy() == *n)
        })
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
    std::fs::write(
        rec.join("recording.toml"),
        "fps = -400.0\num_per_px = 0.2\npressure_mbar = 100.0\nposition_mm = 10.0\n",
    )
    .unwrap();
    let (code, err) = analyze(&[&rec], &out);
    assert_clean_failure(code, &err, &["recording.toml", "fps"]);
    assert_untouched(&out, &files);
    std::fs::write(
        rec.join("recording.toml"),
        "fps = 400.0\num_per_px = 0.2\npressure_mbar = 100.0\n",
    )
    .unwrap();
    let (code, err) = analyze(&[&rec], &out);
    assert_clean_failure(code, &err, &["recording.toml", "position_mm"]);
    std::fs::write(rec.join("recording.toml"), "fps = [oops\n").unwrap();
    let (code, err) = analyze(&[&rec], &out);
    assert_clean_failure(code, &err, &["recording.toml"]);
    assert_untouched(&out, &files);
}

#[test]
fn truncated_and_unreadable_images_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let (out, files) = old_outputs(dir.path());
    let root = dir.path().join("recs");
    synth(&root.join("a_good"), 1, 0.3);
    synth(&root.join("b_bad"), 2, 0.3);
    let f = frames(&root.join("b_bad"));
    let victim = &f[f.len() / 2];
    let bytes = std::fs::read(victim).unwrap();
    std::fs::write(victim, &bytes[..bytes.len() / 2]).unwrap();
    let (code, err) = analyze(&[&root], &out);
    let name = victim.file_name().unwrap().to_string_lossy().into_owned();
    assert_clean_failure(code, &err, &["b_bad", &name]);
    assert_untouched(&out, &files);
    // Not an image at all, under an image name.
    std::fs::write(victim, b"this is not a PNG").unwrap();
    let (code, err) = analyze(&[&root], &out);
    assert_clean_failure(code, &err, &["b_bad", &name]);
    assert_untouched(&out, &files);
}

#[test]
fn mixed_frame_sizes_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let (out, files) = old_outputs(dir.path());
    let rec = dir.path().join("rec");
    synth(&rec, 3, 0.3);
    let other = dir.path().join("other");
    synth(&other, 4, 0.2);
    let f = frames(&rec);
    let intruder = frames(&other)[0].clone();
    // Same name pattern, sorted into the middle of the recording.
    let target = f[f.len() / 2].with_file_name(format!(
        "{}b.{}",
        f[f.len() / 2].file_stem().unwrap().to_string_lossy(),
        intruder.extension().unwrap().to_string_lossy()
    ));
    std::fs::copy(&intruder, &target).unwrap();
    let (code, err) = analyze(&[&rec], &out);
    let name = target.file_name().unwrap().to_string_lossy().into_owned();
    assert_clean_failure(code, &err, &[&name]);
    assert_untouched(&out, &files);
}

/// A recording in which no cell passes: a warning naming it, exit 0, and tables with headers only.
#[test]
fn recording_without_cells_gives_a_warning_and_an_empty_group() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("blank");
    let mut spec = random_spec(5, 0.3, 0.01, 3.0);
    spec.cells.clear();
    write_recording(&rec, &spec, 5).unwrap();
    let out = dir.path().join("out");
    let (code, err) = analyze(&[&rec], &out);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.lines()
            .any(|l| l.contains("warning") && l.contains("blank")),
        "{err}"
    );
    assert!(!err.contains("panicked"));
    for f in ["tracks.csv", "summary.csv", "kde.csv", "entry.csv"] {
        let text = std::fs::read_to_string(out.join(f)).unwrap();
        assert_eq!(
            text.lines().count(),
            1,
            "{f} should hold only its header: {text}"
        );
    }
}

/// A good run replaces old outputs completely and leaves no temporary file.
#[test]
fn good_run_replaces_old_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let (out, files) = old_outputs(dir.path());
    let rec = dir.path().join("rec");
    synth(&rec, 6, 0.3);
    let (code, err) = analyze(&[&rec], &out);
    assert_eq!(code, 0, "{err}");
    for (p, old) in &files {
        let new = std::fs::read_to_string(p).unwrap();
        assert_ne!(&new, old);
    }
    let tracks = std::fs::read_to_string(out.join("tracks.csv")).unwrap();
    assert!(
        tracks.starts_with("recording,pressure_mbar,position_mm,track_id"),
        "{tracks}"
    );
    assert!(tracks.lines().count() >= 3, "two cells tracked: {tracks}");
    let hidden: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(hidden.is_empty());
}

#[test]
fn usage_errors_exit_2_and_jobs_0_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(bin()).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = Command::new(bin())
        .arg(dir.path())
        .args(["--jobs", "0"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_clean_failure(o.status.code().unwrap(), &err, &["--jobs"]);
}

/// The binary under test: `RBC_ANALYZE_BIN` when set (a private copy, when several worktrees
/// share one `CARGO_TARGET_DIR` and may relink `target/debug/rbc-analyze` meanwhile), else cargo's.
fn bin() -> std::path::PathBuf {
    std::env::var_os("RBC_ANALYZE_BIN")
        .map(Into::into)
        .unwrap_or_else(|| env!("CARGO_BIN_EXE_rbc-analyze").into())
}
