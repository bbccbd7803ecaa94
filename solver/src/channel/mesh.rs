//! Wall mesh of the periodic microchannel: a rectangular cross-section with rounded corners, triangulated as an open tube periodic along x.
//!
//! Geometry (Guckenberger et al. 2018, "Simulation setup"): width `L_y` (12 um), height `L_z`
//! (10 um), period `L_x` (42.7 um), corners rounded with radius `r_c` (the paper rounds them
//! "to prevent numerical problems" without giving the radius; default 1.5 um here). The channel
//! axis is the x axis: the fluid fills `|y| <= L_y/2`, `|z| <= L_z/2` minus the corners.
//!
//! Triangulation: `n_s` points per ring equally spaced in arc length around the cross-section,
//! `n_x` (even) rings equally spaced along x, odd rings shifted by half a step in arc length, so
//! that with `dx = (sqrt 3 / 2) ds` the triangles are nearly equilateral; `2 n_s n_x` triangles
//! and `n_s n_x` vertices. Ring `n_x` is ring 0 shifted by `L_x`: vertices at `x = 0` and
//! `x = L_x` are identified, and the triangles of the last strip keep unwrapped corner
//! positions ([`ChannelMesh::corners`]). Triangles are oriented with `(b - a) x (c - a)`
//! pointing out of the fluid (away from the axis).

use nalgebra::Vector3;

use super::ChannelError;

/// Channel dimensions (um).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelGeometry {
    /// Period along the flow direction x (um).
    pub length_x: f64,
    /// Width along y (um).
    pub width_y: f64,
    /// Height along z (um).
    pub height_z: f64,
    /// Radius of the rounded corners of the cross-section (um).
    pub corner_radius: f64,
}

impl Default for ChannelGeometry {
    /// The paper's channel: 42.7 x 12 x 10 um, corner radius 1.5 um (our choice, see the module docs).
    fn default() -> Self {
        Self {
            length_x: 42.7,
            width_y: 12.0,
            height_z: 10.0,
            corner_radius: 1.5,
        }
    }
}

impl ChannelGeometry {
    /// Check positivity and that the corners fit (`0 <= r_c < min(L_y, L_z)/2`).
    pub fn validate(&self) -> Result<(), ChannelError> {
        let bad = |name, value, reason| {
            Err(ChannelError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        for (name, v) in [
            ("length_x", self.length_x),
            ("width_y", self.width_y),
            ("height_z", self.height_z),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(name, v, "must be positive and finite");
            }
        }
        let rc = self.corner_radius;
        if !(rc >= 0.0 && rc < 0.5 * self.width_y.min(self.height_z)) {
            return bad("corner_radius", rc, "must lie in [0, min(width, height)/2)");
        }
        Ok(())
    }

    /// Perimeter of the cross-section (um): `2 (L_y - 2 r_c) + 2 (L_z - 2 r_c) + 2 pi r_c`.
    pub fn perimeter(&self) -> f64 {
        let rc = self.corner_radius;
        2.0 * (self.width_y - 2.0 * rc)
            + 2.0 * (self.height_z - 2.0 * rc)
            + 2.0 * std::f64::consts::PI * rc
    }

    /// Cross-section area (um^2): `L_y L_z - (4 - pi) r_c^2`.
    pub fn cross_section_area(&self) -> f64 {
        self.width_y * self.height_z - (4.0 - std::f64::consts::PI) * self.corner_radius.powi(2)
    }

    /// Whether `(y, z)` lies strictly inside the cross-section (axis at `y = z = 0`).
    pub fn contains(&self, y: f64, z: f64) -> bool {
        self.wall_distance(y, z) > 0.0
    }

    /// Signed distance (um) from `(y, z)` to the wall, positive inside the fluid.
    pub fn wall_distance(&self, y: f64, z: f64) -> f64 {
        let rc = self.corner_radius;
        let (hy, hz) = (0.5 * self.width_y - rc, 0.5 * self.height_z - rc);
        // Distance to the rectangle shrunk by rc, then offset (rounded-rectangle SDF).
        let (qy, qz) = (y.abs() - hy, z.abs() - hz);
        let outside = (qy.max(0.0).powi(2) + qz.max(0.0).powi(2)).sqrt();
        let inside = qy.max(qz).min(0.0);
        rc - (outside + inside)
    }

    /// Point of the cross-section boundary at arc length `s` (um, counter-clockwise seen from
    /// +x, starting at `(y, z) = (L_y/2, 0)`) and the outward unit normal there, as `(y, z, ny, nz)`.
    pub fn boundary_point(&self, s: f64) -> (f64, f64, f64, f64) {
        let rc = self.corner_radius;
        let (hy, hz) = (0.5 * self.width_y - rc, 0.5 * self.height_z - rc);
        let (w2, h2) = (0.5 * self.width_y, 0.5 * self.height_z);
        let arc = 0.5 * std::f64::consts::PI * rc;
        let mut s = s.rem_euclid(self.perimeter());
        // Pieces: right half-side up, corner, top, corner, left, corner, bottom, corner, right half-side up.
        let corner = |cy: f64, cz: f64, a0: f64, t: f64| {
            let a = a0 + if rc > 0.0 { t / rc } else { 0.0 };
            (cy + rc * a.cos(), cz + rc * a.sin(), a.cos(), a.sin())
        };
        if s < hz {
            return (w2, s, 1.0, 0.0);
        }
        s -= hz;
        if s < arc {
            return corner(hy, hz, 0.0, s);
        }
        s -= arc;
        if s < 2.0 * hy {
            return (hy - s, h2, 0.0, 1.0);
        }
        s -= 2.0 * hy;
        if s < arc {
            return corner(-hy, hz, 0.5 * std::f64::consts::PI, s);
        }
        s -= arc;
        if s < 2.0 * hz {
            return (-w2, hz - s, -1.0, 0.0);
        }
        s -= 2.0 * hz;
        if s < arc {
            return corner(-hy, -hz, std::f64::consts::PI, s);
        }
        s -= arc;
        if s < 2.0 * hy {
            return (-hy + s, -h2, 0.0, -1.0);
        }
        s -= 2.0 * hy;
        if s < arc {
            return corner(hy, -hz, 1.5 * std::f64::consts::PI, s);
        }
        s -= arc;
        (w2, -hz + s, 1.0, 0.0)
    }
}

/// The triangulated wall of one period of the channel.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelMesh {
    pub geometry: ChannelGeometry,
    /// Points per ring (around the cross-section) and rings (along x).
    pub n_s: usize,
    pub n_x: usize,
    /// Vertex `k n_s + j`: ring `k` (x = k L_x / n_x), point `j` of the ring (um).
    pub vertices: Vec<Vector3<f64>>,
    /// Outward (away from the fluid) unit normal of the exact surface at each vertex.
    pub vertex_normals: Vec<Vector3<f64>>,
    /// Triangles (vertex indices); see [`Self::corners`] for positions across the seam.
    pub triangles: Vec<[usize; 3]>,
    /// Unwrapped corner positions of each triangle (um): the last strip has x up to `L_x`.
    corner_positions: Vec<[Vector3<f64>; 3]>,
    /// Flat-triangle areas (um^2) and outward unit normals.
    pub triangle_areas: Vec<f64>,
    pub triangle_normals: Vec<Vector3<f64>>,
    /// One third of the incident triangle areas (um^2): `Int f dS = sum_i A_i f_i` for linear `f`.
    pub vertex_areas: Vec<f64>,
    /// Triangles incident to each vertex, with the corner (0, 1, 2) at which it sits.
    pub incident: Vec<Vec<(usize, usize)>>,
}

