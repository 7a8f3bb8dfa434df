//! Ensemble statistics: mean, sample standard deviation, Hyndman–Fan type 7 percentiles and an
//! equal-bin histogram.
//!
//! Used by the migration ensembles, the scenes' per-support statistics and (with
//! [`interval`]'s Wilson score interval) spalling and the scenes' probabilities.

pub mod interval;
pub mod precision;
pub mod quantile;
pub mod rate;

/// Number of histogram bins (api.md: 20 equal bins, 21 edges).
pub const HISTOGRAM_BINS: usize = 20;

/// Histogram with equal bins from the minimum to the maximum.
#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    /// Bin edges (21), in the unit of the data.
    pub edges: Vec<f64>,
    /// Counts per bin (20); the last bin is closed on the right.
    pub counts: Vec<u64>,
}

/// Summary of one quantity over an ensemble, in the unit of the data.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Number of values.
    pub count: u64,
    /// Arithmetic mean.
    pub mean: f64,
    /// Sample standard deviation (N − 1); None for a single value.
    pub std: Option<f64>,
    /// Smallest value.
    pub min: f64,
    /// 5th percentile (type 7).
    pub p05: f64,
    /// Median (type 7).
    pub p50: f64,
    /// 95th percentile (type 7).
    pub p95: f64,
    /// 99th percentile (type 7).
    pub p99: f64,
    /// Largest value.
    pub max: f64,
    /// 20 equal bins from min to max.
    pub histogram: Histogram,
}

