//! An open results file ([`ResultsFile`]): creating it, starting, resuming, listing and reading its runs.

use super::*;
use hdf5::{Dataset, File};
use std::path::{Path, PathBuf};

/// An open `results.h5`, for writing runs (or reading them).
pub struct ResultsFile {
    path: PathBuf,
    file: File,
}

impl ResultsFile {
    /// Open `path` for writing, creating it (with `schema_version` and
    /// `created_by`) when it does not exist; refuses a file of another schema version.
    pub fn create_or_open(path: &Path) -> Result<ResultsFile> {
        Self::create_or_open_by(path, concat!("rbc-toolkit ", env!("CARGO_PKG_VERSION")))
    }

    /// As [`create_or_open`](Self::create_or_open), recording `created_by` (e.g. the command line) in a new file.
    pub fn create_or_open_by(path: &Path, created_by: &str) -> Result<ResultsFile> {
        if path.exists() {
            let file = {
                let _watch = crate::hdf5_watch::arm(path, || "open for writing".into());
                File::open_rw(path).map_err(|e| h5err(path, "open for writing", e))?
            };
            check_version(path, &file)?;
            if !file.link_exists("runs") {
                file.create_group("runs").map_err(|e| h5err(path, "create /runs", e))?;
            }
            return Ok(ResultsFile { path: path.into(), file });
        }
        if let Some(parent) = path.parent() {
            if !parent.as_os_str().is_empty() {
                std::fs::create_dir_all(parent).map_err(|e| SchemaError::io(parent, e))?;
            }
        }
        let file = File::create_excl(path).map_err(|e| h5err(path, "create", e))?;
        set_attr(path, &file, "schema_version", &SCHEMA_VERSION)?;
        set_str(path, &file, "created_by", created_by)?;
        file.create_group("runs").map_err(|e| h5err(path, "create /runs", e))?;
        file.flush().map_err(|e| h5err(path, "flush", e))?;
        Ok(ResultsFile { path: path.into(), file })
    }

