//! Writing a bake: lay out a field (or one shard of it), bake its directions in parallel chunks,
//! and write them in direction order, each byte once.
//!
//! Directions are independent, so they are baked in parallel (rayon) in chunks, and each chunk is
//! written in direction order: the output bytes do not depend on the thread count, and memory does
//! not grow with the field's size. The field is written through [`AtomicFile`], so the path holds
//! the old field or the new one, never a partial one.

use crate::atomic::AtomicFile;
use crate::direction::{DirectionData, Limit, Scratch, build_direction};
use crate::disk::Need;
use crate::error::BakeError;
use crate::floor::EntryFloor;
use crate::params::Choice;
use crate::prepare::Prepared;
use crate::progress::Progress;
use crate::sections::{BAKER_REVISION, SharedSection, input_hash, shared_sections};
use crate::shard::ShardSpec;
use crate::statistics::{Statistics, merge_stats};
use rayon::prelude::*;
use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;
use vlf_format::shard::shared_hash;
use vlf_format::{
    BeamRecord, FieldFile, Header, PER_DIRECTION_KINDS, Request, SHARD_KIND, SHARD_MAGIC, SectionEntry, SectionKind,
    SectionWriter, ShardRecord, StatisticsRecord, size,
};
use vlf_geom::Lattice;
use vlf_geom::frame::frame;

/// What a bake produced.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BakeSummary {
    pub output: PathBuf,
    pub triangles: u64,
    pub dropped_degenerate: u64,
    pub dropped_precision: u64,
    pub dropped_duplicates: u64,
    pub directions: u32,
    pub lattice_n: u32,
    pub tile_resolution: u32,
    pub leaf_size: u32,
    pub max_depth: u32,
    pub automatic: bool,
    pub choice: String,
    pub estimated_bytes: Option<u64>,
    pub bytes: u64,
    pub seconds: f64,
    pub content_hash: String,
    pub input_hash: String,
    pub statistics: Statistics,
}

/// The per-direction sections of a file being baked, after its shared sections, in this order:
/// BEAMS and STATISTICS (reserved, filled last), TILES (reserved, filled direction by direction)
/// and LEAVES (streamed behind it): each byte is written once. Fields and shards share this
/// layout, which `merge` follows to reproduce a field byte for byte.
struct DirectionSections {
    beams_out: SectionWriter,
    stats_out: SectionWriter,
    tiles: SectionWriter,
    leaves: SectionWriter,
}

/// Direction by direction: the BEAMS records (bases counted from the file's first direction) and
/// the STATISTICS of the directions written so far.
#[derive(Default)]
struct DirectionTotals {
    beams: Vec<BeamRecord>,
    stats: Option<StatisticsRecord>,
    leaves_base: u64,
}

impl DirectionSections {
    fn open(f: &mut FieldFile, directions: u64, n2: u64) -> io::Result<Self> {
        Ok(DirectionSections {
            beams_out: f.reserve(SectionKind::Beams, directions * size::BEAM)?,
            stats_out: f.reserve(SectionKind::Statistics, size::STATISTICS)?,
            tiles: f.reserve(SectionKind::Tiles, directions * n2 * size::TILE)?,
            leaves: f.stream(SectionKind::Leaves)?,
        })
    }

    fn push(&mut self, d: &DirectionData, totals: &mut DirectionTotals) -> io::Result<()> {
        self.tiles.write_all(bytemuck::cast_slice(&d.tiles))?;
        self.leaves.write_all(bytemuck::cast_slice(&d.words))?;
        let leaves_words = d.words.len() as u64;
        totals.beams.push(BeamRecord {
            leaves_base: totals.leaves_base,
            leaves_words,
            leaf_count: d.stats.leaf_count,
            ref_count: d.stats.id_count,
        });
        totals.leaves_base += leaves_words;
        merge_stats(totals.stats.get_or_insert_with(StatisticsRecord::zeroed_record), &d.stats);
        Ok(())
    }

