//! Coal-wall spalling statistics by face zone (paper Table 1, physics.md §E): zone shares of the
//! events, the conditional probabilities P₁ = P(A|B) and P₂ = P(A|C), their converses and Wilson
//! 95 % intervals.
//!
//! Events: A spalling, B high support resistance, C low support resistance. Counts may be
//! fractional (the paper prints A∩C = 4.5 and 10.5: events split between zones).

use super::stats::interval::{Z_95, wilson_interval};

/// Event counts of one zone (may be fractional).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ZoneCounts {
    /// |A|: spalling events.
    pub spalling: f64,
    /// |B|: high-resistance events.
    pub high: f64,
    /// |C|: low-resistance events.
    pub low: f64,
    /// |A∩B|.
    pub spalling_and_high: f64,
    /// |A∩C|.
    pub spalling_and_low: f64,
}

impl ZoneCounts {
    /// The paper's Table 1: lower, middle and upper zones.
    #[must_use]
    pub fn table1() -> [ZoneCounts; 3] {
        let z = |a, b, c, ab, ac| ZoneCounts {
            spalling: a,
            high: b,
            low: c,
            spalling_and_high: ab,
            spalling_and_low: ac,
        };
        [
            z(118.0, 8.0, 22.0, 5.0, 4.5),
            z(375.0, 65.0, 17.0, 32.0, 10.5),
            z(150.0, 14.0, 8.0, 9.0, 2.0),
        ]
    }

    fn add(self, o: ZoneCounts) -> ZoneCounts {
        ZoneCounts {
            spalling: self.spalling + o.spalling,
            high: self.high + o.high,
            low: self.low + o.low,
            spalling_and_high: self.spalling_and_high + o.spalling_and_high,
            spalling_and_low: self.spalling_and_low + o.spalling_and_low,
        }
    }
}

/// A percentage that is undefined when its denominator is 0.
pub type Percent = Option<f64>;

/// Derived statistics of one zone (or of the total), percentages in %.
#[derive(Debug, Clone, PartialEq)]
pub struct ZoneStatistics {
    /// The counts.
    pub counts: ZoneCounts,
    /// Zone's share of all A events, %.
    pub spalling_share: Percent,
    /// Zone's share of all B events, %.
    pub high_share: Percent,
    /// Zone's share of all C events, %.
    pub low_share: Percent,
    /// P₁ = P(A|B) = |A∩B|/|B|, %.
    pub spalling_given_high: Percent,
    /// P₂ = P(A|C) = |A∩C|/|C|, %.
    pub spalling_given_low: Percent,
    /// P(B|A) = |A∩B|/|A|, %.
    pub high_given_spalling: Percent,
    /// P(C|A) = |A∩C|/|A|, %.
    pub low_given_spalling: Percent,
    /// Wilson 95 % interval of P₁, %.
    pub spalling_given_high_ci95: Option<[f64; 2]>,
    /// Wilson 95 % interval of P₂, %.
    pub spalling_given_low_ci95: Option<[f64; 2]>,
}

