//! Matrix-free restarted GMRES on vertex vectors, for the implicit stages of [`super::rosenbrock`].
//!
//! Written here rather than taken from a crate because the operator is only
//! available as a closure (each application is a boundary-integral solve) and
//! faer 0.24 offers no GMRES (only CG, BiCGSTAB and LSMR on its own operator
//! trait). Algorithm: Saad & Schultz, SIAM J. Sci. Stat. Comput. 7, 856 (1986),
//! Arnoldi with modified Gram-Schmidt and Givens rotations.
//! [`gmres_preconditioned`] applies a right preconditioner `P^-1` (Saad, *Iterative
//! Methods for Sparse Linear Systems*, 2nd ed., SIAM 2003, Algorithm 9.5): the Krylov space is
//! built for `A P^-1`, so the residual it minimises and reports is the true `|b - A x|_2`
//! and the stopping rule means the same with or without a preconditioner.

use crate::error::SolverError;
use nalgebra::{DMatrix, DVector, Vector3};

/// Stopping rule of [`gmres`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresOptions {
    /// Krylov dimension before a restart.
    pub restart: usize,
    /// Maximal number of operator applications.
    pub max_iterations: usize,
    /// Target for the Euclidean norm of the residual `|b - A x|_2` (units of `b`).
    pub abs_tol: f64,
}

/// Outcome of [`gmres`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresReport {
    pub iterations: usize,
    pub residual: f64,
    pub converged: bool,
}

fn dot(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}

/// Solve `A x = b` with `x` as the initial guess; `apply(v, out)` writes `A v`.
pub fn gmres<F>(apply: F, b: &[Vector3<f64>], x: &mut [Vector3<f64>], opts: GmresOptions) -> Result<GmresReport, SolverError>
where
    F: FnMut(&[Vector3<f64>], &mut [Vector3<f64>]) -> Result<(), SolverError>,
{
    gmres_preconditioned(apply, |_| {}, b, x, opts)
}