/// Percentile of sorted data by linear interpolation between order statistics (Hyndman–Fan
/// type 7): h = (n − 1) p, x[⌊h⌋] + (h − ⌊h⌋)(x[⌊h⌋+1] − x[⌊h⌋]).
///
/// # Special cases
/// Empty data gives NaN; one value gives that value; p is clamped to [0, 1].
///
/// # References
/// Hyndman & Fan (1996), Am. Stat. 50(4), definition 7; api.md "Percentiles".
///
/// # Examples
/// ```
/// use gangue::physics::stats::percentile_sorted;
/// assert_eq!(percentile_sorted(&[1.0, 2.0, 3.0, 4.0], 0.5), 2.5);
/// ```
#[must_use]
pub fn percentile_sorted(sorted: &[f64], p: f64) -> f64 {
    let n = sorted.len();
    if n == 0 {
        return f64::NAN;
    }
    let h = (n - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    if lo + 1 >= n {
        return sorted[n - 1];
    }
    let f = h - lo as f64;
    sorted[lo] + f * (sorted[lo + 1] - sorted[lo])
}

/// Summary of `values` (in their given order for the sums), or None when empty.
///
/// # Special cases
/// One value: std None; equal values: all counts in the first bin, edges all equal.
///
/// # References
/// api.md `POST /v1/migration` (statistics).
#[must_use]
pub fn summarize(values: &[f64]) -> Option<Summary> {
    summarize_owned(values.to_vec())
}

/// [`summarize`] of values the caller no longer needs: they are reordered in place by the
/// percentile selection instead of being copied.
pub(crate) fn summarize_owned(mut work: Vec<f64>) -> Option<Summary> {
    let mut first = FirstPass::default();
    work.iter().for_each(|&x| first.push(x));
    let mut second = first.second_pass()?;
    work.iter().for_each(|&x| second.push(x));
    // the order statistics the percentiles need, found by selection (O(n)) instead of a sort
    let ranks = order_ranks(first.count());
    let mut start = 0;
    for &k in &ranks {
        work[start..].select_nth_unstable_by(k as usize - start, f64::total_cmp);
        start = k as usize + 1;
    }
    let values: Vec<f64> = ranks.iter().map(|&k| work[k as usize]).collect();
    Some(second.finish(&values))
}

/// First streaming pass over a column, in its given (run) order: count, sum, min, max.
///
/// The sum is the left-to-right sum from −0 (that of `Iterator::sum`), so the same values in
/// the same order give the same bits whether they come from memory or from part files.
#[derive(Debug, Clone, Copy)]
pub struct FirstPass {
    n: u64,
    sum: f64,
    min: f64,
    max: f64,
}

impl Default for FirstPass {
    fn default() -> Self {
        Self {
            n: 0,
            sum: -0.0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }
}

impl FirstPass {
    /// Adds the next value.
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        self.sum += x;
        self.min = self.min.min(x);
        self.max = self.max.max(x);
    }

    /// Adds `values` in their order: the same bits as [`FirstPass::push`] of each, with the
    /// running values kept in registers.
    pub fn push_all(&mut self, values: &[f64]) {
        let (mut sum, mut min, mut max) = (self.sum, self.min, self.max);
        for &x in values {
            sum += x;
            min = min.min(x);
            max = max.max(x);
        }
        (self.sum, self.min, self.max) = (sum, min, max);
        self.n += values.len() as u64;
    }

    /// Number of values seen.
    #[must_use]
    pub fn count(&self) -> u64 {
        self.n
    }

    /// The second pass this one sets up (mean, histogram bins), or None for no values.
    #[must_use]
    pub fn second_pass(&self) -> Option<SecondPass> {
        (self.n > 0).then(|| SecondPass {
            n: self.n,
            mean: self.sum / self.n as f64,
            min: self.min,
            max: self.max,
            width: (self.max - self.min) / HISTOGRAM_BINS as f64,
            ss: -0.0,
            counts: [0; HISTOGRAM_BINS],
        })
    }
}

/// The histogram bin of `x` among bins of `width` from `min` (the last bin takes the maximum;
/// one bin when all values are equal).
#[inline]
fn bin(x: f64, min: f64, width: f64) -> usize {
    if width > 0.0 {
        // in [0, HISTOGRAM_BINS] up to rounding; through u32, the same bin as through usize
        // (both saturate, NaN and negatives give 0) with a cheaper conversion
        (((x - min) / width) as u32 as usize).min(HISTOGRAM_BINS - 1)
    } else {
        0
    }
}

/// Second streaming pass over a column, in the same order as the first: the sum of squared
/// deviations from the mean and the histogram counts.
#[derive(Debug, Clone, Copy)]
pub struct SecondPass {
    n: u64,
    mean: f64,
    min: f64,
    max: f64,
    width: f64,
    ss: f64,
    counts: [u64; HISTOGRAM_BINS],
}

impl SecondPass {
    /// Adds the next value (the same sequence as the first pass).
    pub fn push(&mut self, x: f64) {
        self.ss += (x - self.mean) * (x - self.mean);
        self.counts[bin(x, self.min, self.width)] += 1;
    }

    /// Adds `values` in their order: the same bits and counts as [`SecondPass::push`] of
    /// each, with the running sum in a register and the counts in four interleaved tallies (so
    /// that equal neighbours do not wait on each other's count).
    pub fn push_all(&mut self, values: &[f64]) {
        let (mean, min, width) = (self.mean, self.min, self.width);
        let mut ss = self.ss;
        let mut tallies = [[0u64; HISTOGRAM_BINS]; 4];
        let bin = |x: f64| bin(x, min, width);
        let mut quads = values.chunks_exact(4);
        for q in &mut quads {
            for (t, &x) in tallies.iter_mut().zip(q) {
                ss += (x - mean) * (x - mean);
                t[bin(x)] += 1;
            }
        }
        for &x in quads.remainder() {
            ss += (x - mean) * (x - mean);
            tallies[0][bin(x)] += 1;
        }
        self.ss = ss;
        for t in &tallies {
            for (c, k) in self.counts.iter_mut().zip(t) {
                *c += k;
            }
        }
    }

    /// The summary, given the values of the sorted column at the ranks [`order_ranks`] listed
    /// (same length and order).
    #[must_use]
    pub fn finish(&self, order_values: &[f64]) -> Summary {
        let n = self.n as usize;
        let ranks = order_ranks(self.n);
        let at = |k: usize| {
            // order_ranks lists every rank read here: its position is the listed rank's index
            order_values[ranks.partition_point(|&r| r < k as u64)]
        };
        let pct = |p: f64| {
            let h = (n - 1) as f64 * p;
            let lo = h.floor() as usize;
            if lo + 1 >= n {
                return at(n - 1);
            }
            at(lo) + (h - lo as f64) * (at(lo + 1) - at(lo))
        };
        let edges: Vec<f64> = (0..=HISTOGRAM_BINS)
            .map(|k| {
                if k == HISTOGRAM_BINS {
                    self.max
                } else {
                    self.min + k as f64 * self.width
                }
            })
            .collect();
        Summary {
            count: self.n,
            mean: self.mean.clamp(self.min, self.max),
            std: (n > 1).then(|| (self.ss / (n - 1) as f64).sqrt()),
            min: self.min,
            p05: pct(0.05),
            p50: pct(0.50),
            p95: pct(0.95),
            p99: pct(0.99),
            max: self.max,
            histogram: Histogram {
                edges,
                counts: self.counts.to_vec(),
            },
        }
    }
}

/// The key of `x` in the order of `f64::total_cmp`: `order_key(a) < order_key(b)` exactly
/// when `a.total_cmp(&b)` is `Less`, and [`from_order_key`] gives `x` back bit for bit. Keys
/// compare as plain integers, so a selection over them costs one transform per value instead
/// of two per comparison.
#[must_use]
#[inline]
pub fn order_key(x: f64) -> u64 {
    let b = x.to_bits();
    // total_cmp's transform (negative values' magnitude bits flipped), then the sign bit
    // flipped so that the signed order becomes the unsigned one
    (b ^ (((b as i64 >> 63) as u64) >> 1)) ^ (1 << 63)
}

/// The value whose [`order_key`] is `k`.
#[must_use]
#[inline]
pub fn from_order_key(k: u64) -> f64 {
    let t = k ^ (1 << 63);
    f64::from_bits(t ^ (((t as i64 >> 63) as u64) >> 1))
}

/// The values at the 0-based ascending `ranks` (each below `keys.len()`) of a column given by
/// its [`order_key`]s, sorted by `f64::total_cmp`, found by selection; `keys` is reordered. The
/// middle rank is selected first and the ranks on either side within their part only, so a
/// rank next to one already selected (⌊h⌋ + 1 after ⌊h⌋) scans the part between its
/// neighbours, not the whole tail. The value at a rank is unique, so the result does not depend
/// on the order of selection.
///
/// A column of [`BUCKETED_FROM`] values or more, asked for at most [`BUCKETED_RANKS`] ranks, is
/// first counted into buckets of equal key
/// ranges (a key's bucket grows with the key, so every key of a bucket orders before every key of
/// the next); only the buckets holding a listed rank are gathered and selected in, a few
/// percent of the values for a spread column instead of the whole column several times.
#[must_use]
pub fn select_ranks(keys: &mut [u64], ranks: &[u64]) -> Vec<f64> {
    if keys.len() >= BUCKETED_FROM && ranks.len() <= BUCKETED_RANKS {
        return select_by_buckets(keys, ranks);
    }
    select_within(keys, 0, ranks);
    ranks
        .iter()
        .map(|&k| from_order_key(keys[k as usize]))
        .collect()
}

/// Columns from this many values on are selected in by buckets ([`select_ranks`]).
pub const BUCKETED_FROM: usize = 1 << 14;

/// At most this many ranks are selected by buckets ([`select_ranks`]); the order statistics
/// of a summary need nine.
pub const BUCKETED_RANKS: usize = 64;

/// Selects the 0-based ascending `ranks` of `w` (ranks counted from `offset`, the position of
/// `w` in the whole column) in place: the middle rank first, then those on either side within
/// their part.
fn select_within(w: &mut [u64], offset: u64, ranks: &[u64]) {
    let mid = ranks.len() / 2;
    let Some(&k) = ranks.get(mid) else {
        return;
    };
    let (left, _, right) = w.select_nth_unstable((k - offset) as usize);
    select_within(left, offset, &ranks[..mid]);
    select_within(right, k + 1, &ranks[mid + 1..]);
}

/// [`select_ranks`] through buckets: 2¹² buckets of equal key ranges between the least and
/// the greatest key; the ranks' buckets gathered (in key order) and selected in.
fn select_by_buckets(keys: &[u64], ranks: &[u64]) -> Vec<f64> {
    const BITS: u32 = 12;
    let (lo, hi) = keys
        .iter()
        .fold((u64::MAX, u64::MIN), |(lo, hi), &k| (lo.min(k), hi.max(k)));
    // the shift that brings the key range below 2^BITS buckets
    let shift = (u64::BITS - (hi - lo).leading_zeros()).saturating_sub(BITS);
    let bucket = |k: u64| ((k - lo) >> shift) as usize;
    let mut counts = vec![0usize; 1 << BITS];
    for &k in keys {
        counts[bucket(k)] += 1;
    }
    // each rank's bucket and its rank within the bucket; ranks ascend, so buckets do too
    let (mut b, mut below) = (0usize, 0usize);
    let mut at = Vec::with_capacity(ranks.len());
    for &r in ranks {
        let r = r as usize;
        while below + counts[b] <= r {
            below += counts[b];
            b += 1;
        }
        at.push((b, r - below));
    }
    // the parts: one per distinct bucket, in order, gathered in one pass
    let mut slot = vec![u8::MAX; 1 << BITS];
    let mut parts: Vec<Vec<u64>> = Vec::new();
    for &(b, _) in &at {
        if slot[b] == u8::MAX {
            slot[b] = parts.len() as u8;
            parts.push(Vec::with_capacity(counts[b]));
        }
    }
    for &k in keys {
        let s = slot[bucket(k)];
        if s != u8::MAX {
            parts[usize::from(s)].push(k);
        }
    }
    for (i, part) in parts.iter_mut().enumerate() {
        let local: Vec<u64> = at
            .iter()
            .filter(|&&(b, _)| usize::from(slot[b]) == i)
            .map(|&(_, r)| r as u64)
            .collect();
        select_within(part, 0, &local);
    }
    at.iter()
        .map(|&(b, r)| from_order_key(parts[usize::from(slot[b])][r]))
        .collect()
}

/// Percentile levels reported (5th, 50th, 95th, 99th).
pub const PERCENTILES: [f64; 4] = [0.05, 0.50, 0.95, 0.99];

/// The 0-based ranks in the column sorted by `f64::total_cmp` whose values the type-7
/// percentiles of `n` values need (⌊h⌋ and ⌊h⌋ + 1 for each level), ascending, without repeats.
/// Empty for n = 0.
#[must_use]
pub fn order_ranks(n: u64) -> Vec<u64> {
    if n == 0 {
        return Vec::new();
    }
    let mut idx: Vec<u64> = PERCENTILES
        .iter()
        .flat_map(|p| {
            let lo = ((n - 1) as f64 * p).floor() as u64;
            [lo, (lo + 1).min(n - 1)]
        })
        .collect();
    // the last value is needed when ⌊h⌋ + 1 reaches n (the percentile is then the maximum)
    idx.push(n - 1);
    idx.sort_unstable();
    idx.dedup();
    idx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn type7_matches_r_quantile() {
        // R: quantile(c(3, 1, 4, 1, 5, 9, 2, 6), c(.05, .5, .95, .99), type = 7)
        let s = summarize(&[3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0, 6.0]).unwrap();
        assert!((s.p05 - 1.0).abs() < 1e-15);
        assert!((s.p50 - 3.5).abs() < 1e-15);
        assert!((s.p95 - 7.95).abs() < 1e-12);
        assert!((s.p99 - 8.79).abs() < 1e-12);
        assert_eq!(s.mean, 31.0 / 8.0);
        // sample variance: Σ(x − m)² / 7
        let m = 31.0 / 8.0;
        let v: f64 = [3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0, 6.0]
            .iter()
            .map(|x: &f64| (x - m).powi(2))
            .sum::<f64>()
            / 7.0;
        assert!((s.std.unwrap() - v.sqrt()).abs() < 1e-15);
        assert_eq!(s.histogram.counts.iter().sum::<u64>(), 8);
        assert_eq!(s.histogram.edges.len(), 21);
        assert_eq!(s.histogram.counts[0], 2); // 1, 1 in [1, 1.4)
        assert_eq!(s.histogram.counts[19], 1); // 9
    }

    #[test]
    fn selection_equals_sorting() {
        let mut st = 3u64;
        let xs: Vec<f64> = (0..1001)
            .map(|_| {
                st = st
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (st >> 11) as f64
            })
            .collect();
        let s = summarize(&xs).unwrap();
        let mut sorted = xs;
        sorted.sort_by(f64::total_cmp);
        for (p, got) in [(0.05, s.p05), (0.5, s.p50), (0.95, s.p95), (0.99, s.p99)] {
            assert_eq!(got, percentile_sorted(&sorted, p));
        }
        assert_eq!((s.min, s.max), (sorted[0], sorted[1000]));
    }

    #[test]
    fn single_and_constant_values() {
        let s = summarize(&[2.5]).unwrap();
        assert_eq!((s.min, s.p50, s.max, s.std), (2.5, 2.5, 2.5, None));
        let s = summarize(&[1.0, 1.0, 1.0]).unwrap();
        assert_eq!(s.histogram.counts[0], 3);
        assert_eq!(s.std, Some(0.0));
        assert!(summarize(&[]).is_none());
    }

    /// The selected values are those of the column sorted by `total_cmp` (the independent
    /// reference), bit for bit, with repeated values, signed zeros, one value, and ranks at both
    /// ends and next to each other.
    #[test]
    fn selected_ranks_are_those_of_the_sorted_column() {
        let mut state = 7u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            state >> 11
        };
        for n in [1usize, 2, 3, 10, 101, 1000, 4097, BUCKETED_FROM, 40_000] {
            for levels in [1u64, 4, 1000, 1 << 40] {
                let column: Vec<f64> = (0..n)
                    .map(|_| match next() % 5 {
                        0 => 0.0,
                        1 => -0.0,
                        // values over many binades (a heavy tail), beside an even spread
                        2 if levels > 4 => {
                            (next() % levels) as f64 * 2f64.powi((next() % 200) as i32 - 100)
                        }
                        _ => (next() % levels) as f64 - 0.5 * levels as f64,
                    })
                    .collect();
                let mut sorted = column.clone();
                sorted.sort_by(f64::total_cmp);
                let all: Vec<u64> = (0..n as u64).collect();
                let spread: Vec<u64> = (0..n as u64).step_by(n.div_ceil(BUCKETED_RANKS)).collect();
                for ranks in [
                    order_ranks(n as u64),
                    vec![0],
                    vec![n as u64 - 1],
                    spread,
                    all,
                ] {
                    let mut work: Vec<u64> = column.iter().map(|&x| order_key(x)).collect();
                    let got = select_ranks(&mut work, &ranks);
                    let want: Vec<u64> = ranks
                        .iter()
                        .map(|&k| sorted[k as usize].to_bits())
                        .collect();
                    let got: Vec<u64> = got.iter().map(|x| x.to_bits()).collect();
                    assert_eq!(got, want, "n = {n}, ranks {ranks:?}");
                }
            }
        }
    }

    /// The keys order values as `total_cmp` does and give them back bit for bit: every pair of
    /// special values (signed zeros and infinities, NaNs of both signs, subnormals, the extremes)
    /// and of pseudo-random bit patterns.
    #[test]
    fn order_keys_order_as_total_cmp_and_give_the_value_back() {
        let mut xs = vec![
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            -f64::NAN,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            f64::MAX,
            f64::MIN,
            1.0,
            -1.0,
        ];
        let mut state = 11u64;
        for _ in 0..200 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            xs.push(f64::from_bits(state));
        }
        for &a in &xs {
            assert_eq!(from_order_key(order_key(a)).to_bits(), a.to_bits());
            for &b in &xs {
                assert_eq!(
                    order_key(a).cmp(&order_key(b)),
                    a.total_cmp(&b),
                    "{a:e} {b:e}"
                );
            }
        }
    }
}
