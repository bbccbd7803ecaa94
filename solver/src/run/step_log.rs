//! A CSV log of every step attempt (accepted and rejected): what the step-size control saw.
//!
//! One row per [`Attempt`]: the step tried, the error norm, and where the local error estimate
//! sits: the worst vertex (its error, the part of it along the vertex normal, its position
//! relative to the cell's vertex centroid) and the root-mean-square error over all vertices,
//! total and normal. The normal part moves the surface (shape and position); the tangential part
//! moves vertices along it. Units: s, um. Columns:
//!
//! `t_s,h_s,step,accepted,error_norm,velocity_evals,worst_vertex,worst_error_um,worst_normal_um,`
//! `worst_dx_um,worst_dy_um,worst_dz_um,rms_error_um,rms_normal_um,max_normal_um,`
//! `cell_error_norm,wall_error_norm`
//!
//! The vertex normals are the mesh's area-weighted ones ([`Mesh::vertex_normals`]), of the state
//! at the start of the step. With the paper's penalty walls the state carries the wall
//! displacements after the cell's vertices ([`crate::dynamics::penalty`]): the normal and rms
//! columns are the cell's, a `worst_vertex` past the cell's last vertex is a wall vertex (its
//! `worst_error_um` is the displacement's error times `atol_um / wall_atol_um`, the scaled value
//! the error norm compares with `atol_um`; its normal and offset columns 0), and
//! the last two columns split the step's error between the two: the largest error over the
//! tolerance of the cell's vertices and of the wall displacements (against their own tolerance,
//! `integrator.wall_atol_um`; empty without walls in the state). The larger of the two is the
//! `error_norm` of the max norm: the one that set the step.

use super::{Attempt, Observer, RunSummary, Sample};
use crate::error::SolverError;
use crate::mesh::Mesh;
use nalgebra::Vector3;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The header line of the step log.
pub const HEADER: &str = "t_s,h_s,step,accepted,error_norm,velocity_evals,worst_vertex,worst_error_um,worst_normal_um,worst_dx_um,worst_dy_um,worst_dz_um,rms_error_um,rms_normal_um,max_normal_um,cell_error_norm,wall_error_norm";

/// Writes one CSV row per step attempt to a file.
pub struct StepLog {
    path: PathBuf,
    out: std::io::BufWriter<std::fs::File>,
    /// The cell's surface at the start of the attempt (its vertex normals: [`Mesh::vertex_normals`]).
    mesh: Mesh,
    /// Number of the cell's vertices: the state's entries past them are wall displacements.
    n_cell: usize,
    /// The first write error, reported at [`Observer::finish`].
    failed: Option<std::io::Error>,
}

/// Where the local error of one attempt sits (um).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorSplit {
    /// `|err . n|` at the worst vertex.
    pub worst_normal_um: f64,
    /// Worst vertex minus the vertex centroid.
    pub worst_offset_um: Vector3<f64>,
    /// `sqrt(1/N sum |err_i|^2)` and `sqrt(1/N sum (err_i . n_i)^2)`.
    pub rms_error_um: f64,
    pub rms_normal_um: f64,
    /// `max_i |err_i . n_i|`.
    pub max_normal_um: f64,
}

/// Split the per-vertex errors `err` of the state `x` with unit vertex normals `normals`.
pub fn split_error(x: &[Vector3<f64>], err: &[Vector3<f64>], normals: &[Vector3<f64>], worst: usize) -> ErrorSplit {
    let n = x.len().max(1) as f64;
    let centroid = x.iter().fold(Vector3::zeros(), |a, p| a + p) / n;
    let (mut s2, mut sn2, mut max_n) = (0.0, 0.0, 0.0f64);
    for (e, nv) in err.iter().zip(normals) {
        let en = e.dot(nv);
        s2 += e.norm_squared();
        sn2 += en * en;
        max_n = max_n.max(en.abs());
    }
    ErrorSplit {
        worst_normal_um: err.get(worst).zip(normals.get(worst)).map_or(0.0, |(e, nv)| e.dot(nv).abs()),
        worst_offset_um: x.get(worst).map_or(Vector3::zeros(), |p| p - centroid),
        rms_error_um: (s2 / n).sqrt(),
        rms_normal_um: (sn2 / n).sqrt(),
        max_normal_um: max_n,
    }
}

