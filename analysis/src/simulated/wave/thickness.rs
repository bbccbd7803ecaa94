//! Thickness maps `T(x, y)` (um) of a cell along the viewing axis z, on a square grid: the thin object the wave renderer images.
//!
//! Two sources:
//! - a projected outline ([`Polygon`], the synthesiser's truth shapes): inside the outline the
//!   thickness rises over a rounding width `w` like the cross-section of a torus' tube,
//!   `T(d) = T0 sqrt(1 - (1 - min(d / w, 1))^2)` with `d` the distance to the outline (um, inside
//!   positive), and `T0` set so that the enclosed volume `sum T s^2` equals the cell's volume
//!   (a red cell's ~90 um^3), clamped to [0.5, 5] um;
//! - a closed triangle mesh (the solver's 3D shapes): `T(x, y) = sum_t sign(n_z,t) z_t(x, y)` over the
//!   triangles `t` whose projection covers `(x, y)`, i.e. the sum of the exit heights minus the sum of
//!   the entry heights of the vertical ray (outward normals: `n_z > 0` where the ray leaves the cell).
//!
//! Grid convention: sample `(i, j)` (column `i`, row `j`) is at `x = x0 + i s`, `y = y0 + j s`.

use crate::simulated::render3d::CellMesh;
use crate::simulated::synth::shape::Polygon;

/// A thickness map: `nx` x `ny` samples, row-major (`T[j nx + i]`), spacing `s` um, sample
/// `(0, 0)` at `(x0, y0)` um.
#[derive(Debug, Clone, PartialEq)]
pub struct ThicknessMap {
    pub nx: usize,
    pub ny: usize,
    pub s: f64,
    pub x0: f64,
    pub y0: f64,
    pub t_um: Vec<f64>,
}

impl ThicknessMap {
    /// A zero map covering `[xmin, xmax] x [ymin, ymax]` (um) plus `margin` um on every side.
    pub fn empty(bbox: [f64; 4], margin: f64, s: f64) -> ThicknessMap {
        let nx = (((bbox[1] - bbox[0]) + 2.0 * margin) / s).ceil() as usize + 1;
        let ny = (((bbox[3] - bbox[2]) + 2.0 * margin) / s).ceil() as usize + 1;
        ThicknessMap { nx, ny, s, x0: bbox[0] - margin, y0: bbox[2] - margin, t_um: vec![0.0; nx * ny] }
    }

    /// Enclosed volume, um^3: `sum T s^2`.
    pub fn volume_um3(&self) -> f64 {
        self.t_um.iter().sum::<f64>() * self.s * self.s
    }

    /// Thickness-weighted centroid `(x, y)`, um (the centre of the cell's mass in projection).
    pub fn centroid(&self) -> [f64; 2] {
        let (mut m, mut mx, mut my) = (0.0, 0.0, 0.0);
        for j in 0..self.ny {
            for i in 0..self.nx {
                let t = self.t_um[j * self.nx + i];
                m += t;
                mx += t * (self.x0 + i as f64 * self.s);
                my += t * (self.y0 + j as f64 * self.s);
            }
        }
        [mx / m, my / m]
    }
}

/// Rounding width of the outline model, um: the rim of a red cell is ~1 um thick and curved.
pub const ROUNDING_UM: f64 = 1.0;

/// Thickness map of an outline (centred polygon, um) holding `volume_um3`, sampled at spacing `s`
/// with `margin` um of empty border (see the module documentation).
pub fn from_outline(poly: &Polygon, volume_um3: f64, s: f64, margin: f64) -> ThicknessMap {
    let mut m = ThicknessMap::empty(poly.bbox(), margin, s);
    for j in 0..m.ny {
        let y = m.y0 + j as f64 * s;
        for i in 0..m.nx {
            let x = m.x0 + i as f64 * s;
            let d = -poly.signed_distance(x, y);
            if d > 0.0 {
                let u = 1.0 - (d / ROUNDING_UM).min(1.0);
                m.t_um[j * m.nx + i] = (1.0 - u * u).sqrt();
            }
        }
    }
    let unit = m.volume_um3();
    let t0 = if unit > 0.0 { (volume_um3 / unit).clamp(0.5, 5.0) } else { 0.0 };
    m.t_um.iter_mut().for_each(|t| *t *= t0);
    m
}

