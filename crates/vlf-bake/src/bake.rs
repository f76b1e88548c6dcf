//! The bake (paper §3.1, §3.2, §4 and §5): for every direction, rotate the scene into the
//! direction's canonical frame, rasterise every triangle conservatively into the `n × n` tiles,
//! and give each tile a linearised 1D BSP along the beam.
//!
//! Directions are independent, so they are baked in parallel (rayon) in chunks, and each chunk is
//! written in direction order to spill files: the output bytes do not depend on the thread count,
//! and memory does not grow with the field's size. The spill files are anonymous temporary files
//! in the output directory; the field itself is written to a named temporary file there, flushed,
//! synced and renamed over the output path, so the path holds the old field or the new one, never
//! a partial one.

use crate::params::{Choice, DepthPolicy, Params};
use crate::raster::rasterize;
use crate::scene::Scene;
use crate::shard::ShardSpec;
use rayon::prelude::*;
use std::borrow::Cow;
use std::fs::File;
use std::io::{self, BufWriter, Seek, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use vlf_format::shard::{PER_DIRECTION_KINDS, SHARD_KIND, SHARD_MAGIC, ShardRecord, shard_directions, shared_hash};
use vlf_format::{
    BeamRecord, FieldFile, HashingWriter, Header, ParamsRecord, Request, SceneRecord, SectionEntry, SectionKind,
    SectionWriter, StatisticsRecord, TileRecord, VERSION_MAJOR, Z_LEVELS,
};
use vlf_geom::Lattice;
use vlf_geom::frame::{frame, mul};

/// Bumped whenever the baker's output for the same inputs and request changes (part of the input
/// hash, `formats/vlf.md` §3.2). Revision 2 (format 1.1) adds the MATERIALS, CAMERAS and LIGHTS
/// sections, and with them what an OBJ's `.mtl` files hold, to the input hash.
pub const BAKER_REVISION: u32 = 2;

/// The conservative margin as a fraction of the bounding radius (`formats/vlf.md` §6.2).
pub const MARGIN_FRACTION: f64 = 1.0 / (1u64 << 20) as f64;

/// Why a bake failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BakeError {
    #[error("cannot write {path}: {error}")]
    Io { path: PathBuf, error: io::Error },
    #[error("{0}")]
    Params(String),
    #[error(
        "direction {direction} needs {count} {what}, more than the format's 2^32 - 1 per direction; lower --tiles or the scene size"
    )]
    DirectionTooLarge { direction: usize, count: u64, what: &'static str },
    /// Explicit parameters produced more bytes than `--max-bytes` allows; the bake stopped as soon
    /// as it knew, and removed what it had written.
    #[error(
        "the field outgrew the --max-bytes ceiling of {ceiling} bytes ({at_least} bytes or more after {baked} of {directions} directions); lower --directions or --tiles, or raise --max-bytes"
    )]
    OverBudget { ceiling: u64, at_least: u64, baked: usize, directions: usize },
}

/// Progress callbacks; the CLI draws a bar, tests pass [`NoProgress`].
pub trait Progress: Sync {
    /// A phase with `total` units of work begins.
    fn begin(&self, _phase: &str, _total: u64) {}
    /// `done` more units of the current phase are complete.
    fn advance(&self, _done: u64) {}
    /// The current phase ended.
    fn end(&self) {}
}

/// Reports nothing.
pub struct NoProgress;
impl Progress for NoProgress {}

/// The scene prepared once for all directions: unique vertices relative to the sphere centre and
/// triangles as vertex indices.
pub struct Prepared<'a> {
    pub scene: &'a Scene,
    pub center: [f64; 3],
    pub radius: f64,
    pub aabb: ([f64; 3], [f64; 3]),
    /// Unique vertex positions minus the centre, in f64.
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl<'a> Prepared<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        let mut index = std::collections::HashMap::with_capacity(scene.triangles.len());
        let mut unique: Vec<[f32; 3]> = Vec::with_capacity(scene.triangles.len());
        let mut triangles = Vec::with_capacity(scene.triangles.len());
        for t in &scene.triangles {
            let mut tri = [0u32; 3];
            for (k, slot) in tri.iter_mut().enumerate() {
                let v = t.vertex(k);
                // Bit patterns as keys: -0.0 and 0.0 stay distinct, which is harmless.
                let key = v.map(f32::to_bits);
                *slot = *index.entry(key).or_insert_with(|| {
                    unique.push(v);
                    (unique.len() - 1) as u32
                });
            }
            triangles.push(tri);
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &unique {
            for i in 0..3 {
                lo[i] = lo[i].min(v[i] as f64);
                hi[i] = hi[i].max(v[i] as f64);
            }
        }
        let center: [f64; 3] = std::array::from_fn(|i| 0.5 * (lo[i] + hi[i]));
        let vertices: Vec<[f64; 3]> = unique.iter().map(|v| std::array::from_fn(|i| v[i] as f64 - center[i])).collect();
        let r2 = vertices.iter().map(|v| v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).fold(0.0f64, f64::max);
        // Grown a little so every vertex is strictly inside despite rounding.
        let radius = r2.sqrt() * (1.0 + 1e-9) + f64::MIN_POSITIVE;
        Prepared { scene, center, radius, aabb: (lo, hi), vertices, triangles }
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
}

