//! The GLB container (glTF 2.0 §4.4), checked here before any of it is used, because the `gltf`
//! crate's reader reports damage vaguely ("unknown chunk type", "failed to fill whole buffer")
//! and accepts some: a header length shorter than the file, bytes after the last chunk.
//!
//! A GLB is a 12-byte header (the magic `glTF`, version 2, and the length of the whole file),
//! then chunks, each an 8-byte header (the length of its data and its type) and its data: first
//! one JSON chunk (type `0x4E4F534A`), then at most one BIN chunk (`0x004E4942`), then chunks of
//! other types, which readers must ignore. Every chunk starts and ends on a 4-byte boundary, so
//! its length is a multiple of 4 (JSON is padded with spaces, BIN with zeros). Every error names
//! the chunk, its byte offset and what is wrong with it.

/// The GLB header: magic, version, length.
const HEADER: u64 = 12;
/// A chunk's header: length, type.
const CHUNK_HEADER: u64 = 8;
/// The JSON chunk's type, `JSON` read as a little-endian u32.
const JSON: u32 = 0x4E4F_534A;
/// The BIN chunk's type, `BIN\0` read as a little-endian u32.
const BIN: u32 = 0x004E_4942;

/// The chunks of a GLB file: the JSON, the binary buffer if any, and the first chunk of a type
/// the format does not define, if any (ignored, as the format requires).
pub(super) struct Chunks<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
    pub ignored: Option<String>,
}

/// A chunk type as it reads: `0x4D4F534A ("JSOM")`, the text where it is printable.
fn show_type(ty: u32) -> String {
    let bytes = ty.to_le_bytes();
    if bytes.iter().all(|b| b.is_ascii_graphic() || *b == b' ') {
        format!("0x{ty:08X} (\"{}\")", String::from_utf8_lossy(&bytes))
    } else {
        format!("0x{ty:08X}")
    }
}

/// Checks the GLB file whose first bytes are `bytes` (the whole file, or its start) and whose
/// size is `size`: the header, and every chunk whose header `bytes` holds. Returns the chunks
/// when `bytes` is the whole file.
pub(super) fn check(bytes: &[u8], size: u64) -> Result<Option<Chunks<'_>>, String> {
    let word = |at: u64| {
        let at = usize::try_from(at).ok()?;
        bytes.get(at..at.checked_add(4)?).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(format!("truncated GLB: {size} bytes, shorter than the {HEADER}-byte GLB header"));
    };
    if version != 2 {
        return Err(format!("GLB version {version} is not supported (glTF 2.0 files are GLB version 2)"));
    }
    let length = u64::from(length);
    if length < HEADER {
        return Err(format!(
            "not a valid GLB container: its header gives its length as {length} bytes, less than the {HEADER}-byte header"
        ));
    }
    if length > size {
        return Err(format!("truncated GLB: its header gives its length as {length} bytes, but the file has {size}"));
    }
    if length < size {
        return Err(format!(
            "not a valid GLB container: its header gives its length as {length} bytes, but the file has {size} ({} bytes after the end the header gives)",
            size - length
        ));
    }
    if size == HEADER {
        return Err(format!(
            "not a valid GLB container: it ends after its {HEADER}-byte header, with no JSON chunk (chunk 0)"
        ));
    }
    let whole = bytes.len() as u64 == size;
    let slice = |from: u64, len: u64| &bytes[from as usize..(from + len) as usize];
    let mut chunks = Chunks { json: &[], bin: None, ignored: None };
    let (mut offset, mut index) = (HEADER, 0u64);
    while offset < size {
        let left = size - offset;
        if left < CHUNK_HEADER {
            return Err(format!(
                "not a valid GLB container: chunk {index} at byte {offset}: only {left} bytes are left, too few for its {CHUNK_HEADER}-byte chunk header"
            ));
        }
        let (Some(length), Some(ty)) = (word(offset), word(offset + 4)) else {
            // The rest is checked when the whole file is read.
            break;
        };
        let length = u64::from(length);
        let at = format!("not a valid GLB container: chunk {index} at byte {offset}");
        match (index, ty) {
            (0, JSON) => {}
            (0, _) => {
                return Err(format!(
                    "{at} has type {}, but the first chunk must be JSON (0x{JSON:08X})",
                    show_type(ty)
                ));
            }
            (_, JSON) => return Err(format!("{at} is a second JSON chunk (a GLB has one, the first)")),
            (1, BIN) => {}
            (_, BIN) => return Err(format!("{at} is a BIN chunk, but only chunk 1 (the second) may be BIN")),
            _ => {}
        }
        let name = match ty {
            JSON => "JSON".to_string(),
            BIN => "BIN".to_string(),
            _ => format!("type {}", show_type(ty)),
        };
        if length > left - CHUNK_HEADER {
            return Err(format!(
                "{at} ({name}): its length {length} runs past the end of the file ({size} bytes) by {} bytes",
                length - (left - CHUNK_HEADER)
            ));
        }
        if length % 4 != 0 {
            return Err(format!(
                "{at} ({name}): its length {length} is not a multiple of 4 (chunks are padded to 4-byte boundaries)"
            ));
        }
        if index == 0 && length == 0 {
            return Err(format!("{at} (JSON) is empty"));
        }
        if whole {
            let data = slice(offset + CHUNK_HEADER, length);
            match ty {
                JSON => chunks.json = data,
                BIN => chunks.bin = Some(data),
                _ => {
                    chunks
                        .ignored
                        .get_or_insert_with(|| format!("chunk {index} at byte {offset}, of type {}", show_type(ty)));
                }
            }
        }
        offset += CHUNK_HEADER + length;
        index += 1;
    }
    Ok(whole.then_some(chunks))
}
