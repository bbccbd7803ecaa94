//! Typed errors of mesh construction and of deformation checks, each carrying the offending index.

/// Why a set of vertex/triangle arrays is not a valid cell mesh, or why a
/// deformed mesh is no longer usable (carries the index for a diagnosis).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("flat {array} array has length {len}, not a multiple of 3")]
    FlatLength { array: &'static str, len: usize },
    #[error("mesh is empty ({vertices} vertices, {triangles} triangles)")]
    Empty { vertices: usize, triangles: usize },
    #[error("vertex {vertex} has a non-finite coordinate {value:?}")]
    NonFiniteVertex { vertex: usize, value: [f64; 3] },
    #[error(
        "triangle {triangle} refers to vertex {index}, but there are only {vertices} vertices"
    )]
    IndexOutOfRange {
        triangle: usize,
        index: usize,
        vertices: usize,
    },
    #[error("triangle {triangle} repeats a vertex: {corners:?}")]
    RepeatedVertex {
        triangle: usize,
        corners: [usize; 3],
    },
    #[error(
        "triangle {triangle} has area {area:e} um^2 (degenerate; reference {reference:e} um^2)"
    )]
    Degenerate {
        triangle: usize,
        area: f64,
        reference: f64,
    },
    #[error("edge ({a}, {b}) is used by {count} triangles with this orientation (mesh not manifold or not consistently oriented)")]
    EdgeOrientation { a: usize, b: usize, count: usize },
    #[error("edge ({a}, {b}) of triangle {triangle} has no opposite half-edge (mesh not closed)")]
    OpenEdge { a: usize, b: usize, triangle: usize },
    #[error("vertex {vertex} is used by no triangle")]
    UnusedVertex { vertex: usize },
    #[error(
        "Euler characteristic V - E + F = {chi}, expected 2 (not a sphere-like closed surface)"
    )]
    NotSphereLike { chi: i64 },
    #[error("enclosed volume {volume:e} um^3 is not positive: triangles point inward")]
    InwardOriented { volume: f64 },
    #[error("triangle count {found} differs from the reference's {expected}")]
    ConnectivityMismatch { expected: usize, found: usize },
    #[error("triangles {t1} and {t2} sharing edge ({a}, {b}) fold onto each other (normals' cosine {cosine:.3})")]
    Folded {
        t1: usize,
        t2: usize,
        a: usize,
        b: usize,
        cosine: f64,
    },
    #[error("triangle {triangle} is inverted relative to the reference (area {area:e} um^2, reference {reference:e} um^2)")]
    Inverted {
        triangle: usize,
        area: f64,
        reference: f64,
    },
}
