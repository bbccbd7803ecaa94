//! Probability calibration of a score: Platt's sigmoid, its maximum-likelihood fit, and the
//! reliability measures that check it on held-out data (reliability diagram, ECE, Brier score).
//!
//! The shape classifier ([`crate::experiment::classify`]) turns its score into the probability
//! that the cell is a croissant with a [`Platt`] sigmoid whose constants were fitted here on
//! labelled synthetic tracks (`rbc-bench shape-calibration`).
//!
//! References: J. Platt, "Probabilistic outputs for support vector machines" (1999), the sigmoid
//! and its smoothed targets; H.-T. Lin, C.-J. Lin, R. C. Weng, "A note on Platt's probabilistic
//! outputs for support vector machines", Machine Learning 68 (2007), the Newton iteration with
//! backtracking used by [`fit_platt`]; M. P. Naeini, G. Cooper, M. Hauskrecht, AAAI 2015, the
//! expected calibration error; G. W. Brier, Monthly Weather Review 78 (1950), the Brier score.

/// Why a calibration could not be fitted or evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CalibrationError {
    #[error("calibration: {scores} scores but {labels} labels")]
    LengthMismatch { scores: usize, labels: usize },
    #[error("calibration: no samples")]
    Empty,
    #[error("calibration: every sample has the same label ({positive}); a sigmoid needs both classes")]
    OneClass { positive: bool },
    #[error("calibration: value {index} is {value}, not a finite number")]
    NotFinite { index: usize, value: f64 },
    #[error("calibration: the Newton iteration did not converge in {iterations} iterations (gradient {gradient:e})")]
    NoConvergence { iterations: usize, gradient: f64 },
}

/// Platt's sigmoid $p(s) = 1 / (1 + e^{-(a s + b)})$: the probability of the positive class
/// given the score $s$ (dimensionless). With $a > 0$ it is strictly increasing in $s$.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Platt {
    /// Slope per unit score.
    pub a: f64,
    /// Offset: $p(0) = 1 / (1 + e^{-b})$.
    pub b: f64,
}

impl Platt {
    /// $p(s)$, in (0, 1) for finite $s$; evaluated without overflow for any argument.
    pub fn probability(&self, score: f64) -> f64 {
        sigmoid(self.a * score + self.b)
    }

    /// The score at which $p(s) = p$ (the inverse, $s = (\ln\frac{p}{1-p} - b) / a$), for
    /// reading a probability threshold as a score threshold.
    pub fn score_at(&self, p: f64) -> f64 {
        ((p / (1.0 - p)).ln() - self.b) / self.a
    }
}

/// $\sigma(z) = 1 / (1 + e^{-z})$, computed from $e^{-|z|}$ so that it never overflows.
pub fn sigmoid(z: f64) -> f64 {
    if z >= 0.0 {
        1.0 / (1.0 + (-z).exp())
    } else {
        let e = z.exp();
        e / (1.0 + e)
    }
}

/// $\ln(1 + e^{z})$ without overflow.
fn softplus(z: f64) -> f64 {
    z.max(0.0) + (-z.abs()).exp().ln_1p()
}

fn check(scores: &[f64], labels: &[bool]) -> Result<(), CalibrationError> {
    if scores.len() != labels.len() {
        return Err(CalibrationError::LengthMismatch { scores: scores.len(), labels: labels.len() });
    }
    if scores.is_empty() {
        return Err(CalibrationError::Empty);
    }
    if let Some((index, &value)) = scores.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(CalibrationError::NotFinite { index, value });
    }
    Ok(())
}

