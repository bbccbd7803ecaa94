//! Appending a run's samples and snapshots ([`RunWriter`]), then finishing or failing it.

use super::*;
use hdf5::Group;
use std::path::PathBuf;

/// Appends samples and snapshots to one run, then finishes or fails it.
///
/// Holds its own HDF5 handles, so it stays valid independently of the
/// [`ResultsFile`] borrow that created it (the file closes when both are dropped).
pub struct RunWriter {
    path: PathBuf,
    run_id: String,
    group: Group,
    /// Samples already in the datasets.
    n_written: usize,
    /// Samples appended but not yet written.
    pending: Vec<TimeSample>,
    n_snapshots: usize,
    nv: usize,
    /// Names of the run's per-vertex scalar fields (`snapshots/<name>`, `[k, nv]`).
    fields: Vec<String>,
}

/// Accessor of a scalar timeseries column.
type Column1 = fn(&TimeSample) -> f64;
/// Accessor of an `[n, 3]` timeseries column.
type Column3 = fn(&TimeSample) -> [f64; 3];

/// Rows of the timeseries buffered by [`RunWriter::append_sample`] before they are written.
pub const SAMPLE_BUFFER: usize = 256;

impl RunWriter {
    pub(super) fn open(path: PathBuf, run_id: &str, group: Group) -> Result<RunWriter> {
        let ctx = |n: &str| format!("runs/{run_id}/{n}");
        let t = group.dataset("timeseries/t_s").map_err(|e| h5err(&path, &ctx("timeseries/t_s"), e))?;
        let sn = group.dataset("snapshots/times_s").map_err(|e| h5err(&path, &ctx("snapshots/times_s"), e))?;
        let vd = group.dataset("snapshots/vertices_um").map_err(|e| h5err(&path, &ctx("snapshots/vertices_um"), e))?;
        let n_written = t.shape()[0];
        let n_snapshots = sn.shape()[0].min(vd.shape()[0]);
        let nv = vd.shape().get(1).copied().unwrap_or(0);
        let sg = group.group("snapshots").map_err(|e| h5err(&path, &ctx("snapshots"), e))?;
        let mut fields: Vec<String> = sg
            .member_names()
            .map_err(|e| h5err(&path, &ctx("snapshots"), e))?
            .into_iter()
            .filter(|n| !["times_s", "vertices_um", "triangles"].contains(&n.as_str()))
            .filter(|n| sg.dataset(n).map(|d| d.shape() == [d.shape()[0], nv]).unwrap_or(false))
            .collect();
        fields.sort();
        Ok(RunWriter { path, run_id: run_id.to_string(), group, n_written, pending: Vec::new(), n_snapshots, nv, fields })
    }

    /// Names of the run's per-vertex scalar fields, in name order.
    pub fn fields(&self) -> &[String] {
        &self.fields
    }

    /// The run's id.
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    /// Samples appended so far (written or buffered).
    pub fn n_samples(&self) -> usize {
        self.n_written + self.pending.len()
    }

    /// Snapshots written so far.
    pub fn n_snapshots(&self) -> usize {
        self.n_snapshots
    }

    fn ds(&self, name: &str) -> Result<Dataset> {
        self.group.dataset(name).map_err(|e| h5err(&self.path, &format!("runs/{}/{name}", self.run_id), e))
    }

    fn err(&self, name: &str, e: hdf5::Error) -> SchemaError {
        h5err(&self.path, &format!("runs/{}/{name}", self.run_id), e)
    }

