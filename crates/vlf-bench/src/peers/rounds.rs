//! The rounds of a peers timing, paired: the field's rate over another contestant's in the same
//! round ([`super::time_round_robin`] has the contestants take turns), and which rounds began in
//! a slow spell of the host (the core probe timed before each round, `crate::latency::core_probe_ns`).

use super::model::SetResult;

/// `a`'s rate over `b`'s on `set` at `threads`, run by run: the contestants took turns in each
/// round ([`super::time_round_robin`]), so run `k` of `a` is paired with run `k` of `b` and each
/// pair gives one ratio, measured under the same conditions. Sorted; `None` if either contestant
/// is missing or their runs do not pair up.
pub fn paired_ratios(set: &SetResult, a: &str, b: &str, threads: usize) -> Option<Vec<f64>> {
    let mut v = round_ratios(set, a, b, threads)?;
    v.sort_by(f64::total_cmp);
    Some(v)
}

/// The [`paired_ratios`] in round order.
fn round_ratios(set: &SetResult, a: &str, b: &str, threads: usize) -> Option<Vec<f64>> {
    let runs = |c: &str| set.speeds.iter().find(|s| s.contestant == c && s.threads == threads).map(|s| &s.runs_s);
    let (ra, rb) = (runs(a)?, runs(b)?);
    if ra.is_empty() || ra.len() != rb.len() {
        return None;
    }
    Some(ra.iter().zip(rb).map(|(ta, tb)| tb / ta).collect())
}

/// `a`'s rate over `b`'s on `set` at `threads`: the median of the [`paired_ratios`].
pub fn ratio(set: &SetResult, a: &str, b: &str, threads: usize) -> Option<f64> {
    Some(crate::median(&mut paired_ratios(set, a, b, threads)?))
}

/// A round began in one of the host's slow spells if the core probe before it
/// ([`crate::latency::core_probe_ns`]) took at least this many times the scene's fastest probe at
/// the same thread count. In the spells measured on 2026-12-07 (`examples/core_probe.rs`, one
/// thread) the probe ran about 20% slower and up to 2.3 times; outside them its fastest was also
/// its median.
pub const SLOW_PROBE: f64 = 1.10;

/// The fastest core probe recorded by any of a scene's `sets` at `threads`.
pub fn fastest_probe(sets: &[SetResult], threads: usize) -> Option<f64> {
    sets.iter()
        .flat_map(|set| {
            set.speeds.iter().filter(|s| s.threads == threads).flat_map(|s| s.core_probe_ns.iter().copied())
        })
        .filter(|p| p.is_finite() && *p > 0.0)
        .min_by(f64::total_cmp)
}

/// Which of `set`'s timed rounds at `threads` began in a slow spell of the host: a core probe at
/// least [`SLOW_PROBE`] times `fastest`. `None` if the set recorded no probes (older reports).
pub fn slow_spells(set: &SetResult, threads: usize, fastest: f64) -> Option<Vec<bool>> {
    let probes = &set.speeds.iter().find(|s| s.threads == threads)?.core_probe_ns;
    (!probes.is_empty()).then(|| probes.iter().map(|&p| p >= SLOW_PROBE * fastest).collect())
}

/// For each of a scene's `sets` that recorded core probes at `threads`: its name, how many of its
/// timed rounds began in a slow spell ([`slow_spells`], against the [`fastest_probe`] of all of
/// `sets`), and how many rounds it had.
pub fn slow_rounds(sets: &[SetResult], threads: usize) -> Vec<(String, usize, usize)> {
    let Some(fastest) = fastest_probe(sets, threads) else { return Vec::new() };
    sets.iter()
        .filter_map(|set| {
            let slow = slow_spells(set, threads, fastest)?;
            Some((set.name.clone(), slow.iter().filter(|&&x| x).count(), slow.len()))
        })
        .collect()
}