/// One direction's part of the TILES, LEAF_BOUNDS and TRIANGLE_IDS sections.
pub struct DirectionData {
    pub tiles: Vec<TileRecord>,
    /// `leaf_count + 1` bounds, relative to the direction's first id.
    pub bounds: Vec<u32>,
    pub ids: Vec<u32>,
    pub stats: StatisticsRecord,
}

impl DirectionData {
    /// Bytes this direction adds to the file.
    pub fn bytes(&self) -> u64 {
        (self.tiles.len() * size_of::<TileRecord>() + 4 * (self.bounds.len() + self.ids.len())) as u64
            + size_of::<BeamRecord>() as u64
    }
}

/// One rasterised (tile, triangle) pair with the triangle's z range in the tile, grown by μ.
#[derive(Clone, Copy)]
struct Entry {
    tile: u32,
    tri: u32,
    z0: f64,
    z1: f64,
}

/// Reusable per-thread buffers.
#[derive(Default)]
pub struct Scratch {
    projected: Vec<[f64; 3]>,
    entries: Vec<Entry>,
    sorted: Vec<Entry>,
    tile_start: Vec<u32>,
    leaf_fill: Vec<u32>,
}

/// Bakes direction `j` (rotation `m`).
pub fn bake_direction(
    prep: &Prepared<'_>,
    params: &Params,
    m: &[f64; 9],
    j: usize,
    s: &mut Scratch,
) -> Result<DirectionData, BakeError> {
    let n = params.tiles;
    let n2 = n as usize * n as usize;
    let r = prep.radius;
    let w = 2.0 * r / n as f64;
    let margin = params.margin;
    let e = margin / w;

    // Canonical coordinates: (u, v) in tile units, z in world units.
    s.projected.clear();
    s.projected.extend(prep.vertices.iter().map(|&v| {
        let p = mul(m, v);
        [(p[0] + r) / w, (p[1] + r) / w, p[2]]
    }));
    s.entries.clear();
    for (id, tri) in prep.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|k| s.projected[k as usize]);
        let entries = &mut s.entries;
        rasterize(a, b, c, n, e, |ix, iy, z0, z1| {
            entries.push(Entry { tile: iy * n + ix, tri: id as u32, z0: z0 - margin, z1: z1 + margin });
        });
    }

    // Counting sort by tile; stable, so each tile's entries stay in triangle-id order.
    s.tile_start.clear();
    s.tile_start.resize(n2 + 1, 0);
    for en in &s.entries {
        s.tile_start[en.tile as usize + 1] += 1;
    }
    for i in 0..n2 {
        s.tile_start[i + 1] += s.tile_start[i];
    }
    s.sorted.clear();
    s.sorted.resize(s.entries.len(), Entry { tile: 0, tri: 0, z0: 0.0, z1: 0.0 });
    {
        let mut cursor = s.tile_start.clone();
        for en in &s.entries {
            let slot = &mut cursor[en.tile as usize];
            s.sorted[*slot as usize] = *en;
            *slot += 1;
        }
    }

    let mut out = DirectionData {
        tiles: Vec::with_capacity(n2),
        bounds: Vec::with_capacity(n2 + 1),
        ids: Vec::with_capacity(s.entries.len() + s.entries.len() / 2),
        stats: StatisticsRecord::zeroed_record(),
    };
    out.stats.tile_count = n2 as u64;
    let z_step = 2.0 * r / Z_LEVELS as f64;
    let mut first_leaf: u64 = 0;
    for tile in 0..n2 {
        let entries = &s.sorted[s.tile_start[tile] as usize..s.tile_start[tile + 1] as usize];
        if first_leaf > u32::MAX as u64 {
            return Err(BakeError::DirectionTooLarge { direction: j, count: first_leaf, what: "leaves" });
        }
        if entries.is_empty() {
            out.tiles.push(TileRecord::empty(first_leaf as u32));
            out.bounds.push(out.ids.len() as u32);
            out.stats.empty_tiles += 1;
            first_leaf += 1;
            continue;
        }
        let (zmin, zmax) =
            entries.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), en| (a.min(en.z0), b.max(en.z1)));
        // Quantise outward; a non-empty tile has z_lo < z_hi. (Casts truncate toward zero, which
        // equals floor here because negative values clamp to 0 anyway, and avoids a libm call.)
        let q_lo = (((zmin + r) / z_step) as i64).clamp(0, Z_LEVELS as i64 - 1) as u32;
        let above = (zmax + r) / z_step;
        let q_hi =
            (above as i64 + ((above as i64 as f64) < above) as i64).clamp(q_lo as i64 + 1, Z_LEVELS as i64) as u32;
        let z0 = -r + q_lo as f64 * z_step;
        let z1 = -r + q_hi as f64 * z_step;
        let depth = params.depth.depth_for(entries.len() as u64);
        let count = 1usize << depth;
        let h = (z1 - z0) / count as f64;
        // Truncation equals floor under the clamp (see above); the runtime computes the same.
        let leaf_of = |z: f64| (((z - z0) / h) as i64).clamp(0, count as i64 - 1) as usize;

        // Push each triangle to the leaves its (clipped, grown) z range overlaps: count, then fill.
        s.leaf_fill.clear();
        s.leaf_fill.resize(count + 1, 0);
        for en in entries {
            for k in leaf_of(en.z0)..=leaf_of(en.z1) {
                s.leaf_fill[k + 1] += 1;
            }
        }
        for k in 0..count {
            s.leaf_fill[k + 1] += s.leaf_fill[k];
        }
        let base = out.ids.len();
        for k in 0..count {
            out.bounds.push((base + s.leaf_fill[k] as usize) as u32);
        }
        out.ids.resize(base + s.leaf_fill[count] as usize, 0);
        for en in entries {
            for k in leaf_of(en.z0)..=leaf_of(en.z1) {
                out.ids[base + s.leaf_fill[k] as usize] = en.tri;
                s.leaf_fill[k] += 1;
            }
        }
        if out.ids.len() as u64 > u32::MAX as u64 {
            return Err(BakeError::DirectionTooLarge {
                direction: j,
                count: out.ids.len() as u64,
                what: "triangle ids",
            });
        }
        out.tiles.push(TileRecord {
            first_leaf: first_leaf as u32,
            z_lo: q_lo as u16,
            z_hi: q_hi as u16,
            depth: depth as u8,
            reserved: [0; 3],
        });
        first_leaf += count as u64;
        out.stats.tile_triangle_sum += entries.len() as u64;
        out.stats.max_tile_triangles = out.stats.max_tile_triangles.max(entries.len() as u32);
        out.stats.max_depth_used = out.stats.max_depth_used.max(depth);
        out.stats.depth_histogram[depth as usize] += 1;
    }
    if first_leaf > u32::MAX as u64 {
        return Err(BakeError::DirectionTooLarge { direction: j, count: first_leaf, what: "leaves" });
    }
    out.bounds.push(out.ids.len() as u32);
    out.stats.leaf_count = first_leaf;
    out.stats.id_count = out.ids.len() as u64;
    Ok(out)
}

