//! `rbc-sweep --xdmf`: the `.xmf` files it writes beside a results file are read back by
//! ParaView (`pvpython`, its "XDMF Reader") as exactly what the HDF5 file holds, every snapshot's
//! points, triangles, per-vertex fields and time; the shipped `.xmf` files are current; bad input
//! gets a one-line error naming the file.
//! `scripts/setup.sh` installs ParaView (Debian's `paraview` and `python3-paraview`); without
//! `pvpython` the reader test fails, it does not skip.

use rbc_schema::results::{read_runs, read_snapshots, ResultsFile};
use rbc_schema::xdmf::{xdmf_path, xdmf_text};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples")
}

fn sweep(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).args(args).output().unwrap()
}

/// Reads every time step of each `.xmf` with ParaView's XDMF Reader and prints, per step,
/// `T t`, `P x y z ...` (all point coordinates), `C type i j k` per cell and `A name v ...` per
/// point array, numbers in Python's shortest round-trip form.
const PV_READ: &str = r#"
import sys
from paraview.simple import XDMFReader
from paraview import servermanager as sm
for fn in sys.argv[1:]:
    r = XDMFReader(FileNames=[fn])
    r.PointArrayStatus = r.PointArrayStatus.Available
    tv = r.TimestepValues
    times = [tv] if isinstance(tv, float) else list(tv)
    print("F", fn)
    for t in times:
        r.UpdatePipeline(t)
        d = sm.Fetch(r)
        print("T", repr(t))
        pts = d.GetPoints().GetData()
        assert pts.GetDataTypeAsString() == "double", pts.GetDataTypeAsString()
        print("P", " ".join(repr(pts.GetComponent(i, c)) for i in range(d.GetNumberOfPoints()) for c in range(3)))
        for c in range(d.GetNumberOfCells()):
            ids = d.GetCell(c).GetPointIds()
            print("C", d.GetCellType(c), " ".join(str(ids.GetId(j)) for j in range(ids.GetNumberOfIds())))
        pd = d.GetPointData()
        for a in range(pd.GetNumberOfArrays()):
            arr = pd.GetArray(a)
            n, m = arr.GetNumberOfTuples(), arr.GetNumberOfComponents()
            print("A", arr.GetName(), " ".join(repr(arr.GetComponent(i, c)) for i in range(n) for c in range(m)))
"#;

/// One time step as ParaView read it.
#[derive(Debug, Default)]
struct Step {
    t: f64,
    points: Vec<f64>,
    cells: Vec<(u32, Vec<u32>)>,
    arrays: BTreeMap<String, Vec<f64>>,
}

fn floats(s: &str) -> Vec<f64> {
    s.split_whitespace().map(|x| x.parse().unwrap_or_else(|_| panic!("not a number: {x}"))).collect()
}

/// The steps of every file, by file name.
fn paraview_read(files: &[PathBuf]) -> BTreeMap<String, Vec<Step>> {
    let ok = Command::new("pvpython").arg("--version").output().map(|o| o.status.success()).unwrap_or(false);
    assert!(ok, "pvpython (ParaView) is missing: run `bash scripts/setup.sh`");
    let out = Command::new("pvpython").arg("-c").arg(PV_READ).args(files).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "pvpython: {}\n{text}", String::from_utf8_lossy(&out.stderr));
    let mut all: BTreeMap<String, Vec<Step>> = BTreeMap::new();
    let mut file = String::new();
    for line in text.lines() {
        let (tag, rest) = line.split_once(' ').unwrap_or((line, ""));
        let steps = all.entry(file.clone()).or_default();
        match tag {
            "F" => file = Path::new(rest).file_name().unwrap().to_string_lossy().into_owned(),
            "T" => steps.push(Step { t: rest.parse().unwrap(), ..Default::default() }),
            "P" => steps.last_mut().unwrap().points = floats(rest),
            "C" => {
                let v: Vec<u32> = rest.split_whitespace().map(|x| x.parse().unwrap()).collect();
                steps.last_mut().unwrap().cells.push((v[0], v[1..].to_vec()));
            }
            "A" => {
                let (name, values) = rest.split_once(' ').unwrap_or((rest, ""));
                steps.last_mut().unwrap().arrays.insert(name.to_string(), floats(values));
            }
            _ => {} // ParaView's own messages
        }
    }
    all.remove("");
    all
}

/// Per-vertex fields a later writer may store beside the positions: written here into a copy of
/// the example sweep (real solver output) so that the export of attributes is checked too.
fn add_fields(path: &Path, run: &str, k: usize, nv: usize) -> (Vec<f64>, Vec<f64>) {
    let scalar: Vec<f64> = (0..k * nv).map(|i| 0.1 * i as f64 - 3.25).collect();
    let vector: Vec<f64> = (0..k * nv * 3).map(|i| (i as f64).sqrt() / 7.0).collect();
    let f = hdf5::File::open_rw(path).unwrap();
    let g = f.group(&format!("runs/{run}/snapshots")).unwrap();
    g.new_dataset::<f64>().shape((k, nv)).create("h_per_um").unwrap().write_raw(&scalar).unwrap();
    g.new_dataset::<f64>().shape((k, nv, 3)).create("force_pn").unwrap().write_raw(&vector).unwrap();
    (scalar, vector)
}