    fn finish(mut self, f: &mut FieldFile, totals: &DirectionTotals) -> io::Result<StatisticsRecord> {
        f.finish_section(self.tiles)?;
        f.finish_section(self.leaves)?;
        self.beams_out.write_all(bytemuck::cast_slice(&totals.beams))?;
        f.finish_section(self.beams_out)?;
        let stats = totals.stats.unwrap_or_else(StatisticsRecord::zeroed_record);
        self.stats_out.write_all(bytemuck::bytes_of(&stats))?;
        f.finish_section(self.stats_out)?;
        Ok(stats)
    }
}

/// Writes the field of the prepared scene with the chosen `choice` to `output`, atomically: the
/// whole bake, from the shared sections to the last direction.
pub fn write_field(
    prep: &Prepared<'_>,
    choice: &Choice,
    request: &Request,
    output: &Path,
    progress: &dyn Progress,
) -> Result<BakeSummary, BakeError> {
    let start = Instant::now();
    let io_err = |error: io::Error| BakeError::Io { path: output.to_path_buf(), error };
    let tmp = AtomicFile::create(output).map_err(io_err)?;
    let baked = write_into(prep, choice, request, tmp.file(), output, None, progress)?;
    tmp.commit().map_err(io_err)?;
    progress.end();
    Ok(baked.summary(prep, choice, output, start.elapsed().as_secs_f64()))
}

/// What [`write_into`] wrote.
#[derive(Clone, Debug)]
pub struct Baked {
    pub header: Header,
    pub statistics: StatisticsRecord,
    /// The directions the file holds: all of them for a field, the shard's for a shard.
    pub directions: std::ops::Range<u32>,
    pub direction_count: u32,
}

impl Baked {
    /// The summary `bake` prints.
    pub fn summary(&self, prep: &Prepared<'_>, choice: &Choice, output: &Path, seconds: f64) -> BakeSummary {
        let params = &choice.params;
        BakeSummary {
            output: output.to_path_buf(),
            triangles: prep.scene.triangles.len() as u64,
            dropped_degenerate: prep.scene.report.dropped_degenerate,
            dropped_precision: prep.scene.report.dropped_precision,
            dropped_duplicates: prep.scene.report.dropped_duplicates,
            directions: self.direction_count,
            lattice_n: params.lattice_n,
            tile_resolution: params.tiles,
            leaf_size: params.depth.leaf_size,
            max_depth: params.depth.max_depth,
            automatic: choice.automatic,
            choice: choice.reason.clone(),
            estimated_bytes: choice.estimated_bytes,
            bytes: self.header.file_length,
            seconds,
            content_hash: vlf_format::hex(&self.header.content_hash),
            input_hash: vlf_format::hex(&self.header.input_hash),
            statistics: Statistics::from_record(&self.statistics),
        }
    }
}