/// Adds one direction's statistics into the field's.
pub(crate) fn merge_stats(total: &mut StatisticsRecord, d: &StatisticsRecord) {
    total.tile_count += d.tile_count;
    total.empty_tiles += d.empty_tiles;
    total.tile_triangle_sum += d.tile_triangle_sum;
    total.max_tile_triangles = total.max_tile_triangles.max(d.max_tile_triangles);
    total.max_depth_used = total.max_depth_used.max(d.max_depth_used);
    total.leaf_count += d.leaf_count;
    total.id_count += d.id_count;
    for (a, b) in total.depth_histogram.iter_mut().zip(&d.depth_histogram) {
        *a += b;
    }
}

/// What a bake produced.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BakeSummary {
    pub output: PathBuf,
    pub triangles: u64,
    pub dropped_degenerate: u64,
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

/// Human-facing digest of STATISTICS.
#[derive(Clone, Debug, serde::Serialize, PartialEq)]
pub struct Statistics {
    pub tiles: u64,
    pub empty_tile_share: f64,
    pub mean_triangles_per_tile: f64,
    pub mean_triangles_per_nonempty_tile: f64,
    pub max_triangles_per_tile: u32,
    pub max_depth_used: u32,
    pub mean_depth_nonempty: f64,
    pub depth_histogram: Vec<u64>,
    pub triangle_ids: u64,
    pub leaves: u64,
}

