//! Restarted GMRES on vertex vectors, matrix-free and optionally right-preconditioned: the one Krylov solver of the solver (the viscosity-contrast equation in free space and in the channel, the implicit stages of the Rosenbrock schemes).
//!
//! Written here rather than taken from a crate: the operators are only available as
//! closures (each application is a boundary-integral solve, which may fail) and faer 0.24
//! offers no GMRES (only CG, BiCGSTAB and LSMR on its own operator trait; the boundary-integral
//! operator is neither symmetric nor cheap enough for BiCGSTAB's two applications per step).
//! Algorithm: Saad & Schultz, SIAM J. Sci. Stat. Comput. 7, 856 (1986), Arnoldi with modified
//! Gram-Schmidt, Givens rotations for the least-squares problem, restart after
//! [`GmresOptions::restart`] steps. [`gmres_preconditioned`] applies a right preconditioner
//! `P^-1` (Saad, *Iterative Methods for Sparse Linear Systems*, 2nd ed., SIAM 2003,
//! Algorithm 9.5): the Krylov space is built for `A P^-1`, so the residual it minimises and
//! reports is the true `|b - A x|_2` and the stopping rule means the same with or without a
//! preconditioner. Deflation (e.g. [`crate::bim::deflation::Wielandt`]) plugs in through the
//! operator.
//!
//! Vectors are vertex vectors (`[Vector3<f64>]`, um/s for the velocity equations); the
//! Euclidean norm is over all components.

use nalgebra::Vector3;

/// When GMRES stops: at `|b - A x|_2 <= target`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance {
    /// `target = tolerance |b|_2` (dimensionless).
    Relative(f64),
    /// `target` in the units of `b`.
    Absolute(f64),
}

/// Stopping rule and Krylov size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresOptions {
    pub tolerance: Tolerance,
    /// Krylov dimension between restarts.
    pub restart: usize,
    /// Arnoldi steps allowed in total.
    pub max_iterations: usize,
}

/// Why GMRES stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GmresStop {
    /// The residual met the tolerance.
    Converged,
    /// [`GmresOptions::max_iterations`] Arnoldi steps without meeting it.
    MaxIterations,
    /// A restart cycle did not reduce the true residual: restarting again cannot help (the
    /// operator is singular on the Krylov space, or rounding dominates).
    Stagnated,
    /// A non-finite value appeared (in `b`, the operator's output or the residual).
    NonFinite,
}

/// Outcome of a solve (`x` holds the last iterate whatever the outcome).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresReport {
    pub stop: GmresStop,
    /// Arnoldi steps (operator applications inside the Krylov loop).
    pub iterations: usize,
    /// Number of restarts.
    pub restarts: usize,
    /// Operator applications in total: Arnoldi steps plus true residuals at (re)starts (none
    /// for a zero initial guess, whose residual is `b`).
    pub operator_applications: usize,
    /// `|b - A x|_2` at exit (units of `b`): the Arnoldi estimate `|g_k|` when a Krylov cycle
    /// converged (the true residual up to rounding, by the Arnoldi relation
    /// `A V_k = V_{k+1} H_k`), else the recomputed true residual.
    pub residual: f64,
    /// `residual / |b|_2` (0 for `b = 0`).
    pub relative_residual: f64,
}

impl GmresReport {
    /// Did the residual meet the tolerance?
    pub fn converged(&self) -> bool {
        self.stop == GmresStop::Converged
    }
}

fn dot(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}

/// Solve `A x = b` with `x` as the initial guess (overwritten by the last iterate);
/// `apply(v, out)` writes `A v`, and its error ends the solve. GMRES's own outcome
/// (converged or why not) is in the report.
pub fn gmres<F, E>(apply: F, b: &[Vector3<f64>], x: &mut [Vector3<f64>], opts: &GmresOptions) -> Result<GmresReport, E>
where
    F: FnMut(&[Vector3<f64>], &mut [Vector3<f64>]) -> Result<(), E>,
{
    solve(apply, None, b, x, opts)
}