    /// Append one timeseries row (refuses non-finite values: a blow-up must be diagnosed, not stored).
    ///
    /// Rows are buffered and written in blocks of [`SAMPLE_BUFFER`] rows (one
    /// resize and one write per dataset per block: about 200 us per row unbuffered,
    /// measured), and at every [`flush`](Self::flush), snapshot, `finish`, `fail` and drop.
    pub fn append_sample(&mut self, s: &TimeSample) -> Result<()> {
        let all = [s.t_s, s.area_um2, s.volume_um3, s.asphericity]
            .into_iter()
            .chain(s.centroid_um)
            .chain(s.velocity_mm_s)
            .chain(s.extents_um);
        if all.into_iter().any(|v| !v.is_finite()) {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{}/timeseries", self.run_id),
                format!("sample at t = {} s has a non-finite value", s.t_s),
            ));
        }
        self.pending.push(*s);
        if self.pending.len() >= SAMPLE_BUFFER {
            self.write_pending()?;
        }
        Ok(())
    }

    /// Write the buffered samples to the datasets.
    fn write_pending(&mut self) -> Result<()> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let n = self.n_written;
        let m = self.pending.len();
        let cols1: [(&str, Column1); 4] = [
            ("timeseries/t_s", |s| s.t_s),
            ("timeseries/area_um2", |s| s.area_um2),
            ("timeseries/volume_um3", |s| s.volume_um3),
            ("timeseries/asphericity", |s| s.asphericity),
        ];
        for (name, get) in cols1 {
            let d = self.ds(name)?;
            let v: Vec<f64> = self.pending.iter().map(get).collect();
            d.resize(n + m).map_err(|e| self.err(name, e))?;
            d.write_slice(&v[..], n..n + m).map_err(|e| self.err(name, e))?;
        }
        let cols3: [(&str, Column3); 3] = [
            ("timeseries/centroid_um", |s| s.centroid_um),
            ("timeseries/velocity_mm_s", |s| s.velocity_mm_s),
            ("timeseries/extents_um", |s| s.extents_um),
        ];
        for (name, get) in cols3 {
            let d = self.ds(name)?;
            let rows = ndarray::Array2::from_shape_fn((m, 3), |(i, j)| get(&self.pending[i])[j]);
            d.resize((n + m, 3)).map_err(|e| self.err(name, e))?;
            d.write_slice(&rows, (n..n + m, 0..3)).map_err(|e| self.err(name, e))?;
        }
        self.n_written = n + m;
        self.pending.clear();
        Ok(())
    }

    /// Append one snapshot of all vertex positions (um) at time `t_s` (s), for a run without
    /// per-vertex fields (see [`append_snapshot_with`](Self::append_snapshot_with)).
    pub fn append_snapshot(&mut self, t_s: f64, vertices_um: &[[f64; 3]]) -> Result<()> {
        self.append_snapshot_with(t_s, vertices_um, &[])
    }

    /// Append one snapshot: vertex positions (um) at time `t_s` (s) and per-vertex scalar fields
    /// `(name, one value per vertex)`. A field's dataset `snapshots/<name>` is created with the
    /// run's first snapshot; later, a field the run does not have is left out (a run begun by an
    /// older build, resumed, stays without it), and a field the run has must be given (its rows
    /// stay aligned with the snapshots).
    pub fn append_snapshot_with(&mut self, t_s: f64, vertices_um: &[[f64; 3]], fields: &[(&str, &[f64])]) -> Result<()> {
        let ctx = |name: &str| format!("runs/{}/snapshots/{name}", self.run_id);
        for (name, v) in fields {
            if v.len() != self.nv || v.iter().any(|x| !x.is_finite()) || name.is_empty() || name.contains('/') {
                return Err(SchemaError::field(&self.path, ctx(name), format!("snapshot at t = {t_s} s: {} values (the mesh has {} vertices) or a non-finite value", v.len(), self.nv)));
            }
        }
        if let Some(missing) = self.fields.iter().find(|f| !fields.iter().any(|(n, _)| n == f)) {
            return Err(SchemaError::field(&self.path, ctx(missing), format!("snapshot at t = {t_s} s does not give this field, which the run has")));
        }
        if vertices_um.len() != self.nv {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{}/snapshots/vertices_um", self.run_id),
                format!("{} vertices, the mesh has {}", vertices_um.len(), self.nv),
            ));
        }
        if !t_s.is_finite() || vertices_um.iter().flatten().any(|v| !v.is_finite()) {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{}/snapshots/vertices_um", self.run_id),
                format!("snapshot at t = {t_s} s has a non-finite value"),
            ));
        }
        self.write_pending()?;
        let k = self.n_snapshots;
        let vd = self.ds("snapshots/vertices_um")?;
        vd.resize((k + 1, self.nv, 3)).map_err(|e| self.err("snapshots/vertices_um", e))?;
        let arr = ndarray::Array3::from_shape_fn((1, self.nv, 3), |(_, i, j)| vertices_um[i][j]);
        vd.write_slice(&arr, (k..k + 1, 0..self.nv, 0..3)).map_err(|e| self.err("snapshots/vertices_um", e))?;
        for (name, v) in fields {
            let full = format!("snapshots/{name}");
            if !self.fields.iter().any(|f| f == name) {
                if k > 0 {
                    continue; // the run began without this field
                }
                let sg = self.group.group("snapshots").map_err(|e| self.err("snapshots", e))?;
                sg.new_dataset::<f64>().chunk((1, self.nv)).shape((0.., self.nv)).create(*name).map_err(|e| self.err(&full, e))?;
                self.fields.push(name.to_string());
                self.fields.sort();
            }
            let d = self.ds(&full)?;
            d.resize((k + 1, self.nv)).map_err(|e| self.err(&full, e))?;
            let row = ndarray::Array2::from_shape_fn((1, self.nv), |(_, i)| v[i]);
            d.write_slice(&row, (k..k + 1, 0..self.nv)).map_err(|e| self.err(&full, e))?;
        }
        // times_s last: a snapshot counts only once its time is written
        let td = self.ds("snapshots/times_s")?;
        td.resize(k + 1).map_err(|e| self.err("snapshots/times_s", e))?;
        td.write_slice(&[t_s][..], k..k + 1).map_err(|e| self.err("snapshots/times_s", e))?;
        self.n_snapshots = k + 1;
        Ok(())
    }

    /// Drop samples and snapshots later than `t_s` (used when resuming from a checkpoint at `t_s`).
    pub fn truncate_after(&mut self, t_s: f64) -> Result<()> {
        self.write_pending()?;
        let t = self.ds("timeseries/t_s")?.read_raw::<f64>().map_err(|e| self.err("timeseries/t_s", e))?;
        let n = t.iter().take(self.n_written).take_while(|&&x| x <= t_s).count();
        for name in ["timeseries/t_s", "timeseries/area_um2", "timeseries/volume_um3", "timeseries/asphericity"] {
            self.ds(name)?.resize(n).map_err(|e| self.err(name, e))?;
        }
        for name in ["timeseries/centroid_um", "timeseries/velocity_mm_s", "timeseries/extents_um"] {
            self.ds(name)?.resize((n, 3)).map_err(|e| self.err(name, e))?;
        }
        self.n_written = n;
        let ts = self.ds("snapshots/times_s")?.read_raw::<f64>().map_err(|e| self.err("snapshots/times_s", e))?;
        let k = ts.iter().take(self.n_snapshots).take_while(|&&x| x <= t_s).count();
        self.resize_snapshots(k)?;
        Ok(())
    }

    /// Keep the first `n_samples` timeseries rows and the first `n_snapshots` snapshots, dropping
    /// the rest (used when resuming from a checkpoint that recorded these counts: rows written
    /// after it, possibly half-written by a killed process, go). Refuses counts larger than what
    /// the file holds (the checkpoint does not belong to this run).
    pub fn truncate_to(&mut self, n_samples: usize, n_snapshots: usize) -> Result<()> {
        self.write_pending()?;
        let rows = ["timeseries/t_s", "timeseries/area_um2", "timeseries/volume_um3", "timeseries/asphericity", "timeseries/centroid_um", "timeseries/velocity_mm_s", "timeseries/extents_um"]
            .iter()
            .map(|n| self.ds(n).map(|d| d.shape()[0]))
            .collect::<Result<Vec<_>>>()?;
        let have_rows = rows.into_iter().min().unwrap_or(0);
        let have_snaps = self.ds("snapshots/times_s")?.shape()[0].min(self.ds("snapshots/vertices_um")?.shape()[0]);
        if n_samples > have_rows || n_snapshots > have_snaps {
            return Err(invalid(
                &self.path,
                format!(
                    "run `{}`: the checkpoint needs {n_samples} samples and {n_snapshots} snapshots, the file holds {have_rows} and {have_snaps}",
                    self.run_id
                ),
            ));
        }
        for name in ["timeseries/t_s", "timeseries/area_um2", "timeseries/volume_um3", "timeseries/asphericity"] {
            self.ds(name)?.resize(n_samples).map_err(|e| self.err(name, e))?;
        }
        for name in ["timeseries/centroid_um", "timeseries/velocity_mm_s", "timeseries/extents_um"] {
            self.ds(name)?.resize((n_samples, 3)).map_err(|e| self.err(name, e))?;
        }
        self.resize_snapshots(n_snapshots)?;
        self.n_written = n_samples;
        Ok(())
    }

    /// Cut the snapshot datasets (times, positions, fields) to `k` rows.
    fn resize_snapshots(&mut self, k: usize) -> Result<()> {
        self.ds("snapshots/times_s")?.resize(k).map_err(|e| self.err("snapshots/times_s", e))?;
        self.ds("snapshots/vertices_um")?.resize((k, self.nv, 3)).map_err(|e| self.err("snapshots/vertices_um", e))?;
        for f in &self.fields {
            let name = format!("snapshots/{f}");
            self.ds(&name)?.resize((k, self.nv)).map_err(|e| self.err(&name, e))?;
        }
        self.n_snapshots = k;
        Ok(())
    }

    /// Write the buffered samples and flush everything to disk (call at each checkpoint).
    pub fn flush(&mut self) -> Result<()> {
        self.write_pending()?;
        self.group.file().and_then(|f| f.flush()).map_err(|e| self.err("", e))
    }

    /// Write the summary attributes and the final status (steady, periodic or unsteady).
    pub fn finish(mut self, summary: &RunSummary) -> Result<()> {
        if !summary.status.is_finished() {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{}.status", self.run_id),
                format!("finish needs steady, periodic or unsteady, not {}", summary.status.as_str()),
            ));
        }
        self.write_pending()?;
        let (p, g) = (&self.path, &self.group);
        set_str(p, g, "final_shape", summary.final_shape.as_str())?;
        set_attr(p, g, "tank_treading", &summary.tank_treading)?;
        set_attr(p, g, "tumbling", &summary.tumbling)?;
        set_f64(p, g, "mean_velocity_mm_s", summary.mean_velocity_mm_s)?;
        set_f64(p, g, "min_velocity_mm_s", summary.min_velocity_mm_s)?;
        set_f64(p, g, "max_velocity_mm_s", summary.max_velocity_mm_s)?;
        set_f64(p, g, "mean_radial_um", summary.mean_radial_um)?;
        set_f64(p, g, "mean_y_um", summary.mean_y_um)?;
        set_f64(p, g, "mean_z_um", summary.mean_z_um)?;
        for (k, v) in &summary.evidence {
            set_f64(p, g, &format!("evidence_{k}"), *v)?;
        }
        set_str(p, g, "status", summary.status.as_str())?;
        self.flush()
    }

    /// Record (or record again: the attributes are overwritten) where and what the cell was when
    /// it had travelled `t.distance_mm` (layout in the module documentation).
    pub fn set_transit(&mut self, t: &Transit) -> Result<()> {
        write_transit(&self.path, &self.group, t)
    }

    /// Mark the run failed with a one-line diagnosis (the data written so far are kept).
    pub fn fail(mut self, message: &str) -> Result<()> {
        self.write_pending()?;
        set_str(&self.path, &self.group, "failure", message)?;
        set_str(&self.path, &self.group, "status", RunStatus::Failed.as_str())?;
        self.flush()
    }
}

impl Drop for RunWriter {
    /// Buffered samples are written when a writer is dropped without `flush`,
    /// `finish` or `fail` (best effort: an error here cannot be reported).
    fn drop(&mut self) {
        let _ = self.write_pending();
    }
}