/// Which quantity of a zone was undefined (its denominator is 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Undefined {
    /// A share: the total of that event over all zones is 0.
    Share(&'static str),
    /// A conditional probability: the conditioning event has no count in this zone.
    Conditional(&'static str),
}

/// The statistics of every zone, in order, and of the total.
#[derive(Debug, Clone, PartialEq)]
pub struct SpallingResult {
    /// One entry per zone, in the given order.
    pub zones: Vec<ZoneStatistics>,
    /// The zones summed.
    pub total: ZoneStatistics,
    /// (zone index or `None` for the total, quantity) of each undefined percentage.
    pub undefined: Vec<(Option<usize>, Undefined)>,
}

/// Which count of a zone breaks a consistency rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CountError {
    /// A count is negative or not finite.
    NotCount(usize, &'static str),
    /// |A∩B| > min(|A|, |B|).
    SpallingAndHigh(usize),
    /// |A∩C| > min(|A|, |C|).
    SpallingAndLow(usize),
}

/// Checks that every count is a finite non-negative number and that no intersection is larger
/// than either of its events. Returns every violation (zone index and which rule).
#[must_use]
pub fn check_counts(zones: &[ZoneCounts]) -> Vec<CountError> {
    let mut out = Vec::new();
    for (i, z) in zones.iter().enumerate() {
        let fields = [
            ("spalling", z.spalling),
            ("high_resistance", z.high),
            ("low_resistance", z.low),
            ("spalling_and_high", z.spalling_and_high),
            ("spalling_and_low", z.spalling_and_low),
        ];
        let mut ok = true;
        for (name, v) in fields {
            if !(v.is_finite() && v >= 0.0) {
                out.push(CountError::NotCount(i, name));
                ok = false;
            }
        }
        if !ok {
            continue;
        }
        if z.spalling_and_high > z.spalling.min(z.high) {
            out.push(CountError::SpallingAndHigh(i));
        }
        if z.spalling_and_low > z.spalling.min(z.low) {
            out.push(CountError::SpallingAndLow(i));
        }
    }
    out
}

/// `100 · num / den` %, formed as 100 · (num / den) so that a part never exceeds 100 %
/// (num ≤ den gives a quotient ≤ 1, and 100 · 1 is exact).
fn pct(num: f64, den: f64) -> Percent {
    (den > 0.0).then(|| 100.0 * (num / den))
}

fn ci_pct(num: f64, den: f64) -> Option<[f64; 2]> {
    wilson_interval(num, den, Z_95).map(|[a, b]| [100.0 * a, 100.0 * b])
}

fn statistics(
    c: ZoneCounts,
    total: ZoneCounts,
    at: Option<usize>,
    undefined: &mut Vec<(Option<usize>, Undefined)>,
) -> ZoneStatistics {
    let mut note = |p: Percent, u: Undefined| {
        if p.is_none() {
            undefined.push((at, u));
        }
        p
    };
    ZoneStatistics {
        counts: c,
        spalling_share: note(
            pct(c.spalling, total.spalling),
            Undefined::Share("spalling"),
        ),
        high_share: note(pct(c.high, total.high), Undefined::Share("high_resistance")),
        low_share: note(pct(c.low, total.low), Undefined::Share("low_resistance")),
        spalling_given_high: note(
            pct(c.spalling_and_high, c.high),
            Undefined::Conditional("high_resistance"),
        ),
        spalling_given_low: note(
            pct(c.spalling_and_low, c.low),
            Undefined::Conditional("low_resistance"),
        ),
        high_given_spalling: note(
            pct(c.spalling_and_high, c.spalling),
            Undefined::Conditional("spalling"),
        ),
        low_given_spalling: pct(c.spalling_and_low, c.spalling),
        spalling_given_high_ci95: ci_pct(c.spalling_and_high, c.high),
        spalling_given_low_ci95: ci_pct(c.spalling_and_low, c.low),
    }
}

/// Zone shares, conditional probabilities and Wilson intervals of validated counts
/// (see [`check_counts`]).
///
/// # Examples
/// ```
/// use gangue::physics::spalling::{spalling_statistics, ZoneCounts};
/// let r = spalling_statistics(&ZoneCounts::table1());
/// assert_eq!(r.zones[0].spalling_given_high, Some(62.5)); // 5/8, paper Table 1
/// assert_eq!(r.total.counts.spalling_and_low, 17.0);
/// ```
///
/// # Special cases
/// * A denominator of 0 gives `None` for that percentage (and its interval), listed in
///   `undefined` once per zone and quantity (P(C|A) shares its denominator with P(B|A)).
/// * The total's shares are 100 % (or `None` when the event never occurs).
///
/// # References
/// physics.md §E (P₁ = |A∩B|/|B|, P₂ = |A∩C|/|C|); Wilson (1927) for the intervals.
#[must_use]
pub fn spalling_statistics(zones: &[ZoneCounts]) -> SpallingResult {
    let total = zones
        .iter()
        .fold(ZoneCounts::default(), |acc, z| acc.add(*z));
    let mut undefined = Vec::new();
    let zs = zones
        .iter()
        .enumerate()
        .map(|(i, z)| statistics(*z, total, Some(i), &mut undefined))
        .collect();
    let t = statistics(total, total, None, &mut undefined);
    SpallingResult {
        zones: zs,
        total: t,
        undefined,
    }
}

/// One observation of a support: whether the wall spalled and the support's resistance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// Support number.
    pub support: i64,
    /// Spalling observed (event A).
    pub spalling: bool,
    /// Support resistance, N.
    pub resistance: f64,
}

/// A zone of the face as a range of support numbers, inclusive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ZoneRange {
    /// First support of the zone.
    pub first: i64,
    /// Last support of the zone (≥ first).
    pub last: i64,
}

/// Why an event log cannot be counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventError {
    /// Event `i` names a support in no zone.
    OutsideZones(usize),
    /// Zone `i` overlaps an earlier zone.
    Overlap(usize),
}

