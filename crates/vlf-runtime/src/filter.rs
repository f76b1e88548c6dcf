//! The ref filter: which refs of a leaf have a box that the ray's box meets
//! (`formats/vlf.md` §5.6). A leaf's refs are tested sixteen at a time against the ray's box, from
//! the block's four arrays of quantized box bounds, without touching the triangles; only the refs
//! that pass go on to the triangle test.
//!
//! A ref passes when `x_lo ≤ rx_hi`, `x_hi ≥ rx_lo`, `y_lo ≤ ry_hi` and `y_hi ≥ ry_lo`. The block
//! stores `255 − x_hi` and `255 − y_hi`, so all four tests read "stored ≤ limit", that is
//! `stored −sat limit = 0`: one saturating subtraction per array and a compare with zero, which
//! SSE2 (part of every x86-64) does for sixteen refs at once. [`pass_mask_scalar`] is the plain
//! twin the tests hold it to, and what other targets use.

use crate::prefetch::prefetch;
use vlf_format::TriangleRecord;
#[cfg(doc)]
use vlf_format::block::Block;

/// The limits a ref's stored box bytes must not exceed: `[rx_hi, 255 − rx_lo, ry_hi, 255 − ry_lo]`.
pub(crate) type Limits = [u8; 4];

/// The limits for a ray box covering the cells `x_lo..=x_hi`, `y_lo..=y_hi`.
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
pub(crate) fn limits(x_lo: u8, x_hi: u8, y_lo: u8, y_hi: u8) -> Limits {
    [x_hi, 255 - x_lo, y_hi, 255 - y_lo]
}

/// The limits ([`limits`]) of the box of cells covering the segment from `a` to `b` (points in a
/// tile's cells, `[x, y]`), grown by `margin` cells: the plain twin of [`segment_limits`].
///
/// Each bound is clamped to `[0, 255]` and truncated to its cell. The minimum and maximum are
/// those of SSE2 (`minpd`, `maxpd`: the second operand when the comparison fails, a NaN among
/// them), so that the two twins agree on every input; a NaN from a lying file gives some valid
/// limits, never a panic.
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
pub(crate) fn segment_limits_scalar(a: [f64; 2], b: [f64; 2], margin: f64) -> Limits {
    let min = |p: f64, q: f64| if p < q { p } else { q };
    let max = |p: f64, q: f64| if p > q { p } else { q };
    let cell = |v: f64| min(max(v, 0.0), 255.0) as u8;
    let lo = |i: usize| cell(min(a[i], b[i]) - margin);
    let hi = |i: usize| cell(max(a[i], b[i]) + margin);
    limits(lo(0), hi(0), lo(1), hi(1))
}

/// [`segment_limits_scalar`], both axes per instruction.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn segment_limits(a: [f64; 2], b: [f64; 2], margin: f64) -> Limits {
    use std::arch::x86_64::*;
    // SAFETY: these intrinsics need SSE2, which every x86-64 CPU has (it is in the target's
    // baseline features); they read and write only their register arguments.
    unsafe {
        let (a, b) = (_mm_set_pd(a[1], a[0]), _mm_set_pd(b[1], b[0]));
        let mu = _mm_set1_pd(margin);
        let cells = |v: __m128d| _mm_cvttpd_epi32(_mm_min_pd(_mm_max_pd(v, _mm_setzero_pd()), _mm_set1_pd(255.0)));
        let lo = cells(_mm_sub_pd(_mm_min_pd(a, b), mu));
        let hi = cells(_mm_add_pd(_mm_max_pd(a, b), mu));
        // [x_hi, 255 − x_lo, y_hi, 255 − y_lo] as four i32, then as four bytes (all in 0..=255).
        let words = _mm_unpacklo_epi32(hi, _mm_sub_epi32(_mm_set1_epi32(255), lo));
        let bytes = _mm_packus_epi16(_mm_packs_epi32(words, words), _mm_setzero_si128());
        (_mm_cvtsi128_si32(bytes) as u32).to_le_bytes()
    }
}

/// [`segment_limits_scalar`] on targets without a vector twin.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
pub(crate) fn segment_limits(a: [f64; 2], b: [f64; 2], margin: f64) -> Limits {
    segment_limits_scalar(a, b, margin)
}

/// Bit `i` set if ref `i` of the sixteen in `lanes` (one array per box bound) passes: the plain
/// twin of [`pass_mask`].
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
pub(crate) fn pass_mask_scalar(lanes: &[[u8; 16]; 4], limits: Limits) -> u32 {
    (0..16).filter(|&i| lanes.iter().zip(limits).all(|(lane, limit)| lane[i] <= limit)).fold(0, |mask, i| mask | 1 << i)
}

/// [`pass_mask_scalar`], sixteen refs per instruction.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn pass_mask(lanes: &[[u8; 16]; 4], limits: Limits) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: these intrinsics need SSE2, which every x86-64 CPU has (it is in the target's
    // baseline features); they read and write only their register arguments.
    unsafe {
        let over = |a: usize| {
            let lane: __m128i = bytemuck::cast(lanes[a]);
            _mm_subs_epu8(lane, _mm_set1_epi8(limits[a] as i8))
        };
        let any_over = _mm_or_si128(_mm_or_si128(over(0), over(1)), _mm_or_si128(over(2), over(3)));
        _mm_movemask_epi8(_mm_cmpeq_epi8(any_over, _mm_setzero_si128())) as u32
    }
}