impl ChannelMesh {
    /// `n_s` points per ring (>= 8), `n_x` rings (even, >= 4).
    pub fn new(geometry: ChannelGeometry, n_s: usize, n_x: usize) -> Result<Self, ChannelError> {
        geometry.validate()?;
        if n_s < 8 {
            return Err(ChannelError::InvalidParameter {
                name: "n_s",
                value: n_s as f64,
                reason: "needs at least 8 points per ring",
            });
        }
        if n_x < 4 || !n_x.is_multiple_of(2) {
            return Err(ChannelError::InvalidParameter {
                name: "n_x",
                value: n_x as f64,
                reason: "needs an even number of rings >= 4",
            });
        }
        let p = geometry.perimeter();
        let (ds, dx) = (p / n_s as f64, geometry.length_x / n_x as f64);
        let ring_point = |k: usize, j: usize| {
            let s = (j as f64 + 0.5 * (k % 2) as f64) * ds;
            let (y, z, ny, nz) = geometry.boundary_point(s);
            (Vector3::new(k as f64 * dx, y, z), Vector3::new(0.0, ny, nz))
        };
        let mut vertices = Vec::with_capacity(n_s * n_x);
        let mut vertex_normals = Vec::with_capacity(n_s * n_x);
        for k in 0..n_x {
            for j in 0..n_s {
                let (v, n) = ring_point(k, j);
                vertices.push(v);
                vertex_normals.push(n);
            }
        }
        let idx = |k: usize, j: usize| (k % n_x) * n_s + (j % n_s);
        // Unwrapped position: ring k (k may be n_x) and point j (j may be n_s).
        let pos = |k: usize, j: usize| {
            let mut v = vertices[idx(k, j)];
            v.x = k as f64 * dx;
            v
        };
        let mut triangles = Vec::with_capacity(2 * n_s * n_x);
        let mut corner_positions = Vec::with_capacity(2 * n_s * n_x);
        for k in 0..n_x {
            for j in 0..n_s {
                // (ring, point) triples; orientation (b - a) x (c - a) = t_s x e_x (outward).
                let tris: [[(usize, usize); 3]; 2] = if k % 2 == 0 {
                    [
                        [(k, j), (k, j + 1), (k + 1, j)],
                        [(k + 1, j), (k, j + 1), (k + 1, j + 1)],
                    ]
                } else {
                    [
                        [(k, j), (k, j + 1), (k + 1, j + 1)],
                        [(k, j), (k + 1, j + 1), (k + 1, j)],
                    ]
                };
                for t in tris {
                    triangles.push(t.map(|(a, b)| idx(a, b)));
                    corner_positions.push(t.map(|(a, b)| pos(a, b)));
                }
            }
        }
        let nv = vertices.len();
        let mut triangle_areas = Vec::with_capacity(triangles.len());
        let mut triangle_normals = Vec::with_capacity(triangles.len());
        let mut vertex_areas = vec![0.0; nv];
        let mut incident = vec![Vec::new(); nv];
        for (t, (tri, c)) in triangles.iter().zip(&corner_positions).enumerate() {
            let cross = (c[1] - c[0]).cross(&(c[2] - c[0]));
            let area = 0.5 * cross.norm();
            triangle_areas.push(area);
            triangle_normals.push(cross / cross.norm());
            for (corner, &i) in tri.iter().enumerate() {
                vertex_areas[i] += area / 3.0;
                incident[i].push((t, corner));
            }
        }
        Ok(Self {
            geometry,
            n_s,
            n_x,
            vertices,
            vertex_normals,
            triangles,
            corner_positions,
            triangle_areas,
            triangle_normals,
            vertex_areas,
            incident,
        })
    }

