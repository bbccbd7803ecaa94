//! A short run of the input fuzzer (`rbc-bench fuzz`) over every format: no panic, no hang, no crash.
//!
//! The full run is `rbc-bench fuzz --cases 1e5` (README, "The commands"); this one runs a few
//! hundred cases per format. It also checks that the mutations reach both sides of every reader:
//! each format has accepted cases and refused ones, and the refusals name the input file.
//!
//! Damaged HDF5 metadata can crash or hang the HDF5 C library itself (libhdf5 1.10.8: a segfault
//! or an endless loop in its global heap; measured about 1 case in 1000 of the `results` format,
//! see the README): there the test allows at most 1 % of the cases. Checkpoints carry a checksum
//! that is verified before libhdf5 parses them (`rbc_schema::checkpoint`), so no damaged checkpoint
//! reaches libhdf5: none is allowed there, nor anywhere else. Panics are never allowed.

use std::process::Command;

/// Per-format row of the fuzzer's table: (format, cases, ok, error, unnamed, panic, hang, crash).
fn rows(stdout: &str) -> Vec<(String, [usize; 7])> {
    stdout
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| format") && !l.starts_with("| ---"))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
            let n = |i: usize| cells[i].parse::<usize>().unwrap_or_else(|_| panic!("cell {i} of `{l}`"));
            (cells[0].to_string(), [n(1), n(2), n(3), n(4), n(5), n(6), n(7)])
        })
        .collect()
}

#[test]
fn a_short_fuzzing_run_finds_no_panic_hang_or_crash() {
    let cases = 250;
    let out = Command::new(env!("CARGO_BIN_EXE_rbc-bench"))
        .args(["fuzz", "--cases", &cases.to_string(), "--seed", "7", "--timeout-ms", "20000"])
        .output()
        .expect("run rbc-bench fuzz");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let table = rows(&stdout);
    let failures: usize = table.iter().map(|(_, r)| r[4] + r[5] + r[6]).sum();
    assert_eq!(out.status.success(), failures == 0, "exit status follows the findings:\n{stdout}\n{stderr}");
    let formats: Vec<&str> = table.iter().map(|(f, _)| f.as_str()).collect();
    assert_eq!(formats, ["recording", "scene", "sweep", "csv", "frames", "results", "checkpoint"], "{stdout}");
    for (f, [n, ok, error, unnamed, panic, hang, crash]) in &table {
        assert_eq!(*n, cases, "{f}: cases\n{stdout}");
        assert_eq!(*panic, 0, "{f}: panics\n{stdout}");
        let in_libhdf5 = if f == "results" { cases / 100 } else { 0 };
        assert!(hang + crash <= in_libhdf5, "{f}: {hang} hangs and {crash} crashes (at most {in_libhdf5})\n{stdout}");
        assert_eq!(ok + error + panic + hang + crash, *n, "{f}: outcomes add up\n{stdout}");
        assert!(*ok > 0 && *error > 0, "{f}: the mutations should give accepted and refused inputs ({ok} ok, {error} refused)\n{stdout}");
        assert_eq!(*unnamed, 0, "{f}: every refusal is one line naming the input\n{stdout}");
    }
}

/// The exact inputs of the fuzzer's findings, replayed (`--case`): each was a panic, an abort or a hang
/// before its fix and is a one-line refusal now (unit tests beside each fix check the message).
#[test]
fn the_findings_replay_as_refusals() {
    for (format, seed, case, what) in [
        ("results", 1, 57, "triangle index beyond the vertices: index out of bounds in the classifier"),
        ("results", 3, 64, "dataspace claiming 3.8e17 bytes: allocation abort"),
        ("checkpoint", 2, 56, "scene attribute not UTF-8: str slicing panic"),
        ("checkpoint", 2, 139, "a vertex missing: index out of bounds in --study-status"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_rbc-bench"))
            .args(["fuzz", "--format", format, "--seed", &seed.to_string(), "--case", &case.to_string(), "--timeout-ms", "20000"])
            .output()
            .expect("run rbc-bench fuzz");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let table = rows(&stdout);
        assert_eq!(table.len(), 1, "{stdout}");
        let (_, [n, ok, error, unnamed, panic, hang, crash]) = table[0];
        assert_eq!((n, ok, error, unnamed, panic, hang, crash), (1, 0, 1, 0, 0, 0, 0), "{format} seed {seed} case {case} ({what}):\n{stdout}");
        assert!(out.status.success(), "{stdout}");
    }
}

/// The sweep findings' inputs, kept as files (`tests/fuzz_findings/`, saved with `rbc-bench fuzz
/// --format sweep --seed 1 --case I --save DIR` before the example sweep they were mutated from
/// changed, which moves the mutations of those indices): each expanded a grid of 300000 runs for
/// minutes before its fix and is a one-line refusal naming the file and the largest axis now.
#[test]
fn the_sweep_findings_inputs_are_refused_in_one_line() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_findings");
    for (case, axis, grid) in [("sweep-1-4149", "mean_velocity_mm_s", "3 x 10000 x 10 = 300000 runs"), ("sweep-1-5002", "r_init_um", "3 x 11 x 10000 = 330000 runs")] {
        let sweep = dir.join(case).join("sweep.toml");
        let out = Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).arg(&sweep).arg("--list").output().expect("run rbc-sweep");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{case}: {stderr}");
        assert!(out.stdout.is_empty(), "{case}: no partial listing");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{case}: {stderr}");
        assert!(stderr.contains(&*sweep.to_string_lossy()) && stderr.contains(&format!("field `{axis}`")) && stderr.contains(grid), "{case}: {stderr}");
    }
}

