//! glTF 2.0 import (`.gltf` with external or `data:` buffers, and `.glb`) through the `gltf` crate.
//!
//! The scene imported is the document's default scene, else its first scene, else (no scenes) every
//! root node. Nodes are walked depth-first in document order, composing transforms in f64; each
//! (node, mesh primitive) pair is one source, and its positions are transformed to world space in
//! f64 and rounded to f32. Triangle lists, strips and fans are imported; point and line primitives
//! are skipped and counted. Images are never loaded.
//!
//! Every material of the document becomes a MATERIALS record (mapped to the Whitted model of
//! `formats/vlf.md` §5.10), and every camera and `KHR_lights_punctual` light that a visited node
//! carries becomes a CAMERAS or LIGHTS record in world space (§5.11, §5.12). Cameras and lights
//! are read from the JSON structs, not the crate's wrappers, which unwrap what validation does not
//! guarantee (a perspective camera with only orthographic parameters, say).
//!
//! The crate is used defensively, because its happy path trusts the file: its validation indexes
//! the POSITION accessor without a bounds check, its accessor reader computes byte ranges with
//! unchecked arithmetic and asserts element sizes, and it refuses any `extensionsRequired` entry
//! (no extension features are enabled). So this module inspects the raw JSON for extensions first,
//! runs the validation itself (tolerating what does not matter for geometry), loads the buffers
//! itself (naming a missing file), and checks every accessor it reads against its buffer view and
//! buffer before handing it to the reader.

mod accessor;
mod expand;
mod glb;
mod raw;
mod records;
mod transform;

use super::input::ReadFile;
use crate::scene::{ImportError, MaterialDesc, SceneBuilder, SourceDesc};
use ::gltf as gl;
use accessor::{Checked, check_primitive};
use gl::json::validation::Validate;
use gl::mesh::Mode;
use raw::{Raw, raw_node};
use records::{camera_record, light_record};
use serde_json::Value;
use std::path::{Path, PathBuf};
use transform::{IDENTITY, Mat4, local_matrix, mul, non_finite_part, transform_point};
use vlf_format::{NO_INDEX, source_kind};

/// Whether a required extension leaves geometry alone (materials, textures, lights, metadata), so
/// that the triangles can be imported without understanding it.
fn geometry_neutral(extension: &str) -> bool {
    ["KHR_materials_", "EXT_materials_", "KHR_texture_", "EXT_texture_", "MSFT_texture_"]
        .iter()
        .any(|prefix| extension.starts_with(prefix))
        || matches!(extension, "KHR_lights_punctual" | "EXT_lights_image_based" | "KHR_xmp_json_ld" | "KHR_xmp")
}

/// Mesh compression carried by a primitive: its triangles live in a compressed stream.
const PRIMITIVE_COMPRESSION: &str = "KHR_draco_mesh_compression";

struct Ctx<'p> {
    path: &'p Path,
    input: u32,
    /// Fetches external buffers, at most the bytes asked for.
    read_file: &'p ReadFile<'p>,
}

impl Ctx<'_> {
    fn err(&self, message: String) -> ImportError {
        ImportError::Gltf { path: self.path.to_path_buf(), message }
    }

    fn warn(&self, builder: &mut SceneBuilder, message: String) {
        builder.report_mut().warnings.push(format!("{}: {message}", self.path.display()));
    }
}