/// Solve `A x = b` with `x` as the initial guess and the right preconditioner
/// `precondition(v)`, which overwrites `v` with `P^-1 v` (`P ~ A`, cheap to invert).
pub fn gmres_preconditioned<F, P>(mut apply: F, mut precondition: P, b: &[Vector3<f64>], x: &mut [Vector3<f64>], opts: GmresOptions) -> Result<GmresReport, SolverError>
where
    F: FnMut(&[Vector3<f64>], &mut [Vector3<f64>]) -> Result<(), SolverError>,
    P: FnMut(&mut [Vector3<f64>]),
{
    let n = b.len();
    let mut z = vec![Vector3::zeros(); n];
    let m = opts.restart.max(1);
    let mut iterations = 0;
    let mut r = vec![Vector3::zeros(); n];
    let mut w = vec![Vector3::zeros(); n];
    loop {
        apply(x, &mut r)?;
        for i in 0..n {
            r[i] = b[i] - r[i];
        }
        let beta = dot(&r, &r).sqrt();
        if beta <= opts.abs_tol || iterations >= opts.max_iterations {
            return Ok(GmresReport { iterations, residual: beta, converged: beta <= opts.abs_tol });
        }
        let mut basis: Vec<Vec<Vector3<f64>>> = vec![r.iter().map(|v| v / beta).collect()];
        let mut h = DMatrix::<f64>::zeros(m + 1, m);
        let mut g = DVector::<f64>::zeros(m + 1);
        g[0] = beta;
        let mut cs = vec![0.0; m];
        let mut sn = vec![0.0; m];
        let mut k_used = 0;
        let mut res = beta;
        for k in 0..m {
            z.copy_from_slice(&basis[k]);
            precondition(&mut z);
            apply(&z, &mut w)?;
            iterations += 1;
            for (j, v) in basis.iter().enumerate() {
                let hj = dot(&w, v);
                h[(j, k)] = hj;
                for i in 0..n {
                    w[i] -= hj * v[i];
                }
            }
            let hn = dot(&w, &w).sqrt();
            h[(k + 1, k)] = hn;
            for j in 0..k {
                let t = cs[j] * h[(j, k)] + sn[j] * h[(j + 1, k)];
                h[(j + 1, k)] = -sn[j] * h[(j, k)] + cs[j] * h[(j + 1, k)];
                h[(j, k)] = t;
            }
            let d = h[(k, k)].hypot(h[(k + 1, k)]);
            if d == 0.0 {
                k_used = k;
                break;
            }
            cs[k] = h[(k, k)] / d;
            sn[k] = h[(k + 1, k)] / d;
            h[(k, k)] = d;
            h[(k + 1, k)] = 0.0;
            g[k + 1] = -sn[k] * g[k];
            g[k] *= cs[k];
            res = g[k + 1].abs();
            k_used = k + 1;
            if res <= opts.abs_tol || iterations >= opts.max_iterations || hn == 0.0 {
                break;
            }
            basis.push(w.iter().map(|v| v / hn).collect());
        }
        // back substitution for the k_used x k_used upper triangular system
        let mut y = vec![0.0; k_used];
        for i in (0..k_used).rev() {
            let mut s = g[i];
            for j in i + 1..k_used {
                s -= h[(i, j)] * y[j];
            }
            y[i] = s / h[(i, i)];
        }
        // x += P^-1 (V y)
        z.iter_mut().for_each(|v| *v = Vector3::zeros());
        for (j, yj) in y.iter().enumerate() {
            for i in 0..n {
                z[i] += *yj * basis[j][i];
            }
        }
        precondition(&mut z);
        for i in 0..n {
            x[i] += z[i];
        }
        if res <= opts.abs_tol || iterations >= opts.max_iterations {
            // the Givens residual is exact in exact arithmetic; report it
            return Ok(GmresReport { iterations, residual: res, converged: res <= opts.abs_tol });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn solves_nonsymmetric_system_to_tolerance() {
        // A = I*4 + random nonsymmetric perturbation on 3*20 unknowns (seeded)
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = 20;
        let a = DMatrix::<f64>::from_fn(3 * n, 3 * n, |i, j| (if i == j { 4.0 } else { 0.0 }) + rng.random_range(-0.1..0.1));
        let xs: Vec<Vector3<f64>> = (0..n).map(|i| Vector3::new(i as f64, 1.0, -(i as f64).sqrt())).collect();
        let apply = |v: &[Vector3<f64>], out: &mut [Vector3<f64>]| {
            let flat = DVector::from_iterator(3 * n, v.iter().flat_map(|p| [p.x, p.y, p.z]));
            let r = &a * flat;
            for i in 0..n {
                out[i] = Vector3::new(r[3 * i], r[3 * i + 1], r[3 * i + 2]);
            }
            Ok(())
        };
        let mut b = vec![Vector3::zeros(); n];
        apply(&xs, &mut b).unwrap();
        let mut x = vec![Vector3::zeros(); n];
        let rep = gmres(apply, &b, &mut x, GmresOptions { restart: 8, max_iterations: 200, abs_tol: 1e-10 }).unwrap();
        assert!(rep.converged, "{rep:?}");
        let err: f64 = x.iter().zip(&xs).map(|(p, q)| (p - q).norm_squared()).sum::<f64>().sqrt();
        // |x - x*| <= |A^-1| |r| with |A^-1| ~ 1/(4 - 0.1*sqrt(60)*...) < 1
        assert!(err < 1e-9, "error {err}");
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
        let to_flat = |v: &[Vector3<f64>]| DVector::from_iterator(3 * n, v.iter().flat_map(|p| [p.x, p.y, p.z]));
        let apply = |v: &[Vector3<f64>], out: &mut [Vector3<f64>]| {
            let r = &a * to_flat(v);
            for i in 0..n {
                out[i] = Vector3::new(r[3 * i], r[3 * i + 1], r[3 * i + 2]);
            }
            Ok(())
        };
        let xs: Vec<Vector3<f64>> = (0..n).map(|i| Vector3::new(1.0, -(i as f64), 0.5)).collect();
        let mut b = vec![Vector3::zeros(); n];
        apply(&xs, &mut b).unwrap();
        let bnorm = dot(&b, &b).sqrt();
        let opts = GmresOptions { restart: 3 * n, max_iterations: 3 * n, abs_tol: 1e-10 * bnorm };
        let mut x_plain = vec![Vector3::zeros(); n];
        let plain = gmres(apply, &b, &mut x_plain, opts).unwrap();
        let mut x_pre = vec![Vector3::zeros(); n];
        let pre = gmres_preconditioned(
            apply,
            |v: &mut [Vector3<f64>]| {
                for (i, p) in v.iter_mut().enumerate() {
                    for k in 0..3 {
                        p[k] /= d[3 * i + k];
                    }
                }
            },
            &b,
            &mut x_pre,
            opts,
        )
        .unwrap();
        assert!(pre.converged, "{pre:?}");
        // the reported residual is the true one: recompute it
        let mut ax = vec![Vector3::zeros(); n];
        apply(&x_pre, &mut ax).unwrap();
        let r: f64 = ax.iter().zip(&b).map(|(p, q)| (p - q).norm_squared()).sum::<f64>().sqrt();
        assert!(r <= 1.01 * pre.residual + 1e-14 * bnorm, "true residual {r} vs reported {}", pre.residual);
        let err: f64 = x_pre.iter().zip(&xs).map(|(p, q)| (p - q).norm_squared()).sum::<f64>().sqrt();
        let xnorm: f64 = xs.iter().map(|p| p.norm_squared()).sum::<f64>().sqrt();
        assert!(err < 1e-8 * xnorm, "error {err}");
        // |E| ~ 0.02 sqrt(120)/sqrt(3) ~ 0.13: I + E needs ~10 iterations to 1e-10, the stiff D far more
        assert!(pre.iterations <= 15, "{pre:?}");
        assert!(pre.iterations * 3 < plain.iterations.max(1) || !plain.converged, "preconditioned {pre:?}, plain {plain:?}");
    }
}
