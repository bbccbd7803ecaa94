//! r_trans(u) per start shape: the columns of [`crate::simulated::threshold`] interpolated in the velocity u, with the bracket at any velocity.

use crate::simulated::threshold::Threshold;

/// r_trans at one velocity with its uncertainty interval, um.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bracket {
    pub r_trans_um: f64,
    /// Lower and upper end of the uncertainty interval (`lo <= r_trans <= hi`).
    pub lo_um: f64,
    pub hi_um: f64,
    /// The velocity lies outside the simulated range (the nearest column was used).
    pub extrapolated: bool,
}

/// r_trans(u) of one start shape: its columns, sorted by velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct ThresholdCurve {
    nodes: Vec<Threshold>,
}

/// Linear interpolation that stays infinite when either end is infinite.
fn lerp(a: f64, b: f64, w: f64) -> f64 {
    if a.is_infinite() || b.is_infinite() {
        f64::INFINITY
    } else {
        a + w * (b - a)
    }
}

impl ThresholdCurve {
    /// The curve of `start_shape` from [`thresholds`](crate::simulated::threshold::thresholds) output; `None` if it has no column.
    pub fn new(thresholds: &[Threshold], start_shape: &str) -> Option<ThresholdCurve> {
        let mut nodes: Vec<Threshold> = thresholds.iter().filter(|t| t.start_shape == start_shape).cloned().collect();
        if nodes.is_empty() {
            return None;
        }
        nodes.sort_by(|a, b| a.velocity_mm_s.total_cmp(&b.velocity_mm_s));
        Some(ThresholdCurve { nodes })
    }

    /// The columns, by increasing velocity.
    pub fn nodes(&self) -> &[Threshold] {
        &self.nodes
    }

    /// r_trans at velocity `u` (mm/s) with its bracket.
    ///
    /// Between two columns `u_i <= u <= u_{i+1}` with weight `w = (u - u_i) / (u_{i+1} - u_i)`:
    /// - both r_trans finite: linear interpolation of r_trans and of both interval ends;
    /// - one of them infinite (the edge of the croissant-only window lies somewhere
    ///   between the columns): r_trans of the nearer column (the finite one at
    ///   `w = 1/2`), interval from the smaller of the two lower ends to `inf`;
    /// - both infinite: `inf`, lower end interpolated.
    ///
    /// Outside the simulated range the nearest column is used (`extrapolated`).
    pub fn at(&self, u: f64) -> Bracket {
        let n = &self.nodes;
        let node = |t: &Threshold, extrapolated: bool| {
            let (lo, hi) = t.interval();
            Bracket { r_trans_um: t.r_trans_um, lo_um: lo, hi_um: hi, extrapolated }
        };
        if u <= n[0].velocity_mm_s {
            return node(&n[0], u < n[0].velocity_mm_s);
        }
        let last = &n[n.len() - 1];
        if u >= last.velocity_mm_s {
            return node(last, u > last.velocity_mm_s);
        }
        let i = n.partition_point(|t| t.velocity_mm_s <= u) - 1;
        let (a, b) = (&n[i], &n[i + 1]);
        if u == a.velocity_mm_s {
            return node(a, false);
        }
        let w = (u - a.velocity_mm_s) / (b.velocity_mm_s - a.velocity_mm_s);
        let ((alo, ahi), (blo, bhi)) = (a.interval(), b.interval());
        match (a.r_trans_um.is_infinite(), b.r_trans_um.is_infinite()) {
            (false, false) => Bracket {
                r_trans_um: lerp(a.r_trans_um, b.r_trans_um, w),
                lo_um: lerp(alo, blo, w),
                hi_um: lerp(ahi, bhi, w),
                extrapolated: false,
            },
            (true, true) => Bracket { r_trans_um: f64::INFINITY, lo_um: alo + w * (blo - alo), hi_um: f64::INFINITY, extrapolated: false },
            (a_inf, _) => {
                let nearer_a = if a_inf { w < 0.5 } else { w <= 0.5 };
                let r = if nearer_a { a.r_trans_um } else { b.r_trans_um };
                Bracket { r_trans_um: r, lo_um: alo.min(blo), hi_um: f64::INFINITY, extrapolated: false }
            }
        }
    }

    /// The widest interval of r_trans over the velocities `[u_lo, u_hi]` (mm/s):
    /// the smallest lower end and the largest upper end at both ends and at every
    /// column inside (the bracket is piecewise linear between columns, so its
    /// extremes lie there). Returns `(lo, hi)`, um.
    pub fn interval_over(&self, u_lo: f64, u_hi: f64) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let inside = self.nodes.iter().map(|t| t.velocity_mm_s).filter(|&v| v > u_lo && v < u_hi);
        for u in [u_lo, u_hi].into_iter().chain(inside) {
            let b = self.at(u);
            lo = lo.min(b.lo_um);
            hi = hi.max(b.hi_um);
            // nodes inside: the nearest-column rule can switch r_trans there, include both sides' values
            lo = lo.min(b.r_trans_um);
            hi = hi.max(b.r_trans_um);
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn th(u: f64, r: f64, lo: f64, hi: f64) -> Threshold {
        Threshold { start_shape: "discocyte".into(), velocity_mm_s: u, r_trans_um: r, r_lo_um: lo, r_hi_um: hi, n_croissant: 1, n_slipper: 1 }
    }

    #[test]
    fn interpolation_cases() {
        let c = ThresholdCurve::new(
            &[th(1.0, 0.5, 0.4, 0.6), th(2.0, 1.5, 1.4, 1.6), th(2.5, f64::INFINITY, 2.0, f64::INFINITY), th(3.0, f64::INFINITY, 2.2, f64::INFINITY), th(4.0, 1.0, 0.9, 1.1)],
            "discocyte",
        )
        .unwrap();
        // linear between finite columns
        let b = c.at(1.25);
        assert!((b.r_trans_um - 0.75).abs() < 1e-12 && (b.lo_um - 0.65).abs() < 1e-12 && (b.hi_um - 0.85).abs() < 1e-12, "{b:?}");
        // at a column: its own values
        assert_eq!(c.at(2.0), Bracket { r_trans_um: 1.5, lo_um: 1.4, hi_um: 1.6, extrapolated: false });
        // finite -> inf: nearest column, interval [min lo, inf]
        let b = c.at(2.2);
        assert_eq!((b.r_trans_um, b.lo_um, b.hi_um), (1.5, 1.4, f64::INFINITY));
        let b = c.at(2.3);
        assert_eq!((b.r_trans_um, b.lo_um, b.hi_um), (f64::INFINITY, 1.4, f64::INFINITY));
        // midpoint rule: finite wins at w = 1/2
        assert_eq!(c.at(2.25).r_trans_um, 1.5);
        assert_eq!(c.at(3.5).r_trans_um, 1.0);
        // inf -> inf
        let b = c.at(2.75);
        assert_eq!(b.r_trans_um, f64::INFINITY);
        assert!((b.lo_um - 2.1).abs() < 1e-12);
        // clamped outside
        assert_eq!(c.at(0.5), Bracket { r_trans_um: 0.5, lo_um: 0.4, hi_um: 0.6, extrapolated: true });
        assert!(c.at(9.0).extrapolated && c.at(9.0).r_trans_um == 1.0);
        // interval over a velocity range spanning a column
        let (lo, hi) = c.interval_over(1.0, 2.0);
        assert_eq!((lo, hi), (0.4, 1.6));
        let (lo, hi) = c.interval_over(1.9, 2.4);
        assert!((lo - 1.3).abs() < 1e-12 && hi == f64::INFINITY, "{lo} {hi}");
    }
}
