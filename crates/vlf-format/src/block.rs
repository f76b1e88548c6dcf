//! Tile blocks: one non-empty tile's leaves and their triangle references, as stored in LEAVES
//! (`formats/vlf.md` §5.6). This module knows the bytes of a block (how to write one and how to
//! read one in place, bounds-checked); what a block means to a ray is the runtime's business.
//!
//! ```text
//! u32  leaf_count K                 1 ≤ K ≤ MAX_LEAVES
//! u16  bounds[K + 1]                leaf k is the slab z(bounds[k]) ≤ z ≤ z(bounds[k + 1])
//! u8   zero padding to a multiple of 4
//! u32  ends[K]                      refs in leaves 0..=k; m = ends[K − 1]
//! per leaf k, its c = ends[k] − ends[k − 1] refs (ends[−1] = 0):
//!   u8   x_lo[c], x_hi_c[c], y_lo[c], y_hi_c[c]   the refs' quantized boxes (x_hi_c = 255 − x_hi)
//!   u32  ids[c]                                   the refs' triangle ids
//! u8   zero padding to a multiple of 8
//! ```
//!
//! A leaf's refs take 8 bytes each and lie together, so a ray reading a small leaf touches one or
//! two cache lines past the header.

use bytemuck::try_cast_slice;

/// The most leaves a tile may have. A reader skips a block that claims more, which bounds the
/// work of one ray in one tile whatever the file says.
pub const MAX_LEAVES: u32 = 1 << crate::layout::MAX_DEPTH;

/// Quantization of the refs' boxes: cells per tile side.
pub const BOX_CELLS: u32 = 256;

/// Offset of `ends` in a block with `k` leaves.
#[inline(always)]
const fn ends_offset(k: usize) -> usize {
    (4 + 2 * (k + 1)).next_multiple_of(4)
}

/// Bytes of the header of a block with `k` leaves (`K`, bounds, padding, ends).
#[inline(always)]
pub const fn header_bytes(k: usize) -> usize {
    ends_offset(k) + 4 * k
}

/// Length in 8-byte words of a block with `k` leaves and `m` refs.
pub const fn block_words(k: usize, m: usize) -> usize {
    (header_bytes(k) + 8 * m).div_ceil(8)
}

/// A reference from a leaf to a triangle, with the cells of the triangle's box in the tile.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Ref {
    /// The triangle id.
    pub id: u32,
    /// First and last box cell along x, `x_lo ≤ x_hi`.
    pub x: [u8; 2],
    /// First and last box cell along y, `y_lo ≤ y_hi`.
    pub y: [u8; 2],
}

/// Appends the block of one tile to `out`: `bounds` are the `K + 1` quantized leaf boundaries,
/// `leaves` the refs of each of the `K` leaves, in order.
///
/// # Panics
/// If `bounds.len() != leaves.len() + 1`, if there is no leaf or more than [`MAX_LEAVES`], or if
/// the tile holds 2³² or more refs (the baker checks its sizes before it writes).
pub fn write_block(bounds: &[u16], leaves: &[&[Ref]], out: &mut Vec<u64>) {
    let k = leaves.len();
    assert!(k >= 1 && k <= MAX_LEAVES as usize && bounds.len() == k + 1, "a block has 1 to MAX_LEAVES leaves");
    let m: usize = leaves.iter().map(|l| l.len()).sum();
    assert!(m <= u32::MAX as usize, "at most 2^32 - 1 refs in a tile");
    let mut bytes = Vec::with_capacity(block_words(k, m) * 8);
    bytes.extend((k as u32).to_le_bytes());
    for b in bounds {
        bytes.extend(b.to_le_bytes());
    }
    bytes.resize(ends_offset(k), 0);
    let mut end = 0u32;
    for leaf in leaves {
        end += leaf.len() as u32;
        bytes.extend(end.to_le_bytes());
    }
    for leaf in leaves {
        bytes.extend(leaf.iter().map(|r| r.x[0]));
        bytes.extend(leaf.iter().map(|r| 255 - r.x[1]));
        bytes.extend(leaf.iter().map(|r| r.y[0]));
        bytes.extend(leaf.iter().map(|r| 255 - r.y[1]));
        for r in leaf.iter() {
            bytes.extend(r.id.to_le_bytes());
        }
    }
    bytes.resize(block_words(k, m) * 8, 0);
    out.extend(bytes.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes"))));
}

/// The refs of one leaf of a [`Block`]: where they start (in bytes, from the block's start) and
/// how many there are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LeafRefs {
    /// Byte offset of the leaf's first box array from the block's start.
    start: usize,
    /// Its number of refs, `c`.
    pub len: usize,
}

