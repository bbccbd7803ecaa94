//! GMRES's starting velocity predicted from the path of the last solves: the multi-secant (least-squares) extrapolation of the velocity as a function of the vertex positions.
//!
//! The velocity of a viscosity-contrast solve is a smooth function `u(x)` of the vertex
//! positions `x` (um; the traction is a function of `x` as well). Between two evaluations of a
//! time step `u` changes by `J (x - x_m)` to first order. The last `m + 1` solves
//! `(x_0, u_0) ... (x_m, u_m)` give the secant relations `u_i - u_m ~ J (x_i - x_m)`, so for a
//! new state `x` whose step from `x_m` is close to a combination `sum_i c_i (x_i - x_m)` of
//! the earlier steps,
//!
//! ```text
//! u(x) ~ u_m + sum_i c_i (u_i - u_m),   c = argmin |x - x_m - sum_i c_i (x_i - x_m)|_2
//! ```
//!
//! (the multi-secant update of quasi-Newton methods, e.g. Fang & Saad, Numer. Linear Algebra
//! Appl. 16, 197 (2009), Anderson mixing's least-squares step). The coefficients solve the normal
//! equations `G c = r`, `G_ij = <dx_i, dx_j>`, `r_i = <dx_i, x - x_m>`, through the eigenvectors
//! of `G`, dropping those below [`DROP`] of the largest (the steps of a Rosenbrock method's stages
//! are nearly collinear: the cell mostly translates). The part of `x - x_m` outside the span
//! predicts no change, as the last velocity would.
//!
//! Only GMRES's start changes: its stopping rule is relative to the right-hand side, so the
//! velocity it returns meets the same tolerance. Measured in the paper's channel (`solver/README.md`,
//! session 16): a late-run window takes 189 GMRES iterations instead of 223 with 8 solves of
//! history (194 with 4), and the two-point extrapolation along the last step alone (session 5)
//! took more than the last velocity (80 against 69 over 0.3 ms).

use nalgebra::{DMatrix, DVector, SymmetricEigen, Vector3};

/// Eigenvalues of the Gram matrix below this fraction of the largest are dropped.
pub const DROP: f64 = 1e-8;

/// Solves kept for the prediction ([`super::stokes::ChannelOptions::extrapolate_guess`]).
pub const HISTORY: usize = 8;

/// `(vertices, velocity)` of one solve (um, um/s).
pub type PathPoint = (Vec<Vector3<f64>>, Vec<Vector3<f64>>);

fn dot(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p.dot(q)).sum()
}

