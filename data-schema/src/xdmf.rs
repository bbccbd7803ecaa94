//! XDMF descriptions of the snapshots in `results.h5`, for ParaView: one `.xmf` file per run that
//! points into the HDF5 datasets (nothing is copied).
//!
//! # Layout
//!
//! `results.h5` gives `results.<run_id>.xmf` beside it (file name rule in [`xdmf_path`]), XDMF 2
//! (whose HyperSlab form XDMF 3 kept):
//!
//! ```text
//! <Xdmf Version="2.0"><Domain>
//!   <Grid Name="<run_id>" GridType="Collection" CollectionType="Temporal">
//!     <Grid Name="<run_id>_<k>" GridType="Uniform">          one per snapshot k
//!       <Time Value="<times_s[k]>"/>                          seconds, exactly as stored
//!       <Topology TopologyType="Triangle">                    results.h5:/runs/<id>/snapshots/triangles
//!       <Geometry GeometryType="XYZ">                         HyperSlab: row k of snapshots/vertices_um (um)
//!       <Attribute Name="<field>" Center="Node">              HyperSlab: row k of every other per-vertex
//!                                                              f64 dataset of snapshots/ ([k, nv] or [k, nv, 3])
//! ```
//!
//! The HDF5 file is referred to by its file name alone, so the `.xmf` must stay beside it (move
//! both together). Snapshots appended after the export (a run still going) are not listed: export
//! again (and to read a file that a simulation still holds open, start ParaView with
//! `HDF5_USE_FILE_LOCKING=FALSE`, as for any HDF5 reader). Data sets are referenced with their full shape and a HyperSlab DataItem (start, stride,
//! count) selects the snapshot.
//!
//! # Readers
//!
//! ParaView's "XDMF Reader" reads these files exactly (every snapshot's points, triangles, fields
//! and time: `tests/xdmf_export.rs`, with ParaView 5.11's `pvpython`). Its "Xdmf3 Reader S/T"
//! read the times and the triangles but give no points: the Xdmf3 library behind them does not
//! evaluate HyperSlab DataItems in XML (measured with ParaView 5.11), so pick "XDMF Reader" when
//! ParaView asks. meshio (5.3) reads neither hyperslabs nor a geometry that changes in time, so it
//! cannot read a deforming mesh without copies of every snapshot.
//!
//! One file per run, because a temporal collection is what ParaView turns into a time series:
//! open `results.<run_id>.xmf`, Apply, and the time slider walks through the snapshots. Runs have
//! different snapshot times, so one file per run also keeps every time step a real snapshot.
//!
//! Fields: runs written by this build store the mean curvature of every snapshot
//! (`snapshots/mean_curvature_per_um`, an attribute here); runs written before have positions
//! only. Per-vertex velocity and membrane force are not stored (the velocity would cost a Stokes
//! solve per snapshot, the force the scene's membrane model in the writer); a per-vertex dataset
//! added to `snapshots/` later is exported as an attribute without a change here.

use crate::error::{Result, SchemaError};
use crate::results::{ResultsFile, SnapshotLayout};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The `.xmf` file of run `run_id` beside `results`: `<dir>/<stem>.<run_id>.xmf`, where `<stem>`
/// is the results file name without its extension (`results.h5` -> `results.r1.xmf`).
pub fn xdmf_path(results: &Path, run_id: &str) -> PathBuf {
    let stem = results.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    results.with_file_name(format!("{stem}.{run_id}.xmf"))
}