/// Counts an event log into zones: B is resistance > `high` N, C is resistance < `low` N.
///
/// # Errors
/// [`EventError::Overlap`] when two zones share a support; [`EventError::OutsideZones`] for an
/// event whose support is in no zone.
pub fn count_events(
    events: &[Event],
    zones: &[ZoneRange],
    high: f64,
    low: f64,
) -> Result<Vec<ZoneCounts>, EventError> {
    for (i, z) in zones.iter().enumerate() {
        if zones[..i]
            .iter()
            .any(|o| z.first <= o.last && o.first <= z.last)
        {
            return Err(EventError::Overlap(i));
        }
    }
    let mut counts = vec![ZoneCounts::default(); zones.len()];
    for (i, e) in events.iter().enumerate() {
        let k = zones
            .iter()
            .position(|z| (z.first..=z.last).contains(&e.support))
            .ok_or(EventError::OutsideZones(i))?;
        let c = &mut counts[k];
        let a = if e.spalling { 1.0 } else { 0.0 };
        c.spalling += a;
        if e.resistance > high {
            c.high += 1.0;
            c.spalling_and_high += a;
        }
        if e.resistance < low {
            c.low += 1.0;
            c.spalling_and_low += a;
        }
    }
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// physics.md §E: every printed percentage of Table 1 and the totals.
    #[test]
    fn table1_percentages() {
        let r = spalling_statistics(&ZoneCounts::table1());
        let got: Vec<f64> = r.zones.iter().map(|z| z.spalling_share.unwrap()).collect();
        let exp = [118.0 / 643.0, 375.0 / 643.0, 150.0 / 643.0];
        for (g, e) in got.iter().zip(exp) {
            assert!((g - 100.0 * e).abs() <= 1e-12 * g);
        }
        assert_eq!(r.total.counts.spalling, 643.0);
        assert_eq!(r.total.counts.high, 87.0);
        assert_eq!(r.total.counts.low, 47.0);
        assert_eq!(r.total.counts.spalling_and_high, 46.0);
        assert!((r.total.spalling_given_high.unwrap() - 100.0 * 46.0 / 87.0).abs() < 1e-12);
        assert!((r.total.spalling_given_low.unwrap() - 100.0 * 17.0 / 47.0).abs() < 1e-12);
        assert!(r.undefined.is_empty());
        // P(B|A) is the definition the paper does not use: 4.2, 8.5, 6.0 %.
        let pba: Vec<f64> = r
            .zones
            .iter()
            .map(|z| (z.high_given_spalling.unwrap() * 10.0).round() / 10.0)
            .collect();
        assert_eq!(pba, vec![4.2, 8.5, 6.0]);
    }

    #[test]
    fn zero_denominators_are_none_and_listed() {
        let z = ZoneCounts {
            spalling: 3.0,
            ..ZoneCounts::default()
        };
        let r = spalling_statistics(&[z]);
        assert_eq!(r.zones[0].spalling_given_high, None);
        assert_eq!(r.zones[0].spalling_given_high_ci95, None);
        assert_eq!(r.zones[0].high_share, None);
        assert!(
            r.undefined
                .contains(&(Some(0), Undefined::Conditional("high_resistance")))
        );
        assert!(
            r.undefined
                .contains(&(None, Undefined::Share("low_resistance")))
        );
    }

    #[test]
    fn intersections_larger_than_events_are_named() {
        let mut t = ZoneCounts::table1();
        t[1].spalling_and_high = 66.0;
        t[2].spalling_and_low = -1.0;
        let e = check_counts(&t);
        assert_eq!(
            e,
            vec![
                CountError::SpallingAndHigh(1),
                CountError::NotCount(2, "spalling_and_low")
            ]
        );
        assert!(check_counts(&ZoneCounts::table1()).is_empty());
    }

    #[test]
    fn event_log_counts_by_zone() {
        let zones = [
            ZoneRange { first: 1, last: 21 },
            ZoneRange {
                first: 22,
                last: 42,
            },
        ];
        let ev = |s, a, r| Event {
            support: s,
            spalling: a,
            resistance: r,
        };
        let events = [
            ev(3, true, 7e6),
            ev(21, false, 0.5e6),
            ev(22, true, 0.2e6),
            ev(30, false, 3e6),
        ];
        let c = count_events(&events, &zones, 6e6, 1e6).unwrap();
        assert_eq!(
            c[0],
            ZoneCounts {
                spalling: 1.0,
                high: 1.0,
                low: 1.0,
                spalling_and_high: 1.0,
                spalling_and_low: 0.0
            }
        );
        assert_eq!(c[1].spalling_and_low, 1.0);
        assert_eq!(c[1].high, 0.0);
        assert_eq!(
            count_events(&[ev(50, true, 0.0)], &zones, 6e6, 1e6),
            Err(EventError::OutsideZones(0))
        );
        let overlapping = [
            zones[0],
            ZoneRange {
                first: 21,
                last: 30,
            },
        ];
        assert_eq!(
            count_events(&events, &overlapping, 6e6, 1e6),
            Err(EventError::Overlap(1))
        );
    }
}
