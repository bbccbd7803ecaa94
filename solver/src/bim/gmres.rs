//! Restarted GMRES for a matrix-free real linear operator (Saad & Schultz, SIAM J. Sci. Stat. Comput. 7, 856 (1986)).
//!
//! faer 0.24 ships conjugate gradients, BiCGSTAB and LSMR for matrix-free operators but no
//! GMRES, and the boundary-integral operator is neither symmetric nor cheap enough for
//! BiCGSTAB's two applications per step, hence this implementation: Arnoldi with modified
//! Gram-Schmidt, Givens rotations for the least-squares problem, restart after `restart`
//! steps. Deflation plugs in through the operator: the "hook" is the [`LinearOperator`]
//! trait, and the free-space solve applies the double layer followed by the low-rank
//! [`super::deflation::Wielandt`] correction inside its operator.

/// A linear map `y = A x` on `R^n`, applied without forming `A`.
pub trait LinearOperator {
    /// Dimension `n`.
    fn dim(&self) -> usize;
    /// `y = A x` (`x` and `y` have length `dim()`).
    fn apply(&self, x: &[f64], y: &mut [f64]);
}

/// Stopping rule and Krylov size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresOptions {
    /// Stop at `|b - A x| <= tolerance |b|`.
    pub tolerance: f64,
    /// Krylov dimension between restarts.
    pub restart: usize,
    /// Total Arnoldi steps allowed.
    pub max_iterations: usize,
}

/// Outcome of a converged solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresStats {
    /// Arnoldi steps (operator applications inside the Krylov loop).
    pub iterations: usize,
    /// Number of restarts.
    pub restarts: usize,
    /// Relative residual `|b - A x| / |b|` at exit: the Arnoldi estimate `|g_k|` when the Krylov
    /// cycle converged (equal to the true residual up to rounding, by the Arnoldi relation
    /// `A V_k = V_{k+1} H_k`), else the recomputed true residual.
    pub relative_residual: f64,
    /// Operator applications in total: Arnoldi steps plus true residuals at (re)starts
    /// (none for a zero initial guess, whose residual is `b`).
    pub operator_applications: usize,
}

