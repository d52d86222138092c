//! Plain statistics over samples: median, mean, sample standard deviation, the distribution-free 95% interval of
//! a median (order statistics, as the sign test gives it) and a percentile-bootstrap 95% interval of a ratio of
//! two independent medians. Deterministic: the bootstrap takes a seed. No interval below
//! [`MIN_SAMPLES_FOR_INTERVAL`] samples (docs/statistics.md, "The interval").

use tracer::rng::SplitMix64;

/// Bootstrap resamples per interval.
pub const RESAMPLES: usize = 2000;
/// Two-sided coverage of the intervals.
pub const LEVEL: f64 = 0.95;
/// Mixed into every bootstrap seed, so report seeds differ from scene seeds.
const SEED_BASE: u64 = 0x6276_686C_6162_2D72; // "bvhlab-r"

/// A value with its 95% interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The point estimate.
    pub value: f64,
    /// Lower end of the interval.
    pub lo: f64,
    /// Upper end of the interval.
    pub hi: f64,
}

/// Median (mean of the two middle values for even counts); NaN for no samples.
pub fn median(samples: &[f64]) -> f64 {
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    median_of_sorted(&sorted)
}

fn median_of_sorted(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => sorted[n / 2],
        _ => (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0,
    }
}

/// Arithmetic mean; NaN for no samples.
#[allow(dead_code)] // the reference polars' aggregates are tested against (summary.rs)
pub fn mean(samples: &[f64]) -> f64 {
    samples.iter().sum::<f64>() / samples.len() as f64
}

/// Sample standard deviation (divisor n-1); 0 for fewer than two samples.
#[allow(dead_code)] // the reference polars' aggregates are tested against (summary.rs)
pub fn std_dev(samples: &[f64]) -> f64 {
    if samples.len() < 2 {
        return 0.0;
    }
    let m = mean(samples);
    let ss: f64 = samples.iter().map(|x| (x - m) * (x - m)).sum();
    (ss / (samples.len() - 1) as f64).sqrt()
}

/// Quantile `p` in [0, 1] of sorted values, linearly interpolated between order statistics.
pub fn quantile_of_sorted(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = p.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let below = pos.floor() as usize;
    let above = pos.ceil() as usize;
    sorted[below] + (sorted[above] - sorted[below]) * (pos - below as f64)
}

/// FNV-1a hash of a string: a stable way to turn a key (a config id, a point) into a seed.
pub fn hash_str(key: &str) -> u64 {
    key.bytes().fold(0xCBF2_9CE4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01B3))
}

/// The bootstrap seed for a key: a fixed constant xor the key's hash.
pub fn seed_for(key: &str) -> u64 {
    SEED_BASE ^ hash_str(key)
}

/// Median of one resample (with replacement) of `samples`, using `scratch` as buffer.
pub(crate) fn resampled_median(samples: &[f64], rng: &mut SplitMix64, scratch: &mut Vec<f64>) -> f64 {
    scratch.clear();
    scratch.extend((0..samples.len()).map(|_| samples[rng.below(samples.len() as u64) as usize]));
    scratch.sort_by(f64::total_cmp);
    median_of_sorted(scratch)
}

/// The percentile interval of bootstrap replicates.
pub(crate) fn percentile_interval(mut replicates: Vec<f64>) -> (f64, f64) {
    replicates.sort_by(f64::total_cmp);
    let tail = (1.0 - LEVEL) / 2.0;
    (quantile_of_sorted(&replicates, tail), quantile_of_sorted(&replicates, 1.0 - tail))
}

/// The samples in ascending order: resampling sorted samples makes an interval depend on the
/// multiset of samples only, not on the order the rows came in.
pub(crate) fn sorted(samples: &[f64]) -> Vec<f64> {
    let mut sorted = samples.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted
}

/// The smallest number of samples with a distribution-free 95% interval of their median: with five, even the
/// whole range `[min, max]` holds the median only with probability 1 - 2/2^5 = 93.75%.
pub const MIN_SAMPLES_FOR_INTERVAL: usize = 6;

