//! The triangles inserted into a mapped field, in the field's own directions, tiles and leaves
//! (the paper's §7: "reinserted into both the tiling and BSP structures"), kept in memory beside
//! the untouched mapped bytes.
//!
//! The overlay is a field of its own in every respect a query reads: the mapped field's
//! directions, rotations, lattice lookup, tile grid and margin, and its own TILES, LEAVES, BEAMS
//! and TRIANGLES, built by the bake's kernel (`vlf-raster`) into the blocks of `formats/vlf.md`
//! §5.6. So the runtime's query walks it unchanged ([`FieldView::from_reader`]), with every
//! guarantee of §6.2.
//!
//! An edit rebuilds only the tiles it touches: per direction, the inserted triangles and the
//! removed ones are rasterised (the paper's delete: "the object rasterised into the tiling
//! coordinate system as usual, except that in this case the identifiers of the object are removed
//! rather than added"); each touched tile's block is rebuilt from the triangles it keeps (found in
//! its old block and rasterised again, which gives their entries exactly) plus the new ones, and
//! appended; the old block becomes garbage, compacted away once it is half the words.
//!
//! Memory: the TILES of every direction (`4 · l · n²` bytes, allocated at the first insertion,
//! as large as the mapped field's TILES section) plus the blocks, about what the same triangles
//! take in a baked field.

use std::ops::Range;
use std::sync::Arc;
use vlf_format::block::Block;
use vlf_format::{BeamRecord, EMPTY_TILE, FieldReader, SceneRecord, TriangleRecord};
use vlf_raster::{Entry, Grid, Scratch};
use vlf_runtime::{Field, FieldView};

/// The overlay's owned sections, with the mapped field they extend.
pub(crate) struct Sections {
    pub(crate) base: Arc<Field>,
    grid: Grid,
    /// The inserted triangles, relative to the field's centre; overlay id `k` is field id
    /// `base.triangle_count() + k`.
    pub(crate) triangles: Vec<TriangleRecord>,
    /// `l · n²` entries: a block's first word in `words`, or `EMPTY_TILE`. Empty until the first
    /// insertion.
    tiles: Vec<u32>,
    words: Vec<u64>,
    /// Words of `words` no tile points to any more.
    garbage: usize,
    beams: Vec<BeamRecord>,
    /// The mapped field's SCENE with the box of the live inserted triangles.
    scene: SceneRecord,
}

self_cell::self_cell!(
    /// The sections and the query engine over them.
    pub(crate) struct Overlay {
        owner: Sections,
        #[covariant]
        dependent: FieldView,
    }
);

/// Why an overlay could not take an edit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TooLarge;

impl Sections {
    fn new(base: Arc<Field>) -> Sections {
        let reader = *base.reader();
        let p = base.parameters();
        let grid = Grid {
            tiles: p.tiles,
            lattice_n: p.lattice_n,
            radius: reader.scene.radius,
            margin: p.margin,
            depth: vlf_raster::DepthPolicy { leaf_size: p.leaf_size, max_depth: p.max_depth },
        };
        let mut scene = *reader.scene;
        scene.aabb_min = [f64::INFINITY; 3];
        scene.aabb_max = [f64::NEG_INFINITY; 3];
        scene.triangle_count = 0;
        Sections {
            base,
            grid,
            triangles: Vec::new(),
            tiles: Vec::new(),
            words: Vec::new(),
            garbage: 0,
            beams: Vec::new(),
            scene,
        }
    }

    /// The live inserted triangles.
    pub(crate) fn live(&self) -> u64 {
        self.scene.triangle_count
    }

    /// The reader of the overlay: the mapped field's shared sections, the overlay's own tiles.
    fn reader(&self) -> FieldReader<'_> {
        let r = *self.base.reader();
        FieldReader {
            bytes: &[],
            scene: &self.scene,
            beams: &self.beams,
            tiles: &self.tiles,
            leaves: &self.words,
            triangles: &self.triangles,
            provenance: &[],
            sources: &[],
            inputs: &[],
            strings: &[],
            materials: &[],
            cameras: &[],
            lights: &[],
            duplicates: &[],
            ..r
        }
    }
}

impl Overlay {
    pub(crate) fn empty(base: Arc<Field>) -> Overlay {
        Overlay::build(Sections::new(base))
    }

    fn build(sections: Sections) -> Overlay {
        Overlay::new(sections, |s| FieldView::from_reader(s.reader()))
    }