/// Imports the glTF or GLB file `bytes` (read from `path`) as input `input`; external buffers are
/// fetched with `read_file`.
pub(super) fn import(
    builder: &mut SceneBuilder,
    input: u32,
    path: &Path,
    bytes: &[u8],
    read_file: &ReadFile,
) -> Result<(), ImportError> {
    let ctx = Ctx { path, input, read_file };
    check_start(path, bytes, bytes.len() as u64)?;
    // The JSON and binary chunks of a GLB, its container checked whole (`glb::check`).
    let (json, bin, ignored) = if bytes.starts_with(b"glTF") {
        let chunks = glb::check(bytes, bytes.len() as u64).map_err(|e| ctx.err(e))?;
        let chunks = chunks.ok_or_else(|| ctx.err("not a valid GLB container".to_string()))?;
        (chunks.json, chunks.bin, chunks.ignored)
    } else {
        (bytes, None, None)
    };
    if let Some(chunk) = &ignored {
        ctx.warn(builder, format!("GLB {chunk} is not a chunk type glTF 2.0 defines; ignored"));
    }

    // The raw JSON, for what the typed document drops (extensions on primitives and buffer views).
    // A document whose raw parts do not have the types read (`nodes` not an array, say) is
    // judged by the typed parse below, which says what is wrong in glTF's terms.
    let raw: Result<Raw, _> = serde_json::from_slice(json);
    if let Err(e) = &raw
        && !e.is_data()
    {
        return Err(ctx.err(format!("the JSON does not parse: {e}")));
    }
    if let Ok(raw) = &raw {
        check_extensions(&ctx, raw)?;
    }
    let document = gl::Document::from_json_without_validation(
        gl::json::Root::from_slice(json).map_err(|e| ctx.err(format!("{e}")))?,
    );
    let raw = raw.map_err(|e| ctx.err(format!("invalid document: {e}")))?;
    validate(&ctx, document.as_json())?;
    let buffers = load_buffers(&ctx, &document, bin.map(<[u8]>::to_vec), ignored.as_deref())?;

    for (i, node) in raw.nodes.iter().enumerate() {
        if node.uses_gpu_instancing() {
            ctx.warn(
                builder,
                format!("node {i} uses EXT_mesh_gpu_instancing (not supported): only the node itself is imported"),
            );
        }
    }

    // The nodes to import from.
    let scene_count = document.scenes().len();
    let roots: Vec<usize> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => {
            if scene_count > 1 {
                ctx.warn(
                    builder,
                    format!("the document has {scene_count} scenes; only scene {} is imported", scene.index()),
                );
            }
            scene.nodes().map(|n| n.index()).collect()
        }
        None => {
            let mut child = vec![false; document.nodes().len()];
            for node in document.nodes() {
                for c in node.children() {
                    child[c.index()] = true;
                }
            }
            (0..child.len()).filter(|&i| !child[i]).collect()
        }
    };

    import_materials(builder, &ctx, &document);

    // The walk first (the nodes that carry something in order, with their world transforms), then the triangles it
    // will make are counted and judged (`expand`), and only then are they made.
    let nodes: Vec<gl::Node> = document.nodes().collect();
    let mut visited = vec![false; nodes.len()];
    let mut visits: Vec<(usize, Mat4)> = Vec::new();
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&i| (i, IDENTITY)).collect();
    while let Some((index, parent)) = stack.pop() {
        let node =
            nodes.get(index).ok_or_else(|| ctx.err(format!("the scene names node {index}, which does not exist")))?;
        if std::mem::replace(&mut visited[index], true) {
            return Err(ctx.err(format!(
                "node {index} is reached twice: nodes must form trees (a cycle, or a node with two parents)"
            )));
        }
        let transform = node.transform();
        if let Some((property, k)) = non_finite_part(&transform) {
            let raw_value = raw_node(json, index).and_then(|n| n.get(property).cloned());
            let shown = raw_value
                .as_ref()
                .and_then(|v| v.get(k))
                .and_then(Value::as_f64)
                .map_or("inf".into(), |v| format!("{v:e}"));
            return Err(ctx.err(format!(
                "node {index}: its {property} does not fit in f32: element {k} ({shown}) is beyond ±3.4e38"
            )));
        }
        let world = mul(&parent, &local_matrix(transform));
        if !world.as_flattened().iter().all(|c| c.is_finite()) {
            return Err(ctx.err(format!(
                "node {index}: its transform composed with its ancestors' overflows (not finite in f64)"
            )));
        }
        // Only a node that carries a mesh, a camera or a light keeps its world transform (136
        // bytes): a chain of a million empty nodes keeps one.
        let carried = document.as_json().nodes.get(index).is_some_and(|n| {
            n.mesh.is_some()
                || n.camera.is_some()
                || n.extensions.as_ref().is_some_and(|e| e.khr_lights_punctual.is_some())
        });
        if carried {
            visits.push((index, world));
        }
        let children: Vec<usize> = node.children().map(|c| c.index()).collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    let order: Vec<usize> = visits.iter().map(|&(index, _)| index).collect();
    expand::check(builder, path, &nodes, document.meshes().len(), &order, &buffers)?;

    let mut mesh_used = vec![false; document.meshes().len()];
    for (index, world) in visits {
        import_camera_and_light(builder, &ctx, document.as_json(), index, &world);
        if let Some(mesh) = nodes[index].mesh() {
            mesh_used[mesh.index()] = true;
            if nodes[index].skin().is_some() {
                ctx.warn(builder, format!("node {index} is skinned; its mesh is imported in its bind pose"));
            }
            for primitive in mesh.primitives() {
                import_primitive(builder, &ctx, &buffers, index, &world, &mesh, &primitive)?;
            }
        }
    }
    let unused = mesh_used.iter().filter(|&&u| !u).count();
    if unused > 0 {
        ctx.warn(builder, format!("{unused} mesh(es) are not instanced by any node of the imported scene"));
    }
    Ok(())
}