/// [`pass_mask_scalar`] on targets without a vector twin.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
pub(crate) fn pass_mask(lanes: &[[u8; 16]; 4], limits: Limits) -> u32 {
    pass_mask_scalar(lanes, limits)
}

/// Refs filtered at a time: the bits of a `u64` mask, four groups of sixteen.
const CHUNK: usize = 64;

/// The triangle ids of the refs of a leaf of a block whose boxes pass `limits`, in ref order.
#[derive(Clone)]
pub(crate) struct Passing<'a> {
    /// The leaf's bytes from its first box array on ([`Block::leaf_bytes`]): box array `a` at
    /// `a · len`, the ids at `4 · len`.
    bytes: &'a [u8],
    len: usize,
    limits: Limits,
    /// First ref of the current chunk of up to [`CHUNK`] refs.
    chunk: usize,
    /// The refs of the current chunk that passed and are not yet returned.
    mask: u64,
    /// Triangle records to start loading for each chunk's passing refs (empty: none).
    load: &'a [TriangleRecord],
}

impl<'a> Passing<'a> {
    /// The passing refs of the leaf of `len` refs whose bytes are `bytes` ([`Block::leaf_bytes`]);
    /// as each chunk is filtered, the records in `load` of its passing refs start loading (pass
    /// `&[]` for no such hint).
    #[inline(always)]
    pub(crate) fn new(bytes: &'a [u8], len: usize, limits: Limits, load: &'a [TriangleRecord]) -> Self {
        let mut p = Passing { bytes, len, limits, chunk: 0, mask: 0, load };
        p.fill();
        p
    }

    /// The triangle id of ref `i`, if the leaf's bytes hold it.
    #[inline(always)]
    fn id(&self, i: usize) -> Option<u32> {
        let at = 4 * (self.len + i);
        Some(u32::from_le_bytes(self.bytes.get(at..at + 4)?.try_into().ok()?))
    }

    /// Starts loading the records of the current chunk's passing refs.
    #[inline(always)]
    fn load_chunk(&self) {
        if self.load.is_empty() {
            return;
        }
        let mut mask = self.mask;
        while mask != 0 {
            let i = self.chunk + mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if let Some(record) = self.id(i).and_then(|id| self.load.get(id as usize)) {
                prefetch(record);
            }
        }
    }

    /// Sixteen bytes of each box array from ref `at` on, 255 past the section's end.
    #[inline(always)]
    fn lanes(&self, at: usize) -> [[u8; 16]; 4] {
        let len = self.len;
        let lane = |from: &[u8], a: usize| -> [u8; 16] { from[a * len..a * len + 16].try_into().expect("16 bytes") };
        match self.bytes.get(at..at + 3 * len + 16) {
            // One bounds check for the four arrays (the last one's lane may run into the ids).
            Some(window) => [lane(window, 0), lane(window, 1), lane(window, 2), lane(window, 3)],
            None => std::array::from_fn(|a| {
                let mut lane = [255u8; 16];
                let tail = self.bytes.get(at + a * len..).unwrap_or(&[]);
                let n = tail.len().min(16);
                lane[..n].copy_from_slice(&tail[..n]);
                lane
            }),
        }
    }

    /// The pass mask of the `n ≤ CHUNK` refs from the current chunk on, in groups of sixteen
    /// (bits past `n` are those of the bytes that follow, to be masked off).
    #[inline(always)]
    fn chunk_mask(&self, n: usize) -> u64 {
        let (at, len) = (self.chunk, self.len);
        let span = n.next_multiple_of(16);
        let array = |window: &'a [u8], a: usize| &window[a * len..a * len + span];
        match self.bytes.get(at..at + 3 * len + span) {
            // One bounds check for the chunk's four arrays (the last one's groups may run into
            // the ids), and its groups as exact chunks of sixteen, which need none.
            Some(window) => {
                let (x_lo, x_hi) = (array(window, 0).chunks_exact(16), array(window, 1).chunks_exact(16));
                let (y_lo, y_hi) = (array(window, 2).chunks_exact(16), array(window, 3).chunks_exact(16));
                let lane = |c: &[u8]| -> [u8; 16] { c.try_into().expect("an exact chunk of sixteen") };
                x_lo.zip(x_hi).zip(y_lo.zip(y_hi)).enumerate().fold(0, |mask, (g, ((a, b), (c, d)))| {
                    mask | (pass_mask(&[lane(a), lane(b), lane(c), lane(d)], self.limits) as u64) << (16 * g)
                })
            }
            None => (0..span)
                .step_by(16)
                .fold(0, |mask, g| mask | (pass_mask(&self.lanes(at + g), self.limits) as u64) << g),
        }
    }