/// [`gmres`] with the right preconditioner `precondition(v)`, which overwrites `v` with
/// `P^-1 v` (`P ~ A`, cheap to invert).
pub fn gmres_preconditioned<F, P, E>(apply: F, mut precondition: P, b: &[Vector3<f64>], x: &mut [Vector3<f64>], opts: &GmresOptions) -> Result<GmresReport, E>
where
    F: FnMut(&[Vector3<f64>], &mut [Vector3<f64>]) -> Result<(), E>,
    P: FnMut(&mut [Vector3<f64>]),
{
    solve(apply, Some(&mut precondition), b, x, opts)
}

/// A right preconditioner: overwrites `v` with `P^-1 v`.
type Precondition<'a> = &'a mut dyn FnMut(&mut [Vector3<f64>]);

fn solve<F, E>(mut apply: F, mut precondition: Option<Precondition<'_>>, b: &[Vector3<f64>], x: &mut [Vector3<f64>], opts: &GmresOptions) -> Result<GmresReport, E>
where
    F: FnMut(&[Vector3<f64>], &mut [Vector3<f64>]) -> Result<(), E>,
{
    let n = b.len();
    assert_eq!(x.len(), n, "GMRES: initial guess and right-hand side differ in length");
    let m = opts.restart.max(1);
    let bnorm = dot(b, b).sqrt();
    let mut report = GmresReport { stop: GmresStop::Converged, iterations: 0, restarts: 0, operator_applications: 0, residual: 0.0, relative_residual: 0.0 };
    if bnorm == 0.0 {
        x.iter_mut().for_each(|v| *v = Vector3::zeros());
        return Ok(report);
    }
    let target = match opts.tolerance {
        Tolerance::Relative(t) => t * bnorm,
        Tolerance::Absolute(a) => a,
    };
    let end = |mut report: GmresReport, stop: GmresStop, residual: f64| {
        report.stop = stop;
        report.residual = residual;
        report.relative_residual = residual / bnorm;
        report
    };
    if !bnorm.is_finite() {
        return Ok(end(report, GmresStop::NonFinite, bnorm));
    }
    let mut r = vec![Vector3::zeros(); n];
    let mut w = vec![Vector3::zeros(); n];
    let mut z = vec![Vector3::zeros(); n];
    let mut basis: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(m + 1);
    let mut h = vec![vec![0.0; m]; m + 1]; // h[i][j], Hessenberg
    let (mut cs, mut sn, mut g) = (vec![0.0; m], vec![0.0; m], vec![0.0; m + 1]);
    let mut last_residual = f64::INFINITY;
    loop {
        // true residual r = b - A x (no application for x = 0)
        if x.iter().all(|v| *v == Vector3::zeros()) {
            r.copy_from_slice(b);
        } else {
            apply(x, &mut r)?;
            report.operator_applications += 1;
            r.iter_mut().zip(b).for_each(|(r, b)| *r = b - *r);
        }
        let beta = dot(&r, &r).sqrt();
        if !beta.is_finite() {
            return Ok(end(report, GmresStop::NonFinite, beta));
        }
        if beta <= target {
            return Ok(end(report, GmresStop::Converged, beta));
        }
        if report.iterations >= opts.max_iterations {
            return Ok(end(report, GmresStop::MaxIterations, beta));
        }
        if beta >= last_residual {
            return Ok(end(report, GmresStop::Stagnated, beta));
        }
        last_residual = beta;
        if report.iterations > 0 {
            report.restarts += 1;
        }
        basis.clear();
        basis.push(r.iter().map(|v| v / beta).collect());
        g.iter_mut().for_each(|g| *g = 0.0);
        g[0] = beta;
        let mut k_done = 0;
        let mut estimate = beta;
        for k in 0..m {
            z.copy_from_slice(&basis[k]);
            if let Some(p) = precondition.as_mut() {
                p(&mut z);
            }
            apply(&z, &mut w)?;
            report.iterations += 1;
            report.operator_applications += 1;
            let wnorm0 = dot(&w, &w).sqrt();
            for (j, v) in basis.iter().enumerate() {
                let hj = dot(&w, v);
                h[j][k] = hj;
                w.iter_mut().zip(v).for_each(|(w, v)| *w -= hj * v);
            }
            let hn = dot(&w, &w).sqrt();
            h[k + 1][k] = hn;
            if !hn.is_finite() {
                return Ok(end(report, GmresStop::NonFinite, hn));
            }
            // the previous rotations on column k, then a new one to zero h[k+1][k]
            for j in 0..k {
                let t = cs[j] * h[j][k] + sn[j] * h[j + 1][k];
                h[j + 1][k] = -sn[j] * h[j][k] + cs[j] * h[j + 1][k];
                h[j][k] = t;
            }
            let d = h[k][k].hypot(h[k + 1][k]);
            if d <= 1e-14 * wnorm0 {
                // a zero column: the operator maps v_k into the span of v_0..v_{k-1} (singular on
                // the Krylov space); the previous columns are kept and the restart sees no progress
                break;
            }
            (cs[k], sn[k]) = (h[k][k] / d, h[k + 1][k] / d);
            h[k][k] = d;
            h[k + 1][k] = 0.0;
            g[k + 1] = -sn[k] * g[k];
            g[k] *= cs[k];
            estimate = g[k + 1].abs();
            k_done = k + 1;
            // hn ~ 0: the Krylov space is invariant, the cycle's solution exact (lucky breakdown)
            let breakdown = hn <= 1e-14 * wnorm0;
            if estimate <= target || report.iterations >= opts.max_iterations || breakdown {
                break;
            }
            basis.push(w.iter().map(|v| v / hn).collect());
        }
        // back substitution H y = g, then x += P^-1 (V y)
        let mut y = vec![0.0; k_done];
        for i in (0..k_done).rev() {
            let mut s = g[i];
            for j in i + 1..k_done {
                s -= h[i][j] * y[j];
            }
            y[i] = s / h[i][i];
        }
        z.iter_mut().for_each(|v| *v = Vector3::zeros());
        for (yj, vj) in y.iter().zip(&basis) {
            z.iter_mut().zip(vj).for_each(|(z, v)| *z += *yj * v);
        }
        if let Some(p) = precondition.as_mut() {
            p(&mut z);
        }
        x.iter_mut().zip(&z).for_each(|(x, z)| *x += z);
        // converged within the cycle: trust the Arnoldi estimate and save one application
        if k_done > 0 && estimate <= target && estimate.is_finite() {
            return Ok(end(report, GmresStop::Converged, estimate));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};
    use rand::{Rng, SeedableRng};
    use std::convert::Infallible;

    /// `A v` for a dense `A` on `3n` unknowns (row `3 i + k` = component `k` of vertex `i`).
    fn dense(a: &DMatrix<f64>) -> impl Fn(&[Vector3<f64>], &mut [Vector3<f64>]) -> Result<(), Infallible> + '_ {
        move |v, out| {
            let r = a * DVector::from_iterator(3 * v.len(), v.iter().flat_map(|p| [p.x, p.y, p.z]));
            for (i, o) in out.iter_mut().enumerate() {
                *o = Vector3::new(r[3 * i], r[3 * i + 1], r[3 * i + 2]);
            }
            Ok(())
        }
    }

    fn norm(v: &[Vector3<f64>]) -> f64 {
        dot(v, v).sqrt()
    }

    fn true_residual(a: &DMatrix<f64>, x: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
        let mut ax = vec![Vector3::zeros(); x.len()];
        let Ok(()) = dense(a)(x, &mut ax);
        norm(&ax.iter().zip(b).map(|(p, q)| q - p).collect::<Vec<_>>())
    }

    /// Identity plus a small random non-symmetric perturbation: GMRES reproduces a known solution,
    /// with and without restarts, and reports the true residual.
    #[test]
    fn solves_nonsymmetric_system_to_tolerance() {
        let n = 20;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let a = DMatrix::<f64>::from_fn(3 * n, 3 * n, |i, j| rng.random_range(-1.0..1.0) / ((3 * n) as f64).sqrt() * 0.5 + if i == j { 1.0 } else { 0.0 });
        let xs: Vec<Vector3<f64>> = (0..n).map(|i| Vector3::new((i as f64 * 0.37).sin(), 1.0, -(i as f64).sqrt())).collect();
        let mut b = vec![Vector3::zeros(); n];
        let Ok(()) = dense(&a)(&xs, &mut b);
        for restart in [5, 3 * n] {
            let mut x = vec![Vector3::zeros(); n];
            let opts = GmresOptions { tolerance: Tolerance::Relative(1e-10), restart, max_iterations: 1000 };
            let Ok(st) = gmres(dense(&a), &b, &mut x, &opts);
            assert!(st.converged() && st.relative_residual <= 1e-10, "{st:?}");
            // the reported (Arnoldi) residual is the true one up to rounding
            let true_res = true_residual(&a, &x, &b) / norm(&b);
            assert!((true_res - st.relative_residual).abs() < 1e-13, "{true_res} vs {}", st.relative_residual);
            // from x = 0 every application is an Arnoldi step, plus one true residual per restart
            assert_eq!(st.operator_applications, st.iterations + st.restarts, "{st:?}");
            let err = x.iter().zip(&xs).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max);
            assert!(err < 1e-8, "restart {restart}: {err}");
            if restart == 3 * n {
                // without restarts GMRES terminates in at most 3n steps (exact arithmetic)
                assert!(st.iterations <= 3 * n && st.restarts == 0, "{st:?}");
            }
        }
        // an absolute tolerance, from a non-zero guess
        let mut x = vec![Vector3::new(1.0, 0.0, 0.0); n];
        let opts = GmresOptions { tolerance: Tolerance::Absolute(1e-9), restart: 8, max_iterations: 200 };
        let Ok(st) = gmres(dense(&a), &b, &mut x, &opts);
        assert!(st.converged() && true_residual(&a, &x, &b) <= 1.01e-9, "{st:?}");
    }

    /// A diagonal operator with k distinct eigenvalues is solved in k iterations (minimal polynomial).
    #[test]
    fn converges_in_number_of_distinct_eigenvalues() {
        let n = 10;
        let eig = [1.0, 2.0, 5.0];
        let a = DMatrix::<f64>::from_fn(3 * n, 3 * n, |i, j| if i == j { eig[i % 3] } else { 0.0 });
        let b: Vec<Vector3<f64>> = (0..n).map(|i| Vector3::new(1.0, 2.0, 3.0) * (1.0 + i as f64)).collect();
        let mut x = vec![Vector3::zeros(); n];
        let Ok(st) = gmres(dense(&a), &b, &mut x, &GmresOptions { tolerance: Tolerance::Relative(1e-12), restart: 20, max_iterations: 100 });
        assert_eq!(st.iterations, 3, "{st:?}");
    }

    /// A singular system with b outside the range cannot converge: a report that says why, not a hang.
    #[test]
    fn reports_non_convergence() {
        let mut a = DMatrix::<f64>::zeros(6, 6);
        a[(0, 0)] = 1.0;
        a[(1, 1)] = 1.0;
        let b = vec![Vector3::repeat(1.0); 2];
        let mut x = vec![Vector3::zeros(); 2];
        let Ok(st) = gmres(dense(&a), &b, &mut x, &GmresOptions { tolerance: Tolerance::Relative(1e-8), restart: 2, max_iterations: 50 });
        assert!(!st.converged() && matches!(st.stop, GmresStop::Stagnated | GmresStop::MaxIterations), "{st:?}");
        // the operator's own error ends the solve and is returned
        let mut x = vec![Vector3::repeat(1.0); 2];
        let e = gmres(|_: &[Vector3<f64>], _: &mut [Vector3<f64>]| Err("boom"), &b, &mut x, &GmresOptions { tolerance: Tolerance::Relative(1e-8), restart: 2, max_iterations: 50 });
        assert_eq!(e, Err("boom"));
        // a non-finite operator output is a stop, not a panic
        let mut x = vec![Vector3::zeros(); 2];
        let Ok(st) = gmres(
            |_: &[Vector3<f64>], out: &mut [Vector3<f64>]| -> Result<(), Infallible> {
                out.iter_mut().for_each(|o| *o = Vector3::repeat(f64::NAN));
                Ok(())
            },
            &b,
            &mut x,
            &GmresOptions { tolerance: Tolerance::Relative(1e-8), restart: 2, max_iterations: 50 },
        );
        assert_eq!(st.stop, GmresStop::NonFinite, "{st:?}");
    }

    #[test]
    fn right_preconditioning_keeps_the_answer_and_cuts_iterations() {
        // A = D (I + E): D spans five decades (a stiff spectrum), E a small random coupling.
        // With P = D (known exactly) A P^-1 = D (I + E) D^-1 is a similarity of I + E, so
        // GMRES needs only as many iterations as I + E does; without P it must resolve D.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let n = 40;
        let d: Vec<f64> = (0..3 * n).map(|i| 10f64.powf(5.0 * i as f64 / (3 * n - 1) as f64)).collect();
        let e = DMatrix::<f64>::from_fn(3 * n, 3 * n, |_, _| rng.random_range(-0.02..0.02));
        let a = DMatrix::from_diagonal(&DVector::from_vec(d.clone())) * (DMatrix::identity(3 * n, 3 * n) + e);
        let xs: Vec<Vector3<f64>> = (0..n).map(|i| Vector3::new(1.0, -(i as f64), 0.5)).collect();
        let mut b = vec![Vector3::zeros(); n];
        let Ok(()) = dense(&a)(&xs, &mut b);
        let bnorm = norm(&b);
        let opts = GmresOptions { tolerance: Tolerance::Absolute(1e-10 * bnorm), restart: 3 * n, max_iterations: 3 * n };
        let mut x_plain = vec![Vector3::zeros(); n];
        let Ok(plain) = gmres(dense(&a), &b, &mut x_plain, &opts);
        let mut x_pre = vec![Vector3::zeros(); n];
        let precondition = |v: &mut [Vector3<f64>]| {
            for (i, p) in v.iter_mut().enumerate() {
                for k in 0..3 {
                    p[k] /= d[3 * i + k];
                }
            }
        };
        let Ok(pre) = gmres_preconditioned(dense(&a), precondition, &b, &mut x_pre, &opts);
        assert!(pre.converged(), "{pre:?}");
        // the reported residual is the true one: recompute it
        let r = true_residual(&a, &x_pre, &b);
        assert!(r <= 1.01 * pre.residual + 1e-14 * bnorm, "true residual {r} vs reported {}", pre.residual);
        let err = norm(&x_pre.iter().zip(&xs).map(|(p, q)| p - q).collect::<Vec<_>>());
        assert!(err < 1e-8 * norm(&xs), "error {err}");
        // |E| ~ 0.02 sqrt(120)/sqrt(3) ~ 0.13: I + E needs ~10 iterations to 1e-10, the stiff D far more
        assert!(pre.iterations <= 15, "{pre:?}");
        assert!(pre.iterations * 3 < plain.iterations.max(1) || !plain.converged(), "preconditioned {pre:?}, plain {plain:?}");
    }
}
