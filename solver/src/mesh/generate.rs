//! The octahedron subdivision projected onto the unit sphere, from which every mesh generator starts, and its triangle and vertex counts.
//!
//! The maps of the unit sphere onto the sphere, spheroid and Evans-Fung discocyte, and their
//! meshes ([`super::sphere`], [`super::spheroid`], [`super::discocyte`]), are in [`super::shapes`].

use std::collections::HashMap;

use nalgebra::Vector3;

use super::Mesh;

/// Number of triangles of a level-`level` octahedron subdivision: `8 * 4^level`
/// (128, 512, 2048, 8192 for levels 2 to 5).
pub fn triangle_count(level: usize) -> usize {
    8 * 4usize.pow(level as u32)
}

/// Number of vertices of a level-`level` octahedron subdivision: `4 * 4^level + 2`
/// (Euler: `V = F / 2 + 2`; 1026 at level 4).
pub fn vertex_count(level: usize) -> usize {
    4 * 4usize.pow(level as u32) + 2
}

/// Unit sphere from a regular octahedron (vertices `+-e_x, +-e_y, +-e_z`)
/// subdivided `level` times, each triangle into four by its edge midpoints,
/// the new vertices projected radially onto the unit sphere after every level.
///
/// Vertex order is deterministic: the 6 octahedron vertices first, then the
/// midpoints of each level in order of creation, so the same `level` always
/// gives the same numbering (meshes of different shapes at the same level
/// share connectivity and can serve as each other's reference state).
pub fn octahedron_sphere(level: usize) -> Mesh {
    octahedron_sphere_with_parents(level).0
}

/// [`octahedron_sphere`]`(level)` and the two ends of the edge whose midpoint each of its
/// vertices beyond the octahedron's six is (entry `k` for vertex `6 + k`); an edge's ends always
/// have lower numbers than its midpoint, so interpolating in vertex order fills a field level by
/// level.
pub fn octahedron_sphere_with_parents(level: usize) -> (Mesh, Vec<[usize; 2]>) {
    let mut parents = Vec::new();
    let mut vertices = vec![
        Vector3::x(),
        Vector3::y(),
        Vector3::z(),
        -Vector3::x(),
        -Vector3::y(),
        -Vector3::z(),
    ];
    // One face per octant (sx, sy, sz); (e_x, e_y, e_z) is counter-clockwise from
    // outside, and each sign flip of an axis is a reflection that reverses it.
    let mut triangles = Vec::with_capacity(triangle_count(level));
    for &sx in &[1i32, -1] {
        for &sy in &[1i32, -1] {
            for &sz in &[1i32, -1] {
                let ix = if sx > 0 { 0 } else { 3 };
                let iy = if sy > 0 { 1 } else { 4 };
                let iz = if sz > 0 { 2 } else { 5 };
                if sx * sy * sz > 0 {
                    triangles.push([ix, iy, iz]);
                } else {
                    triangles.push([ix, iz, iy]);
                }
            }
        }
    }
    for _ in 0..level {
        let mut midpoint: HashMap<(usize, usize), usize> = HashMap::new();
        let mut next = Vec::with_capacity(triangles.len() * 4);
        let mut mid = |a: usize, b: usize, vertices: &mut Vec<Vector3<f64>>| -> usize {
            let key = (a.min(b), a.max(b));
            *midpoint.entry(key).or_insert_with(|| {
                vertices.push((vertices[a] + vertices[b]).normalize());
                parents.push([a, b]);
                vertices.len() - 1
            })
        };
        for &[a, b, c] in &triangles {
            let ab = mid(a, b, &mut vertices);
            let bc = mid(b, c, &mut vertices);
            let ca = mid(c, a, &mut vertices);
            next.push([a, ab, ca]);
            next.push([ab, b, bc]);
            next.push([ca, bc, c]);
            next.push([ab, bc, ca]);
        }
        triangles = next;
    }
    (Mesh { vertices, triangles }, parents)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every vertex beyond the octahedron's six is the projected midpoint of its parents, which
    /// are numbered before it and joined by an edge of the previous level; a level's parents are
    /// the next level's first ones (the subdivision is nested).
    #[test]
    fn parents_are_the_edge_ends_of_each_midpoint() {
        for level in 1..=4 {
            let (m, parents) = octahedron_sphere_with_parents(level);
            assert_eq!(parents.len(), vertex_count(level) - 6);
            let coarse_edges: std::collections::HashSet<[usize; 2]> = level
                .checked_sub(1)
                .map(|l| octahedron_sphere(l).edges().into_iter().map(|[a, b]| [a.min(b), a.max(b)]).collect())
                .unwrap_or_default();
            for (k, &[a, b]) in parents.iter().enumerate() {
                let v = 6 + k;
                assert!(a < v && b < v, "vertex {v}: parents {a}, {b}");
                assert!(((m.vertices[a] + m.vertices[b]).normalize() - m.vertices[v]).norm() < 1e-15);
                if v >= vertex_count(level - 1) {
                    assert!(coarse_edges.contains(&[a.min(b), a.max(b)]), "vertex {v}: {a}-{b} is no edge of level {}", level - 1);
                }
            }
            assert_eq!(octahedron_sphere_with_parents(level - 1).1[..], parents[..vertex_count(level - 1) - 6]);
        }
    }
}