/// Says what is wrong with the start of a file that should be glTF JSON or a GLB container, from
/// its first bytes `prefix` (all of them, or the first [`super::input::PREFIX`]) and its size, so
/// that a file that is neither is refused before it is read whole, and before a parser reports a
/// JSON syntax error or a short read: no `{` and no `glTF` magic (naming what the bytes look like
/// instead), or a damaged GLB container ([`glb::check`], as much of it as `prefix` holds).
pub(super) fn check_start(path: &Path, prefix: &[u8], size: u64) -> Result<(), ImportError> {
    let err = |message: String| ImportError::Gltf { path: path.to_path_buf(), message };
    if prefix.starts_with(b"glTF") {
        glb::check(prefix, size).map_err(err)?;
        // The JSON chunk (checked to be chunk 0, inside the file), as far as `prefix` holds it.
        let Some(length) = prefix.get(12..16) else { return Ok(()) };
        let end = 20usize.saturating_add(u32::from_le_bytes([length[0], length[1], length[2], length[3]]) as usize);
        let json = prefix.get(20..end.min(prefix.len())).unwrap_or_default();
        return check_json_start(json, end <= prefix.len()).map_err(err);
    }
    let text = prefix.strip_prefix(b"\xEF\xBB\xBF".as_slice()).unwrap_or(prefix);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => return check_json_start(prefix, prefix.len() as u64 == size).map_err(err),
        // Only spaces so far: the whole file tells.
        None if (prefix.len() as u64) < size => return Ok(()),
        _ => {}
    }
    let looks_like = if super::obj::looks_like_obj(text) {
        " (it looks like OBJ text: give it the .obj extension)"
    } else if prefix.starts_with(&vlf_format::MAGIC) {
        " (it is a VLF field, not a mesh)"
    } else {
        ""
    };
    let glb = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    Err(err(if glb {
        format!("not a GLB file: it does not start with the GLB magic \"glTF\"{looks_like}")
    } else {
        format!("neither glTF JSON nor GLB: the file starts with neither '{{' nor the GLB magic \"glTF\"{looks_like}")
    }))
}

/// `Err` ("the JSON does not parse: ...", as the import would say) if `start`, the first bytes of
/// a JSON text (all of it when `whole`), breaks JSON's grammar: checked as far as they go, so
/// that a `{` followed by gigabytes of zero bytes is refused from its first bytes.
fn check_json_start(start: &[u8], whole: bool) -> Result<(), String> {
    // A start cut inside a number or a literal ("1e", "1.", "-", "tr") would be a syntax error to
    // the parser: the characters they are made of are dropped from its end (inside a string, it
    // still ends inside one; anything else, a zero byte say, stays and is judged).
    let start = if whole {
        start
    } else {
        let token = |b: &u8| b"0123456789+-.eEtruefalsn".contains(b);
        &start[..start.iter().rposition(|b| !token(b)).map_or(0, |i| i + 1)]
    };
    match serde_json::from_slice::<serde::de::IgnoredAny>(start) {
        Ok(_) => Ok(()),
        Err(e) if e.is_eof() && !whole => Ok(()),
        Err(e) => Err(format!("the JSON does not parse: {e}")),
    }
}