impl Statistics {
    /// Digests a record as stored; saturating, because an unverified file may hold anything.
    pub fn from_record(s: &StatisticsRecord) -> Self {
        let nonempty = s.tile_count.saturating_sub(s.empty_tiles);
        let used = (s.max_depth_used as usize).saturating_add(1).min(32);
        let depth_sum = s
            .depth_histogram
            .iter()
            .enumerate()
            .fold(0u64, |acc, (d, c)| acc.saturating_add((d as u64).saturating_mul(*c)));
        let ratio = |a: u64, b: u64| if b == 0 { 0.0 } else { a as f64 / b as f64 };
        Statistics {
            tiles: s.tile_count,
            empty_tile_share: ratio(s.empty_tiles, s.tile_count),
            mean_triangles_per_tile: ratio(s.tile_triangle_sum, s.tile_count),
            mean_triangles_per_nonempty_tile: ratio(s.tile_triangle_sum, nonempty),
            max_triangles_per_tile: s.max_tile_triangles,
            max_depth_used: s.max_depth_used,
            mean_depth_nonempty: ratio(depth_sum, nonempty),
            depth_histogram: s.depth_histogram[..used].to_vec(),
            triangle_ids: s.id_count,
            leaves: s.leaf_count,
        }
    }
}

/// The input hash of `formats/vlf.md` §3.2.
pub fn input_hash(scene: &Scene, request: &Request) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"VLF-INPUT\0");
    h.update(&VERSION_MAJOR.to_le_bytes());
    h.update(&BAKER_REVISION.to_le_bytes());
    h.update(bytemuck::bytes_of(request));
    for (_, bytes) in input_sections(scene) {
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    }
    *h.finalize().as_bytes()
}

/// Raw bytes of TRIANGLES, PROVENANCE, SOURCES, INPUTS, STRINGS, MATERIALS, CAMERAS, LIGHTS, in
/// that order: what the input hash covers (the last three are empty when the inputs define none).
fn input_sections(scene: &Scene) -> [(SectionKind, &[u8]); 8] {
    [
        (SectionKind::Triangles, bytemuck::cast_slice(&scene.triangles)),
        (SectionKind::Provenance, bytemuck::cast_slice(&scene.provenance)),
        (SectionKind::Sources, bytemuck::cast_slice(&scene.sources)),
        (SectionKind::Inputs, bytemuck::cast_slice(&scene.inputs)),
        (SectionKind::Strings, &scene.strings),
        (SectionKind::Materials, bytemuck::cast_slice(&scene.materials)),
        (SectionKind::Cameras, bytemuck::cast_slice(&scene.cameras)),
        (SectionKind::Lights, bytemuck::cast_slice(&scene.lights)),
    ]
}

/// A section that every file of a bake holds whole: a field, and each of its shards
/// (`formats/vlf-shard.md`), byte for byte.
pub struct SharedSection<'a> {
    pub kind: u32,
    pub element_size: u32,
    pub bytes: Cow<'a, [u8]>,
}

impl<'a> SharedSection<'a> {
    fn new(kind: SectionKind, bytes: impl Into<Cow<'a, [u8]>>) -> Self {
        SharedSection { kind: kind as u32, element_size: kind.element_size(), bytes: bytes.into() }
    }

    /// The table entry this section gets, but for its offset.
    pub fn entry(&self) -> SectionEntry {
        let len = self.bytes.len() as u64;
        SectionEntry {
            kind: self.kind,
            codec: vlf_format::codec::RAW,
            offset: 0,
            stored_length: len,
            raw_length: len,
            element_size: self.element_size,
            reserved: 0,
            raw_hash: *blake3::hash(&self.bytes).as_bytes(),
        }
    }
}

/// The kinds of the shared sections computed from the chosen parameters (with the scene's
/// sphere). Every other shared section depends on the scene alone, which is what the bake cache
/// keys on (`crate::cache`).
pub const PARAMETER_KINDS: [SectionKind; 4] =
    [SectionKind::Params, SectionKind::Directions, SectionKind::Rotations, SectionKind::Lookup];