/// The ranks `k` and `n + 1 - k` (1-based) of the order statistics that bound the median's 95% interval of `n`
/// samples: `k` is the largest rank with `P(Binomial(n, 1/2) < k) <= 2.5%`; `None` below
/// [`MIN_SAMPLES_FOR_INTERVAL`].
pub fn median_interval_ranks(n: usize) -> Option<(usize, usize)> {
    let tail = (1.0 - LEVEL) / 2.0;
    // P(X <= j) summed term by term, ln P(X = j) = ln C(n, j) - n ln 2: one pass, no overflow for large n.
    let (mut k, mut cdf, mut ln_term) = (0, 0.0, -(n as f64) * std::f64::consts::LN_2);
    while k < n {
        cdf += ln_term.exp();
        if cdf > tail {
            break;
        }
        ln_term += ((n - k) as f64 / (k + 1) as f64).ln();
        k += 1;
    }
    (k >= 1).then_some((k, n + 1 - k))
}

/// The median with its distribution-free 95% interval `[x(k), x(n+1-k)]` ([`median_interval_ranks`]): coverage
/// of at least 95% whatever the samples' distribution, where a bootstrap of the median covers far less with few
/// samples (87% with four, 92-93% with six to ten, docs/statistics.md). Below [`MIN_SAMPLES_FOR_INTERVAL`]
/// samples the interval is NaN: no verdict rests on it.
pub fn median_ci(samples: &[f64]) -> Estimate {
    let sorted = sorted(samples);
    let value = median_of_sorted(&sorted);
    match median_interval_ranks(sorted.len()) {
        Some((k, upper)) => Estimate { value, lo: sorted[k - 1], hi: sorted[upper - 1] },
        None => Estimate { value, lo: f64::NAN, hi: f64::NAN },
    }
}

/// `median(numerator) / median(denominator)` of two independent sample sets with a 95% bootstrap interval, both
/// sets resampled independently; `seed` fixes the resamples. NaN interval when either set has fewer than
/// [`MIN_SAMPLES_FOR_INTERVAL`] samples.
pub fn ratio_ci(numerator: &[f64], denominator: &[f64], seed: u64) -> Estimate {
    let (numerator, denominator) = (&sorted(numerator)[..], &sorted(denominator)[..]);
    let value = median(numerator) / median(denominator);
    if numerator.len().min(denominator.len()) < MIN_SAMPLES_FOR_INTERVAL {
        return Estimate { value, lo: f64::NAN, hi: f64::NAN };
    }
    let mut rng = SplitMix64::new(seed);
    let mut scratch = Vec::with_capacity(numerator.len().max(denominator.len()));
    let replicates = (0..RESAMPLES)
        .map(|_| {
            let num = resampled_median(numerator, &mut rng, &mut scratch);
            let den = resampled_median(denominator, &mut rng, &mut scratch);
            num / den
        })
        .collect();
    let (lo, hi) = percentile_interval(replicates);
    Estimate { value, lo, hi }
}