/// Escape text for an XML attribute or element.
fn xml(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// A hyperslab DataItem selecting row `k` of an `[rows, nv]` or `[rows, nv, 3]` f64 dataset at `href`.
fn row_slab(out: &mut String, indent: &str, href: &str, k: usize, rows: usize, nv: usize, components: usize) {
    let (dims, full, start, stride, count) = if components == 1 {
        (format!("{nv}"), format!("{rows} {nv}"), format!("{k} 0"), "1 1".to_string(), format!("1 {nv}"))
    } else {
        (format!("{nv} {components}"), format!("{rows} {nv} {components}"), format!("{k} 0 0"), "1 1 1".to_string(), format!("1 {nv} {components}"))
    };
    let rank = if components == 1 { 2 } else { 3 };
    let _ = writeln!(out, "{indent}<DataItem ItemType=\"HyperSlab\" Dimensions=\"{dims}\" NumberType=\"Float\" Precision=\"8\">");
    let _ = writeln!(out, "{indent}  <DataItem Dimensions=\"3 {rank}\" NumberType=\"UInt\" Format=\"XML\">{start} {stride} {count}</DataItem>");
    let _ = writeln!(out, "{indent}  <DataItem Dimensions=\"{full}\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{href}</DataItem>");
    let _ = writeln!(out, "{indent}</DataItem>");
}

/// The XDMF text of one run's snapshots (layout in the module documentation); `h5_name` is how
/// the `.xmf` refers to the HDF5 file (its file name when the two lie side by side).
pub fn run_xdmf(layout: &SnapshotLayout, run_id: &str, h5_name: &str) -> String {
    let base = xml(&format!("{h5_name}:/runs/{run_id}/snapshots"));
    let (nv, nt) = (layout.n_vertices, layout.n_triangles);
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    out.push_str("<!-- written by rbc-toolkit rbc-sweep, xdmf export: positions in um, time in s, data in the HDF5 file -->\n");
    out.push_str("<Xdmf Version=\"2.0\">\n<Domain>\n");
    let _ = writeln!(out, "<Grid Name=\"{}\" GridType=\"Collection\" CollectionType=\"Temporal\">", xml(run_id));
    for (k, t) in layout.times_s.iter().enumerate() {
        let _ = writeln!(out, "  <Grid Name=\"{}_{k}\" GridType=\"Uniform\">", xml(run_id));
        // f64 Display prints the shortest decimal that parses back to the same value
        let _ = writeln!(out, "    <Time Value=\"{t}\"/>");
        let _ = writeln!(out, "    <Topology TopologyType=\"Triangle\" NumberOfElements=\"{nt}\">");
        let _ = writeln!(out, "      <DataItem Dimensions=\"{nt} 3\" NumberType=\"UInt\" Precision=\"4\" Format=\"HDF\">{base}/triangles</DataItem>");
        out.push_str("    </Topology>\n    <Geometry GeometryType=\"XYZ\">\n");
        row_slab(&mut out, "      ", &format!("{base}/vertices_um"), k, layout.rows, nv, 3);
        out.push_str("    </Geometry>\n");
        for f in &layout.fields {
            let kind = if f.components == 1 { "Scalar" } else { "Vector" };
            let _ = writeln!(out, "    <Attribute Name=\"{}\" AttributeType=\"{kind}\" Center=\"Node\">", xml(&f.name));
            row_slab(&mut out, "      ", &format!("{base}/{}", xml(&f.name)), k, f.rows, nv, f.components);
            out.push_str("    </Attribute>\n");
        }
        out.push_str("  </Grid>\n");
    }
    out.push_str("</Grid>\n</Domain>\n</Xdmf>\n");
    out
}

/// What [`export`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    /// Run id, `.xmf` path and number of snapshots, for every file written.
    pub written: Vec<(String, PathBuf, usize)>,
    /// Runs left out because they have no snapshot yet.
    pub empty: Vec<String>,
}

/// How an `.xmf` beside `path` refers to it: its file name (XDMF readers split `file:/dataset`
/// at the first colon, so a name with one is refused).
fn h5_name(path: &Path) -> Result<String> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    if name.contains(':') {
        return Err(SchemaError::Invalid { path: path.into(), message: "an HDF5 file name with `:` cannot be referred to from XDMF".into() });
    }
    Ok(name)
}

