//! Mesh importers: Wavefront OBJ (through `tobj`) and glTF 2.0 (through `gltf`).
//!
//! [`import_paths`] turns a list of files into one [`Scene`]; [`import_path`] adds one file to a
//! [`SceneBuilder`]; [`import_bytes`] adds a mesh held in memory. Each file becomes one INPUTS record (its final path component and the BLAKE3
//! hash of its bytes); each OBJ object/group and each glTF primitive instanced by a node becomes one
//! SOURCES record. The importers never panic on malformed input: every problem is an
//! [`ImportError`] naming the file.

mod gltf;
mod input;
mod obj;

pub use input::{NotARegularFile, check_regular_file, read_regular_file};

use crate::scene::{ImportError, Scene, SceneBuilder};
use input::{Expect, Fetch, ReadFile, Refused};
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
/// An empty file is [`ImportError::Empty`]. A file that contributes no triangle (vertices without
/// faces, only points or lines, only zero-area triangles) is an error,
/// [`ImportError::NoTriangles`] saying which, even when other inputs have triangles: it is almost
/// certainly not what the caller meant to bake. Zero-area triangles dropped from a file that has
/// others are counted, with a warning naming the file.
///
/// Only regular files are read, the mesh and the files it refers to alike ([`read_regular_file`]):
/// a directory, a pipe or a device is an error saying which, before it is opened. An external
/// glTF buffer is read up to its declared `byteLength`, however long its file.
///
/// No file is read whole before its first bytes are judged and its size is compared with the
/// memory the process may use ([`crate::memory::budget`]): a mesh whose first bytes are not
/// what its format starts with (the GLB header and chunks, the `{` of glTF JSON, OBJ text) is
/// refused from its first 64 KiB, and one larger than the budget is an error naming its size
/// and the budget. A material library whose first bytes are not text is skipped with a warning,
/// like a missing one.
pub fn import_path(builder: &mut SceneBuilder, path: &Path) -> Result<(), ImportError> {
    let bytes = input::read_checked(path, u64::MAX, |prefix, size| check_start(path, prefix, size).map(drop)).map_err(
        |refused| match refused {
            Refused::Read(error) => ImportError::Io { path: path.to_path_buf(), error },
            Refused::Check(e) => e,
        },
    )?;
    import_with(builder, path, &bytes, &input::read_referenced)
}

/// Adds a mesh held in memory to a builder, exactly as [`import_path`] adds a file: `path` names
/// it (its extension chooses the format, its final component is the stored input name, and files
/// the mesh refers to are resolved against its directory), and `read_file` fetches those files
/// (OBJ material libraries, external glTF buffers); a caller holding everything in memory passes a
/// closure that serves the bytes it has. The first bytes of the mesh and of the files it refers
/// to are judged as [`import_path`] judges them.
pub fn import_bytes(
    builder: &mut SceneBuilder,
    path: &Path,
    bytes: &[u8],
    read_file: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<(), ImportError> {
    import_with(builder, path, bytes, &|file, _, expect| {
        let bytes = read_file(file)?;
        expect.check(&bytes[..bytes.len().min(input::PREFIX)], bytes.len() as u64)?;
        Ok(bytes)
    })
}

/// [`import_bytes`] with a `fetch` that is told the most bytes wanted of a file and what its
/// first bytes must look like.
fn import_with(builder: &mut SceneBuilder, path: &Path, bytes: &[u8], fetch: &Fetch) -> Result<(), ImportError> {
    let format = check_start(path, bytes, bytes.len() as u64)?;
    let before = builder.triangle_count();
    let report = builder.report_mut();
    let (dropped, points, lines) = (report.dropped_degenerate, report.skipped_points, report.skipped_lines);
    let input = builder.begin_input(&path.to_string_lossy(), *blake3::hash(bytes).as_bytes());
    let expect = match format {
        Format::Obj => Expect::Text,
        Format::Gltf => Expect::Bytes,
    };
    let read_file: &ReadFile = &|file, limit| fetch(file, limit, expect);
    match format {
        Format::Obj => obj::import(builder, input, path, bytes, read_file)?,
        Format::Gltf => gltf::import(builder, input, path, bytes, read_file)?,
    }
    let report = builder.report_mut();
    let dropped = report.dropped_degenerate - dropped;
    let (points, lines) = (report.skipped_points - points, report.skipped_lines - lines);
    if builder.triangle_count() == before {
        let detail = if dropped > 0 {
            format!(": all {dropped} of its triangles have zero area")
        } else if points + lines > 0 {
            format!(": it holds only points and lines ({points} point and {lines} line primitives skipped)")
        } else {
            match format {
                Format::Obj => ": it has no face with three or more vertices".to_string(),
                Format::Gltf => ": no node of its scene instances a triangle mesh".to_string(),
            }
        };
        return Err(ImportError::NoTriangles { what: path.display().to_string(), detail });
    }
    if dropped > 0 {
        let s = if dropped == 1 { "" } else { "s" };
        builder
            .report_mut()
            .warnings
            .push(format!("{}: dropped {dropped} degenerate (zero-area) triangle{s}", path.display()));
    }
    Ok(())
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Obj,
    Gltf,
}

/// The format of the file at `path`, judged by its first bytes `prefix` (all of them, or the first
/// [`input::PREFIX`]) and its size: an empty file, a file of unknown format, and a file whose
/// first bytes are not what its format starts with are refused. The same rule before a file is
/// read whole and after, and for a mesh held in memory.
fn check_start(path: &Path, prefix: &[u8], size: u64) -> Result<Format, ImportError> {
    if size == 0 {
        return Err(ImportError::Empty { path: path.to_path_buf() });
    }
    let format = detect_format(path, prefix).ok_or_else(|| ImportError::UnknownFormat { path: path.to_path_buf() })?;
    match format {
        Format::Obj => {
            let err = |message: String| ImportError::Obj { path: path.to_path_buf(), message };
            if prefix.starts_with(b"glTF") {
                return Err(err(
                    "this is a binary glTF (GLB) file, not OBJ text: give it the .glb extension".to_string()
                ));
            }
            if prefix.starts_with(&vlf_format::MAGIC) {
                return Err(err("this is a VLF field, not a mesh".to_string()));
            }
            if let Some(why) = input::not_text(prefix, size) {
                return Err(err(format!("{why}; is this an OBJ file?")));
            }
        }
        Format::Gltf => gltf::check_start(path, prefix, size)?,
    }
    Ok(format)
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
