//! Bounds checks of glTF accessors against their buffer views and buffers, before the `gltf`
//! crate's reader (which trusts them) touches a byte.

use ::gltf as gl;
use gl::accessor::{DataType, Dimensions};
use gl::mesh::Mode;

/// A sparse accessor without a buffer view expands `count` zeros from a few bytes; refuse counts
/// beyond this rather than allocate whatever a hostile file asks for.
const SPARSE_ONLY_MAX_COUNT: usize = 1 << 24;

/// The accessors of a triangle primitive, checked: what [`triangles`] counts and the import reads.
pub(super) struct Checked<'a> {
    pub position: gl::Accessor<'a>,
    pub indices: Option<gl::Accessor<'a>>,
}

/// What the import will make of `primitive`, known before it reads a vertex: `Ok(None)` for a
/// primitive it skips (points, lines, no POSITION), its checked accessors for triangles, or what
/// is wrong with them (a POSITION that is not VEC3 of FLOAT, indices that are not SCALAR unsigned
/// integers, an accessor whose bytes lie outside its buffer). The one check, so that the count of
/// the triangles a file expands to (`super::expand`) refuses the primitives the import would.
pub(super) fn check_primitive<'a>(
    primitive: &gl::Primitive<'a>,
    buffers: &[Vec<u8>],
) -> Result<Option<Checked<'a>>, String> {
    if !matches!(primitive.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
        return Ok(None);
    }
    let Some(position) = primitive.get(&gl::Semantic::Positions) else { return Ok(None) };
    if position.data_type() != DataType::F32 || position.dimensions() != Dimensions::Vec3 {
        return Err(format!(
            "POSITION accessor {} holds {:?} of {:?}; only VEC3 of FLOAT is supported",
            position.index(),
            position.dimensions(),
            position.data_type()
        ));
    }
    check_layout(&position, 12, buffers).map_err(|why| format!("POSITION accessor {}: {why}", position.index()))?;
    let indices = primitive.indices();
    if let Some(ia) = &indices {
        if ia.dimensions() != Dimensions::Scalar
            || !matches!(ia.data_type(), DataType::U8 | DataType::U16 | DataType::U32)
        {
            return Err(format!(
                "index accessor {} holds {:?} of {:?}; indices must be SCALAR unsigned integers",
                ia.index(),
                ia.dimensions(),
                ia.data_type()
            ));
        }
        check_layout(ia, ia.data_type().size(), buffers)
            .map_err(|why| format!("index accessor {}: {why}", ia.index()))?;
    }
    Ok(Some(Checked { position, indices }))
}

/// The triangles a primitive of `mode` makes from its checked accessors: a list `n / 3`, a strip
/// or fan `n − 2`, of its `n` indices (or vertices, without indices).
pub(super) fn triangles(mode: Mode, checked: &Checked) -> u64 {
    let n = checked.indices.as_ref().unwrap_or(&checked.position).count() as u64;
    match mode {
        Mode::Triangles => n / 3,
        Mode::TriangleStrip | Mode::TriangleFan => n.saturating_sub(2),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => 0,
    }
}

/// Checks that every byte the reader will touch for `accessor` (elements of `element_size` bytes,
/// plus sparse indices and values) lies inside its buffer view and buffer, with no arithmetic
/// overflow, so that the crate's unchecked reader cannot panic or misread.
fn check_layout(accessor: &gl::Accessor, element_size: usize, buffers: &[Vec<u8>]) -> Result<(), String> {
    let count = accessor.count();
    match accessor.view() {
        Some(view) => check_run(&view, accessor.offset(), count, element_size, buffers)?,
        None if accessor.sparse().is_none() => return Err("it has neither a buffer view nor sparse values".to_string()),
        None if count > SPARSE_ONLY_MAX_COUNT => {
            return Err(format!(
                "a sparse accessor without a buffer view may hold at most {SPARSE_ONLY_MAX_COUNT} elements, not {count}"
            ));
        }
        None => {}
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 || n > count {
            return Err(format!("sparse count {n} must be between 1 and the accessor count {count}"));
        }
        let indices = sparse.indices();
        check_run(&indices.view(), indices.offset(), n, indices.index_type().size(), buffers)
            .map_err(|why| format!("sparse indices: {why}"))?;
        let values = sparse.values();
        check_run(&values.view(), values.offset(), n, element_size, buffers)
            .map_err(|why| format!("sparse values: {why}"))?;
    }
    Ok(())
}

/// Checks `count` elements of `size` bytes from `offset` in `view` (with its stride).
fn check_run(
    view: &gl::buffer::View,
    offset: usize,
    count: usize,
    size: usize,
    buffers: &[Vec<u8>],
) -> Result<(), String> {
    let (v, b) = (view.index(), view.buffer().index());
    let buffer_len = buffers.get(b).map_or(0, Vec::len);
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|end| end > buffer_len) {
        return Err(format!(
            "buffer view {v} (offset {}, length {}) lies outside buffer {b} ({buffer_len} bytes)",
            view.offset(),
            view.length()
        ));
    }
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!("buffer view {v} has byteStride {stride}, less than the element size {size}"));
    }
    if count == 0 {
        return Ok(());
    }
    let end = stride.checked_mul(count - 1).and_then(|x| x.checked_add(size)).and_then(|x| x.checked_add(offset));
    if end.is_none_or(|end| end > view.length()) {
        return Err(format!(
            "{count} elements of {size} bytes from byte {offset}, stride {stride}, overrun buffer view {v} ({} B)",
            view.length()
        ));
    }
    Ok(())
}