/// Why GMRES stopped without converging.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum GmresError {
    #[error("no convergence after {iterations} iterations: relative residual {residual:e}")]
    NotConverged { iterations: usize, residual: f64 },
    #[error("non-finite value at iteration {iteration}")]
    NonFinite { iteration: usize },
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Solve `A x = b` starting from the given `x` (overwritten by the solution).
pub fn gmres(a: &dyn LinearOperator, b: &[f64], x: &mut [f64], opts: &GmresOptions) -> Result<GmresStats, GmresError> {
    let n = a.dim();
    assert_eq!(b.len(), n);
    assert_eq!(x.len(), n);
    let m = opts.restart.max(1);
    let bnorm = norm(b);
    if bnorm == 0.0 {
        x.iter_mut().for_each(|v| *v = 0.0);
        return Ok(GmresStats { iterations: 0, restarts: 0, relative_residual: 0.0, operator_applications: 0 });
    }
    if !bnorm.is_finite() {
        return Err(GmresError::NonFinite { iteration: 0 });
    }
    let mut iterations = 0;
    let mut restarts = 0;
    let mut r = vec![0.0; n];
    let mut w = vec![0.0; n];
    let mut v: Vec<Vec<f64>> = Vec::with_capacity(m + 1);
    let mut h = vec![vec![0.0; m]; m + 1]; // h[i][j], Hessenberg
    let (mut cs, mut sn, mut g) = (vec![0.0; m], vec![0.0; m], vec![0.0; m + 1]);
    let mut last_residual = f64::INFINITY;
    let mut applications = 0;
    loop {
        // True residual r = b - A x (no application needed for x = 0).
        if x.iter().all(|&v| v == 0.0) {
            r.copy_from_slice(b);
        } else {
            a.apply(x, &mut r);
            applications += 1;
            r.iter_mut().zip(b).for_each(|(r, b)| *r = b - *r);
        }
        let beta = norm(&r);
        let rel = beta / bnorm;
        if !rel.is_finite() {
            return Err(GmresError::NonFinite { iteration: iterations });
        }
        if rel <= opts.tolerance {
            return Ok(GmresStats { iterations, restarts, relative_residual: rel, operator_applications: applications });
        }
        // A restart cycle that did not reduce the residual cannot help: stagnation.
        if iterations >= opts.max_iterations || rel >= last_residual {
            return Err(GmresError::NotConverged { iterations, residual: rel });
        }
        last_residual = rel;
        if iterations > 0 {
            restarts += 1;
        }
        v.clear();
        v.push(r.iter().map(|r| r / beta).collect());
        g.iter_mut().for_each(|g| *g = 0.0);
        g[0] = beta;
        let mut k_done = 0;
        for j in 0..m {
            a.apply(&v[j], &mut w);
            iterations += 1;
            applications += 1;
            let wnorm0 = norm(&w);
            for (i, vi) in v.iter().enumerate() {
                let hij = dot(&w, vi);
                h[i][j] = hij;
                w.iter_mut().zip(vi).for_each(|(w, vi)| *w -= hij * vi);
            }
            let hn = norm(&w);
            h[j + 1][j] = hn;
            if !hn.is_finite() {
                return Err(GmresError::NonFinite { iteration: iterations });
            }
            // Apply the previous rotations to column j, then make a new one to zero h[j+1][j].
            for i in 0..j {
                let t = cs[i] * h[i][j] + sn[i] * h[i + 1][j];
                h[i + 1][j] = -sn[i] * h[i][j] + cs[i] * h[i + 1][j];
                h[i][j] = t;
            }
            let d = h[j][j].hypot(h[j + 1][j]);
            if d <= 1e-14 * wnorm0 {
                // A zero column: the operator is singular on the Krylov space (it maps v_j into
                // the span of v_0..v_{j-1}). Keep the previous columns; the restart then sees
                // no progress and reports non-convergence.
                break;
            }
            (cs[j], sn[j]) = (h[j][j] / d, h[j + 1][j] / d);
            h[j][j] = d;
            h[j + 1][j] = 0.0;
            g[j + 1] = -sn[j] * g[j];
            g[j] *= cs[j];
            k_done = j + 1;
            let breakdown = hn <= 1e-14 * wnorm0;
            if !breakdown {
                v.push(w.iter().map(|w| w / hn).collect());
            }
            if g[j + 1].abs() <= opts.tolerance * bnorm || iterations >= opts.max_iterations || breakdown {
                break;
            }
        }
        // Back substitution H y = g, then x += V y.
        let mut y = vec![0.0; k_done];
        for i in (0..k_done).rev() {
            let s: f64 = g[i] - (i + 1..k_done).map(|k| h[i][k] * y[k]).sum::<f64>();
            y[i] = s / h[i][i];
        }
        for (yi, vi) in y.iter().zip(&v) {
            x.iter_mut().zip(vi).for_each(|(x, v)| *x += yi * v);
        }
        // Converged within the cycle: trust the Arnoldi estimate and save one application.
        let estimate = g[k_done].abs() / bnorm;
        if k_done > 0 && estimate <= opts.tolerance && estimate.is_finite() {
            return Ok(GmresStats { iterations, restarts, relative_residual: estimate, operator_applications: applications });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    struct Dense {
        n: usize,
        a: Vec<f64>,
    }
    impl LinearOperator for Dense {
        fn dim(&self) -> usize {
            self.n
        }
        fn apply(&self, x: &[f64], y: &mut [f64]) {
            for (yi, row) in y.iter_mut().zip(self.a.chunks_exact(self.n)) {
                *yi = row.iter().zip(x).map(|(a, x)| a * x).sum();
            }
        }
    }

    /// Identity plus a small random non-symmetric perturbation: GMRES reproduces a known solution.
    #[test]
    fn solves_nonsymmetric_system_to_tolerance() {
        let n = 60;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = rng.random_range(-1.0..1.0) / (n as f64).sqrt() * 0.5 + if i == j { 1.0 } else { 0.0 };
            }
        }
        let op = Dense { n, a };
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut b = vec![0.0; n];
        op.apply(&x_true, &mut b);
        for restart in [5, 60] {
            let mut x = vec![0.0; n];
            let opts = GmresOptions { tolerance: 1e-10, restart, max_iterations: 1000 };
            let st = gmres(&op, &b, &mut x, &opts).unwrap();
            assert!(st.relative_residual <= 1e-10);
            // The reported (Arnoldi) residual is the true one up to rounding.
            let mut ax = vec![0.0; n];
            op.apply(&x, &mut ax);
            let true_res = norm(&ax.iter().zip(&b).map(|(a, b)| b - a).collect::<Vec<_>>()) / norm(&b);
            assert!((true_res - st.relative_residual).abs() < 1e-13, "{true_res} vs {}", st.relative_residual);
            // From x = 0 every application is an Arnoldi step, plus one true residual per restart.
            assert_eq!(st.operator_applications, st.iterations + st.restarts, "{st:?}");
            let err = x.iter().zip(&x_true).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-8, "restart {restart}: {err}");
            if restart == 60 {
                // Without restarts GMRES terminates in at most n steps (exact arithmetic).
                assert!(st.iterations <= n && st.restarts == 0, "{st:?}");
            }
        }
    }

    /// A diagonal operator with k distinct eigenvalues is solved in k iterations (minimal polynomial).
    #[test]
    fn converges_in_number_of_distinct_eigenvalues() {
        let n = 30;
        let eig = [1.0, 2.0, 5.0];
        let a: Vec<f64> = (0..n * n).map(|k| if k / n == k % n { eig[(k / n) % 3] } else { 0.0 }).collect();
        let op = Dense { n, a };
        let b: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut x = vec![0.0; n];
        let st = gmres(&op, &b, &mut x, &GmresOptions { tolerance: 1e-12, restart: 20, max_iterations: 100 }).unwrap();
        assert_eq!(st.iterations, 3, "{st:?}");
    }

    /// A singular system with b outside the range cannot converge: a typed error, not a hang.
    #[test]
    fn reports_non_convergence() {
        let n = 4;
        let mut a = vec![0.0; 16];
        a[0] = 1.0;
        a[5] = 1.0;
        let op = Dense { n, a };
        let b = vec![1.0; 4];
        let mut x = vec![0.0; 4];
        let e = gmres(&op, &b, &mut x, &GmresOptions { tolerance: 1e-8, restart: 2, max_iterations: 50 }).unwrap_err();
        assert!(matches!(e, GmresError::NotConverged { .. }), "{e:?}");
    }
}