/// Fit $a, b$ of [`Platt`] by maximum likelihood on `scores` with `labels` (true = positive).
///
/// Platt's smoothed targets stand for the labels, $t_+ = (N_+ + 1)/(N_+ + 2)$ and
/// $t_- = 1/(N_- + 2)$ (a prior that keeps the fit finite on separable data), and
/// $F(a, b) = \sum_i \ln(1 + e^{z_i}) - t_i z_i$, $z_i = a s_i + b$, is minimised by Newton's
/// method with a backtracking line search from $a = 0$, $b = \ln\frac{N_+ + 1}{N_- + 1}$
/// (Lin, Lin and Weng 2007, Algorithm 1, in this sign convention). Converged when the gradient's
/// largest component is below $10^{-10} N$.
pub fn fit_platt(scores: &[f64], labels: &[bool]) -> Result<Platt, CalibrationError> {
    check(scores, labels)?;
    let n_pos = labels.iter().filter(|&&l| l).count();
    let n_neg = labels.len() - n_pos;
    if n_pos == 0 || n_neg == 0 {
        return Err(CalibrationError::OneClass { positive: n_pos > 0 });
    }
    let hi = (n_pos as f64 + 1.0) / (n_pos as f64 + 2.0);
    let lo = 1.0 / (n_neg as f64 + 2.0);
    let t: Vec<f64> = labels.iter().map(|&l| if l { hi } else { lo }).collect();
    let objective = |a: f64, b: f64| -> f64 {
        scores.iter().zip(&t).map(|(&s, &ti)| {
            let z = a * s + b;
            softplus(z) - ti * z
        }).sum()
    };
    let (mut a, mut b) = (0.0, ((n_pos as f64 + 1.0) / (n_neg as f64 + 1.0)).ln());
    let mut f = objective(a, b);
    const MAX_ITER: usize = 100;
    // Levenberg-style ridge on the Hessian, as in Lin et al.: keeps it invertible when every score is equal.
    const RIDGE: f64 = 1e-12;
    let tol = 1e-10 * scores.len() as f64;
    let mut gradient = f64::INFINITY;
    for _ in 0..MAX_ITER {
        let (mut ga, mut gb, mut haa, mut hab, mut hbb) = (0.0, 0.0, RIDGE, 0.0, RIDGE);
        for (&s, &ti) in scores.iter().zip(&t) {
            let p = sigmoid(a * s + b);
            let d = p * (1.0 - p);
            ga += (p - ti) * s;
            gb += p - ti;
            haa += d * s * s;
            hab += d * s;
            hbb += d;
        }
        gradient = ga.abs().max(gb.abs());
        if gradient < tol {
            return Ok(Platt { a, b });
        }
        let det = haa * hbb - hab * hab;
        let da = -(hbb * ga - hab * gb) / det;
        let db = -(-hab * ga + haa * gb) / det;
        let slope = ga * da + gb * db;
        let mut step = 1.0;
        loop {
            let (na, nb) = (a + step * da, b + step * db);
            let nf = objective(na, nb);
            if nf <= f + 1e-4 * step * slope {
                (a, b, f) = (na, nb, nf);
                break;
            }
            step *= 0.5;
            if step < 1e-10 {
                return Err(CalibrationError::NoConvergence { iterations: MAX_ITER, gradient });
            }
        }
    }
    Err(CalibrationError::NoConvergence { iterations: MAX_ITER, gradient })
}

/// One bin of a reliability diagram: predictions in `[lo, hi)` (the last bin includes 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReliabilityBin {
    pub lo: f64,
    pub hi: f64,
    /// Predictions in the bin.
    pub count: usize,
    /// Mean predicted probability of the bin (NaN when empty).
    pub mean_predicted: f64,
    /// Fraction of the bin's samples that are positive (NaN when empty).
    pub observed: f64,
}

/// The reliability diagram of predicted probabilities `p` against outcomes `labels` in
/// `n_bins` equal-width bins of [0, 1] (DeGroot and Fienberg 1983): a calibrated predictor has
/// `observed` close to `mean_predicted` in every bin with samples.
pub fn reliability(p: &[f64], labels: &[bool], n_bins: usize) -> Result<Vec<ReliabilityBin>, CalibrationError> {
    check(p, labels)?;
    let n_bins = n_bins.max(1);
    let mut sum_p = vec![0.0; n_bins];
    let mut pos = vec![0usize; n_bins];
    let mut count = vec![0usize; n_bins];
    for (&pi, &l) in p.iter().zip(labels) {
        let k = ((pi.clamp(0.0, 1.0) * n_bins as f64) as usize).min(n_bins - 1);
        count[k] += 1;
        sum_p[k] += pi;
        pos[k] += l as usize;
    }
    Ok((0..n_bins)
        .map(|k| {
            let c = count[k] as f64;
            ReliabilityBin {
                lo: k as f64 / n_bins as f64,
                hi: (k + 1) as f64 / n_bins as f64,
                count: count[k],
                mean_predicted: sum_p[k] / c,
                observed: pos[k] as f64 / c,
            }
        })
        .collect())
}