    /// A mesh with edges of about `edge_um` (um): `n_s = round(P / h)`, `n_x` the even integer
    /// nearest `L_x / (h sqrt(3)/2)` (nearly equilateral triangles).
    pub fn with_edge(geometry: ChannelGeometry, edge_um: f64) -> Result<Self, ChannelError> {
        geometry.validate()?;
        if !(edge_um > 0.0 && edge_um.is_finite()) {
            return Err(ChannelError::InvalidParameter {
                name: "edge_um",
                value: edge_um,
                reason: "must be positive",
            });
        }
        let (n_s, n_x) = Self::counts_for_edge(&geometry, edge_um);
        Self::new(geometry, n_s, n_x)
    }

    /// `(n_s, n_x)` of [`Self::with_edge`] (the mesh has `n_s n_x` vertices), without building it.
    pub fn counts_for_edge(geometry: &ChannelGeometry, edge_um: f64) -> (usize, usize) {
        let n_s = ((geometry.perimeter() / edge_um).round() as usize).max(8);
        let n_x = ((geometry.length_x / (edge_um * 0.75f64.sqrt()) / 2.0).round() as usize * 2).max(4);
        (n_s, n_x)
    }

    /// Unwrapped corner positions of triangle `t` (um).
    pub fn corners(&self, t: usize) -> [Vector3<f64>; 3] {
        self.corner_positions[t]
    }

    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Total wall area of one period (um^2).
    pub fn area(&self) -> f64 {
        self.triangle_areas.iter().sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boundary parametrisation is continuous, closed and runs along the exact rounded rectangle.
    #[test]
    fn boundary_is_closed_and_on_the_rounded_rectangle() {
        let g = ChannelGeometry::default();
        let p = g.perimeter();
        let n = 4000;
        let mut prev = g.boundary_point(0.0);
        for i in 1..=n {
            let q = g.boundary_point(p * i as f64 / n as f64);
            let step = ((q.0 - prev.0).powi(2) + (q.1 - prev.1).powi(2)).sqrt();
            assert!(step < 1.0001 * p / n as f64 + 1e-12, "jump at {i}: {step}");
            assert!(
                g.wall_distance(q.0, q.1).abs() < 1e-12,
                "off the wall at {i}"
            );
            prev = q;
        }
        // Outward normal: a step inward along -n is inside the fluid.
        for i in 0..37 {
            let (y, z, ny, nz) = g.boundary_point(p * i as f64 / 37.0);
            assert!((g.wall_distance(y - 0.1 * ny, z - 0.1 * nz) - 0.1).abs() < 1e-12);
        }
    }

    /// Counts, orientation (out of the fluid), area close to perimeter x length (flat-facet error
    /// only at the rounded corners), and each vertex sees six triangles (a closed periodic tube).
    #[test]
    fn tube_mesh_is_periodic_oriented_and_complete() {
        let g = ChannelGeometry::default();
        let m = ChannelMesh::new(g, 30, 36).unwrap();
        assert_eq!(m.triangles.len(), 2160);
        assert_eq!(m.n_vertices(), 1080);
        assert!(m.incident.iter().all(|v| v.len() == 6));
        for t in 0..m.triangles.len() {
            let c = m.corners(t);
            let mid = (c[0] + c[1] + c[2]) / 3.0;
            let radial = Vector3::new(0.0, mid.y, mid.z);
            assert!(
                m.triangle_normals[t].dot(&radial) > 0.0,
                "triangle {t} points into the fluid"
            );
            assert!(c.iter().all(|v| v.x >= -1e-12 && v.x <= g.length_x + 1e-12));
        }
        let exact = g.perimeter() * g.length_x;
        let rel = (m.area() - exact).abs() / exact;
        // Chords cut the rounded corners (about two per quarter circle at this resolution):
        // measured 0.54 % less area than the exact surface.
        assert!(
            rel < 1e-2 && m.area() < exact,
            "area {} vs {exact}",
            m.area()
        );
        let va: f64 = m.vertex_areas.iter().sum();
        assert!((va - m.area()).abs() < 1e-9 * exact);
    }
}
