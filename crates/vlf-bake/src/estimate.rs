//! Size estimates for parameter choice: a candidate's directions are measured by baking a few
//! sample directions for real ([`sample_direction_bytes`]), which is how a [`Prepared`] scene
//! answers [`crate::params::Measure`].

use crate::direction::{DirectionData, Scratch, build_direction};
use crate::error::BakeError;
use crate::floor::EntryFloor;
use crate::params::{Measure, Params, Sample};
use crate::prepare::Prepared;
use crate::statistics::merge_stats;
use rayon::prelude::*;
use vlf_format::StatisticsRecord;
use vlf_geom::Lattice;
use vlf_geom::frame::frame;

/// Bakes `samples` directions of a field with `params`, spread evenly over the lattice, and
/// returns the mean bytes a direction adds to the file and their summed statistics.
pub fn sample_direction_bytes(
    prep: &Prepared<'_>,
    params: &Params,
    samples: usize,
) -> Result<(u64, StatisticsRecord), BakeError> {
    let lattice = Lattice::new(params.lattice_n);
    let dirs = lattice.directions();
    let l = dirs.len();
    let picks: Vec<usize> = (0..samples.min(l))
        .map(|i| (i * l) / samples.min(l) + (l / samples.min(l)) / 2)
        .map(|j| j.min(l - 1))
        .collect();
    let results: Vec<Result<DirectionData, BakeError>> = picks
        .par_iter()
        .map_init(Scratch::default, |s, &j| build_direction(prep, params, &frame(dirs[j]), j, s))
        .collect();
    let mut bytes = 0;
    let mut stats = StatisticsRecord::zeroed_record();
    for r in results {
        let d = r?;
        bytes += d.bytes();
        merge_stats(&mut stats, &d.stats);
    }
    Ok((bytes / picks.len() as u64, stats))
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

    fn sample(&self, params: &Params, directions: usize) -> Result<Sample, BakeError> {
        let (bytes_per_direction, statistics) = sample_direction_bytes(self, params, directions)?;
        Ok(Sample { bytes_per_direction, statistics })
    }

    fn entries_at_least(&self, params: &Params) -> u64 {
        let directions = Lattice::new(params.lattice_n).direction_count() as u32;
        EntryFloor::measure(self, &params.grid(self.radius), 0..directions).total
    }
}