/// Writes into `out` (an empty, writable file that will be at `path`; its directory holds the
/// spill file): the whole field, or with `shard` one shard of it (`formats/vlf-shard.md`).
/// `choice` is one made for `prep` ([`crate::params::choose`]): its coverage is the field's.
///
/// The file is written in place, each byte once: the shared sections first (after the SHARD
/// record of a shard), then the per-direction sections (`DirectionSections`). Leaves the
/// "writing" progress phase open; the caller ends it after committing the file.
pub fn write_into(
    prep: &Prepared<'_>,
    choice: &Choice,
    request: &Request,
    out: &File,
    path: &Path,
    shard: Option<ShardSpec>,
    progress: &dyn Progress,
) -> Result<Baked, BakeError> {
    let params = &choice.params;
    let io_err = |error: io::Error| BakeError::Io { path: path.to_path_buf(), error };
    let direction_count = Lattice::new(params.lattice_n).direction_count() as u32;
    let range = match shard {
        None => 0..direction_count,
        Some(s) => s.directions(direction_count),
    };
    // The room the bake needs, before any work: memory for its directions, disk for its output.
    // A field's floor was measured when its parameters were chosen; a shard's covers its own.
    let floor = if range.len() == direction_count as usize {
        EntryFloor::of_field(choice.coverage, direction_count)
    } else {
        EntryFloor::measure(prep, &params.grid(prep.radius), range.clone())
    };
    let tables = crate::sections::parameter_bytes(params.lattice_n) + range.len() as u64 * size::BEAM;
    crate::memory::check(
        params.tiles,
        rayon::current_num_threads(),
        range.len() as u64,
        floor.coverage.largest,
        tables,
    )?;
    let what = if shard.is_some() { "shard" } else { "field" };
    crate::disk::check(path, what, Need::of(choice, prep.triangle_count() as u64, &floor))?;

    let shared = shared_sections(prep, params, request);
    let lattice = Lattice::new(params.lattice_n);
    let n2 = params.tiles as u64 * params.tiles as u64;
    let hash = input_hash(prep.scene, request);

    let section_count = shared.len() + PER_DIRECTION_KINDS.len() + shard.is_some() as usize;
    let out = out.try_clone().map_err(io_err)?;
    let mut f = match shard {
        None => FieldFile::create(out, section_count),
        Some(_) => FieldFile::create_with_magic(out, section_count, SHARD_MAGIC),
    }
    .map_err(io_err)?;
    if let Some(s) = shard {
        let entries: Vec<SectionEntry> = shared.iter().map(SharedSection::entry).collect();
        let record = ShardRecord {
            shard_index: s.index,
            shard_count: s.count,
            direction_count,
            first_direction: range.start,
            end_direction: range.end,
            baker_revision: BAKER_REVISION,
            field_section_count: (section_count - 1) as u32,
            reserved: 0,
            shared_hash: shared_hash(&entries),
        };
        f.append_kind(SHARD_KIND, size_of::<ShardRecord>() as u32, bytemuck::bytes_of(&record)).map_err(io_err)?;
    }
    for s in &shared {
        f.append_kind(s.kind, s.element_size, &s.bytes).map_err(io_err)?;
    }
    // Explicit parameters are held to --max-bytes as a ceiling (automatic ones were chosen to fit
    // it by estimate): the bake stops as soon as the bytes the field needs exceed it. `fixed`
    // counts every section of the field whose size is known now, without padding, and a shard
    // adds its own directions' leaves and ids to it: a lower bound on the field's size, so the
    // running check never fires early. A field's exact length is checked once it is complete,
    // a sharded field's by merge.
    let ceiling = if choice.automatic { u64::MAX } else { request.max_bytes };
    let l = direction_count as u64;
    let fixed = size::head(shared.len() + PER_DIRECTION_KINDS.len())
        + shared.iter().map(|s| s.bytes.len() as u64).sum::<u64>()
        + l * (size::BEAM + n2 * size::TILE)
        + size::STATISTICS;
    let over_budget =
        |at_least: u64, baked: usize| BakeError::OverBudget { ceiling, at_least, baked, directions: l as usize };
    // A direction alone may take no more than its thread's share of the memory, nor than the
    // ceiling: long triangles on fine tiles land in many tiles and leaves, and a direction that
    // cannot fit stops as soon as it passes instead of when it is done.
    let limit = Limit::memory(rayon::current_num_threads())
        .min(Limit::new(ceiling / size::LEAF_WORD, "the --max-bytes ceiling"));
    let mut sections = DirectionSections::open(&mut f, range.len() as u64, n2).map_err(io_err)?;

    // Directions are baked in parallel, chunk by chunk; a writer thread appends each finished
    // chunk in direction order while the next one is computed. The channel holds at most two
    // chunks, and chunks are sized from the bytes the directions baked so far produced (about
    // CHUNK_BYTES each, at least one direction per thread), which bounds memory whatever the
    // scene and tile resolution.
    const CHUNK_BYTES: u64 = 64 << 20;
    let threads = rayon::current_num_threads().max(1);
    let (send, receive) = std::sync::mpsc::sync_channel::<Vec<DirectionData>>(2);
    progress.begin("baking directions", range.len() as u64);
    let mut totals = DirectionTotals::default();
    let (sections_w, totals_w) = (&mut sections, &mut totals);
    let (written, baked) = std::thread::scope(|scope| {
        let writer = scope.spawn(move || -> Result<(), BakeError> {
            for chunk in receive {
                for d in chunk {
                    let at_least = fixed + (totals_w.leaves_base + d.words.len() as u64) * size::LEAF_WORD;
                    if at_least > ceiling {
                        return Err(over_budget(at_least, totals_w.beams.len() + 1));
                    }
                    sections_w.push(&d, totals_w).map_err(io_err)?;
                }
            }
            Ok(())
        });
        let mut baked = Ok(());
        let (mut chunk_start, mut chunk, mut produced) = (range.start as usize, threads, 0u64);
        while chunk_start < range.end as usize {
            let chunk_range = chunk_start..(chunk_start + chunk).min(range.end as usize);
            chunk_start = chunk_range.end;
            let result: Result<Vec<DirectionData>, BakeError> = chunk_range
                .into_par_iter()
                .map_init(Scratch::default, |s, j| {
                    // Each direction's rotation when it is baked, not all of them up front (72
                    // bytes each, and a field may have 2²⁵ + 1 directions).
                    let rotation = frame(lattice.direction_at(j as u64).expect("a field's direction"));
                    let d = build_direction(prep, params, &rotation, j, s, limit);
                    progress.advance(1);
                    d
                })
                .collect();
            match result {
                // A send fails only if the writer stopped on an error, which join reports below.
                Ok(done) => {
                    produced += done.iter().map(DirectionData::bytes).sum::<u64>();
                    let per_direction = (produced / (chunk_start - range.start as usize) as u64).max(1);
                    chunk = ((CHUNK_BYTES / per_direction) as usize).clamp(threads, 64 * threads);
                    if send.send(done).is_err() {
                        break;
                    }
                }
                Err(e) => {
                    baked = Err(e);
                    break;
                }
            }
        }
        drop(send);
        let written = writer.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (written, baked)
    });
    progress.end();
    baked?;
    written?;

    progress.begin("writing", 1);
    let statistics = sections.finish(&mut f, &totals).map_err(io_err)?;
    let (_, header) = f.finish(hash).map_err(io_err)?;
    if shard.is_none() && header.file_length > ceiling {
        return Err(over_budget(header.file_length, direction_count as usize));
    }
    Ok(Baked { header, statistics, directions: range, direction_count })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{BakeConfig, choose};
    use crate::progress::NoProgress;
    use crate::scene::Scene;

    #[test]
    fn a_field_is_checked_against_the_coverage_its_choice_measured() {
        let scene = Scene::from_triangles("one", &[[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]).unwrap();
        let prep = Prepared::new(&scene);
        let config = BakeConfig { directions: Some(3), tiles: Some(4), ..BakeConfig::default() };
        let mut choice = choose(&prep, &config).unwrap();
        // A choice that says its largest direction makes 2⁵⁰ pairs is refused for memory: the
        // bake takes the choice's figures, it does not measure the one triangle again.
        choice.coverage.largest = 1 << 50;
        let output = std::env::temp_dir().join(format!("vlf-handed-on-{}.vlf", std::process::id()));
        let e = write_field(&prep, &choice, &config.request(), &output, &NoProgress).unwrap_err();
        assert!(matches!(e, BakeError::NotEnoughMemory { entries: 1_125_899_906_842_624, .. }), "{e}");
        assert!(!output.exists());
    }
}