    pub(crate) fn sections(&self) -> &Sections {
        self.borrow_owner()
    }

    pub(crate) fn view(&self) -> &FieldView<'_> {
        self.borrow_dependent()
    }

    /// The box of the live inserted triangles relative to the field's centre (empty if none).
    pub(crate) fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let s = &self.sections().scene;
        (s.aabb_min, s.aabb_max)
    }

    /// Appends `triangles` (relative to the centre, inside the bounding sphere: the caller
    /// checked) and rasterises them into every direction; `dead(k)` tells which overlay ids are
    /// removed. Returns the overlay ids they got.
    pub(crate) fn insert(
        self,
        triangles: &[TriangleRecord],
        dead: &(dyn Fn(u32) -> bool + Sync),
    ) -> Result<(Overlay, Range<u32>), (Overlay, TooLarge)> {
        let mut s = self.into_owner();
        let first = s.triangles.len() as u32;
        s.triangles.extend_from_slice(triangles);
        let added = first..s.triangles.len() as u32;
        match update(&mut s, added.clone(), &[], dead) {
            Ok(()) => Ok((Overlay::build(s), added)),
            Err(e) => {
                s.triangles.truncate(first as usize);
                Err((Overlay::build(s), e))
            }
        }
    }

    /// Removes the overlay ids `removed` (already marked by `dead`) from every tile that holds
    /// them.
    pub(crate) fn remove(
        self,
        removed: &[u32],
        dead: &(dyn Fn(u32) -> bool + Sync),
    ) -> Result<Overlay, (Overlay, TooLarge)> {
        let mut s = self.into_owner();
        match update(&mut s, 0..0, removed, dead) {
            Ok(()) => Ok(Overlay::build(s)),
            Err(e) => Err((Overlay::build(s), e)),
        }
    }
}

/// One direction's new blocks: `(tile, offset in words or EMPTY_TILE)` for every touched tile,
/// and the words of its blocks.
struct DirectionUpdate {
    tiles: Vec<(u32, u32)>,
    words: Vec<u64>,
}

/// Rasterises `added` and `removed` into every direction and rebuilds the tiles they touch, then
/// recomputes the box. Nothing changes on an error.
fn update(
    s: &mut Sections,
    added: Range<u32>,
    removed: &[u32],
    dead: &(dyn Fn(u32) -> bool + Sync),
) -> Result<(), TooLarge> {
    if added.is_empty() && removed.is_empty() {
        return Ok(());
    }
    let reader = *s.base.reader();
    let l = reader.rotations.len();
    let n2 = s.grid.tiles as usize * s.grid.tiles as usize;
    if s.tiles.is_empty() {
        s.tiles = vec![EMPTY_TILE; l * n2];
        s.beams = vec![BeamRecord { leaves_base: 0, leaves_words: 0, leaf_count: 0, ref_count: 0 }; l];
    }
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).min(l.max(1));
    let per = l.div_ceil(threads);
    let (grid, tiles, words, tris) = (&s.grid, &s.tiles, &s.words, &s.triangles);
    let results: Vec<Result<Vec<DirectionUpdate>, TooLarge>> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|t| {
                let range = (t * per).min(l)..((t + 1) * per).min(l);
                let added = added.clone();
                scope.spawn(move || {
                    let mut scratch = Scratch::default();
                    range
                        .map(|j| {
                            let dir_tiles = &tiles[j * n2..(j + 1) * n2];
                            update_direction(
                                grid,
                                &reader.rotations[j],
                                dir_tiles,
                                words,
                                tris,
                                added.clone(),
                                removed,
                                dead,
                                &mut scratch,
                            )
                        })
                        .collect()
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join().unwrap_or_else(|p| std::panic::resume_unwind(p))).collect()
    });
    let mut updates = Vec::with_capacity(l);
    for r in results {
        updates.extend(r?);
    }
    let new_words: usize = updates.iter().map(|u| u.words.len()).sum();
    if s.words.len() - s.garbage + new_words >= EMPTY_TILE as usize {
        return Err(TooLarge);
    }
    if s.words.len() + new_words >= EMPTY_TILE as usize {
        compact(s);
    }
    for (j, u) in updates.into_iter().enumerate() {
        let base = s.words.len() as u32;
        for (tile, offset) in u.tiles {
            let slot = &mut s.tiles[j * n2 + tile as usize];
            if *slot != EMPTY_TILE {
                s.garbage += Block::parse(&s.words[*slot as usize..]).map_or(0, |b| b.words());
            }
            *slot = if offset == EMPTY_TILE { EMPTY_TILE } else { base + offset };
        }
        s.words.extend_from_slice(&u.words);
    }
    if s.garbage > s.words.len() / 2 {
        compact(s);
    }
    let (mut lo, mut hi, mut live) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3], 0u64);
    for (k, t) in s.triangles.iter().enumerate() {
        if dead(k as u32) {
            continue;
        }
        live += 1;
        for v in t.v {
            for a in 0..3 {
                lo[a] = lo[a].min(v[a] as f64);
                hi[a] = hi[a].max(v[a] as f64);
            }
        }
    }
    s.scene.aabb_min = lo;
    s.scene.aabb_max = hi;
    s.scene.triangle_count = live;
    Ok(())
}