/// The XDMF text of run `run_id` of an open results file, referring to it by file name (what
/// [`export`] writes into [`xdmf_path`]).
pub fn xdmf_text(file: &ResultsFile, run_id: &str) -> Result<String> {
    Ok(run_xdmf(&file.snapshot_layout(run_id)?, run_id, &h5_name(file.path())?))
}

/// Write `<stem>.<run_id>.xmf` beside `results` (atomically) for every run with at least one
/// snapshot, or for run `only`. Refuses a missing or unreadable file, an unknown run, a chosen run
/// without snapshots, and a file in which no run has one.
pub fn export(results: &Path, only: Option<&str>) -> Result<Exported> {
    let file = ResultsFile::open(results)?;
    let name = h5_name(results)?;
    let ids = match only {
        Some(id) if !file.has_run(id) => {
            return Err(SchemaError::Invalid { path: results.into(), message: format!("no run `{id}` in /runs") })
        }
        Some(id) => vec![id.to_string()],
        None => file.run_ids()?,
    };
    let mut texts = Vec::new();
    let mut empty = Vec::new();
    for id in ids {
        // a run never run (its cell overlaps the wall) has no snapshot group
        if file.run(&id).is_ok_and(|r| r.status == crate::results::RunStatus::OverlapsWall) {
            empty.push(id);
            continue;
        }
        let layout = file.snapshot_layout(&id)?;
        if layout.times_s.is_empty() {
            empty.push(id);
        } else {
            texts.push((run_xdmf(&layout, &id, &name), layout.times_s.len(), id));
        }
    }
    if texts.is_empty() {
        let what = only.map_or("no run has a snapshot".to_string(), |id| format!("run `{id}` has no snapshot yet"));
        return Err(SchemaError::Invalid { path: results.into(), message: what });
    }
    let mut written = Vec::new();
    for (text, n, id) in texts {
        let target = xdmf_path(results, &id);
        crate::atomic::write_atomic(&target, |w| std::io::Write::write_all(w, text.as_bytes()).map_err(|e| SchemaError::io(&target, e)))?;
        written.push((id, target, n));
    }
    Ok(Exported { written, empty })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::VertexField;

    #[test]
    fn path_is_beside_the_results_file() {
        assert_eq!(xdmf_path(Path::new("a/b/results.h5"), "u6.5_r0.7"), PathBuf::from("a/b/results.u6.5_r0.7.xmf"));
        assert_eq!(xdmf_path(Path::new("x.h5"), "r"), PathBuf::from("x.r.xmf"));
    }

    #[test]
    fn slabs_select_the_row_of_each_snapshot_and_names_are_escaped() {
        let layout = SnapshotLayout {
            times_s: vec![0.0, 0.025],
            rows: 3,
            n_vertices: 4,
            n_triangles: 2,
            fields: vec![VertexField { name: "h".into(), components: 1, rows: 3 }],
        };
        let x = run_xdmf(&layout, "a<b", "r.h5");
        assert!(x.contains("<Grid Name=\"a&lt;b\" GridType=\"Collection\" CollectionType=\"Temporal\">"), "{x}");
        assert!(x.contains("<Time Value=\"0.025\"/>"), "{x}");
        assert!(x.contains(">1 0 0 1 1 1 1 4 3</DataItem>"), "{x}");
        assert!(x.contains("Dimensions=\"3 4 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">r.h5:/runs/a&lt;b/snapshots/vertices_um<"), "{x}");
        assert!(x.contains(">1 0 1 1 1 4</DataItem>") && x.contains("AttributeType=\"Scalar\""), "{x}");
        assert_eq!(x.matches("GridType=\"Uniform\"").count(), 2);
        // XML comments may not contain a double hyphen
        assert!(!x.contains("<!--") || x.split("<!--").skip(1).all(|c| !c.split("-->").next().unwrap().contains("--")), "{x}");
    }
}
