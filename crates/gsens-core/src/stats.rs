//! Order statistics of samples: the median and the sample quantile every crate uses.
//!
//! All of them work in place on a `&mut [f64]` (the slice is reordered by
//! `select_nth_unstable_by`, O(n) on average), so they need no allocation and
//! stay available without `std`. The order is [`f64::total_cmp`]: a positive
//! NaN sorts above +∞ and a negative NaN below −∞, so a NaN among the values
//! takes a rank like any other value and the result is NaN exactly when one
//! of the values it is made of is NaN. Callers that want NaNs ignored filter
//! them out first. An empty slice gives NaN.

/// The value of rank `rank` (0-based) among `values` in [`f64::total_cmp`]
/// order: the `rank + 1`-th smallest. NaN when `rank >= values.len()`.
/// Reorders `values`.
pub fn order_statistic_in_place(values: &mut [f64], rank: usize) -> f64 {
    if rank >= values.len() {
        return f64::NAN;
    }
    *values.select_nth_unstable_by(rank, f64::total_cmp).1
}

/// The sample median of `values`: for n values sorted x₍₀₎ ≤ … ≤ x₍ₙ₋₁₎,
/// x₍ₙ/₂₎ when n is odd and ½(x₍ₙ/₂₋₁₎ + x₍ₙ/₂₎) when n is even (the usual
/// definition, e.g. Hyndman & Fan 1996, definition 7 at p = ½). NaN when
/// `values` is empty. Reorders `values`.
pub fn median_in_place(values: &mut [f64]) -> f64 {
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    let m = n / 2;
    let (lower, upper_middle, _) = values.select_nth_unstable_by(m, f64::total_cmp);
    let upper_middle = *upper_middle;
    if n % 2 == 1 {
        return upper_middle;
    }
    // Everything below rank m is in `lower`: its largest is the value of rank m − 1.
    let lower_middle = lower.iter().copied().max_by(f64::total_cmp).unwrap_or(upper_middle);
    0.5 * (lower_middle + upper_middle)
}

/// The high median of `values`: x₍ₙ/₂₎ of the sorted values, the upper of
/// the two middle ones when n is even (Python's `statistics.median_high`).
/// Always one of the values, which the estimate of a typical sampling step
/// relies on. NaN when `values` is empty. Reorders `values`.
pub fn median_high_in_place(values: &mut [f64]) -> f64 {
    order_statistic_in_place(values, values.len() / 2)
}

/// The low median of `values`: x₍₍ₙ₋₁₎/₂₎ of the sorted values, the lower of
/// the two middle ones when n is even (Python's `statistics.median_low`).
/// NaN when `values` is empty. Reorders `values`.
pub fn median_low_in_place(values: &mut [f64]) -> f64 {
    order_statistic_in_place(values, values.len().saturating_sub(1) / 2)
}

/// The sample `q`-quantile of `values` without interpolation: x₍ₖ₎ of the
/// sorted values with k = min(⌊q·n⌋, n − 1), so q = ½ is
/// [`median_high_in_place`] and q = 0.1 the value of rank ⌊n/10⌋. `q` is
/// clamped to [0, 1]. NaN when `values` is empty or `q` is NaN. Reorders
/// `values`.
pub fn quantile_in_place(values: &mut [f64], q: f64) -> f64 {
    let n = values.len();
    if n == 0 || q.is_nan() {
        return f64::NAN;
    }
    // ⌊q·n⌋ by truncation (q·n ≥ 0), so no libm floor is needed.
    let rank = ((q.clamp(0.0, 1.0) * n as f64) as usize).min(n - 1);
    order_statistic_in_place(values, rank)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty_samples() {
        assert_eq!(median_in_place(&mut [3.0, 1.0, 2.0]), 2.0);
        // Even: the mean of the two middle values, 2 and 3.
        assert_eq!(median_in_place(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median_in_place(&mut [7.0]), 7.0);
        assert_eq!(median_in_place(&mut [-1.0, 5.0]), 2.0);
        // Ties and a repeated middle.
        assert_eq!(median_in_place(&mut [1.0, 2.0, 2.0, 9.0]), 2.0);
        assert!(median_in_place(&mut []).is_nan());
    }

    #[test]
    fn high_and_low_medians_pick_one_of_the_middle_values() {
        let v = [4.0, 1.0, 3.0, 2.0];
        let (mut a, mut b) = (v, v);
        assert_eq!(median_high_in_place(&mut a), 3.0);
        assert_eq!(median_low_in_place(&mut b), 2.0);
        assert_eq!(median_high_in_place(&mut [5.0, 9.0, 1.0]), 5.0);
        assert_eq!(median_low_in_place(&mut [5.0, 9.0, 1.0]), 5.0);
        assert!(median_high_in_place(&mut []).is_nan());
        assert!(median_low_in_place(&mut []).is_nan());
    }

    #[test]
    fn quantile_takes_the_value_of_rank_floor_q_n() {
        // Sorted: 10 20 … 200 (20 values); ⌊0.1·20⌋ = 2 → 30.
        let mut v: Vec<f64> = (1..=20).rev().map(|k| 10.0 * k as f64).collect();
        assert_eq!(quantile_in_place(&mut v, 0.1), 30.0);
        assert_eq!(quantile_in_place(&mut v, 0.0), 10.0);
        assert_eq!(quantile_in_place(&mut v, 1.0), 200.0);
        assert_eq!(quantile_in_place(&mut v, 0.5), 110.0);
        // Nine values: ⌊0.9⌋ = 0 → the smallest.
        assert_eq!(quantile_in_place(&mut [9.0, 8.0, 7.0, 6.0, 5.0, 4.0, 3.0, 2.0, 1.0], 0.1), 1.0);
        assert!(quantile_in_place(&mut [], 0.5).is_nan());
        assert!(quantile_in_place(&mut [1.0], f64::NAN).is_nan());
    }

    #[test]
    fn quantile_at_a_tenth_is_the_rank_n_over_ten_for_every_length() {
        for n in 1..2000usize {
            let mut v: Vec<f64> = (0..n).map(|k| ((k * 7919) % n) as f64).collect();
            assert_eq!(quantile_in_place(&mut v, 0.1), (n / 10) as f64, "n = {n}");
        }
    }

    #[test]
    fn nan_takes_its_total_order_rank() {
        // A positive NaN sorts last: the median of [1, 2, NaN] is 2, of [1, NaN] NaN.
        assert_eq!(median_in_place(&mut [f64::NAN, 1.0, 2.0]), 2.0);
        assert!(median_in_place(&mut [1.0, f64::NAN]).is_nan());
        // A negative NaN sorts first.
        assert_eq!(median_in_place(&mut [-f64::NAN, 1.0, 2.0]), 1.0);
        assert!(order_statistic_in_place(&mut [3.0, 1.0], 2).is_nan());
    }
}
