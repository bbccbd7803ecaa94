//! Mesh connectivity: unique edges, edge-triangle and vertex-triangle adjacency, vertex neighbours.

use std::collections::HashMap;

use super::Mesh;

/// Connectivity of a closed triangle mesh (computed once; it does not change
/// when vertices move).
#[derive(Debug, Clone, PartialEq)]
pub struct Topology {
    /// Unique edges `[a, b]` with `a < b`, sorted.
    pub edges: Vec<[usize; 2]>,
    /// For each edge, the triangle in which it runs `a -> b` and the one in
    /// which it runs `b -> a` (`usize::MAX` if missing: only for invalid meshes).
    pub edge_triangles: Vec<[usize; 2]>,
    /// Triangles around each vertex (unordered).
    pub vertex_triangles: Vec<Vec<usize>>,
    /// Neighbouring vertices of each vertex (sorted).
    pub vertex_neighbours: Vec<Vec<usize>>,
}

impl Topology {
    /// Builds the connectivity of `mesh` (assumes indices in range).
    pub fn new(mesh: &Mesh) -> Topology {
        let nv = mesh.vertices.len();
        let mut index: HashMap<[usize; 2], usize> =
            HashMap::with_capacity(mesh.triangles.len() * 3 / 2);
        let mut edges = Vec::new();
        let mut edge_triangles = Vec::new();
        let mut vertex_triangles = vec![Vec::new(); nv];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                vertex_triangles[a].push(t);
                let key = [a.min(b), a.max(b)];
                let e = *index.entry(key).or_insert_with(|| {
                    edges.push(key);
                    edge_triangles.push([usize::MAX; 2]);
                    edges.len() - 1
                });
                let slot = if a < b { 0 } else { 1 };
                edge_triangles[e][slot] = t;
            }
        }
        // Sort edges for a deterministic order independent of hashing.
        let mut order: Vec<usize> = (0..edges.len()).collect();
        order.sort_by_key(|&e| edges[e]);
        let edges: Vec<[usize; 2]> = order.iter().map(|&e| edges[e]).collect();
        let edge_triangles: Vec<[usize; 2]> = order.iter().map(|&e| edge_triangles[e]).collect();
        let mut vertex_neighbours = vec![Vec::new(); nv];
        for &[a, b] in &edges {
            vertex_neighbours[a].push(b);
            vertex_neighbours[b].push(a);
        }
        for n in &mut vertex_neighbours {
            n.sort_unstable();
        }
        Topology {
            edges,
            edge_triangles,
            vertex_triangles,
            vertex_neighbours,
        }
    }
}
