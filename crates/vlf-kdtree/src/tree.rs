//! The tree's types: its parameters, its 8-byte nodes and the tree itself. The build
//! (`build.rs`) makes one; the traversal (`lib.rs`) walks it.

/// The deepest tree the build makes, whatever [`KdParams::max_depth`] asks for; it bounds the
/// traversal stack.
pub const MAX_DEPTH: u32 = 64;

/// Build parameters: the two knobs the paper tunes for CRT (§6.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct KdParams {
    /// A node at this depth (the root has depth 0) becomes a leaf. Clamped to [`MAX_DEPTH`];
    /// 0 gives a single leaf holding every triangle.
    pub max_depth: u32,
    /// A node with at most this many triangle references becomes a leaf.
    pub leaf_size: u32,
}

impl Default for KdParams {
    /// A typical CRT setting: depth 20, at most 2 triangles per leaf.
    fn default() -> Self {
        KdParams { max_depth: 20, leaf_size: 2 }
    }
}

/// One 8-byte node, as in Wald's thesis: the split position (or a leaf's triangle count) and a
/// word whose low two bits hold the axis (0, 1, 2) or 3 for a leaf, and whose upper 30 bits hold
/// the index of the first of the two adjacent children (or the offset of a leaf's triangle list).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct KdNode {
    word: u32,
    link: u32,
}

const LEAF: u32 = 3;

/// The largest child index or triangle-list offset a node can hold.
pub const MAX_LINK: u32 = (1 << 30) - 1;

impl KdNode {
    pub(crate) fn inner(axis: usize, split: f32, first_child: u32) -> Self {
        assert!(first_child <= MAX_LINK, "kd-tree too large: more than 2^30 nodes");
        KdNode { word: split.to_bits(), link: first_child << 2 | axis as u32 }
    }

    pub(crate) fn leaf(offset: u32, count: u32) -> Self {
        assert!(offset <= MAX_LINK, "kd-tree too large: more than 2^30 triangle references");
        KdNode { word: count, link: offset << 2 | LEAF }
    }

    /// Whether this is a leaf.
    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.link & 3 == LEAF
    }

    /// The split axis of an inner node (3 for a leaf).
    #[inline(always)]
    pub fn axis(self) -> usize {
        (self.link & 3) as usize
    }

    /// The splitting plane's coordinate of an inner node.
    #[inline(always)]
    pub fn split(self) -> f32 {
        f32::from_bits(self.word)
    }

    /// The index of an inner node's lower child; the upper child follows it.
    #[inline(always)]
    pub fn first_child(self) -> usize {
        (self.link >> 2) as usize
    }

    /// A leaf's range in the triangle-reference list.
    #[inline(always)]
    pub fn references(self) -> std::ops::Range<usize> {
        let start = (self.link >> 2) as usize;
        start..start + self.word as usize
    }
}

/// What a built tree looks like ([`KdTree::stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KdTreeStats {
    /// Nodes, inner and leaf.
    pub nodes: u64,
    pub leaves: u64,
    /// Leaves holding no triangle (spatial-median splits make many).
    pub empty_leaves: u64,
    /// The depth of the deepest leaf (the root has depth 0).
    pub max_depth: u32,
    /// Triangle references over all leaves (a straddling triangle counts once per leaf).
    pub references: u64,
    /// Triangles stored (input triangles that lie in some leaf: all of them).
    pub triangles: u64,
    /// Heap bytes of the nodes, reference list and triangles.
    pub bytes: u64,
}

/// A spatial-median kd-tree over a triangle soup. Owns its triangles (reordered by first use in
/// leaf order, for locality; hits report the input index).
#[derive(Clone, Debug)]
pub struct KdTree {
    pub(crate) params: KdParams,
    /// Nodes; the root is node 0. The two children of an inner node are adjacent.
    pub(crate) nodes: Vec<KdNode>,
    /// The leaves' triangle lists, concatenated: indices into `triangles`.
    pub(crate) references: Vec<u32>,
    /// Triangles in storage order.
    pub(crate) triangles: Vec<[[f32; 3]; 3]>,
    /// The input index of each stored triangle.
    pub(crate) prims: Vec<u32>,
    /// The scene box grown by `margin` (the ray is clipped to it), in f64; `None` when empty.
    pub(crate) root: Option<([f64; 3], [f64; 3])>,
    /// The exact scene box.
    pub(crate) bounds: Option<([f32; 3], [f32; 3])>,
    pub(crate) margin: f64,
    pub(crate) max_depth_reached: u32,
    /// The point the triangles' coordinates are relative to (zero: world coordinates).
    pub(crate) origin: [f64; 3],
}