/// The median of paired ratios timed in several processes, with a 95% interval that resamples processes, not
/// ratios: `clusters[i]` names the process (pair) that timed `ratios[i]`. Runs of one process share its offset
/// (where its memory happened to lie), so its ratios are not independent draws; a cluster bootstrap draws whole
/// processes with replacement and takes the median of their pooled ratios. NaN interval below
/// [`MIN_SAMPLES_FOR_INTERVAL`] processes; `seed` fixes the resamples.
pub fn clustered_ratio_ci(ratios: &[f64], clusters: &[u64], seed: u64) -> Estimate {
    assert_eq!(ratios.len(), clusters.len(), "every ratio names its process");
    let value = median(ratios);
    let mut groups: std::collections::BTreeMap<u64, Vec<f64>> = std::collections::BTreeMap::new();
    for (&r, &c) in ratios.iter().zip(clusters) {
        groups.entry(c).or_default().push(r);
    }
    let groups: Vec<Vec<f64>> = groups.into_values().map(|g| sorted(&g)).collect();
    if groups.len() < MIN_SAMPLES_FOR_INTERVAL {
        return Estimate { value, lo: f64::NAN, hi: f64::NAN };
    }
    let mut rng = SplitMix64::new(seed);
    let mut pooled = Vec::with_capacity(ratios.len() * 2);
    let replicates = (0..RESAMPLES)
        .map(|_| {
            pooled.clear();
            for _ in 0..groups.len() {
                pooled.extend_from_slice(&groups[rng.below(groups.len() as u64) as usize]);
            }
            pooled.sort_by(f64::total_cmp);
            median_of_sorted(&pooled)
        })
        .collect();
    let (lo, hi) = percentile_interval(replicates);
    Estimate { value, lo, hi }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clustered_interval_carries_the_offset_between_processes() {
        // Eight processes, each with its own offset of up to ±3%, each timing five rounds with ±0.1% noise: the
        // rounds alone look precise, the processes say how far apart two of them can sit.
        let offsets = [0.97, 1.03, 0.99, 1.02, 0.98, 1.01, 1.0, 1.025];
        let (mut ratios, mut clusters) = (Vec::new(), Vec::new());
        for (p, offset) in offsets.iter().enumerate() {
            for round in 0..5 {
                ratios.push(offset * (1.0 + 0.001 * (round as f64 - 2.0)));
                clusters.push(p as u64);
            }
        }
        let rounds = median_ci(&ratios);
        let processes = clustered_ratio_ci(&ratios, &clusters, 7);
        assert!(processes.lo < rounds.lo && processes.hi > rounds.hi, "{processes:?} vs {rounds:?}");
        assert!(processes.lo < processes.value && processes.value < processes.hi, "{processes:?}");
        assert!(processes.lo >= 0.97 && processes.hi <= 1.03, "{processes:?}");
        // Fewer than six processes give no interval.
        let few: Vec<u64> = clusters.iter().map(|c| c % 5).collect();
        assert!(clustered_ratio_ci(&ratios, &few, 7).lo.is_nan());
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&[7.0]), 7.0);
        assert!(median(&[]).is_nan());
    }

    #[test]
    fn mean_and_sample_std() {
        let xs = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
        assert_eq!(mean(&xs), 5.0);
        // Sum of squared deviations is 32; the sample variance divides by n-1 = 7.
        assert!((std_dev(&xs) - (32.0f64 / 7.0).sqrt()).abs() < 1e-15);
        assert_eq!(std_dev(&[1.0, 3.0]), 2.0f64.sqrt());
        assert_eq!(std_dev(&[5.0]), 0.0);
    }

    #[test]
    fn quantiles_interpolate() {
        let xs = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(quantile_of_sorted(&xs, 0.0), 1.0);
        assert_eq!(quantile_of_sorted(&xs, 0.5), 3.0);
        assert_eq!(quantile_of_sorted(&xs, 0.125), 1.5);
        assert_eq!(quantile_of_sorted(&xs, 1.0), 5.0);
    }

    #[test]
    fn the_median_interval_is_bounded_by_order_statistics() {
        // Known ranks (sign-test tables): n = 6 gives the range (coverage 96.9%), n = 9 [x2, x8], n = 10 [x2, x9],
        // n = 20 [x6, x15], n = 50 [x18, x33].
        assert_eq!(median_interval_ranks(5), None);
        assert_eq!(median_interval_ranks(6), Some((1, 6)));
        assert_eq!(median_interval_ranks(9), Some((2, 8)));
        assert_eq!(median_interval_ranks(10), Some((2, 9)));
        assert_eq!(median_interval_ranks(20), Some((6, 15)));
        assert_eq!(median_interval_ranks(50), Some((18, 33)));
        let xs = [1.0, 1.2, 0.9, 1.1, 1.05, 0.95, 1.3, 1.0, 0.98, 1.01];
        let a = median_ci(&xs);
        assert_eq!((a.value, a.lo, a.hi), (1.005, 0.95, 1.2));
        // The order of the samples does not matter.
        let mut reversed = xs;
        reversed.reverse();
        assert_eq!(a, median_ci(&reversed));
    }

    #[test]
    fn the_interval_covers_the_median_at_least_95_percent_of_the_time() {
        // Skewed samples (exponential): 4000 draws of n samples; the interval holds the true median ln 2 in at
        // least 95% of them (the exact coverage of the ranks, minus sampling error), where a percentile bootstrap
        // of the median held it 87% of the time with four samples and 92-93% with six to ten.
        let mut rng = SplitMix64::new(7);
        for n in [6, 7, 10, 20] {
            let held = (0..4000)
                .filter(|_| {
                    let xs: Vec<f64> = (0..n).map(|_| -(1.0 - rng.next_f64()).ln()).collect();
                    let e = median_ci(&xs);
                    e.lo <= std::f64::consts::LN_2 && std::f64::consts::LN_2 <= e.hi
                })
                .count();
            assert!(held as f64 / 4000.0 >= 0.94, "n {n}: {held} of 4000");
        }
    }

    #[test]
    fn fewer_than_six_samples_give_no_interval() {
        for n in 1..MIN_SAMPLES_FOR_INTERVAL {
            let xs: Vec<f64> = (0..n).map(|i| i as f64).collect();
            let e = median_ci(&xs);
            assert_eq!(e.value, median(&xs));
            assert!(e.lo.is_nan() && e.hi.is_nan(), "n {n}: {e:?}");
        }
        let r = ratio_ci(&[3.0; 5], &[1.5; 6], 17);
        assert_eq!(r.value, 2.0);
        assert!(r.lo.is_nan() && r.hi.is_nan(), "{r:?}");
    }

    #[test]
    fn ratio_interval_brackets_the_ratio_of_medians() {
        let num = [10.0, 11.0, 12.0, 10.5, 11.5, 11.2];
        let den = [2.0, 2.2, 1.8, 2.1, 1.9, 2.05];
        let r = ratio_ci(&num, &den, 99);
        assert_eq!(r.value, median(&num) / median(&den));
        assert!(r.lo < r.value && r.value < r.hi, "{r:?}");
        // No resample can leave the range min/max .. max/min.
        assert!(r.lo >= 10.0 / 2.2 && r.hi <= 12.0 / 1.8, "{r:?}");
        assert_eq!(r, ratio_ci(&num, &den, 99));
    }

    #[test]
    fn paired_ratios_cancel_what_both_sides_of_a_round_share() {
        // Each round slows both series alike (1x, 1.5x, 2x ...): independently the interval spans the slowdowns,
        // paired it is the constant ratio 1.1 exactly.
        let rounds = [1.0, 1.5, 2.0, 1.2, 3.0, 1.1, 1.7];
        let den: Vec<f64> = rounds.to_vec();
        let num: Vec<f64> = rounds.iter().map(|r| r * 1.1).collect();
        let paired_ratio_ci =
            |n: &[f64], d: &[f64]| median_ci(&n.iter().zip(d).map(|(n, d)| n / d).collect::<Vec<_>>());
        let paired = paired_ratio_ci(&num, &den);
        assert!((paired.value - 1.1).abs() < 1e-12 && (paired.hi - paired.lo) < 1e-12, "{paired:?}");
        let independent = ratio_ci(&num, &den, 5);
        assert!(independent.hi - independent.lo > 0.5, "{independent:?}");
        // A ratio that varies from round to round gets an interval around the median ratio.
        let noisy: Vec<f64> = den.iter().zip([1.0, 1.2, 0.9, 1.1, 1.05, 0.95, 1.3]).map(|(d, r)| d * r).collect();
        let e = paired_ratio_ci(&noisy, &den);
        assert!((e.value - 1.05).abs() < 1e-12);
        assert!(e.lo < e.value && e.value < e.hi && e.lo >= 0.9 - 1e-12 && e.hi <= 1.3 + 1e-12, "{e:?}");
    }

    #[test]
    fn seeds_depend_on_the_key_only() {
        assert_eq!(seed_for("0123456789abcdef"), seed_for("0123456789abcdef"));
        assert_ne!(seed_for("0123456789abcdef"), seed_for("0123456789abcdee"));
        // FNV-1a of the empty string is its offset basis.
        assert_eq!(hash_str(""), 0xCBF2_9CE4_8422_2325);
    }
}