#[test]
fn paraview_reads_every_snapshot_exactly_as_the_hdf5_file_holds_it() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = dir.path().join("results.h5");
    std::fs::copy(examples().join("demo-results.h5"), &h5).unwrap();
    let with_fields = "capsule_u1_r1";
    let snap = read_snapshots(&h5, with_fields).unwrap();
    let (scalar, vector) = add_fields(&h5, with_fields, snap.times_s.len(), snap.vertices_um[0].len());

    let o = sweep(&["--xdmf".as_ref(), h5.as_os_str()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let runs = read_runs(&h5).unwrap();
    assert_eq!(runs.len(), 4);
    let files: Vec<PathBuf> = runs.iter().map(|r| xdmf_path(&h5, &r.run_id)).collect();
    for (r, f) in runs.iter().zip(&files) {
        assert!(err.contains(&format!("run {}: {} snapshots", r.run_id, r.n_snapshots)), "{err}");
        assert!(f.exists(), "{}", f.display());
    }

    let read = paraview_read(&files);
    assert_eq!(read.len(), 4, "{:?}", read.keys());
    for (r, f) in runs.iter().zip(&files) {
        let snap = read_snapshots(&h5, &r.run_id).unwrap();
        let steps = &read[&f.file_name().unwrap().to_string_lossy().into_owned()];
        let times: Vec<f64> = steps.iter().map(|s| s.t).collect();
        assert_eq!(times, snap.times_s, "{}", r.run_id);
        let cells: Vec<(u32, Vec<u32>)> = snap.triangles.iter().map(|t| (5, t.to_vec())).collect(); // 5 = VTK_TRIANGLE
        for (k, step) in steps.iter().enumerate() {
            let points: Vec<f64> = snap.vertices_um[k].iter().flatten().copied().collect();
            assert_eq!(step.points, points, "{} snapshot {k}", r.run_id);
            assert_eq!(step.cells, cells, "{} snapshot {k}", r.run_id);
            // the solver's mean curvature of every run, and the two fields added to one of them
            let mut expected: BTreeMap<String, Vec<f64>> = BTreeMap::new();
            expected.insert("mean_curvature_per_um".into(), snap.fields["mean_curvature_per_um"][k].clone());
            if r.run_id == with_fields {
                let nv = snap.vertices_um[0].len();
                expected.insert("h_per_um".into(), scalar[k * nv..(k + 1) * nv].to_vec());
                expected.insert("force_pn".into(), vector[k * nv * 3..(k + 1) * nv * 3].to_vec());
            }
            assert_eq!(step.arrays, expected, "{} snapshot {k}", r.run_id);
        }
    }
    // the snapshots really differ (the hyperslab follows the time step)
    let steps = &read["results.capsule_u0.5_r1.xmf"];
    assert_ne!(steps[0].points, steps[steps.len() - 1].points);
}

/// The `.xmf` files shipped beside the example results (the study's ended runs and the demo) and the channel fixture are what
/// `rbc-sweep --xdmf` writes for them now, one for each run and no other.
#[test]
fn shipped_xmf_files_are_current() {
    for h5 in [examples().join("results.h5"), examples().join("demo-results.h5"), examples().join("fixtures/science-6p5-r1.2.h5")] {
        let file = ResultsFile::open(&h5).unwrap();
        let stem = h5.file_stem().unwrap().to_string_lossy().into_owned();
        let mut expected = Vec::new();
        for id in file.run_ids().unwrap() {
            let path = xdmf_path(&h5, &id);
            let shipped = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e} (run `rbc-sweep --xdmf {}`)", path.display(), h5.display()));
            assert_eq!(shipped, xdmf_text(&file, &id).unwrap(), "{} is stale: run `rbc-sweep --xdmf {}`", path.display(), h5.display());
            expected.push(path);
        }
        let mut found: Vec<PathBuf> = std::fs::read_dir(h5.parent().unwrap())
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| {
                let n = p.file_name().unwrap().to_string_lossy();
                n.starts_with(&format!("{stem}.")) && n.ends_with(".xmf")
            })
            .collect();
        found.sort();
        expected.sort();
        assert_eq!(found, expected, "stray .xmf files beside {}", h5.display());
    }
}

#[test]
fn bad_input_gets_one_line_naming_the_file_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.h5");
    let junk = dir.path().join("junk.h5");
    std::fs::write(&junk, "not HDF5").unwrap();
    let good = dir.path().join("good.h5");
    std::fs::copy(examples().join("demo-results.h5"), &good).unwrap();
    let cases: Vec<(Vec<&std::ffi::OsStr>, &str)> = vec![
        (vec!["--xdmf".as_ref(), missing.as_os_str()], "missing.h5"),
        (vec!["--xdmf".as_ref(), junk.as_os_str()], "junk.h5"),
        (vec!["--xdmf".as_ref(), good.as_os_str(), "--run".as_ref(), "nope".as_ref()], "nope"),
    ];
    for (args, needle) in cases {
        let o = sweep(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(needle) && err.contains(".h5"), "{err}");
    }
    let names: Vec<String> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert!(names.iter().all(|n| !n.ends_with(".xmf") && !n.ends_with(".tmp")), "{names:?}");
    // one run on request
    let o = sweep(&["--xdmf".as_ref(), good.as_os_str(), "--run".as_ref(), "capsule_u1_r0".as_ref()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(xdmf_path(&good, "capsule_u1_r0").exists() && !xdmf_path(&good, "capsule_u1_r1").exists());
}