/// The shared sections that depend on the scene alone, in file order: SCENE, then TRIANGLES,
/// PROVENANCE, SOURCES, INPUTS, STRINGS and the optional MATERIALS, CAMERAS, LIGHTS when the
/// inputs define any. A new section derived from the inputs goes here, so that
/// fields, shards, merges and the cache key all carry it.
pub fn scene_sections<'a>(prep: &Prepared<'a>) -> Vec<SharedSection<'a>> {
    let scene = prep.scene;
    let record = SceneRecord {
        center: prep.center,
        radius: prep.radius,
        aabb_min: prep.aabb.0,
        aabb_max: prep.aabb.1,
        triangle_count: scene.triangles.len() as u64,
        source_count: scene.sources.len() as u32,
        input_count: scene.inputs.len() as u32,
        dropped_degenerate: scene.report.dropped_degenerate,
        reserved: [0; 3],
    };
    // The optional sections (MATERIALS, CAMERAS, LIGHTS) are written only when not empty.
    std::iter::once(SharedSection::new(SectionKind::Scene, bytemuck::bytes_of(&record).to_vec()))
        .chain(
            input_sections(scene)
                .into_iter()
                .filter(|(kind, bytes)| kind.is_required() || !bytes.is_empty())
                .map(|(kind, bytes)| SharedSection::new(kind, bytes)),
        )
        .collect()
}

/// The shared sections computed from the chosen parameters ([`PARAMETER_KINDS`]), in file order.
fn parameter_sections(params: &Params, request: &Request) -> Vec<SharedSection<'static>> {
    let lattice = Lattice::new(params.lattice_n);
    let directions = lattice.directions();
    let rotations: Vec<[f64; 9]> = directions.iter().map(|&d| frame(d)).collect();
    let dir_records: Vec<[f32; 4]> = directions.iter().map(|d| [d[0] as f32, d[1] as f32, d[2] as f32, 0.0]).collect();
    let record = params_record(params, request);
    vec![
        SharedSection::new(SectionKind::Params, bytemuck::bytes_of(&record).to_vec()),
        SharedSection::new(SectionKind::Directions, bytemuck::cast_slice(&dir_records).to_vec()),
        SharedSection::new(SectionKind::Rotations, bytemuck::cast_slice(&rotations).to_vec()),
        SharedSection::new(SectionKind::Lookup, bytemuck::cast_slice(&lattice.lookup_table()).to_vec()),
    ]
}

/// The PARAMS record (`formats/vlf.md` §5.2) of a bake with `params` chosen for `request`.
pub fn params_record(params: &Params, request: &Request) -> ParamsRecord {
    ParamsRecord {
        lattice_n: params.lattice_n,
        direction_count: Lattice::new(params.lattice_n).direction_count() as u32,
        tile_resolution: params.tiles,
        leaf_size: params.depth.leaf_size,
        max_depth: params.depth.max_depth,
        requested_directions: request.requested_directions,
        requested_tiles: request.requested_tiles,
        reserved0: 0,
        max_bytes: request.max_bytes,
        margin: params.margin,
        max_bytes_per_triangle: request.max_bytes_per_triangle,
        reserved1: 0,
    }
}

/// Every shared section of the field, in file order: SCENE, the parameter sections, then the
/// rest of the scene sections. The per-direction sections (`vlf_format::shard::PER_DIRECTION_KINDS`)
/// follow them in every file a bake writes.
pub fn shared_sections<'a>(prep: &Prepared<'a>, params: &Params, request: &Request) -> Vec<SharedSection<'a>> {
    let mut sections = scene_sections(prep);
    sections.splice(1..1, parameter_sections(params, request));
    sections
}

/// A section spilled to an anonymous temporary file while it is produced.
struct Spill {
    writer: HashingWriter<BufWriter<File>>,
}

impl Spill {
    fn new(dir: &Path) -> io::Result<Spill> {
        Ok(Spill { writer: HashingWriter::new(BufWriter::with_capacity(1 << 20, tempfile::tempfile_in(dir)?)) })
    }

    fn finish(self) -> io::Result<(File, u64, [u8; 32])> {
        let (buf, len, hash) = self.writer.finish()?;
        let mut file = buf.into_inner().map_err(|e| e.into_error())?;
        file.rewind()?;
        Ok((file, len, hash))
    }
}