impl StepLog {
    /// Create (replace) the log at `path` for a cell with these triangles.
    pub fn create(path: &Path, triangles: &[[usize; 3]]) -> Result<Self, SolverError> {
        let io = |e: std::io::Error| SolverError::Output(format!("{}: {e}", path.display()));
        let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
        writeln!(out, "{HEADER}").map_err(io)?;
        let n_cell = crate::mesh::slices::cell_len(triangles);
        Ok(Self { path: path.to_path_buf(), out, mesh: Mesh { vertices: Vec::new(), triangles: triangles.to_vec() }, n_cell, failed: None })
    }
}

impl Observer for StepLog {
    fn sample(&mut self, _s: &Sample<'_>) -> Result<(), SolverError> {
        Ok(())
    }

    fn attempt(&mut self, a: &Attempt<'_>) {
        if self.failed.is_some() {
            return;
        }
        let n = self.n_cell.min(a.x.len());
        self.mesh.vertices.clear();
        self.mesh.vertices.extend_from_slice(&a.x[..n]);
        let (cell_err, wall_err) = a.err.split_at(n.min(a.err.len()));
        let s = split_error(&a.x[..n], cell_err, &self.mesh.vertex_normals(), a.worst_vertex);
        let o = s.worst_offset_um;
        let [cell_norm, wall_norm] = [cell_err, wall_err].map(|e| e.iter().map(|v| v.norm()).fold(0.0, f64::max) / a.atol_um);
        let wall_norm = if wall_err.is_empty() { String::new() } else { format!("{wall_norm:.6e}") };
        let r = writeln!(
            self.out,
            "{:.9e},{:.6e},{},{},{:.6e},{},{},{:.6e},{:.6e},{:.4},{:.4},{:.4},{:.6e},{:.6e},{:.6e},{:.6e},{}",
            a.t_s,
            a.h_s,
            a.step,
            u8::from(a.accepted),
            a.error_norm,
            a.velocity_evals,
            a.worst_vertex,
            a.worst_error_um,
            s.worst_normal_um,
            o.x,
            o.y,
            o.z,
            s.rms_error_um,
            s.rms_normal_um,
            s.max_normal_um,
            cell_norm,
            wall_norm
        );
        if let Err(e) = r {
            self.failed = Some(e);
        }
    }

    fn finish(&mut self, _summary: &RunSummary, _failure: Option<&SolverError>) -> Result<(), SolverError> {
        let io = |e: std::io::Error| SolverError::Output(format!("{}: {e}", self.path.display()));
        if let Some(e) = self.failed.take() {
            return Err(io(e));
        }
        self.out.flush().map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An octahedron: unit vertex normals are the radial directions; a radial error is all normal,
    /// a tangential one has no normal part.
    #[test]
    fn errors_split_into_normal_and_tangential_parts_on_an_octahedron() {
        let x = vec![
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(-1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.0, -1.0, 0.0),
            Vector3::new(0.0, 0.0, 1.0),
            Vector3::new(0.0, 0.0, -1.0),
        ];
        let t = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        let n = Mesh { vertices: x.clone(), triangles: t.to_vec() }.vertex_normals();
        for (p, nv) in x.iter().zip(&n) {
            assert!((nv - p).norm() < 1e-15, "{nv} at {p}");
        }
        let mut err = vec![Vector3::zeros(); 6];
        err[4] = Vector3::new(0.0, 0.0, 3e-3); // radial at the top: normal
        err[0] = Vector3::new(0.0, 4e-3, 0.0); // tangential at +x
        let s = split_error(&x, &err, &n, 0);
        assert_eq!(s.worst_normal_um, 0.0);
        assert_eq!(s.worst_offset_um, Vector3::new(1.0, 0.0, 0.0));
        assert!((s.rms_error_um - (25e-6f64 / 6.0).sqrt()).abs() < 1e-18);
        assert!((s.rms_normal_um - (9e-6f64 / 6.0).sqrt()).abs() < 1e-18);
        assert_eq!(s.max_normal_um, 3e-3);
    }
}