impl LeafRefs {
    /// Whether the leaf holds no ref.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// The triangle ids of a leaf of `len` refs, from its bytes ([`Block::leaf_bytes`] of a parsed
/// block, which holds them).
///
/// # Panics
/// If `leaf_bytes` is shorter than `8 · len`, or not 4-aligned: never for [`Block::leaf_bytes`].
#[inline(always)]
pub fn leaf_ids(leaf_bytes: &[u8], len: usize) -> &[u32] {
    // Aligned: the block starts on a word, its header and every leaf take multiples of 4 bytes,
    // and a leaf's boxes 4 bytes per ref.
    try_cast_slice(&leaf_bytes[4 * len..8 * len]).expect("4-aligned ids")
}

/// A tile block read in place. Every accessor is bounds-checked against the block; a block whose
/// header does not fit in the words it was read from is not parsed at all.
#[derive(Clone, Copy, Debug)]
pub struct Block<'a> {
    /// The block's bytes, from its start to the end of the section (a leaf's arrays are read with
    /// 16-byte loads that may run past its last box into its ids, or into the next leaf).
    bytes: &'a [u8],
    /// The leaf count `K`.
    k: usize,
    /// The ref count `m`.
    m: usize,
    /// The leaf boundaries.
    bounds: &'a [u16],
    /// The ends of the leaves.
    ends: &'a [u32],
    /// The block's 4-byte quarters, from its start to the end of the section.
    quarters: &'a [u32],
}

impl<'a> Block<'a> {
    /// The first and last leaf boundaries of the block that starts at `words[0]` (the tile's z
    /// range), read without parsing the rest of its header: `None` where [`Block::parse`] would
    /// find no leaf or more than [`MAX_LEAVES`], or the boundaries past `words`.
    #[inline(always)]
    pub fn z_range(words: &'a [u64]) -> Option<[u16; 2]> {
        let first = *words.first()?;
        let k = first as u32;
        if k == 0 || k > MAX_LEAVES {
            return None;
        }
        let halves: &[u16] = bytemuck::cast_slice(words);
        Some([(first >> 32) as u16, *halves.get(2 + k as usize)?])
    }

    /// Parses the block that starts at `words[0]`, or `None` if its header claims no leaf, more
    /// than [`MAX_LEAVES`], or more bytes than `words` holds.
    #[inline]
    pub fn parse(words: &'a [u64]) -> Option<Block<'a>> {
        // Words are 8-aligned, so their halves and quarters need no alignment check (the crate
        // builds for little-endian targets only, as the format is).
        let bytes: &[u8] = bytemuck::cast_slice(words);
        let halves: &[u16] = bytemuck::cast_slice(words);
        let quarters: &[u32] = bytemuck::cast_slice(words);
        let k = *quarters.first()?;
        if k == 0 || k > MAX_LEAVES {
            return None;
        }
        let k = k as usize;
        let bounds = halves.get(2..k + 3)?;
        let ends = quarters.get(ends_offset(k) / 4..header_bytes(k) / 4)?;
        let m = ends[k - 1] as usize;
        if header_bytes(k).checked_add(m.checked_mul(8)?)? > bytes.len() {
            return None;
        }
        Some(Block { bytes, k, m, bounds, ends, quarters })
    }

    /// The number of leaves, `K ≥ 1`.
    #[inline(always)]
    pub fn leaf_count(&self) -> usize {
        self.k
    }

    /// The block's bytes, from its start to the end of the section.
    #[inline(always)]
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// The block's 4-byte quarters, from its start to the end of the section: ref `i` of a leaf
    /// whose arrays start at byte `b` (a multiple of 4) has its id at quarter `b / 4 + len + i`.
    #[inline(always)]
    pub fn quarters(&self) -> &'a [u32] {
        self.quarters
    }