/// The directory that will hold `path`.
pub fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The per-direction sections of a file being baked, after its shared sections, in this order:
/// BEAMS and STATISTICS (reserved, filled last), TILES (reserved, filled direction by direction),
/// TRIANGLE_IDS (streamed behind it) and LEAF_BOUNDS (spilled to a temporary file, appended at
/// the end): each byte is written once. Fields and shards share this layout, which `merge`
/// follows to reproduce a field byte for byte.
struct DirectionSections {
    beams_out: SectionWriter,
    stats_out: SectionWriter,
    tiles: SectionWriter,
    ids: SectionWriter,
    bounds: Spill,
}

/// Direction by direction: the BEAMS records (bases counted from the file's first direction) and
/// the STATISTICS of the directions written so far.
#[derive(Default)]
struct DirectionTotals {
    beams: Vec<BeamRecord>,
    stats: Option<StatisticsRecord>,
    leaf_base: u64,
    id_base: u64,
}

impl DirectionSections {
    fn open(f: &mut FieldFile, directions: u64, n2: u64, spill_dir: &Path) -> io::Result<Self> {
        Ok(DirectionSections {
            beams_out: f.reserve(SectionKind::Beams, directions * size_of::<BeamRecord>() as u64)?,
            stats_out: f.reserve(SectionKind::Statistics, size_of::<StatisticsRecord>() as u64)?,
            tiles: f.reserve(SectionKind::Tiles, directions * n2 * size_of::<TileRecord>() as u64)?,
            ids: f.stream(SectionKind::TriangleIds)?,
            bounds: Spill::new(spill_dir)?,
        })
    }

    fn push(&mut self, d: &DirectionData, totals: &mut DirectionTotals) -> io::Result<()> {
        self.tiles.write_all(bytemuck::cast_slice(&d.tiles))?;
        self.ids.write_all(bytemuck::cast_slice(&d.ids))?;
        self.bounds.writer.write_all(bytemuck::cast_slice(&d.bounds))?;
        let leaf_count = d.bounds.len() as u64 - 1;
        let id_count = d.ids.len() as u64;
        totals.beams.push(BeamRecord { leaf_base: totals.leaf_base, leaf_count, id_base: totals.id_base, id_count });
        totals.leaf_base += leaf_count + 1;
        totals.id_base += id_count;
        merge_stats(totals.stats.get_or_insert_with(StatisticsRecord::zeroed_record), &d.stats);
        Ok(())
    }

    fn finish(mut self, f: &mut FieldFile, totals: &DirectionTotals) -> io::Result<StatisticsRecord> {
        f.finish_section(self.tiles)?;
        f.finish_section(self.ids)?;
        let (mut bounds_file, bounds_len, bounds_hash) = self.bounds.finish()?;
        f.append_from(SectionKind::LeafBounds, &mut bounds_file, bounds_len, bounds_hash)?;
        self.beams_out.write_all(bytemuck::cast_slice(&totals.beams))?;
        f.finish_section(self.beams_out)?;
        let stats = totals.stats.unwrap_or_else(StatisticsRecord::zeroed_record);
        self.stats_out.write_all(bytemuck::bytes_of(&stats))?;
        f.finish_section(self.stats_out)?;
        Ok(stats)
    }
}

/// Bakes `scene` with the chosen `choice` into the field file `output`, atomically.
pub fn bake_to_path(
    prep: &Prepared<'_>,
    choice: &Choice,
    request: &Request,
    output: &Path,
    progress: &dyn Progress,
) -> Result<BakeSummary, BakeError> {
    let start = Instant::now();
    let io_err = |error: io::Error| BakeError::Io { path: output.to_path_buf(), error };
    let tmp = AtomicFile::create(output).map_err(io_err)?;
    let baked = bake_into(prep, choice, request, tmp.file(), output, None, progress)?;
    tmp.commit().map_err(io_err)?;
    progress.end();
    Ok(baked.summary(prep, choice, output, start.elapsed().as_secs_f64()))
}

/// What [`bake_into`] wrote.
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

