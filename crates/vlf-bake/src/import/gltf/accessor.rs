//! Bounds checks of glTF accessors against their buffer views and buffers, before the `gltf`
//! crate's reader (which trusts them) touches a byte.

use ::gltf as gl;

/// A sparse accessor without a buffer view expands `count` zeros from a few bytes; refuse counts
/// beyond this rather than allocate whatever a hostile file asks for.
const SPARSE_ONLY_MAX_COUNT: usize = 1 << 24;

/// Checks that every byte the reader will touch for `accessor` (elements of `element_size` bytes,
/// plus sparse indices and values) lies inside its buffer view and buffer, with no arithmetic
/// overflow, so that the crate's unchecked reader cannot panic or misread.
pub(super) fn check_layout(accessor: &gl::Accessor, element_size: usize, buffers: &[Vec<u8>]) -> Result<(), String> {
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