/// Copies every live block to a new word array, dropping the garbage.
fn compact(s: &mut Sections) {
    let mut words = Vec::with_capacity(s.words.len() - s.garbage);
    for slot in s.tiles.iter_mut().filter(|t| **t != EMPTY_TILE) {
        let at = *slot as usize;
        let len = Block::parse(&s.words[at..]).map_or(0, |b| b.words());
        *slot = words.len() as u32;
        words.extend_from_slice(&s.words[at..at + len]);
    }
    s.words = words;
    s.garbage = 0;
}

/// The canonical corners of overlay triangle `k` in the direction of rotation `m`.
fn projected(grid: &Grid, m: &[f64; 9], t: &TriangleRecord) -> [[f64; 3]; 3] {
    t.v.map(|v| grid.project(m, v.map(f64::from)))
}

/// One direction of [`update`]: the tiles that `added` and `removed` touch, rebuilt.
#[allow(clippy::too_many_arguments)]
fn update_direction(
    grid: &Grid,
    m: &[f64; 9],
    tiles: &[u32],
    words: &[u64],
    tris: &[TriangleRecord],
    added: Range<u32>,
    removed: &[u32],
    dead: &(dyn Fn(u32) -> bool + Sync),
    scratch: &mut Scratch,
) -> Result<DirectionUpdate, TooLarge> {
    let mut entries: Vec<Entry> = Vec::new();
    for k in added.clone() {
        let [a, b, c] = projected(grid, m, &tris[k as usize]);
        grid.rasterize(k, a, b, c, |e| entries.push(e));
    }
    // The tiles to rebuild: where the new triangles land and where the removed ones were.
    let mut touched: Vec<u32> = entries.iter().map(|e| e.tile).collect();
    for &k in removed {
        let [a, b, c] = projected(grid, m, &tris[k as usize]);
        grid.rasterize(k, a, b, c, |e| touched.push(e.tile));
    }
    touched.sort_unstable();
    touched.dedup();
    // The triangles those tiles keep, rasterised again for their exact entries there.
    let mut kept: Vec<u32> = Vec::new();
    for &tile in &touched {
        let entry = tiles[tile as usize];
        if entry == EMPTY_TILE {
            continue;
        }
        let Some(block) = words.get(entry as usize..).and_then(Block::parse) else { continue };
        for leaf in (0..block.leaf_count()).filter_map(|k| block.leaf(k)) {
            kept.extend(block.ids(leaf).iter().copied().filter(|&id| !dead(id) && !added.contains(&id)));
        }
    }
    kept.sort_unstable();
    kept.dedup();
    for &k in &kept {
        let [a, b, c] = projected(grid, m, &tris[k as usize]);
        grid.rasterize(k, a, b, c, |e| {
            if touched.binary_search(&e.tile).is_ok() {
                entries.push(e);
            }
        });
    }
    entries.sort_unstable_by_key(|e| (e.tile, e.tri));
    let mut out = DirectionUpdate { tiles: Vec::with_capacity(touched.len()), words: Vec::new() };
    let mut at = 0;
    for &tile in &touched {
        let start = at;
        while at < entries.len() && entries[at].tile == tile {
            at += 1;
        }
        if start == at {
            out.tiles.push((tile, EMPTY_TILE));
            continue;
        }
        let offset = out.words.len() as u32;
        grid.write_tile(&entries[start..at], scratch, &mut out.words, vlf_raster::MAX_WORDS).map_err(|_| TooLarge)?;
        out.tiles.push((tile, offset));
    }
    Ok(out)
}