/// Refuses extensions that change how geometry is stored: compression on a primitive, and any
/// required extension that is not known to leave geometry alone.
fn check_extensions(ctx: &Ctx, raw: &Raw) -> Result<(), ImportError> {
    let unsupported = |location: String, extension: &str| ImportError::UnsupportedExtension {
        path: ctx.path.to_path_buf(),
        location,
        extension: extension.to_string(),
    };
    for (m, p, primitive) in primitives(raw) {
        if has_extension(primitive, PRIMITIVE_COMPRESSION) {
            return Err(unsupported(format!("mesh {m} primitive {p}"), PRIMITIVE_COMPRESSION));
        }
    }
    let required = raw.get("extensionsRequired").and_then(Value::as_array).map(Vec::as_slice).unwrap_or_default();
    for extension in required.iter().filter_map(Value::as_str) {
        if geometry_neutral(extension) {
            continue;
        }
        // Name the first primitive that uses it, directly or through an accessor or buffer view.
        let location = primitives(raw)
            .find(|(_, _, primitive)| {
                has_extension(primitive, extension)
                    || primitive_accessors(primitive).any(|a| accessor_has_extension(raw, a, extension))
            })
            .map_or_else(|| "document".to_string(), |(m, p, _)| format!("mesh {m} primitive {p}"));
        return Err(unsupported(location, extension));
    }
    Ok(())
}

/// Every mesh primitive of the raw JSON, as (mesh index, primitive index, primitive).
fn primitives(raw: &Raw) -> impl Iterator<Item = (usize, usize, &Value)> {
    let meshes = raw.get("meshes").and_then(Value::as_array).map(Vec::as_slice).unwrap_or_default();
    meshes.iter().enumerate().flat_map(|(m, mesh)| {
        let list = mesh.get("primitives").and_then(Value::as_array).map(Vec::as_slice).unwrap_or_default();
        list.iter().enumerate().map(move |(p, primitive)| (m, p, primitive))
    })
}

/// The accessor indices a raw primitive reads: its attributes and its indices.
fn primitive_accessors(primitive: &Value) -> impl Iterator<Item = u64> + '_ {
    let attributes = primitive.get("attributes").and_then(Value::as_object);
    attributes.into_iter().flat_map(|a| a.values()).chain(primitive.get("indices")).filter_map(Value::as_u64)
}

fn accessor_has_extension(raw: &Raw, accessor: u64, extension: &str) -> bool {
    let element = |array: &str, i: u64| raw.get(array).and_then(Value::as_array).and_then(|a| a.get(i as usize));
    let Some(acc) = element("accessors", accessor) else { return false };
    has_extension(acc, extension)
        || acc
            .get("bufferView")
            .and_then(Value::as_u64)
            .and_then(|v| element("bufferViews", v))
            .is_some_and(|view| has_extension(view, extension))
}

fn has_extension(object: &Value, extension: &str) -> bool {
    object.get("extensions").and_then(Value::as_object).is_some_and(|e| e.contains_key(extension))
}

