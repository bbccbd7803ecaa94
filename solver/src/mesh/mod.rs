//! Triangulated closed surfaces: the cell membrane (generators, geometry, topology, quality, validation).
//!
//! Conventions used throughout the solver:
//! - lengths in um, areas in um^2, volumes in um^3;
//! - triangles are counter-clockwise seen from outside, so `(b - a) x (c - a)`
//!   points out of the enclosed volume ([`Mesh::triangle_normals`] are outward);
//! - a "vertex area" is Meyer's mixed Voronoi area ([`Mesh::vertex_areas`]):
//!   membrane force densities are nodal forces divided by it, which makes them
//!   converge pointwise; [`Mesh::barycentric_vertex_areas`] (one third of the
//!   adjacent triangles, the integral of the hat function) is also available.
//!
//! Generators ([`sphere`], [`spheroid`], [`discocyte`]) subdivide an octahedron
//! `level` times (`8 * 4^level` triangles, `4 * 4^level + 2` vertices: 2048
//! triangles and 1026 vertices at level 4, the paper's resolution) and map it
//! onto the target surface ([`octahedron_sphere`] is the subdivision); they live in [`shapes`]
//! with the analytic surfaces and their exact curvatures (for convergence tests).

mod error;
mod generate;
mod geometry;
mod quality;
pub mod shapes;
pub mod slices;
mod topology;
mod validate;

pub use error::MeshError;
pub use generate::{octahedron_sphere, octahedron_sphere_with_parents, triangle_count, vertex_count};
pub use quality::QualityReport;
pub use shapes::{discocyte, sphere, spheroid};
pub use topology::Topology;

use nalgebra::Vector3;

/// A closed, outward-oriented triangle mesh.
///
/// `vertices` are positions in um; `triangles` index `vertices`
/// counter-clockwise seen from outside (so `(b - a) x (c - a)` points outward).
/// Build one with a generator or with the validating [`Mesh::from_arrays`].
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<Vector3<f64>>,
    pub triangles: Vec<[usize; 3]>,
}
