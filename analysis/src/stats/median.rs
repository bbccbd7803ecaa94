//! Medians of samples: the crate's two even-length conventions, each in one place.
//!
//! For `n` values sorted into `s_0 <= ... <= s_{n-1}`:
//! - [`median`]: $s_{(n-1)/2}$ for odd `n`, $\tfrac12 (s_{n/2-1} + s_{n/2})$ for even `n`
//!   (MATLAB's and NumPy's `median`; the statistic the paper's tables use).
//! - [`upper_median`]: $s_{\lfloor n/2 \rfloor}$ for every `n`, the upper of the two middle
//!   values when `n` is even: always one of the samples, never an average of two.
//!
//! Both order by [`f64::total_cmp`], so NaN is a value like any other (a positive NaN above
//! `+inf`, a negative NaN below `-inf`) and `-0.0` sorts below `0.0`; the result is then the
//! value `sort_by(f64::total_cmp)` would put in the middle, to the bit. Both reorder `values`
//! (selection in O(n), the order afterwards unspecified) and return `None` for an empty slice.

/// Median, the mean of the two middle values for even length (module doc); `None` when
/// `values` is empty. Reorders `values`.
pub fn median(values: &mut [f64]) -> Option<f64> {
    let n = values.len();
    if n == 0 {
        return None;
    }
    let (lower, &mut upper, _) = values.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        return Some(upper);
    }
    // `lower` holds the n/2 values at or below the middle: its greatest is s_{n/2-1}
    let below = *lower.iter().max_by(|a, b| a.total_cmp(b)).expect("n >= 2");
    Some(0.5 * (below + upper))
}

/// Median, the upper of the two middle values for even length (module doc); `None` when
/// `values` is empty. Reorders `values`.
pub fn upper_median(values: &mut [f64]) -> Option<f64> {
    let n = values.len();
    if n == 0 {
        return None;
    }
    Some(*values.select_nth_unstable_by(n / 2, f64::total_cmp).1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odd_length_is_the_middle_value_for_both() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(upper_median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut [7.5]), Some(7.5));
        assert_eq!(upper_median(&mut [7.5]), Some(7.5));
        assert_eq!(median(&mut [5.0, -1.0, 4.0, 0.0, 9.0]), Some(4.0));
        assert_eq!(upper_median(&mut [5.0, -1.0, 4.0, 0.0, 9.0]), Some(4.0));
    }

    #[test]
    fn even_length_mean_of_middle_or_upper_middle() {
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(upper_median(&mut [4.0, 1.0, 3.0, 2.0]), Some(3.0));
        assert_eq!(median(&mut [1.0, 0.0]), Some(0.5));
        assert_eq!(median(&mut [0.0, 1.0]), Some(0.5));
        assert_eq!(upper_median(&mut [1.0, 0.0]), Some(1.0));
        // repeated middle values
        assert_eq!(median(&mut [2.0, 9.0, 2.0, -3.0]), Some(2.0));
        assert_eq!(upper_median(&mut [2.0, 9.0, 2.0, -3.0]), Some(2.0));
    }

    #[test]
    fn empty_is_none() {
        assert_eq!(median(&mut []), None);
        assert_eq!(upper_median(&mut []), None);
    }

    #[test]
    fn nan_and_signed_zero_order_by_total_cmp() {
        // a positive NaN sorts above +inf: [1, 2, NaN]
        assert_eq!(median(&mut [f64::NAN, 1.0, 2.0]), Some(2.0));
        assert_eq!(upper_median(&mut [f64::NAN, 1.0, 2.0]), Some(2.0));
        // [1, 2, 3, NaN]: the upper middle is 3; the mean of 2 and 3 is 2.5
        assert_eq!(median(&mut [3.0, f64::NAN, 1.0, 2.0]), Some(2.5));
        assert_eq!(upper_median(&mut [3.0, f64::NAN, 1.0, 2.0]), Some(3.0));
        // [1, NaN]: the middle pair holds the NaN
        assert!(median(&mut [f64::NAN, 1.0]).unwrap().is_nan());
        assert!(upper_median(&mut [f64::NAN, 1.0]).unwrap().is_nan());
        // a negative NaN sorts below -inf: [-NaN, 5, 6]
        assert_eq!(median(&mut [6.0, -f64::NAN, 5.0]), Some(5.0));
        // -0.0 < 0.0: the upper middle of [-0.0, 0.0] is +0.0, the lower -0.0
        let up = upper_median(&mut [0.0, -0.0]).unwrap();
        assert!(up == 0.0 && up.is_sign_positive());
        let up = upper_median(&mut [-0.0, 0.0, -0.0]).unwrap();
        assert!(up == 0.0 && up.is_sign_negative());
    }

    /// The selection gives, to the bit, what sorting by `total_cmp` and taking the middle gave
    /// (the former copies sorted): seeded random samples with ties, signed zeros and NaNs.
    #[test]
    fn equals_the_sorted_middle_to_the_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(24);
        for n in 1..=40 {
            for _ in 0..50 {
                let v: Vec<f64> = (0..n)
                    .map(|_| match rng.random_range(0..10) {
                        0 => f64::NAN,
                        1 => -0.0,
                        2 => 0.0,
                        3 => rng.random_range(0..4) as f64,
                        _ => rng.random_range(-1e3..1e3),
                    })
                    .collect();
                let mut s = v.clone();
                s.sort_by(f64::total_cmp);
                let mean = if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) };
                assert_eq!(median(&mut v.clone()).unwrap().to_bits(), mean.to_bits(), "{v:?}");
                assert_eq!(upper_median(&mut v.clone()).unwrap().to_bits(), s[n / 2].to_bits(), "{v:?}");
            }
        }
    }
}