/// Expected calibration error of a reliability diagram,
/// $\mathrm{ECE} = \sum_k \frac{n_k}{N} \left| \bar p_k - \bar y_k \right|$ over its non-empty bins.
pub fn expected_calibration_error(bins: &[ReliabilityBin]) -> f64 {
    let n: usize = bins.iter().map(|b| b.count).sum();
    bins.iter()
        .filter(|b| b.count > 0)
        .map(|b| b.count as f64 / n as f64 * (b.mean_predicted - b.observed).abs())
        .sum()
}

/// Brier score $\frac{1}{N} \sum_i (p_i - y_i)^2$ (0 is perfect; 0.25 is a constant 1/2).
pub fn brier_score(p: &[f64], labels: &[bool]) -> Result<f64, CalibrationError> {
    check(p, labels)?;
    Ok(p.iter().zip(labels).map(|(&pi, &l)| (pi - l as u8 as f64).powi(2)).sum::<f64>() / p.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Labels drawn from a known sigmoid: the fit finds its constants within the sampling error
    /// (20000 samples: standard errors ~0.05 in a, ~0.03 in b; bound 4 standard errors).
    #[test]
    fn fit_recovers_a_known_sigmoid() {
        let truth = Platt { a: 6.0, b: -1.5 };
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let scores: Vec<f64> = (0..20_000).map(|_| rng.random_range(-1.0..1.0)).collect();
        let labels: Vec<bool> = scores.iter().map(|&s| rng.random::<f64>() < truth.probability(s)).collect();
        let fit = fit_platt(&scores, &labels).unwrap();
        assert!((fit.a - truth.a).abs() < 0.2 && (fit.b - truth.b).abs() < 0.12, "{fit:?}");
        let bins = reliability(&labels.iter().zip(&scores).map(|(_, &s)| fit.probability(s)).collect::<Vec<_>>(), &labels, 10).unwrap();
        assert!(expected_calibration_error(&bins) < 0.02);
    }

    /// Separable data stays finite thanks to the smoothed targets; one class or no data is an error.
    #[test]
    fn separable_one_class_and_bad_input() {
        let s = [-1.0, -0.5, 0.5, 1.0];
        let fit = fit_platt(&s, &[false, false, true, true]).unwrap();
        assert!(fit.a.is_finite() && fit.a > 0.0 && fit.b.abs() < 1e-9, "{fit:?}");
        assert_eq!(fit_platt(&s, &[true; 4]), Err(CalibrationError::OneClass { positive: true }));
        assert_eq!(fit_platt(&[], &[]), Err(CalibrationError::Empty));
        assert_eq!(fit_platt(&s, &[true]), Err(CalibrationError::LengthMismatch { scores: 4, labels: 1 }));
        assert!(matches!(fit_platt(&[0.0, f64::NAN], &[true, false]), Err(CalibrationError::NotFinite { index: 1, .. })));
    }

    /// Exact answers: bins, ECE and Brier of a hand-made set; the sigmoid and its inverse.
    #[test]
    fn reliability_ece_brier_exact() {
        let p = [0.05, 0.15, 0.85, 0.95, 1.0];
        let y = [false, true, true, true, true];
        let bins = reliability(&p, &y, 2).unwrap();
        assert_eq!((bins[0].count, bins[1].count), (2, 3));
        assert_eq!((bins[0].mean_predicted, bins[0].observed), (0.1, 0.5));
        assert_eq!(bins[1].observed, 1.0);
        let ece = expected_calibration_error(&bins);
        assert!((ece - (2.0 / 5.0 * 0.4 + 3.0 / 5.0 * (1.0 - 2.8 / 3.0))).abs() < 1e-15, "{ece}");
        let brier = brier_score(&p, &y).unwrap();
        assert!((brier - (0.0025 + 0.7225 + 0.0225 + 0.0025) / 5.0).abs() < 1e-15);
        let m = Platt { a: 7.0, b: -1.0 };
        assert!((m.probability(m.score_at(0.8)) - 0.8).abs() < 1e-14);
        assert_eq!(sigmoid(0.0), 0.5);
        assert!(sigmoid(-1000.0) >= 0.0 && sigmoid(1000.0) == 1.0);
    }
}