/// `a`'s rate over `b`'s on `set` at `threads` over the rounds that did not begin in a slow spell
/// ([`slow_spells`] against `fastest`): the median of their paired ratios, or `None` if there
/// are no probes or no such round.
pub fn ratio_outside_spells(set: &SetResult, a: &str, b: &str, threads: usize, fastest: f64) -> Option<f64> {
    let slow = slow_spells(set, threads, fastest)?;
    let ratios = round_ratios(set, a, b, threads)?;
    let mut calm: Vec<f64> = ratios.iter().zip(&slow).filter(|(_, s)| !**s).map(|(r, _)| *r).collect();
    (slow.len() == ratios.len() && !calm.is_empty()).then(|| crate::median(&mut calm))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::peers::model::{Query, Speed};

    fn speed(contestant: &str, runs_s: Vec<f64>) -> Speed {
        Speed {
            contestant: contestant.into(),
            threads: 1,
            median_s: 0.0,
            runs_s,
            mrays_per_s: 0.0,
            load: 0.0,
            core_probe_ns: Vec::new(),
        }
    }

    #[test]
    fn ratios_pair_runs_of_the_same_round() {
        // Round 2 was slow for both: paired, every round says the field is twice as fast; the
        // ratio of the two medians (2 s and 3 s) would say 1.5.
        let set = SetResult {
            name: "outside".into(),
            query: Query::Closest,
            rays: 1,
            hits: 1,
            memory_latency_ns: None,
            speeds: vec![speed("field", vec![1.0, 3.0, 2.0]), speed("embree", vec![2.0, 6.0, 4.0])],
            checks: Vec::new(),
        };
        assert_eq!(paired_ratios(&set, "field", "embree", 1), Some(vec![2.0, 2.0, 2.0]));
        assert_eq!(ratio(&set, "field", "embree", 1), Some(2.0));
        assert_eq!(ratio(&set, "embree", "field", 1), Some(0.5));
        // Missing contestants, thread counts, or runs that do not pair up give no ratio.
        assert_eq!(ratio(&set, "field", "obvhs", 1), None);
        assert_eq!(ratio(&set, "field", "embree", 2), None);
        let mut uneven = set.clone();
        uneven.speeds[1].runs_s.pop();
        assert_eq!(ratio(&uneven, "field", "embree", 1), None);
    }

    #[test]
    fn slow_rounds_are_counted_against_the_scenes_fastest_probe() {
        let set = |name: &str, probes: Vec<f64>| SetResult {
            name: name.into(),
            query: Query::Closest,
            rays: 1,
            hits: 1,
            memory_latency_ns: None,
            speeds: vec![Speed { core_probe_ns: probes, ..speed("field", vec![1.0; 3]) }],
            checks: Vec::new(),
        };
        // 4.0 is the fastest: 4.39 is within 10% of it, 4.5 and 6.0 are not; a set of an older
        // report, without probes, is left out.
        let sets = [set("outside", vec![4.0, 4.39, 4.5]), set("inside", vec![6.0, 4.1, 4.2]), set("old", vec![])];
        assert_eq!(slow_rounds(&sets, 1), vec![("outside".to_string(), 1, 3), ("inside".to_string(), 1, 3)]);
        // No probes at a thread count: nothing to say.
        assert!(slow_rounds(&sets, 2).is_empty());
        assert_eq!(fastest_probe(&sets, 1), Some(4.0));
        assert_eq!(slow_spells(&sets[1], 1, 4.0), Some(vec![true, false, false]));
        assert_eq!(slow_spells(&sets[2], 1, 4.0), None);
        // The ratio outside the spells leaves out the slow round: Embree's runs over the field's.
        let mut paired = set("outside", vec![4.0, 4.0, 9.0]);
        paired.speeds.push(speed("embree", vec![1.0, 2.0, 9.0]));
        paired.speeds[0].runs_s = vec![1.0, 1.0, 1.0];
        assert_eq!(ratio_outside_spells(&paired, "field", "embree", 1, 4.0), Some(1.5));
        assert_eq!(ratio(&paired, "field", "embree", 1), Some(2.0));
    }
}