/// Bakes into `out` (an empty, writable file that will be at `path`; its directory holds the
/// spill file): the whole field, or with `shard` one shard of it (`formats/vlf-shard.md`).
///
/// The file is written in place, each byte once: the shared sections first (after the SHARD
/// record of a shard), then the per-direction sections ([`DirectionSections`]). Leaves the
/// "writing" progress phase open; the caller ends it after committing the file.
pub fn bake_into(
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

    let shared = shared_sections(prep, params, request);
    let direction_count = Lattice::new(params.lattice_n).direction_count() as u32;
    let range = match shard {
        None => 0..direction_count,
        Some(s) => shard_directions(s.index, s.count, direction_count),
    };
    let rotations: Vec<[f64; 9]> = Lattice::new(params.lattice_n).directions().iter().map(|&d| frame(d)).collect();
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
    let fixed = (vlf_format::HEADER_SIZE + vlf_format::TABLE_ENTRY_SIZE * (shared.len() + PER_DIRECTION_KINDS.len()))
        as u64
        + shared.iter().map(|s| s.bytes.len() as u64).sum::<u64>()
        + l * (size_of::<BeamRecord>() as u64 + n2 * size_of::<TileRecord>() as u64)
        + size_of::<StatisticsRecord>() as u64;
    let over_budget =
        |at_least: u64, baked: usize| BakeError::OverBudget { ceiling, at_least, baked, directions: l as usize };
    let mut sections = DirectionSections::open(&mut f, range.len() as u64, n2, &parent_dir(path)).map_err(io_err)?;

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
                    let at_least =
                        fixed + 4 * (totals_w.leaf_base + totals_w.id_base + (d.bounds.len() + d.ids.len()) as u64);
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
                    let d = bake_direction(prep, params, &rotations[j], j, s);
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

/// A file being written next to its final path: a temporary file `.NAME.XXXXXX.tmp` in the same
/// directory (`XXXXXX` six random letters and digits), renamed over the path by
/// [`AtomicFile::commit`] after it is flushed and synced, after which the directory is synced too.
/// Dropped without a commit (an error, a panic), it is removed.
///
/// A process killed while writing (`SIGKILL`, a crash, a power cut) leaves the path untouched and
/// the temporary file beside it. The writer holds an exclusive advisory lock (`flock`) on its
/// temporary file, which the kernel releases when the process dies, so a later write of the same
/// path can tell a leftover from a file being written: [`remove_stale_temp_files`] removes the
/// leftovers that nobody holds locked and that are older than [`STALE_TEMP_AGE`].
pub struct AtomicFile {
    tmp: tempfile::NamedTempFile,
    path: PathBuf,
}

/// How old an unlocked temporary file must be before a later write of the same path removes it.
/// The lock decides; the age only covers the instant between a writer creating its temporary
/// file and locking it.
pub const STALE_TEMP_AGE: Duration = Duration::from_secs(60);

/// Length of the random part of a temporary file's name.
const TEMP_RANDOM_LEN: usize = 6;

/// The file type of an existing path that is not a regular file (a device, FIFO or socket), which
/// must be written in place, never replaced by a rename.
fn special_file(path: &Path) -> Option<std::fs::FileType> {
    std::fs::metadata(path).ok().map(|m| m.file_type()).filter(|t| !t.is_file() && !t.is_dir())
}

/// The prefix of the temporary files that write `path`: `.NAME.`.
fn temp_prefix(path: &Path) -> String {
    let name = path.file_name().map_or("field".into(), |n| n.to_string_lossy().into_owned());
    format!(".{name}.")
}

impl AtomicFile {
    /// Starts writing `path`, first removing stale temporary files that killed writers of the same
    /// path left behind. Refuses a path that exists and is not a regular file: a directory, or a
    /// device or FIFO (renaming over it would replace the device node, and a field needs
    /// positioned writes).
    pub fn create(path: &Path) -> io::Result<AtomicFile> {
        if special_file(path).is_some() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{} is not a regular file (a device or FIFO); write the field to a file path", path.display()),
            ));
        }
        if path.is_dir() {
            return Err(io::Error::new(
                io::ErrorKind::IsADirectory,
                "the path is a directory; give the path of a file, such as DIR/scene.vlf",
            ));
        }
        remove_stale_temp_files(path);
        let prefix = temp_prefix(path);
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp").rand_bytes(TEMP_RANDOM_LEN);
        // A new file's usual permissions (0666 less the umask), not tempfile's private 0600.
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let tmp = builder.tempfile_in(parent_dir(path))?;
        // Marks the file as being written for as long as this process lives. Where the file
        // system has no locks, nothing is marked, and no leftover is ever removed as stale.
        try_lock(tmp.as_file());
        Ok(AtomicFile { tmp, path: path.to_path_buf() })
    }

    pub fn file(&self) -> &File {
        self.tmp.as_file()
    }

    /// The temporary file's path (in the destination directory), for checks before the commit.
    pub fn temp_path(&self) -> &Path {
        self.tmp.path()
    }

    /// Syncs the file and renames it over the path, then syncs the directory.
    pub fn commit(self) -> io::Result<()> {
        self.tmp.as_file().sync_all()?;
        self.tmp.persist(&self.path).map_err(|e| e.error)?;
        // Makes the rename durable. Some file systems refuse to sync a directory; the rename has
        // happened either way.
        if let Ok(d) = File::open(parent_dir(&self.path)) {
            let _ = d.sync_all();
        }
        Ok(())
    }
}