    /// `ends[k]`: the refs in leaves `0..=k`, for `k < K`.
    #[inline(always)]
    pub fn ends(&self) -> &'a [u32] {
        self.ends
    }

    /// The number of refs, `m`.
    #[inline(always)]
    pub fn ref_count(&self) -> usize {
        self.m
    }

    /// The `K + 1` leaf boundaries, quantized.
    #[inline(always)]
    pub fn bounds(&self) -> &'a [u16] {
        self.bounds
    }

    /// The refs of leaf `k`, or `None` if the file's ends are not in order.
    #[inline(always)]
    pub fn leaf(&self, k: usize) -> Option<LeafRefs> {
        let start = if k == 0 { 0 } else { *self.ends.get(k - 1)? as usize };
        let end = *self.ends.get(k)? as usize;
        (start <= end && end <= self.m).then(|| LeafRefs { start: header_bytes(self.k) + 8 * start, len: end - start })
    }

    /// The `N` consecutive bytes of box array `a` of a leaf (0: `x_lo`, 1: `x_hi_c`, 2: `y_lo`,
    /// 3: `y_hi_c`) from its ref `i` on, padded with 255 (a box no ray box passes) past the
    /// section's end. Bytes past the leaf's `len` are whatever follows; callers mask them.
    #[inline(always)]
    pub fn box_lane<const N: usize>(&self, leaf: LeafRefs, a: usize, i: usize) -> [u8; N] {
        let at = leaf.start + a * leaf.len + i;
        match self.bytes.get(at..at + N) {
            Some(lane) => lane.try_into().expect("N bytes"),
            None => {
                let mut lane = [255u8; N];
                let tail = self.bytes.get(at..).unwrap_or(&[]);
                lane[..tail.len()].copy_from_slice(tail);
                lane
            }
        }
    }

    /// A leaf's bytes, from its first box array to the end of the section: box array `a` of the
    /// leaf starts at `a · len`, its ids at `4 · len`.
    #[inline(always)]
    pub fn leaf_bytes(&self, leaf: LeafRefs) -> &'a [u8] {
        &self.bytes[leaf.start..]
    }

    /// The box of ref `i < len` of a leaf: `[x_lo, x_hi_c, y_lo, y_hi_c]`.
    #[inline(always)]
    pub fn box_of(&self, leaf: LeafRefs, i: usize) -> [u8; 4] {
        std::array::from_fn(|a| self.bytes[leaf.start + a * leaf.len + i])
    }

    /// The triangle ids of a leaf's refs, in place.
    #[inline(always)]
    pub fn ids(&self, leaf: LeafRefs) -> &'a [u32] {
        leaf_ids(self.leaf_bytes(leaf), leaf.len)
    }

    /// The block's length in words.
    pub fn words(&self) -> usize {
        block_words(self.k, self.m)
    }

    /// Every invariant of a block (`formats/vlf.md` §5.6): boundaries non-decreasing with
    /// `bounds[0] < bounds[K]`, ends non-decreasing, at least one ref, every id below
    /// `triangle_count` and strictly increasing within its leaf, every box with `lo ≤ hi`, and the
    /// padding zero. Returns the number of distinct triangles, or what is wrong.
    pub fn check(&self, triangle_count: u64) -> Result<u64, String> {
        let k = self.k;
        if let Some(i) = self.bounds.windows(2).position(|w| w[0] > w[1]) {
            return Err(format!("leaf boundary {} decreases", i + 1));
        }
        if self.bounds[0] >= self.bounds[k] {
            return Err(format!("the z range {}..{} is empty", self.bounds[0], self.bounds[k]));
        }
        if self.m == 0 {
            return Err("a block holds no ref (an empty tile is EMPTY_TILE)".into());
        }
        let mut all = Vec::with_capacity(self.m);
        for index in 0..k {
            let leaf = self.leaf(index).ok_or_else(|| format!("the ends of leaf {index} are out of order"))?;
            let ids = self.ids(leaf);
            if let Some(&id) = ids.iter().find(|&&id| id as u64 >= triangle_count) {
                return Err(format!("leaf {index}: triangle id {id} >= triangle_count {triangle_count}"));
            }
            if ids.windows(2).any(|w| w[0] >= w[1]) {
                return Err(format!("leaf {index}: ids are not strictly increasing"));
            }
            for i in 0..leaf.len {
                let [x_lo, x_hi_c, y_lo, y_hi_c] = self.box_of(leaf, i);
                if x_lo > 255 - x_hi_c || y_lo > 255 - y_hi_c {
                    return Err(format!("leaf {index}: the box of its ref {i} has lo > hi"));
                }
            }
            all.extend_from_slice(ids);
        }
        let padding = self.bytes[4 + 2 * (k + 1)..ends_offset(k)]
            .iter()
            .chain(&self.bytes[header_bytes(k) + 8 * self.m..self.words() * 8]);
        if padding.copied().any(|b| b != 0) {
            return Err("padding is not zero".into());
        }
        all.sort_unstable();
        all.dedup();
        Ok(all.len() as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(id: u32, x: [u8; 2], y: [u8; 2]) -> Ref {
        Ref { id, x, y }
    }

    #[test]
    fn a_block_reads_back_what_was_written() {
        let leaves: [&[Ref]; 3] = [&[r(4, [0, 10], [5, 6])], &[], &[r(1, [200, 255], [0, 0]), r(9, [3, 3], [7, 250])]];
        let mut words = vec![];
        write_block(&[10, 20, 30, 4000], &leaves, &mut words);
        assert_eq!(words.len(), block_words(3, 3));
        let b = Block::parse(&words).unwrap();
        assert_eq!((b.leaf_count(), b.ref_count(), b.words()), (3, 3, words.len()));
        assert_eq!(b.bounds(), [10, 20, 30, 4000]);
        assert_eq!((b.leaf(1).unwrap().len, b.leaf(3)), (0, None));
        let (l0, l2) = (b.leaf(0).unwrap(), b.leaf(2).unwrap());
        assert_eq!((b.ids(l0), b.ids(l2)), (&[4][..], &[1, 9][..]));
        assert_eq!(b.box_of(l0, 0), [0, 245, 5, 249]);
        assert_eq!(b.box_of(l2, 1), [3, 252, 7, 5]);
        // A lane runs on past its leaf's boxes (here into the next array of the same leaf).
        assert_eq!(b.box_lane::<4>(l2, 0, 0), [200, 3, 255 - 255, 255 - 3]);
        // Past the section's end it reads 255.
        let tail = b.box_lane::<16>(l2, 3, 1);
        assert_eq!(tail[0], 5);
        assert_eq!(b.check(10), Ok(3));
        assert!(b.check(9).unwrap_err().contains("triangle id 9"));
    }

    #[test]
    fn lying_headers_are_not_parsed() {
        let mut words = vec![];
        write_block(&[0, 1], &[&[r(0, [0, 0], [0, 0])]], &mut words);
        let mut bad = words.clone();
        bad[0] = (bad[0] & !0xffff_ffff) | (MAX_LEAVES as u64 + 1);
        assert!(Block::parse(&bad).is_none());
        bad[0] &= !0xffff_ffff;
        assert!(Block::parse(&bad).is_none(), "no leaf");
        // A ref count beyond the section (K = 1: ends[0] at byte 8).
        let mut bad = words.clone();
        bad[1] = (bad[1] & !0xffff_ffff) | 1000;
        assert!(Block::parse(&bad).is_none());
        assert!(Block::parse(&words[..0]).is_none());
        // The z range is read from the same header words, and refused where `parse` refuses K.
        assert_eq!(Block::z_range(&words), Some([0, 1]));
        let mut bad = words.clone();
        bad[0] = (bad[0] & !0xffff_ffff) | (MAX_LEAVES as u64 + 1);
        assert_eq!(Block::z_range(&bad), None);
        bad[0] &= !0xffff_ffff;
        assert_eq!(Block::z_range(&bad), None, "no leaf");
        assert_eq!(Block::z_range(&words[..0]), None);
    }

    /// [`Block::z_range`] is the first and last of [`Block::bounds`] for every leaf count (the
    /// last boundary moves through the header's words as K grows), and `None` when the words end
    /// before the last boundary.
    #[test]
    fn the_z_range_is_the_first_and_last_boundary() {
        for k in 1..=40usize {
            let bounds: Vec<u16> = (0..=k).map(|i| (7 + 31 * i) as u16).collect();
            let leaves: Vec<&[Ref]> = (0..k).map(|_| &[][..]).collect();
            let mut words = vec![];
            write_block(&bounds, &leaves, &mut words);
            let b = Block::parse(&words).unwrap();
            assert_eq!(Block::z_range(&words), Some([b.bounds()[0], b.bounds()[k]]), "K = {k}");
            // The last boundary is half-word 2 + K: in word (2 + K) / 4.
            let needed = (2 + k) / 4 + 1;
            assert_eq!(Block::z_range(&words[..needed]), Some([bounds[0], bounds[k]]), "K = {k}");
            assert_eq!(Block::z_range(&words[..needed - 1]), None, "K = {k}");
        }
    }
}