/// The predicted velocity at `x` from the path (oldest first; the last point is the base), or
/// `None` when the path has fewer than two points, its sizes differ from `x`'s, or its steps are
/// all zero.
pub fn predict(path: &[PathPoint], x: &[Vector3<f64>]) -> Option<Vec<Vector3<f64>>> {
    let (base, earlier) = path.split_last()?;
    if earlier.is_empty() || path.iter().any(|(p, u)| p.len() != x.len() || u.len() != x.len()) {
        return None;
    }
    let (xm, um) = base;
    let steps: Vec<Vec<Vector3<f64>>> = earlier.iter().map(|(p, _)| p.iter().zip(xm).map(|(a, b)| a - b).collect()).collect();
    let d: Vec<Vector3<f64>> = x.iter().zip(xm).map(|(a, b)| a - b).collect();
    let k = steps.len();
    let gram = DMatrix::from_fn(k, k, |i, j| dot(&steps[i], &steps[j]));
    let r = DVector::from_fn(k, |i, _| dot(&steps[i], &d));
    let eig = SymmetricEigen::new(gram);
    let largest = eig.eigenvalues.iter().copied().fold(0.0f64, f64::max);
    if !(largest > 0.0 && largest.is_finite()) {
        return None;
    }
    let mut c = DVector::<f64>::zeros(k);
    for (l, &ev) in eig.eigenvalues.iter().enumerate() {
        if ev > DROP * largest {
            let v = eig.eigenvectors.column(l);
            c += v * (v.dot(&r) / ev);
        }
    }
    let mut out = um.clone();
    for ((_, ui), ci) in earlier.iter().zip(c.iter()) {
        out.iter_mut().zip(ui).zip(um).for_each(|((o, a), b)| *o += (a - b) * *ci);
    }
    out.iter().all(|v| v.iter().all(|c| c.is_finite())).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn random_vertices(rng: &mut impl Rng, n: usize, scale: f64) -> Vec<Vector3<f64>> {
        (0..n).map(|_| Vector3::new(rng.random_range(-scale..scale), rng.random_range(-scale..scale), rng.random_range(-scale..scale))).collect()
    }

    /// The velocity field `u = A x + b` on `n` vertices, `A` dense and random.
    struct Affine {
        a: DMatrix<f64>,
        b: Vec<Vector3<f64>>,
    }

    impl Affine {
        fn random(rng: &mut impl Rng, n: usize) -> Self {
            let a = DMatrix::from_fn(3 * n, 3 * n, |_, _| rng.random_range(-1.0..1.0));
            Self { a, b: random_vertices(rng, n, 5.0) }
        }

        fn at(&self, x: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
            let y = &self.a * DVector::from_iterator(3 * x.len(), x.iter().flat_map(|p| [p.x, p.y, p.z]));
            (0..x.len()).map(|i| Vector3::new(y[3 * i], y[3 * i + 1], y[3 * i + 2]) + self.b[i]).collect()
        }

        /// The path point `(x0 + s d, u(x0 + s d))`.
        fn point(&self, x0: &[Vector3<f64>], d: &[Vector3<f64>], s: f64) -> PathPoint {
            let x: Vec<Vector3<f64>> = x0.iter().zip(d).map(|(p, q)| p + q * s).collect();
            let u = self.at(&x);
            (x, u)
        }
    }

    /// For an affine velocity the prediction is exact when the new step lies in the span of the
    /// path's steps (here: a combination of them), and otherwise equals the velocity at the
    /// projection of `x` onto that span (the part outside predicts no change).
    #[test]
    fn an_affine_velocity_is_predicted_exactly_on_the_span_and_by_projection_off_it() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = 12;
        let field = Affine::random(&mut rng, n);
        let x0 = random_vertices(&mut rng, n, 3.0);
        let steps: Vec<Vec<Vector3<f64>>> = (0..4).map(|_| random_vertices(&mut rng, n, 0.1)).collect();
        let path: Vec<PathPoint> = steps.iter().map(|d| field.point(&x0, d, 1.0)).chain(std::iter::once(field.point(&x0, &steps[0], 0.0))).collect();
        let max_err = |p: &[Vector3<f64>], q: &[Vector3<f64>]| p.iter().zip(q).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max);
        // on the span
        let x: Vec<Vector3<f64>> = (0..n).map(|i| x0[i] + steps[0][i] * 0.7 - steps[2][i] * 1.3 + steps[3][i] * 0.2).collect();
        let u = predict(&path, &x).unwrap();
        let err = max_err(&u, &field.at(&x));
        assert!(err < 1e-10, "on the span: {err:e}");
        // off the span: the velocity at the projection
        let off = random_vertices(&mut rng, n, 0.05);
        let x_off: Vec<Vector3<f64>> = x.iter().zip(&off).map(|(p, q)| p + q).collect();
        let u_off = predict(&path, &x_off).unwrap();
        let k = steps.len();
        let d: Vec<Vector3<f64>> = x_off.iter().zip(&x0).map(|(p, q)| p - q).collect();
        let g = DMatrix::from_fn(k, k, |i, j| dot(&steps[i], &steps[j]));
        let r = DVector::from_fn(k, |i, _| dot(&steps[i], &d));
        let c = g.lu().solve(&r).unwrap();
        let proj: Vec<Vector3<f64>> = (0..n).map(|i| x0[i] + (0..k).map(|j| steps[j][i] * c[j]).sum::<Vector3<f64>>()).collect();
        let err = max_err(&u_off, &field.at(&proj));
        assert!(err < 1e-9, "off the span: {err:e}");
    }

    /// Collinear steps (a cell that only translates) leave one direction: the dropped
    /// eigenvalues keep the coefficients bounded and the prediction exact along it.
    #[test]
    fn collinear_steps_give_a_bounded_prediction() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        let n = 10;
        let field = Affine::random(&mut rng, n);
        let x0 = random_vertices(&mut rng, n, 3.0);
        let dir = random_vertices(&mut rng, n, 0.1);
        let point = |s: f64| field.point(&x0, &dir, s);
        let path = vec![point(-3.0), point(-2.0), point(-1.0), point(0.0)];
        let (x, u_true) = point(1.0);
        let u = predict(&path, &x).unwrap();
        let err = u.iter().zip(&u_true).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max);
        assert!(err < 1e-9, "{err:e}");
    }

    #[test]
    fn a_path_of_one_point_or_of_another_size_predicts_nothing() {
        let x = vec![Vector3::new(1.0, 2.0, 3.0); 4];
        let u = vec![Vector3::new(0.5, 0.0, 0.0); 4];
        assert!(predict(&[(x.clone(), u.clone())], &x).is_none());
        assert!(predict(&[(x.clone(), u.clone()), (x[..3].to_vec(), u[..3].to_vec())], &x).is_none());
        assert!(predict(&[(x.clone(), u.clone()), (x.clone(), u.clone())], &x).is_none(), "all steps zero");
    }
}