/// Removes the temporary files (`.NAME.XXXXXX.tmp`, see [`AtomicFile`]) that writers of `path`
/// killed before they could clean up left in its directory: regular files that no process holds
/// locked and that were last modified at least [`STALE_TEMP_AGE`] ago. Returns how many it removed.
/// Never fails: a file it cannot inspect, lock or remove is left alone.
pub fn remove_stale_temp_files(path: &Path) -> usize {
    let prefix = temp_prefix(path);
    let Ok(entries) = std::fs::read_dir(parent_dir(path)) else { return 0 };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(random) = name.to_str().and_then(|n| n.strip_prefix(&prefix)?.strip_suffix(".tmp")) else {
            continue;
        };
        if random.len() == TEMP_RANDOM_LEN
            && random.bytes().all(|b| b.is_ascii_alphanumeric())
            && remove_if_stale(&entry.path()).unwrap_or(false)
        {
            removed += 1;
        }
    }
    removed
}

/// Takes an exclusive advisory lock (`flock`) on `file` without waiting, held until every handle
/// of this open file is closed (or the process dies). False if another holds it, or the platform or
/// file system has no such locks.
fn try_lock(file: &File) -> bool {
    #[cfg(unix)]
    {
        rustix::fs::flock(file, rustix::fs::FlockOperation::NonBlockingLockExclusive).is_ok()
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        false
    }
}

/// Removes `candidate` if it is a regular file, old enough, and unlocked (its writer is gone).
fn remove_if_stale(candidate: &Path) -> io::Result<bool> {
    let meta = std::fs::symlink_metadata(candidate)?;
    if !meta.file_type().is_file() || meta.modified()?.elapsed().unwrap_or_default() < STALE_TEMP_AGE {
        return Ok(false);
    }
    let file = File::open(candidate)?;
    if !try_lock(&file) {
        return Ok(false);
    }
    // The name still leads to the file we locked (nobody replaced it in between).
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let (now, held) = (std::fs::symlink_metadata(candidate)?, file.metadata()?);
        if (now.dev(), now.ino()) != (held.dev(), held.ino()) {
            return Ok(false);
        }
    }
    std::fs::remove_file(candidate)?;
    Ok(true)
}

/// Writes a file atomically through a buffered writer (see [`AtomicFile`]). A path that exists
/// and is not a regular file (`/dev/null`, a FIFO, `/dev/stdout`) is written in place instead:
/// replacing a device node by a rename would break it for every other program.
pub fn write_atomically<T>(path: &Path, write: impl FnOnce(&mut BufWriter<&File>) -> io::Result<T>) -> io::Result<T> {
    if special_file(path).is_some() {
        let file = File::options().write(true).open(path)?;
        let mut w = BufWriter::with_capacity(1 << 20, &file);
        let value = write(&mut w)?;
        w.flush()?;
        return Ok(value);
    }
    let tmp = AtomicFile::create(path)?;
    let value = {
        let mut w = BufWriter::with_capacity(1 << 20, tmp.file());
        let value = write(&mut w)?;
        w.flush()?;
        value
    };
    tmp.commit()?;
    Ok(value)
}

impl DepthPolicy {
    /// The depth of a tile with `m` distinct triangles (`formats/vlf.md` §6.3).
    pub fn depth_for(&self, m: u64) -> u32 {
        let mut depth = 0;
        while depth < self.max_depth && (self.leaf_size as u64) << depth < m {
            depth += 1;
        }
        depth
    }
}

/// Re-exported for the parameter chooser's size estimates.
pub(crate) fn sample_direction_bytes(
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
        .map_init(Scratch::default, |s, &j| bake_direction(prep, params, &frame(dirs[j]), j, s))
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
