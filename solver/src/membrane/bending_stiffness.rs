//! The nodal stiffness `K_b = dF_b/dx` (N/um) of the bending force, by central differences over a distance colouring of the mesh.
//!
//! The Helfrich force of the paper's Method C (and of the fitted methods) is node-wise: the force
//! at vertex `i` depends only on the vertices within a few rings of `i` (Method C: the cotangent
//! Laplacian of the mean curvature reaches two rings). So the columns of `K_b` of vertices whose
//! neighbourhoods of that reach do not overlap can be taken from one perturbed force evaluation
//! (Curtis, Powell & Reid, "On the estimation of sparse Jacobian matrices", IMA J. Appl. Math. 13,
//! 117 (1974)): vertices of one colour lie more than twice the reach apart in the mesh graph,
//! a perturbation of all of them at once in one coordinate direction changes each force only
//! through the one perturbed vertex within reach, and
//!
//! ```text
//! K_b[3i + k, 3j + d] = (F_i,k(x + eps e_jd) - F_i,k(x - eps e_jd)) / (2 eps)    (dist(i, j) <= reach)
//! ```
//!
//! for every vertex `j` of the colour at once: `6 * colours` force evaluations in all (~60 colours
//! at reach 2 on the paper's meshes). The reach is measured, not assumed: one vertex is perturbed
//! and the farthest vertex whose force changes sets it ([`measured_reach`]). `F_i = Df_i A_i` is
//! the nodal force of the node-wise density before the net force and torque are removed (that
//! removal couples every vertex weakly, `O(1/N)`, and is left out of this stiff-mode Jacobian).
//! The central difference step `eps = 1e-4 um` (a quarter of a thousandth of the paper's edge)
//! keeps truncation (`(eps/l)^2 ~ 1e-7`) and round-off (`~1e-12 l / eps`) far below what a
//! W-method's Jacobian needs; `tests` compare `K_b v` with a directional derivative of the whole
//! force.

use nalgebra::Vector3;

use crate::mesh::Mesh;

/// Central-difference step (um).
pub const EPS_UM: f64 = 1e-4;

/// The vertices within `radius` edges of `start` (itself included), by breadth-first search;
/// `mark` is scratch of one entry per vertex, all `usize::MAX` on entry and on return.
fn ball(nb: &[Vec<usize>], start: usize, radius: usize, mark: &mut [usize], out: &mut Vec<usize>) {
    out.clear();
    out.push(start);
    mark[start] = 0;
    let mut head = 0;
    while head < out.len() {
        let v = out[head];
        head += 1;
        if mark[v] == radius {
            continue;
        }
        for &w in &nb[v] {
            if mark[w] == usize::MAX {
                mark[w] = mark[v] + 1;
                out.push(w);
            }
        }
    }
    for &v in out.iter() {
        mark[v] = usize::MAX;
    }
}

/// Mesh distance (edges) of every vertex from `start` (`usize::MAX` when unconnected).
pub fn levels(nb: &[Vec<usize>], start: usize) -> Vec<usize> {
    let mut level = vec![usize::MAX; nb.len()];
    let mut queue = std::collections::VecDeque::from([start]);
    level[start] = 0;
    while let Some(v) = queue.pop_front() {
        for &w in &nb[v] {
            if level[w] == usize::MAX {
                level[w] = level[v] + 1;
                queue.push_back(w);
            }
        }
    }
    level
}

/// Greedy colouring in which two vertices of one colour are more than `separation` edges apart.
pub fn distance_colouring(nb: &[Vec<usize>], separation: usize) -> Vec<Vec<usize>> {
    let n = nb.len();
    let mut colour = vec![usize::MAX; n];
    let mut mark = vec![usize::MAX; n];
    let mut near = Vec::new();
    let mut used = Vec::new();
    let mut classes: Vec<Vec<usize>> = Vec::new();
    for v in 0..n {
        ball(nb, v, separation, &mut mark, &mut near);
        used.clear();
        used.extend(near.iter().map(|&w| colour[w]).filter(|&c| c != usize::MAX));
        used.sort_unstable();
        used.dedup();
        let c = used.iter().enumerate().find(|(k, &c)| *k != c).map_or(used.len(), |(k, _)| k);
        colour[v] = c;
        if c == classes.len() {
            classes.push(Vec::new());
        }
        classes[c].push(v);
    }
    classes
}

