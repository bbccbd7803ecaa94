//! Triangulated closed surfaces: the cell membrane (and later the channel walls).

use nalgebra::Vector3;

/// A closed, outward-oriented triangle mesh.
///
/// `vertices` are positions in um; `triangles` index `vertices`
/// counter-clockwise seen from outside (so `(b - a) x (c - a)` points outward).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<Vector3<f64>>,
    pub triangles: Vec<[usize; 3]>,
}
