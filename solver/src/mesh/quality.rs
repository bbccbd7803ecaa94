//! Triangle quality report: angles, aspect ratios, edge-length spread.

use std::fmt;

use super::Mesh;

/// Quality of a triangulation. Aspect ratio of a triangle:
/// `l_max * perimeter / (4 sqrt(3) A)` = `l_max / (2 sqrt(3) r_in)`, 1 for an
/// equilateral triangle, growing without bound as it degenerates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QualityReport {
    pub triangles: usize,
    pub vertices: usize,
    /// Smallest interior angle over all triangles (degrees).
    pub min_angle_deg: f64,
    /// Largest interior angle over all triangles (degrees).
    pub max_angle_deg: f64,
    /// Mean over triangles of the smallest angle (degrees).
    pub mean_min_angle_deg: f64,
    /// Largest aspect ratio.
    pub max_aspect_ratio: f64,
    /// Mean aspect ratio.
    pub mean_aspect_ratio: f64,
    /// Shortest and longest edge (um).
    pub min_edge_um: f64,
    pub max_edge_um: f64,
    /// Mean edge length (um) and its coefficient of variation (std / mean).
    pub mean_edge_um: f64,
    pub edge_cv: f64,
    /// Ratio of the largest to the smallest triangle area.
    pub area_ratio: f64,
}

impl Mesh {
    /// Triangle quality report.
    pub fn quality(&self) -> QualityReport {
        let mut min_angle = f64::INFINITY;
        let mut max_angle: f64 = 0.0;
        let mut sum_min_angle = 0.0;
        let mut max_ar: f64 = 0.0;
        let mut sum_ar = 0.0;
        let (mut amin, mut amax) = (f64::INFINITY, 0.0f64);
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.corners(t);
            let l = [(c - b).norm(), (a - c).norm(), (b - a).norm()];
            let area = 0.5 * (b - a).cross(&(c - a)).norm();
            let angle =
                |u: nalgebra::Vector3<f64>, v: nalgebra::Vector3<f64>| u.angle(&v).to_degrees();
            let angles = [
                angle(b - a, c - a),
                angle(a - b, c - b),
                angle(a - c, b - c),
            ];
            let tmin = angles.iter().cloned().fold(f64::INFINITY, f64::min);
            let tmax = angles.iter().cloned().fold(0.0, f64::max);
            min_angle = min_angle.min(tmin);
            max_angle = max_angle.max(tmax);
            sum_min_angle += tmin;
            let lmax = l.iter().cloned().fold(0.0, f64::max);
            let ar = lmax * (l[0] + l[1] + l[2]) / (4.0 * 3f64.sqrt() * area);
            max_ar = max_ar.max(ar);
            sum_ar += ar;
            amin = amin.min(area);
            amax = amax.max(area);
        }
        let lengths: Vec<f64> = self
            .edges()
            .iter()
            .map(|&[a, b]| (self.vertices[a] - self.vertices[b]).norm())
            .collect();
        let n = lengths.len() as f64;
        let mean = lengths.iter().sum::<f64>() / n;
        let var = lengths.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / n;
        let nt = self.triangles.len() as f64;
        QualityReport {
            triangles: self.triangles.len(),
            vertices: self.vertices.len(),
            min_angle_deg: min_angle,
            max_angle_deg: max_angle,
            mean_min_angle_deg: sum_min_angle / nt,
            max_aspect_ratio: max_ar,
            mean_aspect_ratio: sum_ar / nt,
            min_edge_um: lengths.iter().cloned().fold(f64::INFINITY, f64::min),
            max_edge_um: lengths.iter().cloned().fold(0.0, f64::max),
            mean_edge_um: mean,
            edge_cv: var.sqrt() / mean,
            area_ratio: amax / amin,
        }
    }
}

impl fmt::Display for QualityReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:>6} tri {:>6} vert | angle min {:5.1} max {:5.1} mean-min {:5.1} deg | aspect max {:5.2} mean {:5.2} | edge {:.3}..{:.3} um (max/min {:4.2}, cv {:4.2}) | area max/min {:4.2}",
            self.triangles,
            self.vertices,
            self.min_angle_deg,
            self.max_angle_deg,
            self.mean_min_angle_deg,
            self.max_aspect_ratio,
            self.mean_aspect_ratio,
            self.min_edge_um,
            self.max_edge_um,
            self.max_edge_um / self.min_edge_um,
            self.edge_cv,
            self.area_ratio
        )
    }
}