/// The crate's validation, minus what does not matter here: missing or malformed POSITION bounds,
/// a primitive without POSITION (skipped with a warning), and required extensions (already judged
/// by [`check_extensions`]).
fn validate(ctx: &Ctx, root: &gl::json::Root) -> Result<(), ImportError> {
    use gl::json::validation::Error as V;
    // The crate's primitive check indexes the POSITION accessor without a bounds check.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let attribute_accessors = primitive.attributes.values().map(|i| i.value());
            if let Some(a) =
                attribute_accessors.chain(primitive.indices.map(|i| i.value())).find(|&a| a >= root.accessors.len())
            {
                return Err(ctx.err(format!(
                    "mesh {m} primitive {p} reads accessor {a}, but the document has {} accessors",
                    root.accessors.len()
                )));
            }
        }
    }
    let mut problems = Vec::new();
    root.validate(root, gl::json::Path::new, &mut |path: &dyn Fn() -> gl::json::Path, error: V| {
        let path = path().0;
        let ignorable = (error == V::Missing && path.ends_with("attributes[\"POSITION\"]"))
            || path.ends_with("attributes[\"POSITION\"].min")
            || path.ends_with("attributes[\"POSITION\"].max")
            || (error == V::Unsupported && path.starts_with("extensionsRequired"));
        if !ignorable {
            problems.push(format!("{path}: {error}"));
        }
    });
    if problems.is_empty() {
        return Ok(());
    }
    let mut message = format!("invalid document: {}", problems.iter().take(3).cloned().collect::<Vec<_>>().join("; "));
    if problems.len() > 3 {
        message.push_str(&format!("; and {} more problems", problems.len() - 3));
    }
    Err(ctx.err(message))
}

