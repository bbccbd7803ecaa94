//! `results.h5` written by the schema crate reads back in h5py with the documented layout; damaged files get the right hint.
//! `scripts/setup.sh` installs h5py (CI runs it first); without it the test fails, it does not skip.

use rbc_schema::results::*;
use std::collections::BTreeMap;
use std::process::Command;

#[test]
fn h5py_reads_the_documented_layout() {
    let ok = Command::new("python3").args(["-c", "import h5py, numpy"]).output().map(|o| o.status.success()).unwrap_or(false);
    assert!(ok, "python3 with h5py and numpy is missing: run `bash scripts/setup.sh`");
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    let mut f = ResultsFile::create_or_open(&p).unwrap();
    let tri = vec![[0u32, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let attrs = RunAttrs { start_shape: "discocyte".into(), r_init_um: 0.7, y_init_um: 0.6, z_init_um: 0.33, lambda: 5.0, scene: "a = 1\n".into() };
    let mut w = f.begin_run("u6.5_r0.7", &attrs, &tri).unwrap();
    for i in 0..5 {
        let t = i as f64;
        w.append_sample(&TimeSample {
            t_s: t,
            centroid_um: [t, 2.0 * t, 3.0 * t],
            velocity_mm_s: [6.5, 0.0, 0.0],
            area_um2: 140.0,
            volume_um3: 100.0,
            asphericity: 0.1,
            extents_um: [8.0, 7.0, 2.0],
        })
        .unwrap();
    }
    for k in 0..2 {
        let v: Vec<[f64; 3]> = (0..4).map(|i| [k as f64, i as f64, 0.5]).collect();
        w.append_snapshot(k as f64 * 0.5, &v).unwrap();
    }
    w.finish(&RunSummary {
        status: RunStatus::Periodic,
        final_shape: FinalShape::Slipper,
        tank_treading: true,
        tumbling: false,
        mean_velocity_mm_s: 6.5,
        min_velocity_mm_s: 6.4,
        max_velocity_mm_s: 6.6,
        mean_radial_um: 1.3,
        mean_y_um: 1.25,
        mean_z_um: 0.02,
        evidence: BTreeMap::new(),
    })
    .unwrap();
    drop(f);

    let script = r#"
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
assert int(f.attrs["schema_version"]) == 1
assert f.attrs["created_by"].startswith("rbc-toolkit")
r = f["runs/u6.5_r0.7"]
a = r.attrs
assert a["status"] == "periodic" and a["final_shape"] == "slipper" and a["start_shape"] == "discocyte", dict(a)
assert bool(a["tank_treading"]) is True and bool(a["tumbling"]) is False
assert a["mean_velocity_mm_s"] == 6.5 and a["lambda"] == 5.0 and a["scene"] == "a = 1\n"
c = r["timeseries/centroid_um"][:]
assert c.shape == (5, 3) and c.dtype == np.float64 and c[4].tolist() == [4.0, 8.0, 12.0], c
assert r["timeseries/t_s"].shape == (5,) and r["timeseries/extents_um"].shape == (5, 3)
assert r["timeseries/t_s"].maxshape == (None,)
v = r["snapshots/vertices_um"]
assert v.shape == (2, 4, 3) and v.maxshape == (None, 4, 3) and v[1, 3].tolist() == [1.0, 3.0, 0.5]
assert r["snapshots/times_s"][:].tolist() == [0.0, 0.5]
assert r["snapshots/triangles"].shape == (4, 3) and r["snapshots/triangles"][3].tolist() == [1, 2, 3]
print("ok")
"#;
    let out = Command::new("python3").arg("-c").arg(script).arg(&p).output().unwrap();
    assert!(out.status.success(), "h5py: {}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "ok");
}

#[test]
fn a_file_held_open_for_writing_gives_a_locking_hint() {
    let ok = Command::new("python3").args(["-c", "import h5py, numpy"]).output().map(|o| o.status.success()).unwrap_or(false);
    assert!(ok, "python3 with h5py and numpy is missing: run `bash scripts/setup.sh`");
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    drop(ResultsFile::create_or_open(&p).unwrap());
    // another process (h5py) opens the file for writing and keeps it open until stdin closes
    let mut child = Command::new("python3")
        .args(["-c", "import sys, h5py; f = h5py.File(sys.argv[1], 'a'); print('open', flush=True); sys.stdin.read()"])
        .arg(&p)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    std::io::BufRead::read_line(&mut std::io::BufReader::new(child.stdout.take().unwrap()), &mut line).unwrap();
    assert_eq!(line.trim(), "open");
    let result = read_runs(&p);
    drop(child.stdin.take());
    child.wait().unwrap();
    let msg = result.unwrap_err().to_string();
    assert!(msg.contains("results.h5") && msg.contains("HDF5_USE_FILE_LOCKING") && !msg.contains('\n'), "{msg}");
}

/// A file cut short (an interrupted copy) is named as such, not blamed on a lock ("sblock" in
/// HDF5's truncation message once matched the lock hint).
#[test]
fn a_truncated_file_is_named_cut_short() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    let attrs = RunAttrs { start_shape: "discocyte".into(), r_init_um: 0.7, y_init_um: 0.6, z_init_um: 0.33, lambda: 5.0, scene: "a = 1\n".into() };
    let mut f = ResultsFile::create_or_open(&p).unwrap();
    drop(f.begin_run("u6.5_r0.7", &attrs, &[[0u32, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]).unwrap());
    drop(f);
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    let msg = read_runs(&p).unwrap_err().to_string();
    assert!(msg.contains("results.h5") && msg.contains("cut short") && !msg.contains("HDF5_USE_FILE_LOCKING") && !msg.contains('\n'), "{msg}");
}