/// libhdf5 1.10.8 loops forever reading a variable-length string attribute when a global heap
/// collection's size field is enlarged (one flipped bit: 4096 -> 4352 bytes; `rbc-bench fuzz --format
/// results --seed 1 --case 239`). The call cannot be cancelled; the commands' HDF5 watchdog
/// (`rbc_schema::hdf5_watch`) ends them instead, with one line naming the file and the attribute and
/// exit code 2, after `RBC_HDF5_TIMEOUT_S` (2 s here); the fuzzer reports the case as a hang that the
/// watchdog ended.
#[test]
fn a_libhdf5_hang_on_a_damaged_global_heap_ends_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/fixtures/science-6p5-r1.2.h5")).unwrap();
    let gcol = bytes.windows(4).position(|w| w == b"GCOL").expect("the fixture has a global heap collection");
    assert_eq!(&bytes[gcol + 8..gcol + 16], &4096u64.to_le_bytes(), "collection size");
    bytes[gcol + 9] |= 0x01; // 4096 -> 4352
    std::fs::write(dir.path().join("loops.h5"), &bytes).unwrap();
    let t0 = std::time::Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
        .args(["status", "loops.h5"])
        .env("RBC_HDF5_TIMEOUT_S", "2")
        .current_dir(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(t0.elapsed().as_secs_f64() < 30.0, "ended by the watchdog, not by the test");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.starts_with("rbc-sweep: loops.h5: attribute `") && err.contains("libhdf5 did not return within 2 s"), "{err}");

    let (stdout, counts, success) = replay_results_case(1, 239);
    assert_eq!(counts, [1, 0, 1, 0], "{stdout}");
    assert!(stdout.contains("1 of 1 hangs were in a watched libhdf5 call") && stdout.contains("hang in libhdf5, ended by the watchdog: rbc-bench fuzz-worker: "), "{stdout}");
    assert!(!success, "a hang is still a finding: {stdout}");
}

/// `rbc-bench fuzz --format results --seed SEED --case CASE`: its stdout, (cases, panics, hangs, crashes), exit 0.
fn replay_results_case(seed: u64, case: usize) -> (String, [usize; 4], bool) {
    let out = Command::new(env!("CARGO_BIN_EXE_rbc-bench"))
        .args(["fuzz", "--format", "results", "--seed", &seed.to_string(), "--case", &case.to_string(), "--timeout-ms", "8000"])
        .output()
        .expect("run rbc-bench fuzz");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let (_, [n, _, _, _, panic, hang, crash]) = rows(&stdout)[0];
    (stdout, [n, panic, hang, crash], out.status.success())
}

/// libhdf5 1.10.8 segfaults listing a run's attributes when one attribute message has an unknown
/// version (the `status` message's version byte 3 -> 19 in the channel fixture; the fuzzer's `rbc-bench
/// fuzz --format results --seed 3 --case 535` did the same to a `final_shape` of the example results): it
/// reports the bad version, then crashes in `H5A__close` while cleaning up the iteration. The crash
/// cannot be undone; with the watchdog on (the default), the commands end with one line naming the file
/// and the run, exit code 2, instead of a bare `Segmentation fault`. Without it, the signal is libhdf5's.
#[test]
fn a_libhdf5_crash_on_a_damaged_attribute_message_ends_with_one_line() {
    use std::os::unix::process::ExitStatusExt;
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/fixtures/science-6p5-r1.2.h5")).unwrap();
    // attribute message v3: version, flags, name size 7, datatype and dataspace sizes, UTF-8 name
    let name = b"\x01status\x00";
    let at = bytes.windows(name.len()).position(|w| w == name).expect("the fixture's run has a status attribute") - 8;
    assert_eq!(&bytes[at..at + 4], b"\x03\x00\x07\x00", "an attribute message of version 3");
    bytes[at] = 19;
    std::fs::write(dir.path().join("crashes.h5"), &bytes).unwrap();
    let status = |watchdog: &str| Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).args(["status", "crashes.h5"]).env("RBC_HDF5_TIMEOUT_S", watchdog).current_dir(dir.path()).output().unwrap();
    let out = status("off");
    assert_eq!(out.status.signal(), Some(11), "libhdf5 itself crashes: {}", String::from_utf8_lossy(&out.stderr));
    let out = status("60");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.starts_with("rbc-sweep: crashes.h5: run `discocyte_u3.8_r1.2`: attributes: crashed (SIGSEGV) while libhdf5 read it"), "{err}");

    let (stdout, counts, success) = replay_results_case(3, 535);
    assert_eq!(counts, [1, 0, 0, 1], "{stdout}");
    assert!(stdout.contains("1 of 1 crashes were in a marked read") && stdout.contains("crash in a read, one line and exit 2: rbc-bench fuzz-worker: "), "{stdout}");
    assert!(!success, "a crash is still a finding: {stdout}");
}
