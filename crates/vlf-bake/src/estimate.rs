//! Size estimates for parameter choice: a candidate's directions are measured by baking a few
//! sample directions for real ([`sample_direction_bytes`]), which is how a [`Prepared`] scene
//! answers [`crate::params::Measure`].

use crate::direction::{DirectionData, Limit, Scratch, build_direction};
use crate::error::BakeError;
use crate::floor::EntryFloor;
use crate::params::{Coverage, Measure, Params, Sample};
use crate::prepare::Prepared;
use crate::statistics::merge_stats;
use rayon::prelude::*;
use std::sync::atomic::AtomicU64;
use vlf_format::{StatisticsRecord, size};
use vlf_geom::Lattice;
use vlf_geom::frame::frame;

/// Bakes `samples` directions of a field with `params`, spread evenly over the lattice, and
/// returns the mean bytes a direction adds to the file and their summed statistics. Once the
/// samples together pass their share of `max_bytes` (or one passes its thread's share of the
/// memory), they stop: the mean is then `None` (and the statistics empty), the field being more
/// than `max_bytes`.
pub fn sample_direction_bytes(
    prep: &Prepared<'_>,
    params: &Params,
    samples: usize,
    max_bytes: u64,
) -> Result<(Option<u64>, StatisticsRecord), BakeError> {
    // The picked directions only, each found from its index: a lattice may have 2²⁵ + 1.
    let lattice = Lattice::new(params.lattice_n);
    let l = lattice.direction_count() as usize;
    let picks = picks(l, samples);
    // The field's estimate is `l` times the mean of the samples, so once the samples together
    // pass `max_bytes · samples / l` the field cannot fit: they draw their blocks' words from one
    // pool of that size and stop when it runs out. (Long thin triangles on fine tiles make
    // blocks of gigabytes; each sample held to that share on its own, a million slivers took
    // 98 s and 6.9 GB to be refused.)
    let threads = rayon::current_num_threads().min(picks.len());
    let share = (max_bytes as u128 * picks.len() as u128 / l as u128) as u64;
    let pool = AtomicU64::new(share / size::LEAF_WORD);
    let limit = Limit::memory(threads).min(Limit::new(share / size::LEAF_WORD, "the size budget")).sharing(&pool);
    let results: Result<Vec<DirectionData>, BakeError> = picks
        .par_iter()
        .map_init(Scratch::default, |s, &j| {
            let rotation = frame(lattice.direction_at(j as u64).expect("a field's direction"));
            build_direction(prep, params, &rotation, j, s, limit)
        })
        .collect();
    let mut bytes = 0;
    let mut stats = StatisticsRecord::zeroed_record();
    match results {
        Err(BakeError::DirectionOverLimit { .. }) => return Ok((None, stats)),
        Err(e) => return Err(e),
        Ok(directions) => {
            for d in &directions {
                bytes += d.bytes();
                merge_stats(&mut stats, &d.stats);
            }
        }
    }
    Ok((Some(bytes / picks.len() as u64), stats))
}

/// The indices of `samples` directions spread evenly over a lattice of `l`.
fn picks(l: usize, samples: usize) -> Vec<usize> {
    let p = samples.min(l);
    (0..p).map(|i| ((i * l) / p + (l / p) / 2).min(l - 1)).collect()
}

/// A prepared scene measures a candidate's directions by baking a few of them.
impl Measure for Prepared<'_> {
    type Error = BakeError;

    fn triangle_count(&self) -> u64 {
        Prepared::triangle_count(self) as u64
    }

    fn radius(&self) -> f64 {
        self.radius
    }

    fn sample(&self, params: &Params, directions: usize, max_bytes: u64) -> Result<Sample, BakeError> {
        let (bytes, statistics) = sample_direction_bytes(self, params, directions, max_bytes)?;
        Ok(Sample { bytes_per_direction: bytes.unwrap_or(max_bytes.saturating_add(1)), statistics })
    }

    fn coverage(&self, params: &Params) -> Coverage {
        let directions = Lattice::new(params.lattice_n).direction_count() as u32;
        EntryFloor::measure(self, &params.grid(self.radius), 0..directions).coverage
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::DepthPolicy;
    use crate::scene::Scene;

    #[test]
    fn samples_past_their_share_of_the_budget_are_not_baked_to_their_end() {
        // A fan of 2,000 long thin triangles across a disc: on 64² tiles each crosses dozens of
        // tiles, and the leaves of the tiles near the centre hold most of them.
        let n = 2000;
        let point = |k: usize| {
            let a = std::f32::consts::TAU * k as f32 / n as f32;
            [a.cos(), a.sin(), 0.1 * (k % 7) as f32]
        };
        let triangles: Vec<[[f32; 3]; 3]> = (1..n - 1).map(|k| [point(0), point(k), point(k + 1)]).collect();
        let scene = Scene::from_triangles("fan", &triangles).unwrap();
        let prep = Prepared::new(&scene);
        let params = Params { lattice_n: 3, tiles: 64, depth: DepthPolicy::default(), margin: 1e-6 };
        let (Some(mean), _) = sample_direction_bytes(&prep, &params, 4, u64::MAX).unwrap() else {
            panic!("no limit, yet stopped")
        };
        // With a budget the 19 directions fit at that mean, every sample is baked; with one they
        // do not fit by a wide margin, the samples stop.
        let fits = mean * 19;
        assert_eq!(sample_direction_bytes(&prep, &params, 4, fits).unwrap().0, Some(mean));
        assert_eq!(sample_direction_bytes(&prep, &params, 4, mean).unwrap().0, None);

        // The samples share one pool: their words together, not each one's, are held to the
        // budget's share (`max_bytes · 4 / 19` bytes, in whole words). A pool one word short of
        // their sum stops them, though each alone fits it many times over.
        let words: Vec<u64> = picks(19, 4)
            .into_iter()
            .map(|j| {
                let m = frame(Lattice::new(3).direction_at(j as u64).unwrap());
                build_direction(&prep, &params, &m, j, &mut Scratch::default(), Limit::FORMAT).unwrap().words.len()
                    as u64
            })
            .collect();
        let sum: u64 = words.iter().sum();
        assert!(words.iter().all(|&w| w < sum / 2), "{words:?}");
        let budget_for = |pool_words: u64| (8 * pool_words * 19).div_ceil(4);
        assert_eq!(sample_direction_bytes(&prep, &params, 4, budget_for(sum)).unwrap().0, Some(mean));
        assert_eq!(sample_direction_bytes(&prep, &params, 4, budget_for(sum - 1)).unwrap().0, None);
    }
}