    /// Open an existing file read-only (schema_version checked).
    pub fn open(path: &Path) -> Result<ResultsFile> {
        if !path.exists() {
            return Err(SchemaError::io(path, std::io::Error::new(std::io::ErrorKind::NotFound, "no such file")));
        }
        let file = {
            let _watch = crate::hdf5_watch::arm(path, || "open".into());
            File::open(path).map_err(|e| h5err(path, "open", e))?
        };
        check_version(path, &file)?;
        Ok(ResultsFile { path: path.into(), file })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn runs_group(&self) -> Result<Group> {
        self.file.group("runs").map_err(|_| invalid(&self.path, "no /runs group"))
    }

    fn run_group(&self, run_id: &str) -> Result<Group> {
        self.runs_group()?
            .group(run_id)
            .map_err(|_| invalid(&self.path, format!("no run `{run_id}` in /runs")))
    }

    /// Ids of every run, in name order.
    pub fn run_ids(&self) -> Result<Vec<String>> {
        let _reading = crate::hdf5_watch::reading(&self.path, || "listing /runs".into());
        let mut ids = self.runs_group()?.member_names().map_err(|e| h5err(&self.path, "list /runs", e))?;
        ids.sort();
        Ok(ids)
    }

    /// True when `/runs/<run_id>` exists.
    pub fn has_run(&self, run_id: &str) -> bool {
        self.runs_group().map(|g| g.link_exists(run_id)).unwrap_or(false)
    }

    /// Delete a run (e.g. to restart it from scratch). The file does not shrink.
    pub fn remove_run(&mut self, run_id: &str) -> Result<()> {
        self.runs_group()?.unlink(run_id).map_err(|e| h5err(&self.path, &format!("remove run {run_id}"), e))
    }

    /// Start a run: create `/runs/<run_id>` with its start attributes, status `running`,
    /// empty resizable timeseries and snapshot datasets, and the mesh `triangles`.
    /// The vertex count of every snapshot is `max index + 1`. Refuses an existing `run_id`.
    pub fn begin_run(&mut self, run_id: &str, attrs: &RunAttrs, triangles: &[[u32; 3]]) -> Result<RunWriter> {
        let path = self.path.clone();
        check_run_id(&path, run_id)?;
        if self.has_run(run_id) {
            return Err(invalid(&path, format!("run `{run_id}` already exists (resume it or remove it)")));
        }
        if triangles.is_empty() {
            return Err(invalid(&path, format!("run `{run_id}`: empty triangle list")));
        }
        let nv = triangles.iter().flat_map(|t| t.iter()).copied().max().unwrap_or(0) as usize + 1;
        let g = self.runs_group()?.create_group(run_id).map_err(|e| h5err(&path, run_id, e))?;
        set_start_attrs(&path, &g, attrs)?;

        let ts = g.create_group("timeseries").map_err(|e| h5err(&path, "timeseries", e))?;
        for name in ["t_s", "area_um2", "volume_um3", "asphericity"] {
            ts.new_dataset::<f64>()
                .chunk(TIMESERIES_CHUNK)
                .shape(0..)
                .create(name)
                .map_err(|e| h5err(&path, name, e))?;
        }
        for name in ["centroid_um", "velocity_mm_s", "extents_um"] {
            ts.new_dataset::<f64>()
                .chunk((TIMESERIES_CHUNK, 3))
                .shape((0.., 3))
                .create(name)
                .map_err(|e| h5err(&path, name, e))?;
        }
        let sn = g.create_group("snapshots").map_err(|e| h5err(&path, "snapshots", e))?;
        sn.new_dataset::<f64>().chunk(64).shape(0..).create("times_s").map_err(|e| h5err(&path, "times_s", e))?;
        sn.new_dataset::<f64>()
            .chunk((1, nv, 3))
            .shape((0.., nv, 3))
            .create("vertices_um")
            .map_err(|e| h5err(&path, "vertices_um", e))?;
        let tri = ndarray::Array2::from_shape_fn((triangles.len(), 3), |(i, j)| triangles[i][j]);
        sn.new_dataset_builder().with_data(&tri).create("triangles").map_err(|e| h5err(&path, "triangles", e))?;
        // status last: a group without it was interrupted while being created
        set_str(&path, &g, "status", RunStatus::Running.as_str())?;
        self.file.flush().map_err(|e| h5err(&path, "flush", e))?;
        RunWriter::open(path, run_id, g)
    }

    /// True for a run recorded as not run (status `overlaps-wall`, no timeseries or snapshot groups).
    fn not_run(&self, g: &Group) -> bool {
        has_attr(g, "status") && get_str(&self.path, g, "status", "status").is_ok_and(|s| s == RunStatus::OverlapsWall.as_str())
    }

    /// Record run `run_id` as not run because its cell overlaps the channel wall (status
    /// `overlaps-wall`, `reason` in the `not_run` attribute, the start attributes, no rows and no
    /// snapshots), replacing a run of that id (e.g. one an earlier build ran and recorded as failed).
    pub fn record_overlaps_wall(&mut self, run_id: &str, attrs: &RunAttrs, reason: &str) -> Result<()> {
        let path = self.path.clone();
        check_run_id(&path, run_id)?;
        if self.has_run(run_id) {
            self.remove_run(run_id)?;
        }
        let g = self.runs_group()?.create_group(run_id).map_err(|e| h5err(&path, run_id, e))?;
        set_start_attrs(&path, &g, attrs)?;
        set_str(&path, &g, "not_run", reason)?;
        // status last, as in begin_run
        set_str(&path, &g, "status", RunStatus::OverlapsWall.as_str())?;
        self.file.flush().map_err(|e| h5err(&path, "flush", e))
    }

    /// Reopen a run (normally one with status `running`) to append to it after a restart.
    /// Its status is set back to `running` and summary attributes of an earlier finish are removed.
    pub fn resume_run(&mut self, run_id: &str) -> Result<RunWriter> {
        let g = self.run_group(run_id)?;
        for name in SUMMARY_ATTRS.iter().copied().chain(["failure"]) {
            if has_attr(&g, name) {
                g.delete_attr(name).map_err(|e| h5err(&self.path, name, e))?;
            }
        }
        // a steady state carried to a distance is no record of a run that continues: it will pass it
        let names = g.attr_names().map_err(|e| h5err(&self.path, run_id, e))?;
        let carried: Vec<String> = names
            .iter()
            .filter_map(|n| n.strip_prefix("transit_").and_then(|r| r.strip_suffix("_from_steady")))
            .map(|k| format!("transit_{k}_"))
            .collect();
        for name in names {
            if name.starts_with("evidence_") || carried.iter().any(|c| name.starts_with(c.as_str())) {
                g.delete_attr(&name).map_err(|e| h5err(&self.path, &name, e))?;
            }
        }
        set_str(&self.path, &g, "status", RunStatus::Running.as_str())?;
        RunWriter::open(self.path.clone(), run_id, g)
    }

    /// Overwrite the label of a run that ended (`final_shape`, `tank_treading`, `tumbling`), e.g.
    /// decided again from its stored evidence under another classification rule; everything else
    /// of the run stays. A run that has not ended (running, failed) is refused.
    pub fn set_label(&mut self, run_id: &str, shape: FinalShape, tank_treading: bool, tumbling: bool) -> Result<()> {
        self.write_ended(run_id, "a label", |p, g| {
            set_str(p, g, "final_shape", shape.as_str())?;
            set_attr(p, g, "tank_treading", &tank_treading)?;
            set_attr(p, g, "tumbling", &tumbling)
        })
    }

    /// Say where an ended run's data were copied from (attribute `copied_from`, free text, e.g.
    /// `state/a.h5: run r1, snapshot at t = 3.16 s`; see [`crate::start_shape`]).
    pub fn set_copied_from(&mut self, run_id: &str, source: &str) -> Result<()> {
        self.write_ended(run_id, "a copy's source", |p, g| set_str(p, g, "copied_from", source))
    }

    /// Record a transit of a run that ended (a steady state carried to a distance it had not
    /// reached, [`Transit::from_steady`]); a run that has not ended is refused (its transits are
    /// written by its [`RunWriter`] as it passes them).
    pub fn set_transit_of_ended(&mut self, run_id: &str, t: &Transit) -> Result<()> {
        self.write_ended(run_id, "a transit after the end", |p, g| write_transit(p, g, t))
    }

    /// Write attributes of a run that ended (`what` names them in the refusal of one that has not).
    fn write_ended(&mut self, run_id: &str, what: &str, write: impl FnOnce(&Path, &hdf5::Group) -> Result<()>) -> Result<()> {
        let status = self.run(run_id)?.status;
        if !status.is_finished() {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{run_id}.status"),
                format!("{what} belongs to a run that ended, this one is {}", status.as_str()),
            ));
        }
        let g = self.run_group(run_id)?;
        write(&self.path, &g)?;
        self.file.flush().map_err(|e| h5err(&self.path, "flush", e))
    }

    /// Every run with its attributes (see [`read_runs`]).
    pub fn runs(&self) -> Result<Vec<RunRecord>> {
        self.run_ids()?.iter().map(|id| self.run(id)).collect()
    }

    /// One run's attributes. Tolerates failed and running runs (their summary is `None`);
    /// a finished run must carry every summary attribute.
    pub fn run(&self, run_id: &str) -> Result<RunRecord> {
        let p = &self.path;
        let _reading = crate::hdf5_watch::reading(p, || format!("run `{run_id}`: attributes"));
        let g = self.run_group(run_id)?;
        let field = |name: &str| format!("runs/{run_id}.{name}");
        let status = if has_attr(&g, "status") {
            let s = get_str(p, &g, &field("status"), "status")?;
            RunStatus::parse(&s).ok_or_else(|| {
                SchemaError::field(p, field("status"), format!("`{s}` is not one of steady, periodic, unsteady, failed, running, overlaps-wall"))
            })?
        } else {
            RunStatus::Running
        };
        let read_attrs = || -> Result<RunAttrs> {
            Ok(RunAttrs {
                start_shape: get_str(p, &g, &field("start_shape"), "start_shape")?,
                r_init_um: get_f64(p, &g, &field("r_init_um"), "r_init_um")?,
                y_init_um: get_f64(p, &g, &field("y_init_um"), "y_init_um")?,
                z_init_um: get_f64(p, &g, &field("z_init_um"), "z_init_um")?,
                lambda: get_f64(p, &g, &field("lambda"), "lambda")?,
                scene: get_str(p, &g, &field("scene"), "scene").unwrap_or_default(),
            })
        };
        let attrs = match read_attrs() {
            Ok(a) => Some(a),
            Err(_) if !status.is_finished() => None,
            Err(e) => return Err(e),
        };
        let summary = if status.is_finished() {
            let shape = get_str(p, &g, &field("final_shape"), "final_shape")?;
            let final_shape = FinalShape::parse(&shape).ok_or_else(|| {
                SchemaError::field(p, field("final_shape"), format!("`{shape}` is not one of croissant, slipper, other"))
            })?;
            let mut evidence = BTreeMap::new();
            for name in g.attr_names().map_err(|e| h5err(p, run_id, e))? {
                if let Some(key) = name.strip_prefix("evidence_") {
                    evidence.insert(key.to_string(), get_f64(p, &g, &field(&name), &name)?);
                }
            }
            Some(RunSummary {
                status,
                final_shape,
                tank_treading: get_bool(p, &g, &field("tank_treading"), "tank_treading")?,
                tumbling: get_bool(p, &g, &field("tumbling"), "tumbling")?,
                mean_velocity_mm_s: get_f64(p, &g, &field("mean_velocity_mm_s"), "mean_velocity_mm_s")?,
                min_velocity_mm_s: get_f64(p, &g, &field("min_velocity_mm_s"), "min_velocity_mm_s")?,
                max_velocity_mm_s: get_f64(p, &g, &field("max_velocity_mm_s"), "max_velocity_mm_s")?,
                mean_radial_um: get_f64(p, &g, &field("mean_radial_um"), "mean_radial_um")?,
                mean_y_um: get_f64(p, &g, &field("mean_y_um"), "mean_y_um")?,
                mean_z_um: get_f64(p, &g, &field("mean_z_um"), "mean_z_um")?,
                evidence,
            })
        } else {
            None
        };
        let failure = if has_attr(&g, "failure") { get_str(p, &g, &field("failure"), "failure").ok() } else { None };
        let not_run = if has_attr(&g, "not_run") { get_str(p, &g, &field("not_run"), "not_run").ok() } else { None };
        let copied_from = if has_attr(&g, "copied_from") { get_str(p, &g, &field("copied_from"), "copied_from").ok() } else { None };
        let mut transits = Vec::new();
        for name in g.attr_names().map_err(|e| h5err(p, run_id, e))? {
            let Some(key) = name.strip_prefix("transit_").and_then(|r| r.strip_suffix("_t_s")) else { continue };
            let Some(distance_mm) = key.strip_suffix("mm").and_then(|d| d.replace('p', ".").parse::<f64>().ok()) else { continue };
            let get = |q: &str| {
                let n = format!("transit_{key}_{q}");
                get_f64(p, &g, &field(&n), &n)
            };
            let n = format!("transit_{key}_shape");
            let s = get_str(p, &g, &field(&n), &n)?;
            let shape = FinalShape::parse(&s).ok_or_else(|| SchemaError::field(p, field(&n), format!("`{s}` is not one of croissant, slipper, other")))?;
            let n = format!("transit_{key}_from_steady");
            let from_steady = has_attr(&g, &n) && get_bool(p, &g, &field(&n), &n)?;
            transits.push(Transit { distance_mm, t_s: get("t_s")?, x_um: get("x_um")?, y_um: get("y_um")?, z_um: get("z_um")?, velocity_mm_s: get("velocity_mm_s")?, shape, from_steady });
        }
        transits.sort_by(|a, b| a.distance_mm.total_cmp(&b.distance_mm));
        let len = |grp: &str, ds: &str| -> usize {
            g.group(grp).and_then(|x| x.dataset(ds)).map(|d| d.shape().first().copied().unwrap_or(0)).unwrap_or(0)
        };
        Ok(RunRecord {
            run_id: run_id.to_string(),
            status,
            attrs,
            summary,
            failure,
            not_run,
            copied_from,
            transits,
            n_samples: len("timeseries", "t_s"),
            n_snapshots: len("snapshots", "times_s"),
        })
    }

    /// One run's timeseries (rows that were fully written: the shortest dataset decides). A row
    /// the writer would not have stored, a non-finite value or a time not after the previous
    /// row's, is refused, naming the dataset and the row.
    pub fn timeseries(&self, run_id: &str) -> Result<Vec<TimeSample>> {
        let p = &self.path;
        let _reading = crate::hdf5_watch::reading(p, || format!("runs/{run_id}/timeseries"));
        let g = self.run_group(run_id)?;
        if self.not_run(&g) {
            return Ok(Vec::new());
        }
        let ts = g.group("timeseries").map_err(|_| invalid(p, format!("run `{run_id}`: no timeseries")))?;
        let d1 = |name: &str| -> Result<Vec<f64>> {
            let ctx = format!("runs/{run_id}/timeseries/{name}");
            let d = ts.dataset(name).map_err(|e| h5err(p, &ctx, e))?;
            read_all(p, &d, &ctx)
        };
        let d3 = |name: &str| -> Result<Vec<[f64; 3]>> {
            let d = ts.dataset(name).map_err(|e| h5err(p, &format!("runs/{run_id}/timeseries/{name}"), e))?;
            read_rows3(p, &d, &format!("runs/{run_id}/timeseries/{name}"))
        };
        let (t, area, vol, asph) = (d1("t_s")?, d1("area_um2")?, d1("volume_um3")?, d1("asphericity")?);
        let (c, v, ext) = (d3("centroid_um")?, d3("velocity_mm_s")?, d3("extents_um")?);
        let n = [t.len(), area.len(), vol.len(), asph.len(), c.len(), v.len(), ext.len()].into_iter().min().unwrap_or(0);
        // what the writer stores (finite values, times strictly increasing), checked where the
        // rows enter, so that no reader meets a NaN or a time running back
        let field = |name: &str, i: usize, what: String| SchemaError::field(p, format!("runs/{run_id}/timeseries/{name}"), format!("row {i}: {what}"));
        for i in 0..n {
            if !t[i].is_finite() || (i > 0 && t[i] <= t[i - 1]) {
                return Err(field("t_s", i, format!("{} is not a finite time after the previous row's {}", t[i], if i > 0 { t[i - 1] } else { f64::NAN })));
            }
            let columns: [(&str, &[f64]); 6] = [("area_um2", &[area[i]]), ("volume_um3", &[vol[i]]), ("asphericity", &[asph[i]]), ("centroid_um", &c[i]), ("velocity_mm_s", &v[i]), ("extents_um", &ext[i])];
            if let Some((name, _)) = columns.iter().find(|(_, x)| x.iter().any(|x| !x.is_finite())) {
                return Err(field(name, i, "not finite".into()));
            }
        }
        Ok((0..n)
            .map(|i| TimeSample {
                t_s: t[i],
                centroid_um: c[i],
                velocity_mm_s: v[i],
                area_um2: area[i],
                volume_um3: vol[i],
                asphericity: asph[i],
                extents_um: ext[i],
            })
            .collect())
    }

    /// One run's snapshots and triangles.
    pub fn snapshots(&self, run_id: &str) -> Result<Snapshots> {
        let p = &self.path;
        let _reading = crate::hdf5_watch::reading(p, || format!("runs/{run_id}/snapshots"));
        let ctx = |name: &str| format!("runs/{run_id}/snapshots/{name}");
        let g = self.run_group(run_id)?;
        if self.not_run(&g) {
            return Ok(Snapshots { times_s: Vec::new(), vertices_um: Vec::new(), triangles: Vec::new(), fields: BTreeMap::new() });
        }
        let sn = g.group("snapshots").map_err(|_| invalid(p, format!("run `{run_id}`: no snapshots")))?;
        let times_s = read_all::<f64>(p, &sn.dataset("times_s").map_err(|e| h5err(p, &ctx("times_s"), e))?, &ctx("times_s"))?;
        let vd = sn.dataset("vertices_um").map_err(|e| h5err(p, &ctx("vertices_um"), e))?;
        let shape = vd.shape();
        if shape.len() != 3 || shape[2] != 3 {
            return Err(invalid(p, format!("{}: shape {shape:?}, expected [k, nv, 3]", ctx("vertices_um"))));
        }
        let (k, nv) = (shape[0].min(times_s.len()), shape[1]);
        let flat = read_all::<f64>(p, &vd, &ctx("vertices_um"))?;
        // a shape with a vertex that is not finite is refused as the timeseries' rows are
        if let Some(o) = flat[..k * nv * 3].iter().position(|v| !v.is_finite()) {
            let (row, vertex) = (o / (nv * 3), (o / 3) % nv);
            return Err(invalid(p, format!("{}: snapshot {row}, vertex {vertex} is not finite ({})", ctx("vertices_um"), flat[o])));
        }
        let vertices_um = (0..k)
            .map(|s| (0..nv).map(|i| { let o = (s * nv + i) * 3; [flat[o], flat[o + 1], flat[o + 2]] }).collect())
            .collect();
        let td = sn.dataset("triangles").map_err(|e| h5err(p, &ctx("triangles"), e))?;
        let tflat = read_all::<u32>(p, &td, &ctx("triangles"))?;
        if tflat.len() % 3 != 0 {
            return Err(invalid(p, format!("{}: not an [nt, 3] array", ctx("triangles"))));
        }
        let triangles: Vec<[u32; 3]> = tflat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        if let Some((i, t)) = triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= nv)) {
            return Err(invalid(p, format!("{}: triangle {i} {t:?} refers to a vertex beyond the {nv} of vertices_um", ctx("triangles"))));
        }
        let mut fields = BTreeMap::new();
        for f in self.snapshot_layout(run_id)?.fields.iter().filter(|f| f.components == 1) {
            let flat = sn.dataset(&f.name).and_then(|d| d.read_raw::<f64>()).map_err(|e| h5err(p, &ctx(&f.name), e))?;
            fields.insert(f.name.clone(), flat.chunks_exact(nv.max(1)).take(k).map(<[f64]>::to_vec).collect());
        }
        Ok(Snapshots { times_s: times_s[..k].to_vec(), vertices_um, triangles, fields })
    }

    /// Where one run's snapshots lie in the file, without reading the vertex data: dataset shapes,
    /// the snapshot times, and the per-vertex fields stored beside the positions (for
    /// [`crate::xdmf`], which points at these datasets instead of copying them).
    pub fn snapshot_layout(&self, run_id: &str) -> Result<SnapshotLayout> {
        let p = &self.path;
        let _reading = crate::hdf5_watch::reading(p, || format!("runs/{run_id}/snapshots"));
        let ctx = |name: &str| format!("runs/{run_id}/snapshots/{name}");
        let sn = self.run_group(run_id)?.group("snapshots").map_err(|_| invalid(p, format!("run `{run_id}`: no snapshots")))?;
        let times_s = sn.dataset("times_s").and_then(|d| d.read_raw::<f64>()).map_err(|e| h5err(p, &ctx("times_s"), e))?;
        let vd = sn.dataset("vertices_um").map_err(|e| h5err(p, &ctx("vertices_um"), e))?;
        let shape = vd.shape();
        if shape.len() != 3 || shape[2] != 3 {
            return Err(invalid(p, format!("{}: shape {shape:?}, expected [k, nv, 3]", ctx("vertices_um"))));
        }
        let (rows, nv) = (shape[0], shape[1]);
        let td = sn.dataset("triangles").map_err(|e| h5err(p, &ctx("triangles"), e))?;
        let tshape = td.shape();
        if tshape.len() != 2 || tshape[1] != 3 {
            return Err(invalid(p, format!("{}: shape {tshape:?}, expected [nt, 3]", ctx("triangles"))));
        }
        let is = |d: &Dataset, want: hdf5::types::TypeDescriptor| d.dtype().and_then(|t| t.to_descriptor()).map(|t| t == want).unwrap_or(false);
        if !is(&td, hdf5::types::TypeDescriptor::Unsigned(hdf5::types::IntSize::U4)) {
            return Err(invalid(p, format!("{}: not unsigned 32-bit integers", ctx("triangles"))));
        }
        // (the triangles are small: their indices are checked here as `snapshots` checks them)
        let tflat = read_all::<u32>(p, &td, &ctx("triangles"))?;
        if let Some((i, t)) = tflat.chunks_exact(3).enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= nv)) {
            return Err(invalid(p, format!("{}: triangle {i} {t:?} refers to a vertex beyond the {nv} of vertices_um", ctx("triangles"))));
        }
        let f64_type = hdf5::types::TypeDescriptor::Float(hdf5::types::FloatSize::U8);
        let mut fields = Vec::new();
        let mut names = sn.member_names().map_err(|e| h5err(p, &ctx(""), e))?;
        names.sort();
        for name in names {
            if ["times_s", "vertices_um", "triangles"].contains(&name.as_str()) {
                continue;
            }
            let Ok(d) = sn.dataset(&name) else { continue };
            let s = d.shape();
            let components = match s.as_slice() {
                [_, n] if *n == nv => 1,
                [_, n, 3] if *n == nv => 3,
                _ => continue,
            };
            if is(&d, f64_type.clone()) {
                fields.push(VertexField { name, components, rows: s[0] });
            }
        }
        let n = times_s.len().min(rows);
        fields.retain(|f| f.rows >= n);
        Ok(SnapshotLayout { times_s: times_s[..n].to_vec(), rows, n_vertices: nv, n_triangles: tshape[0], fields })
    }

    /// Flush buffered data to disk.
    pub fn flush(&self) -> Result<()> {
        self.file.flush().map_err(|e| h5err(&self.path, "flush", e))
    }
}

fn read_rows3(path: &Path, d: &Dataset, ctx: &str) -> Result<Vec<[f64; 3]>> {
    let shape = d.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(invalid(path, format!("{ctx}: shape {shape:?}, expected [n, 3]")));
    }
    let flat = read_all::<f64>(path, d, ctx)?;
    Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

const SUMMARY_ATTRS: [&str; 9] = [
    "final_shape",
    "tank_treading",
    "tumbling",
    "mean_velocity_mm_s",
    "min_velocity_mm_s",
    "max_velocity_mm_s",
    "mean_radial_um",
    "mean_y_um",
    "mean_z_um",
];