/// The bytes of every buffer: the GLB binary chunk, a `data:` URI, or a file beside the document.
/// `ignored` is the first GLB chunk of a type glTF does not define, if any (named when the binary
/// chunk is missing: it may be a BIN chunk whose type was damaged).
fn load_buffers(
    ctx: &Ctx,
    document: &gl::Document,
    mut blob: Option<Vec<u8>>,
    ignored: Option<&str>,
) -> Result<Vec<Vec<u8>>, ImportError> {
    let base = ctx.path.parent().unwrap_or(Path::new(""));
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gl::buffer::Source::Bin => blob.take().ok_or_else(|| {
                let ignored = ignored.map(|c| format!(" ({c}, is not BIN, 0x004E4942)")).unwrap_or_default();
                ctx.err(format!("buffer {i} is the GLB binary chunk, but the file has none{ignored}"))
            })?,
            source @ gl::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                gl::buffer::Data::from_source(source, None)
                    .map_err(|e| ctx.err(format!("buffer {i}: bad data URI: {e}")))?
                    .0
            }
            gl::buffer::Source::Uri(uri) => {
                let file = resolve_uri(base, uri).map_err(|why| ctx.err(format!("buffer {i}: URI {uri:?}: {why}")))?;
                // No more than the buffer's declared length: a file may be longer (only its first
                // byteLength bytes are the buffer), or endless (a device, refused by `read_file`).
                (ctx.read_file)(&file, buffer.length() as u64).map_err(|e| {
                    ctx.err(format!("buffer {i}: cannot read external file {uri:?} ({}): {e}", file.display()))
                })?
            }
        };
        if data.len() < buffer.length() {
            return Err(ctx.err(format!(
                "buffer {i} holds {} bytes, but the document declares byteLength {}",
                data.len(),
                buffer.length()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// The file a relative (percent-encoded) or `file:` URI names.
fn resolve_uri(base: &Path, uri: &str) -> Result<PathBuf, String> {
    let relative = if uri.contains(':') {
        let Some(rest) = uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:")) else {
            return Err("unsupported URI scheme (only relative paths, file: and data: are read)".to_string());
        };
        rest
    } else {
        uri
    };
    let mut bytes = Vec::with_capacity(relative.len());
    let raw = relative.as_bytes();
    let mut k = 0;
    while k < raw.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (raw[k], raw.get(k + 1).copied().and_then(hex), raw.get(k + 2).copied().and_then(hex)) {
            (b'%', Some(hi), Some(lo)) => {
                bytes.push((hi * 16 + lo) as u8);
                k += 3;
            }
            (b, _, _) => {
                bytes.push(b);
                k += 1;
            }
        }
    }
    let decoded = String::from_utf8(bytes).map_err(|_| "percent-decodes to invalid UTF-8".to_string())?;
    Ok(base.join(decoded))
}

/// Adds every material of the document, mapped as `formats/vlf.md` §5.10 says. Factors outside
/// the ranges glTF allows are clamped into them, with a warning.
fn import_materials(builder: &mut SceneBuilder, ctx: &Ctx, document: &gl::Document) {
    for material in document.materials() {
        let Some(index) = material.index() else { continue };
        let pbr = material.pbr_metallic_roughness();
        let mut clamped = false;
        let mut unit = |v: f32| {
            let c = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
            clamped |= c != v;
            c
        };
        let [r, g, b, _] = pbr.base_color_factor();
        let base = [unit(r), unit(g), unit(b)];
        let metallic = unit(pbr.metallic_factor());
        let roughness = unit(pbr.roughness_factor());
        let transmission = unit(material.transmission().map_or(0.0, |t| t.transmission_factor()));
        let emission = material.emissive_factor().map(&mut unit);
        let ior = material.ior().unwrap_or(1.5);
        let ior = if ior.is_finite() && ior >= 1.0 {
            ior.min(10.0)
        } else {
            clamped = true;
            1.0
        };
        if clamped {
            ctx.warn(builder, format!("material {index}: a factor outside its glTF range was clamped into it"));
        }
        let f0 = base.map(|c| 0.04 * (1.0 - metallic) + c * metallic);
        let gloss = (1.0 - roughness) * (1.0 - roughness);
        let r4 = roughness.powi(4);
        let shininess = if r4 > 0.0 { (2.0 / r4 - 2.0).clamp(1.0, 4096.0) } else { 4096.0 };
        let desc = MaterialDesc {
            name: material.name().unwrap_or("").to_string(),
            diffuse: base.map(|c| c * (1.0 - metallic) * (1.0 - transmission) + c * metallic * (1.0 - gloss)),
            shininess,
            specular: f0,
            ior,
            reflection: f0.map(|c| c * gloss),
            transmission: base.map(|c| c * transmission * (1.0 - metallic)),
            emission,
        };
        builder.add_material(ctx.input, index as u32, &desc);
    }
}

/// Adds the camera and the light node `index` carries, if any, placed by its world transform
/// (`formats/vlf.md` §5.11, §5.12). One that cannot be placed or described (a singular
/// transform, parameters outside glTF's ranges) is skipped with a warning.
fn import_camera_and_light(builder: &mut SceneBuilder, ctx: &Ctx, root: &gl::json::Root, index: usize, world: &Mat4) {
    let Some(node) = root.nodes.get(index) else { return };
    let node_name = node.name.as_deref().unwrap_or("");
    let position = [world[3][0], world[3][1], world[3][2]];
    let forward = normalized([-world[2][0], -world[2][1], -world[2][2]]);
    let up = normalized([world[1][0], world[1][1], world[1][2]]).and_then(|up| {
        let f = forward?;
        let along = up[0] * f[0] + up[1] * f[1] + up[2] * f[2];
        normalized([up[0] - along * f[0], up[1] - along * f[1], up[2] - along * f[2]])
    });
    let finite = |v: [f64; 3]| v.iter().all(|c| c.is_finite() && c.abs() < 1e30);
    let place = (finite(position)).then_some(()).and(forward.zip(up));

    if let Some(camera_index) = node.camera.map(|c| c.value()) {
        let camera = root.cameras.get(camera_index);
        let record = camera.and_then(|c| {
            let (forward, up) = place?;
            camera_record(c, camera_index as u32, index as u32, position, forward, up, ctx.input)
        });
        match (camera, record) {
            (Some(c), Some(record)) => builder.add_camera(c.name.as_deref().unwrap_or(node_name), record),
            _ => ctx.warn(
                builder,
                format!("node {index}: camera {camera_index} skipped (its node transform is singular, or its parameters are invalid)"),
            ),
        }
    }

    let light_index = node.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref()).map(|l| l.light.value());
    if let Some(light_index) = light_index {
        let lights = root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref()).map(|l| &l.lights);
        let light = lights.and_then(|l| l.get(light_index));
        let record = light.and_then(|l| {
            let (forward, _) = place?;
            light_record(l, light_index as u32, index as u32, position, forward, ctx.input)
        });
        match (light, record) {
            (Some(l), Some(record)) => builder.add_light(l.name.as_deref().unwrap_or(node_name), record),
            _ => ctx.warn(
                builder,
                format!("node {index}: light {light_index} skipped (its node transform is singular, or its parameters are invalid)"),
            ),
        }
    }
}