/// Thickness map of a closed, outward-oriented triangle mesh (um) seen along z, sampled at spacing
/// `s` with `margin` um of empty border (see the module documentation). Negative sums (rounding at
/// a silhouette edge) are set to zero.
pub fn from_mesh(mesh: &CellMesh, s: f64, margin: f64) -> ThicknessMap {
    let mut bbox = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
    for p in &mesh.vertices {
        bbox = [bbox[0].min(p[0]), bbox[1].max(p[0]), bbox[2].min(p[1]), bbox[3].max(p[1])];
    }
    let mut m = ThicknessMap::empty(bbox, margin, s);
    for tri in &mesh.triangles {
        let [a, b, c] = tri.map(|v| mesh.vertices[v]);
        // projected signed area (twice): > 0 for n_z > 0 (counter-clockwise seen from +z)
        let area2 = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        if area2.abs() < 1e-14 {
            continue;
        }
        let sign = area2.signum();
        let (xmin, xmax) = (a[0].min(b[0]).min(c[0]), a[0].max(b[0]).max(c[0]));
        let (ymin, ymax) = (a[1].min(b[1]).min(c[1]), a[1].max(b[1]).max(c[1]));
        let i0 = (((xmin - m.x0) / s).ceil().max(0.0)) as usize;
        let i1 = (((xmax - m.x0) / s).floor() as isize).min(m.nx as isize - 1);
        let j0 = (((ymin - m.y0) / s).ceil().max(0.0)) as usize;
        let j1 = (((ymax - m.y0) / s).floor() as isize).min(m.ny as isize - 1);
        for j in j0 as isize..=j1 {
            let y = m.y0 + j as f64 * s;
            for i in i0 as isize..=i1 {
                let x = m.x0 + i as f64 * s;
                // barycentric coordinates (a sample exactly on an edge, a set of measure zero, is
                // left to neither triangle)
                let w0 = ((b[0] - x) * (c[1] - y) - (c[0] - x) * (b[1] - y)) / area2;
                let w1 = ((c[0] - x) * (a[1] - y) - (a[0] - x) * (c[1] - y)) / area2;
                let w2 = 1.0 - w0 - w1;
                if w0 <= 0.0 || w1 <= 0.0 || w2 <= 0.0 {
                    continue;
                }
                let z = w0 * a[2] + w1 * b[2] + w2 * c[2];
                m.t_um[j as usize * m.nx + i as usize] += sign * z;
            }
        }
    }
    m.t_um.iter_mut().for_each(|t| *t = t.max(0.0));
    m
}

/// An ellipsoid centred at `(cx, cy, 0)` with semi-axes `a, b, c` (um) as a closed outward mesh
/// (latitude-longitude, `n` rings): a test shape with known volume, silhouette and thickness.
#[cfg(test)]
pub(crate) fn ellipsoid(cx: f64, cy: f64, a: f64, b: f64, c: f64, n: usize) -> CellMesh {
    let mut v = vec![[cx, cy, c]];
    for i in 1..n {
        let th = std::f64::consts::PI * i as f64 / n as f64;
        for k in 0..2 * n {
            let ph = std::f64::consts::PI * k as f64 / n as f64 + 0.37;
            v.push([cx + a * th.sin() * ph.cos(), cy + b * th.sin() * ph.sin(), c * th.cos()]);
        }
    }
    v.push([cx, cy, -c]);
    let ring = |i: usize, k: usize| 1 + (i - 1) * 2 * n + k % (2 * n);
    let mut t = Vec::new();
    for k in 0..2 * n {
        t.push([0, ring(1, k), ring(1, k + 1)]);
        for i in 1..n - 1 {
            t.push([ring(i, k), ring(i + 1, k), ring(i + 1, k + 1)]);
            t.push([ring(i, k), ring(i + 1, k + 1), ring(i, k + 1)]);
        }
        t.push([ring(n - 1, k), v.len() - 1, ring(n - 1, k + 1)]);
    }
    CellMesh::new(&v, &t).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mesh's thickness integrates to its enclosed volume, and at the centre of an ellipsoid it is
    /// the full height 2c; the map's centroid is the volume centroid's (x, y).
    #[test]
    fn mesh_thickness_integrates_to_the_volume() {
        let mesh = ellipsoid(0.0, 0.0, 4.0, 3.0, 1.2, 48);
        let (vol, c) = mesh.volume_centroid();
        let m = from_mesh(&mesh, 0.05, 0.5);
        assert!((m.volume_um3() / vol - 1.0).abs() < 2e-3, "{} vs {vol}", m.volume_um3());
        let i = ((0.0 - m.x0) / m.s).round() as usize;
        let j = ((0.0 - m.y0) / m.s).round() as usize;
        assert!((m.t_um[j * m.nx + i] - 2.4).abs() < 0.01, "{}", m.t_um[j * m.nx + i]);
        let mc = m.centroid();
        assert!((mc[0] - c[0]).abs() < 0.01 && (mc[1] - c[1]).abs() < 0.01, "{mc:?} {c:?}");
    }

    /// An outline's map holds the requested volume, is zero outside the outline and reaches its
    /// plateau `T0` one rounding width inside.
    #[test]
    fn outline_thickness_holds_the_volume() {
        let r = 3.5;
        let poly = Polygon { pts: (0..256).map(|k| { let a = std::f64::consts::TAU * k as f64 / 256.0; [r * a.cos(), r * a.sin()] }).collect() };
        let m = from_outline(&poly, 90.0, 0.05, 1.0);
        assert!((m.volume_um3() - 90.0).abs() < 1e-9);
        // plateau T0 = V / (pi (r - w)^2 + ring of the rounded profile): about 90 / 33 = 2.7 um
        let centre = m.t_um[(m.ny / 2) * m.nx + m.nx / 2];
        assert!(centre > 2.3 && centre < 3.0, "{centre}");
        for j in 0..m.ny {
            for i in 0..m.nx {
                let (x, y) = (m.x0 + i as f64 * m.s, m.y0 + j as f64 * m.s);
                if x.hypot(y) > r + 0.01 {
                    assert_eq!(m.t_um[j * m.nx + i], 0.0);
                }
            }
        }
    }
}