    /// Whether no ref is left.
    #[inline(always)]
    pub(crate) fn is_done(&self) -> bool {
        self.mask == 0
    }

    /// Moves to the first chunk with a passing ref, or to the end. A chunk's groups of sixteen
    /// are filtered in one tight loop, apart from the triangle tests that consume its refs, so
    /// that the loop keeps its few values in registers (most leaves are one chunk).
    #[inline(always)]
    fn fill(&mut self) {
        while self.chunk < self.len {
            let left = self.len - self.chunk;
            let mask = self.chunk_mask(left.min(CHUNK));
            self.mask = if left >= CHUNK { mask } else { mask & ((1u64 << left) - 1) };
            if self.mask != 0 {
                self.load_chunk();
                return;
            }
            self.chunk += CHUNK;
        }
    }
}

impl Iterator for Passing<'_> {
    type Item = u32;

    #[inline(always)]
    fn next(&mut self) -> Option<u32> {
        if self.mask == 0 {
            return None;
        }
        let i = self.chunk + self.mask.trailing_zeros() as usize;
        self.mask &= self.mask - 1;
        if self.mask == 0 {
            self.chunk += CHUNK;
            self.fill();
        }
        self.id(i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::xorshift;
    use vlf_format::block::{Block, Ref, write_block};

    #[test]
    fn the_vector_mask_is_the_scalar_mask() {
        let mut next = xorshift(7);
        for _ in 0..100_000 {
            let lanes: [[u8; 16]; 4] = std::array::from_fn(|_| std::array::from_fn(|_| next() as u8));
            let l = next().to_le_bytes();
            let limits = [l[0], l[1], l[2], l[3]];
            assert_eq!(pass_mask(&lanes, limits), pass_mask_scalar(&lanes, limits));
        }
    }

    #[test]
    fn the_vector_segment_limits_are_the_scalar_ones() {
        let mut next = xorshift(13);
        // Cells in and around a tile, some far outside, and the values a lying file can give.
        let specials = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 0.0, 255.0, 255.5, 256.0, -1e300, 1e300];
        let mut value = move || match next() % 8 {
            0 => specials[(next() % specials.len() as u64) as usize],
            1 => (next() % 600) as f64 - 300.0,
            _ => (next() % (1 << 20)) as f64 / 2048.0 - 128.0,
        };
        for _ in 0..200_000 {
            let (a, b, margin) = ([value(), value()], [value(), value()], value().abs() / 64.0);
            assert_eq!(segment_limits(a, b, margin), segment_limits_scalar(a, b, margin), "{a:?} {b:?} {margin}");
        }
        // The cells of a segment inside the tile, grown by the margin: x over cells 10..=40 and y
        // over 3..=254 (clamped).
        assert_eq!(segment_limits_scalar([40.5, 3.5], [10.5, 300.0], 0.25), limits(10, 40, 3, 255));
        assert_eq!(segment_limits([40.5, 3.5], [10.5, 300.0], 0.25), limits(10, 40, 3, 255));
    }

    #[test]
    fn passing_refs_are_those_whose_boxes_meet_the_ray_box() {
        let mut next = xorshift(11);
        for round in 0..500 {
            // Leaves of up to three chunks of 64 refs, and partial groups of sixteen.
            let m = (next() % 150) as usize;
            let refs: Vec<Ref> = (0..m)
                .map(|i| {
                    let (a, b, c, d) = (next() as u8, next() as u8, next() as u8, next() as u8);
                    Ref { id: i as u32 * 3 + round, x: [a.min(b), a.max(b)], y: [c.min(d), c.max(d)] }
                })
                .collect();
            let split = if m == 0 { 0 } else { (next() as usize) % (m + 1) };
            let mut words = vec![];
            write_block(&[0, 100, 200], &[&refs[..split], &refs[split..]], &mut words);
            let block = Block::parse(&words).unwrap();
            let (a, b, c, d) = (next() as u8, next() as u8, next() as u8, next() as u8);
            let (x, y) = ([a.min(b), a.max(b)], [c.min(d), c.max(d)]);
            for (k, range) in [(0, 0..split), (1, split..m)] {
                let leaf = block.leaf(k).unwrap();
                assert_eq!(leaf.len, range.len());
                let got: Vec<u32> =
                    Passing::new(block.leaf_bytes(leaf), leaf.len, limits(x[0], x[1], y[0], y[1]), &[]).collect();
                let want: Vec<u32> = refs[range]
                    .iter()
                    .filter(|r| r.x[0] <= x[1] && r.x[1] >= x[0] && r.y[0] <= y[1] && r.y[1] >= y[0])
                    .map(|r| r.id)
                    .collect();
                assert_eq!(got, want);
                // Loading the passing refs' triangles is only a hint: the same refs pass, whether
                // the records exist for their ids or not.
                let records = vec![TriangleRecord { v: [[0.0; 3]; 3] }; 150];
                let loading: Vec<u32> =
                    Passing::new(block.leaf_bytes(leaf), leaf.len, limits(x[0], x[1], y[0], y[1]), &records).collect();
                assert_eq!(loading, want);
            }
        }
    }
}