fn normalized(v: [f64; 3]) -> Option<[f64; 3]> {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (len.is_finite() && len > 1e-12).then(|| v.map(|c| c / len))
}

/// Imports one primitive instanced by node `node`.
fn import_primitive(
    builder: &mut SceneBuilder,
    ctx: &Ctx,
    buffers: &[Vec<u8>],
    node: usize,
    world: &Mat4,
    mesh: &gl::Mesh,
    primitive: &gl::Primitive,
) -> Result<(), ImportError> {
    let location = format!("mesh {} primitive {}", mesh.index(), primitive.index());
    let mode = primitive.mode();
    match mode {
        Mode::Points => {
            builder.report_mut().skipped_points += 1;
            return Ok(());
        }
        Mode::Lines | Mode::LineLoop | Mode::LineStrip => {
            builder.report_mut().skipped_lines += 1;
            return Ok(());
        }
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => {}
    }
    let checked = check_primitive(primitive, buffers).map_err(|why| ctx.err(format!("{location}: {why}")))?;
    let Some(Checked { position, indices: index_accessor }) = checked else {
        ctx.warn(builder, format!("{location} (node {node}) has no POSITION attribute; skipped"));
        return Ok(());
    };

    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let positions: Vec<[f64; 3]> = if position.count() == 0 {
        Vec::new()
    } else {
        let read = reader.read_positions().ok_or_else(|| ctx.err(format!("{location}: cannot read POSITION")))?;
        read.map(|p| transform_point(world, p)).collect()
    };
    let indices: Option<Vec<u32>> = match &index_accessor {
        None => None,
        Some(ia) if ia.count() == 0 => Some(Vec::new()),
        Some(_) => {
            let read = reader.read_indices().ok_or_else(|| ctx.err(format!("{location}: cannot read the indices")))?;
            Some(read.into_u32().collect())
        }
    };
    if let Some(&bad) = indices.as_deref().unwrap_or_default().iter().find(|&&i| i as usize >= positions.len()) {
        return Err(ImportError::IndexOutOfRange {
            path: ctx.path.to_path_buf(),
            location,
            index: bad as u64,
            count: positions.len() as u64,
        });
    }
    let n = indices.as_ref().map_or(positions.len(), Vec::len);
    let vertex = |k: usize| positions[indices.as_ref().map_or(k, |ix| ix[k] as usize)];
    if mode == Mode::Triangles && !n.is_multiple_of(3) {
        ctx.warn(builder, format!("{location}: {n} vertices is not a multiple of 3; the last {} are ignored", n % 3));
    }
    let triangles = match mode {
        Mode::Triangles => n / 3,
        _ => n.saturating_sub(2),
    };
    if triangles == 0 {
        return Ok(());
    }
    let source = builder.add_source(
        ctx.input,
        SourceDesc {
            kind: source_kind::GLTF_PRIMITIVE,
            name: mesh.name().unwrap_or("").to_string(),
            mesh: mesh.index() as u32,
            primitive: primitive.index() as u32,
            node: node as u32,
            material: primitive.material().index().map_or(NO_INDEX, |m| m as u32),
        },
    );
    for t in 0..triangles {
        // glTF 2.0 §3.7.2.1: strips alternate winding, fans pivot on vertex 0.
        let corners = match mode {
            Mode::TriangleStrip if t % 2 == 1 => [t, t + 2, t + 1],
            Mode::TriangleStrip => [t, t + 1, t + 2],
            Mode::TriangleFan => [t + 1, t + 2, 0],
            _ => [3 * t, 3 * t + 1, 3 * t + 2],
        };
        builder.push_triangle(source, t as u64, corners.map(vertex))?;
    }
    Ok(())
}
