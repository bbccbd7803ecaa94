//! Least-squares velocity of a track: slope of x(t) with its standard error.

/// Straight-line fit `x(t) = x0 + v t` by ordinary least squares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineFit {
    /// Slope, in units of x per unit of t (um/s when x is in um and t in s).
    pub slope: f64,
    /// Standard error of the slope, same units; `None` with fewer than 3 points
    /// (no residual degree of freedom).
    pub slope_se: Option<f64>,
    /// Intercept at t = 0.
    pub intercept: f64,
}

/// Fit `x = x0 + v t` to the points `(t_i, x_i)`.
///
/// `v = S_tx / S_tt` with `S_tt = sum (t_i - tbar)^2`, `S_tx = sum (t_i - tbar)(x_i - xbar)`;
/// standard error `se(v) = sqrt( sum r_i^2 / (n - 2) / S_tt )` (e.g. Montgomery & Runger,
/// "Applied Statistics and Probability for Engineers", sec. 11-4). Returns `None` for
/// fewer than 2 points, all points at one time, or non-finite input.
pub fn fit_line(points: &[(f64, f64)]) -> Option<LineFit> {
    let n = points.len();
    if n < 2 || points.iter().any(|(t, x)| !t.is_finite() || !x.is_finite()) {
        return None;
    }
    let nf = n as f64;
    let tbar = points.iter().map(|p| p.0).sum::<f64>() / nf;
    let xbar = points.iter().map(|p| p.1).sum::<f64>() / nf;
    let (mut stt, mut stx) = (0.0, 0.0);
    for &(t, x) in points {
        stt += (t - tbar) * (t - tbar);
        stx += (t - tbar) * (x - xbar);
    }
    if stt <= 0.0 {
        return None;
    }
    let slope = stx / stt;
    let intercept = xbar - slope * tbar;
    let slope_se = if n >= 3 {
        let ssr: f64 = points
            .iter()
            .map(|&(t, x)| (x - intercept - slope * t).powi(2))
            .sum();
        Some((ssr / (nf - 2.0) / stt).sqrt())
    } else {
        None
    };
    Some(LineFit {
        slope,
        slope_se,
        intercept,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn exact_line_is_recovered() {
        let pts: Vec<(f64, f64)> = (0..7)
            .map(|i| (i as f64 * 0.0025, 3.0 + 1234.5 * i as f64 * 0.0025))
            .collect();
        let f = fit_line(&pts).unwrap();
        assert!((f.slope - 1234.5).abs() < 1e-9 && (f.intercept - 3.0).abs() < 1e-12);
        assert!(f.slope_se.unwrap() < 1e-6);
        assert!(fit_line(&pts[..1]).is_none());
        assert!(fit_line(&[(1.0, 2.0), (1.0, 3.0)]).is_none());
        assert!(fit_line(&pts[..2]).unwrap().slope_se.is_none());
    }

    /// The standard error predicts the scatter of the slope over many noisy repetitions
    /// (for n = 10 equally spaced points: se = sigma / sqrt(S_tt)).
    #[test]
    fn standard_error_matches_monte_carlo_scatter() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let noise = Normal::new(0.0, 0.1).unwrap();
        let n = 10;
        let reps = 4000;
        let mut slopes = Vec::new();
        let mut se2 = 0.0;
        for _ in 0..reps {
            let pts: Vec<(f64, f64)> = (0..n)
                .map(|i| (i as f64, 2.0 * i as f64 + noise.sample(&mut rng)))
                .collect();
            let f = fit_line(&pts).unwrap();
            slopes.push(f.slope);
            se2 += f.slope_se.unwrap().powi(2);
        }
        let mean = slopes.iter().sum::<f64>() / reps as f64;
        let sd =
            (slopes.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (reps - 1) as f64).sqrt();
        let stt: f64 = (0..n).map(|i| (i as f64 - 4.5).powi(2)).sum();
        let exact = 0.1 / stt.sqrt();
        // 4000 repetitions: the sample sd is within ~3 % of the truth (1/sqrt(2*4000) = 1.1 %, three sigma).
        assert!((sd / exact - 1.0).abs() < 0.035, "sd {sd} vs {exact}");
        assert!(((se2 / reps as f64).sqrt() / exact - 1.0).abs() < 0.035);
        assert!((mean - 2.0).abs() < 4.0 * exact / (reps as f64).sqrt());
    }
}