/// The largest mesh distance (edges) from a perturbed vertex to a vertex whose force changes,
/// over a few probe vertices; `force` gives the nodal forces (N) of a mesh state.
pub fn measured_reach(mesh: &Mesh, nb: &[Vec<usize>], force: &dyn Fn(&Mesh) -> Vec<Vector3<f64>>) -> usize {
    let n = mesh.vertices.len();
    let base = force(mesh);
    let scale = base.iter().map(|f| f.norm()).fold(0.0, f64::max);
    let mut reach = 0;
    let mut m = mesh.clone();
    for probe in [0, n / 3, 2 * n / 3] {
        m.vertices[probe] += Vector3::new(EPS_UM, 0.7 * EPS_UM, 0.4 * EPS_UM);
        let f = force(&m);
        m.vertices[probe] = mesh.vertices[probe];
        let level = levels(nb, probe);
        for (i, (a, b)) in f.iter().zip(&base).enumerate() {
            if (a - b).norm() > 1e-13 * scale {
                reach = reach.max(level[i]);
            }
        }
    }
    reach
}

/// `K_b = dF/dx` (N/um) of the nodal forces `force` (N) at the state `mesh`, as `(row, column,
/// value)` triplets (row `3 i + k` = component `k` of vertex `i`), for a force whose value at a
/// vertex depends only on the vertices within `reach` edges of it.
pub fn stiffness_triplets(mesh: &Mesh, nb: &[Vec<usize>], reach: usize, force: &dyn Fn(&Mesh) -> Vec<Vector3<f64>>) -> Vec<(usize, usize, f64)> {
    let n = mesh.vertices.len();
    let classes = distance_colouring(nb, 2 * reach);
    let mut mark = vec![usize::MAX; n];
    let mut rows = Vec::new();
    let mut out = Vec::new();
    let mut m = mesh.clone();
    for class in &classes {
        for d in 0..3 {
            let mut step = Vector3::zeros();
            step[d] = EPS_UM;
            for &j in class {
                m.vertices[j] = mesh.vertices[j] + step;
            }
            let fp = force(&m);
            for &j in class {
                m.vertices[j] = mesh.vertices[j] - step;
            }
            let fm = force(&m);
            for &j in class {
                m.vertices[j] = mesh.vertices[j];
                ball(nb, j, reach, &mut mark, &mut rows);
                for &i in &rows {
                    let df = (fp[i] - fm[i]) / (2.0 * EPS_UM);
                    for k in 0..3 {
                        if df[k] != 0.0 {
                            out.push((3 * i + k, 3 * j + d, df[k]));
                        }
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh as generate;

    #[test]
    fn colour_classes_are_separated_and_cover_every_vertex_once() {
        let mesh = generate::sphere(2, 1.0);
        let nb = mesh.topology().vertex_neighbours;
        let classes = distance_colouring(&nb, 4);
        let mut seen = vec![false; mesh.vertices.len()];
        let mut mark = vec![usize::MAX; nb.len()];
        let mut near = Vec::new();
        for class in &classes {
            for &v in class {
                assert!(!seen[v]);
                seen[v] = true;
                ball(&nb, v, 4, &mut mark, &mut near);
                assert!(class.iter().all(|&w| w == v || !near.contains(&w)), "vertex {v}: a vertex of its colour within 4 edges");
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    /// `K_b v` against the directional derivative of the whole nodal force (central difference
    /// along `v`), for Method C on the paper's discocyte at 512 triangles: every dependency of the
    /// force within the measured reach is in `K_b`, and the reach of Method C is two rings.
    #[test]
    fn bending_stiffness_matches_the_directional_derivative_of_the_force() {
        use crate::membrane::bending::{BendingMethod, Helfrich};
        use crate::membrane::MembraneLaw;
        let mesh = generate::discocyte(3);
        let law = Helfrich::with_method(3e-19, BendingMethod::CotangentMethodC).unwrap();
        let force = |m: &Mesh| crate::membrane::nodal_forces(m, &law.node_wise_force_density(m));
        let nb = mesh.topology().vertex_neighbours;
        assert_eq!(measured_reach(&mesh, &nb, &force), 2);
        let k = law.difference_stiffness(&mesh).unwrap();
        let n = mesh.vertices.len();
        // a smooth-ish and a rough direction
        for (w, v) in [(0.3, 1.7), (2.9, 0.4)] {
            let dir: Vec<Vector3<f64>> = (0..n).map(|i| Vector3::new((w * i as f64).sin(), (v * i as f64).cos(), (0.37 * (i * i) as f64).sin())).collect();
            let mut kv = vec![0.0; 3 * n];
            for &(r, c, x) in &k {
                kv[r] += x * dir[c / 3][c % 3];
            }
            let h = 1e-5;
            let shifted = |s: f64| Mesh { vertices: mesh.vertices.iter().zip(&dir).map(|(p, d)| p + s * d).collect(), triangles: mesh.triangles.clone() };
            let (fp, fm) = (force(&shifted(h)), force(&shifted(-h)));
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for i in 0..n {
                let d = (fp[i] - fm[i]) / (2.0 * h);
                for c in 0..3 {
                    num = num.max((kv[3 * i + c] - d[c]).abs());
                    den = den.max(d[c].abs());
                }
            }
            assert!(num < 1e-5 * den, "max |K v - dF/dv| = {num:e} of {den:e}");
        }
    }
}
