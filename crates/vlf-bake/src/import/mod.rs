//! Mesh importers: Wavefront OBJ (through `tobj`) and glTF 2.0 (through `gltf`).
//!
//! [`import_paths`] turns a list of files into one [`Scene`]; [`import_path`] adds one file to a
//! [`SceneBuilder`]. Each file becomes one INPUTS record (its final path component and the BLAKE3
//! hash of its bytes); each OBJ object/group and each glTF primitive instanced by a node becomes one
//! SOURCES record. The importers never panic on malformed input: every problem is an
//! [`ImportError`] naming the file.

mod gltf;
mod obj;

use crate::scene::{ImportError, Scene, SceneBuilder};
use std::path::Path;

/// Imports every path into one scene, in order (several inputs may be baked into one field).
pub fn import_paths(paths: &[impl AsRef<Path>]) -> Result<Scene, ImportError> {
    let mut builder = SceneBuilder::new();
    for path in paths {
        import_path(&mut builder, path.as_ref())?;
    }
    builder.finish()
}

/// Adds one file to a builder; dispatches on extension (.obj / .gltf / .glb, case-insensitive), and
/// for an unknown extension sniffs the bytes ("glTF" magic, '{' JSON, OBJ-looking text) before
/// giving [`ImportError::UnknownFormat`].
///
/// A file that contributes no triangle (empty, vertices without faces, only points or lines, only
/// zero-area triangles) is an error, [`ImportError::NoTriangles`], even when other inputs have
/// triangles: it is almost certainly not what the caller meant to bake.
pub fn import_path(builder: &mut SceneBuilder, path: &Path) -> Result<(), ImportError> {
    let bytes = std::fs::read(path).map_err(|error| ImportError::Io { path: path.to_path_buf(), error })?;
    let format = detect_format(path, &bytes).ok_or_else(|| ImportError::UnknownFormat { path: path.to_path_buf() })?;
    let before = builder.triangle_count();
    let input = builder.begin_input(&path.to_string_lossy(), *blake3::hash(&bytes).as_bytes());
    match format {
        Format::Obj => obj::import(builder, input, path, &bytes)?,
        Format::Gltf => gltf::import(builder, input, path, &bytes)?,
    }
    if builder.triangle_count() == before {
        return Err(ImportError::NoTriangles { what: path.display().to_string() });
    }
    Ok(())
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Obj,
    Gltf,
}

/// The format of a file: by extension, else by content.
fn detect_format(path: &Path, bytes: &[u8]) -> Option<Format> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("obj") => return Some(Format::Obj),
        Some("gltf" | "glb") => return Some(Format::Gltf),
        _ => {}
    }
    if bytes.starts_with(b"glTF") {
        return Some(Format::Gltf);
    }
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF".as_slice()).unwrap_or(bytes);
    if text.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{') {
        return Some(Format::Gltf);
    }
    if obj::looks_like_obj(text) {
        return Some(Format::Obj);
    }
    None
}
