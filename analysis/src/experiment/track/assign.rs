//! Minimum-cost assignment (Hungarian method) with a per-row "leave unassigned" cost.
//!
//! Written here rather than taken from a crate: none of the workspace's
//! dependencies (nalgebra, faer, statrs, imageproc) offers an assignment solver,
//! and the matrices are tiny (the cells in view, usually < 20), so the classic
//! O(n^3) shortest-augmenting-path form (Kuhn 1955, Munkres 1957; potentials as
//! in Jonker & Volgenant 1987) is short and exact.

/// Solve the rectangular assignment problem with optional non-assignment.
///
/// `cost[i][j]` is the cost of giving column `j` to row `i`, `f64::INFINITY`
/// when forbidden. A row left unassigned costs `unassigned_row`, a column left
/// unassigned costs `unassigned_col`. Returns, for each row, the column it gets
/// (or `None`), minimising the total cost. Implemented by embedding into the
/// square problem of size `n + m` with dummy rows and columns.
pub fn assign(
    cost: &[Vec<f64>],
    n_cols: usize,
    unassigned_row: f64,
    unassigned_col: f64,
) -> Vec<Option<usize>> {
    let n = cost.len();
    let m = n_cols;
    let size = n + m;
    if n == 0 {
        return Vec::new();
    }
    if m == 0 {
        return vec![None; n];
    }
    // Forbidden pairs get a cost larger than any feasible total, so they are chosen only if nothing else exists
    // (never the case here: every row can go to its own dummy column).
    let finite_max = cost
        .iter()
        .flat_map(|r| r.iter())
        .copied()
        .filter(|c| c.is_finite())
        .fold(0.0f64, |a, c| a.max(c.abs()));
    let big =
        (finite_max + unassigned_row.abs() + unassigned_col.abs() + 1.0) * (size as f64 + 1.0);
    let c = |i: usize, j: usize| -> f64 {
        match (i < n, j < m) {
            (true, true) => {
                let v = cost[i][j];
                if v.is_finite() {
                    v
                } else {
                    big
                }
            }
            // Row i left unassigned: only its own dummy column.
            (true, false) => {
                if j - m == i {
                    unassigned_row
                } else {
                    big
                }
            }
            // Column j left unassigned: only its own dummy row.
            (false, true) => {
                if i - n == j {
                    unassigned_col
                } else {
                    big
                }
            }
            // Dummy to dummy: free.
            (false, false) => 0.0,
        }
    };
    let row_of_col = hungarian_square(size, c);
    let mut out = vec![None; n];
    for (j, &i) in row_of_col.iter().enumerate() {
        if i < n && j < m && cost[i][j].is_finite() {
            out[i] = Some(j);
        }
    }
    out
}

/// Square Hungarian method; returns `row_of_col[j]`.
fn hungarian_square(size: usize, c: impl Fn(usize, usize) -> f64) -> Vec<usize> {
    // 1-based potentials u (rows), v (columns); p[j] = row matched to column j (0 = none); way = predecessor column.
    let inf = f64::INFINITY;
    let mut u = vec![0.0; size + 1];
    let mut v = vec![0.0; size + 1];
    let mut p = vec![0usize; size + 1];
    let mut way = vec![0usize; size + 1];
    for i in 1..=size {
        p[0] = i;
        let mut j0 = 0usize;
        let mut minv = vec![inf; size + 1];
        let mut used = vec![false; size + 1];
        loop {
            used[j0] = true;
            let i0 = p[j0];
            let mut delta = inf;
            let mut j1 = 0usize;
            for j in 1..=size {
                if !used[j] {
                    let cur = c(i0 - 1, j - 1) - u[i0] - v[j];
                    if cur < minv[j] {
                        minv[j] = cur;
                        way[j] = j0;
                    }
                    if minv[j] < delta {
                        delta = minv[j];
                        j1 = j;
                    }
                }
            }
            for j in 0..=size {
                if used[j] {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if p[j0] == 0 {
                break;
            }
        }
        loop {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
            if j0 == 0 {
                break;
            }
        }
    }
    (1..=size).map(|j| p[j] - 1).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Total cost of an assignment, with the non-assignment costs.
    fn total(cost: &[Vec<f64>], m: usize, a: &[Option<usize>], ur: f64, uc: f64) -> f64 {
        let mut t = 0.0;
        let mut taken = vec![false; m];
        for (i, x) in a.iter().enumerate() {
            match x {
                Some(j) => {
                    assert!(!taken[*j], "column {j} used twice");
                    taken[*j] = true;
                    t += cost[i][*j];
                }
                None => t += ur,
            }
        }
        t + taken.iter().filter(|x| !**x).count() as f64 * uc
    }

    /// Exhaustive minimum over all partial injections rows -> columns.
    fn brute(cost: &[Vec<f64>], m: usize, ur: f64, uc: f64) -> f64 {
        fn rec(
            i: usize,
            cost: &[Vec<f64>],
            m: usize,
            taken: &mut Vec<bool>,
            ur: f64,
            uc: f64,
        ) -> f64 {
            if i == cost.len() {
                return taken.iter().filter(|x| !**x).count() as f64 * uc;
            }
            let mut best = ur + rec(i + 1, cost, m, taken, ur, uc);
            for j in 0..m {
                if !taken[j] && cost[i][j].is_finite() {
                    taken[j] = true;
                    best = best.min(cost[i][j] + rec(i + 1, cost, m, taken, ur, uc));
                    taken[j] = false;
                }
            }
            best
        }
        rec(0, cost, m, &mut vec![false; m], ur, uc)
    }

    #[test]
    fn matches_brute_force_on_random_problems() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..300 {
            let n = rng.random_range(0..6);
            let m = rng.random_range(0..6);
            let cost: Vec<Vec<f64>> = (0..n)
                .map(|_| {
                    (0..m)
                        .map(|_| {
                            if rng.random_bool(0.25) {
                                f64::INFINITY
                            } else {
                                rng.random_range(0.0..2.0)
                            }
                        })
                        .collect()
                })
                .collect();
            let (ur, uc) = (rng.random_range(0.1..1.5), rng.random_range(0.0..1.0));
            let a = assign(&cost, m, ur, uc);
            assert_eq!(a.len(), n);
            let got = total(&cost, m, &a, ur, uc);
            let want = brute(&cost, m, ur, uc);
            assert!(
                (got - want).abs() < 1e-9,
                "got {got}, optimum {want}, cost {cost:?}"
            );
        }
    }

    #[test]
    fn prefers_leaving_unassigned_over_expensive_pairs() {
        let cost = vec![vec![5.0, f64::INFINITY], vec![0.2, 0.3]];
        let a = assign(&cost, 2, 1.0, 0.0);
        assert_eq!(a, vec![None, Some(0)]);
    }
}
