//! Wavefront OBJ import through `tobj`.
//!
//! Every face is fan-triangulated by tobj; point and line elements (`p`, `l`, and `f` with one or
//! two vertices) are ignored. Each tobj model — an `o` object or `g` group, split again by tobj
//! wherever `usemtl` changes the material — becomes one source, named after the model.
//!
//! tobj trusts its input more than an importer of arbitrary files may: an out-of-range texture or
//! normal index overflows its arithmetic (a panic in checked builds), its MTL parser panics on a
//! short colour line, and its errors carry neither a line number nor the offending index. So the
//! text is checked here first — UTF-8, vertex lines, face indices against the vertices of the file —
//! and the MTL libraries are read by a small parser of our own ([`parse_mtl`]), which hands tobj
//! only the material names (to number them as sources record them) and maps each material to the
//! Whitted model of MATERIALS (`formats/vlf.md` §5.10).

use super::input::{NotARegularFile, ReadFile, not_text};
use crate::scene::{ImportError, MaterialDesc, SceneBuilder, SourceDesc};
use std::borrow::Cow;
use std::cell::{Cell, RefCell};
use std::path::Path;
use vlf_format::{NO_INDEX, source_kind};

/// The statement keywords of the OBJ format (geometry, grouping, display and free-form).
#[rustfmt::skip]
const KEYWORDS: &[&str] = &[
    "v", "vt", "vn", "vp", "f", "l", "p", "o", "g", "s", "mg", "mtllib", "usemtl", "cstype", "deg", "bmat", "step",
    "curv", "curv2", "surf", "parm", "trim", "hole", "scrv", "sp", "end", "con", "bevel", "c_interp", "d_interp",
    "lod", "shadow_obj", "trace_obj", "maplib", "usemap", "call", "csh",
];

/// Imports the OBJ text `bytes` (read from `path`) as input `input`; material libraries are
/// fetched with `read_file`.
pub(super) fn import(
    builder: &mut SceneBuilder,
    input: u32,
    path: &Path,
    bytes: &[u8],
    read_file: &ReadFile,
) -> Result<(), ImportError> {
    // A GLB or a field named `.obj`, and a start that is not text, were refused by their first
    // bytes (`super::check_start`); what is not UTF-8 further in is refused here.
    let err = |message: String| ImportError::Obj { path: path.to_path_buf(), message };
    let text = std::str::from_utf8(bytes).map_err(|_| {
        let why = not_text(bytes, bytes.len() as u64).unwrap_or_default();
        err(format!("{why}; is this an OBJ file?"))
    })?;
    // A byte-order mark is no part of the first statement (tobj would read `\u{feff}v` as an
    // unknown word and drop the line, shifting every face's vertices).
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim_start().starts_with('{') {
        return Err(err("this looks like glTF JSON, not OBJ text: give it the .gltf extension".to_string()));
    }
    let scan = scan(path, text)?;

    // tobj reads `l` statements as faces (a three-point polyline would become a triangle): blank
    // them, keeping the line count.
    let text: Cow<str> = if scan.has_lines {
        let mut filtered = String::with_capacity(text.len());
        for line in text.lines() {
            if line.split_whitespace().next() != Some("l") {
                filtered.push_str(line);
            }
            filtered.push('\n');
        }
        Cow::Owned(filtered)
    } else {
        Cow::Borrowed(text)
    };

    let base = path.parent().unwrap_or(Path::new(""));
    let warnings = RefCell::new(Vec::new());
    let loaded_libraries = Cell::new(0usize);
    // A library that must not be read (not a regular file): the import fails naming it.
    let fatal = RefCell::new(None::<String>);
    // The materials of every library tobj merged, in its order (the order of material indices).
    let parsed = RefCell::new(Vec::<MaterialDesc>::new());
    // tobj's `merging`/`reordering` features (off here, but a workspace crate could unify them
    // on) add fields whose defaults are what we want.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, materials) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(text.as_bytes()), &options, |library: &Path| {
            let file = base.join(library);
            let loaded = match read_file(&file, u64::MAX) {
                // Not a warning: a pipe or a device named as a library is no missing file.
                Err(e) if NotARegularFile::of(&e).is_some() => {
                    fatal.borrow_mut().get_or_insert_with(|| {
                        format!("material library {:?} ({}): {e}", library.display().to_string(), file.display())
                    });
                    Err(String::new())
                }
                Err(e) => Err(format!("cannot read it ({e})")),
                Ok(b) => match std::str::from_utf8(&b) {
                    Err(_) => Err("it is not UTF-8 text".to_string()),
                    Ok(t) => parse_mtl(t),
                },
            };
            match loaded {
                Ok(parsed_library) => {
                    loaded_libraries.set(loaded_libraries.get() + 1);
                    for problem in &parsed_library.problems {
                        warnings.borrow_mut().push(format!(
                            "{}: material library {:?}: {problem}; the statement is ignored",
                            path.display(),
                            library.display().to_string()
                        ));
                    }
                    if parsed_library.textures > 0 {
                        warnings.borrow_mut().push(format!(
                            "{}: material library {:?}: {} texture map statement(s) ignored (materials are constant colours)",
                            path.display(),
                            library.display().to_string(),
                            parsed_library.textures
                        ));
                    }
                    let names: Vec<String> = parsed_library.materials.iter().map(|m| m.name.clone()).collect();
                    parsed.borrow_mut().extend(parsed_library.materials);
                    let map = names.iter().enumerate().map(|(i, n)| (n.clone(), i)).collect();
                    Ok((names.into_iter().map(|name| tobj::Material { name, ..Default::default() }).collect(), map))
                }
                Err(_) if fatal.borrow().is_some() => Err(tobj::LoadError::OpenFileFailed),
                Err(why) => {
                    warnings.borrow_mut().push(format!(
                        "{}: material library {:?}: {why}; its materials are left unassigned",
                        path.display(),
                        library.display().to_string()
                    ));
                    Err(tobj::LoadError::OpenFileFailed)
                }
            }
        })
        .map_err(|e| err(fatal.borrow_mut().take().unwrap_or_else(|| tobj_message(e))))?;
    if let Some(message) = fatal.into_inner() {
        return Err(err(message));
    }

    let mut warnings = warnings.into_inner();
    let materials = materials.unwrap_or_default();
    let parsed = parsed.into_inner();
    debug_assert_eq!(parsed.len(), materials.len(), "tobj merges the libraries we parsed, in order");
    for (index, material) in parsed.iter().enumerate() {
        builder.add_material(input, index as u32, material);
    }
    let undefined: Vec<&str> =
        scan.usemtl.iter().copied().filter(|name| !materials.iter().any(|m| m.name == *name)).collect();
    if !undefined.is_empty() {
        if loaded_libraries.get() == 0 {
            if scan.mtllibs == 0 {
                warnings.push(format!(
                    "{}: usemtl names {} material(s) but the file declares no material library (mtllib)",
                    path.display(),
                    undefined.len()
                ));
            }
        } else {
            warnings.push(format!(
                "{}: material(s) not defined by any material library: {}",
                path.display(),
                quoted_list(&undefined)
            ));
        }
    }
    if let Some((line, content)) = scan.first_foreign {
        let shown: String = content.chars().take(40).collect();
        warnings.push(format!(
            "{}: {} line(s) hold no OBJ statement and were skipped; the first, line {line}, reads {shown:?}",
            path.display(),
            scan.foreign
        ));
    }
    builder.report_mut().warnings.extend(warnings);

    for (model_index, model) in models.iter().enumerate() {
        let mesh = &model.mesh;
        if mesh.indices.is_empty() {
            continue;
        }
        let vertex_count = mesh.positions.len() / 3;
        if let Some(&bad) = mesh.indices.iter().find(|&&i| i as usize >= vertex_count) {
            return Err(ImportError::IndexOutOfRange {
                path: path.to_path_buf(),
                location: format!("object {:?}", model.name),
                index: bad as u64,
                count: vertex_count as u64,
            });
        }
        let source = builder.add_source(
            input,
            SourceDesc {
                kind: source_kind::OBJ_OBJECT,
                name: model.name.clone(),
                mesh: model_index as u32,
                primitive: 0,
                node: NO_INDEX,
                material: mesh.material_id.map_or(NO_INDEX, |m| m as u32),
            },
        );
        let p = &mesh.positions;
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let v = [tri[0], tri[1], tri[2]].map(|i| {
                let i = i as usize * 3;
                [p[i], p[i + 1], p[i + 2]]
            });
            builder.push_triangle(source, t as u64, v)?;
        }
    }
    Ok(())
}

/// Whether `bytes` (a file of unknown extension) looks like OBJ text: every statement in the first
/// 64 KiB has an OBJ keyword, and there is at least one vertex.
pub(super) fn looks_like_obj(bytes: &[u8]) -> bool {
    let truncated = bytes.len() > 64 * 1024;
    let sample = &bytes[..bytes.len().min(64 * 1024)];
    let text = match std::str::from_utf8(sample) {
        Ok(t) => t,
        // A character cut at the end of the sample.
        Err(e) if truncated && e.error_len().is_none() => std::str::from_utf8(&sample[..e.valid_up_to()]).unwrap_or(""),
        Err(_) => return false,
    };
    let mut lines: Vec<&str> = text.lines().collect();
    if truncated {
        lines.pop();
    }
    let mut vertices = false;
    for line in lines {
        let Some(word) = line.split_whitespace().next() else { continue };
        if word.starts_with('#') {
            continue;
        }
        if !KEYWORDS.contains(&word) {
            return false;
        }
        vertices |= word == "v";
    }
    vertices
}

/// What the checking pass learned about the text.
struct Scan<'a> {
    /// There are `l` statements (removed before tobj sees the text).
    has_lines: bool,
    /// Lines that are neither a statement nor a comment, which tobj skips, and the first of them
    /// (its number and text).
    foreign: usize,
    first_foreign: Option<(usize, &'a str)>,
    /// Distinct material names given to `usemtl`, in order.
    usemtl: Vec<&'a str>,
    /// Number of `mtllib` statements.
    mtllibs: usize,
}

/// Checks what tobj would accept silently, report without a line number, or panic on: vertex
/// lines, face index syntax and ranges, `usemtl` names. Also tells a text file that is not OBJ at
/// all (no statement of the format) from an empty one.
fn scan<'a>(path: &Path, text: &'a str) -> Result<Scan<'a>, ImportError> {
    let err = |line: usize, message: String| ImportError::Obj {
        path: path.to_path_buf(),
        message: format!("line {line}: {message}"),
    };

    // Pass 1: totals (a face may name any vertex of the file by a positive index).
    let (mut v_total, mut vt_total, mut vn_total) = (0i64, 0i64, 0i64);
    let (mut statements, mut foreign) = (0usize, 0usize);
    let mut first_foreign: Option<(usize, &str)> = None;
    for (n, line) in text.lines().enumerate() {
        let Some(word) = line.split_whitespace().next() else { continue };
        match word {
            "v" => v_total += 1,
            "vt" => vt_total += 1,
            "vn" => vn_total += 1,
            _ => {}
        }
        if word.starts_with('#') {
            continue;
        }
        if KEYWORDS.contains(&word) {
            statements += 1;
        } else {
            foreign += 1;
            first_foreign = first_foreign.or(Some((n + 1, line.trim())));
        }
    }
    if let (0, Some((line, content))) = (statements, first_foreign) {
        let shown: String = content.chars().take(40).collect();
        return Err(ImportError::Obj {
            path: path.to_path_buf(),
            message: format!(
                "no OBJ statement (v, f, o, g, ...) in the file; line {line} reads {shown:?}: this is not an OBJ mesh"
            ),
        });
    }

    // Pass 2: statement by statement.
    let mut scan = Scan { has_lines: false, foreign, first_foreign, usemtl: Vec::new(), mtllibs: 0 };
    let (mut v_seen, mut vt_seen, mut vn_seen) = (0i64, 0i64, 0i64);
    let mut object = "unnamed_object";
    for (n, line) in text.lines().enumerate() {
        let n = n + 1;
        let mut words = line.split_whitespace();
        let Some(word) = words.next() else { continue };
        match word {
            "v" => {
                v_seen += 1;
                let numbers: Vec<&str> = words.collect();
                let parse = |s: &str| s.parse::<f32>().ok();
                if numbers.len() < 3 || numbers[..3].iter().any(|s| parse(s).is_none()) {
                    return Err(err(n, format!("a vertex needs three numbers x y z: {:?}", line.trim())));
                }
                match numbers.len() {
                    3 => {}
                    4 => match parse(numbers[3]) {
                        None => return Err(err(n, format!("vertex weight w is not a number: {:?}", line.trim()))),
                        Some(0.0) => return Err(err(n, "vertex weight w is zero".to_string())),
                        Some(_) => {}
                    },
                    6 if numbers[3..].iter().all(|s| parse(s).is_some()) => {}
                    _ => {
                        return Err(err(
                            n,
                            format!("a vertex line holds x y z, x y z w or x y z r g b; found {:?}", line.trim()),
                        ));
                    }
                }
            }
            "vt" => vt_seen += 1,
            "vn" => vn_seen += 1,
            "l" => scan.has_lines = true,
            "o" | "g" => {
                // As tobj names the model: the rest of the line after the keyword's first character.
                let first = line.chars().next().map_or(0, char::len_utf8);
                object = line[first..].trim();
                if object.is_empty() {
                    object = "unnamed_object";
                }
            }
            "mtllib" => scan.mtllibs += 1,
            "usemtl" => {
                let name = line.split_once(' ').unwrap_or_default().1.trim();
                if name.is_empty() {
                    return Err(err(n, "usemtl without a material name".to_string()));
                }
                if !scan.usemtl.contains(&name) {
                    scan.usemtl.push(name);
                }
            }
            "f" => {
                let mut corners = 0;
                for (k, token) in words.enumerate() {
                    corners += 1;
                    let parts: Vec<&str> = token.split('/').collect();
                    let bad = || err(n, format!("face vertex {} is malformed: {token:?}", k + 1));
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(bad());
                    }
                    let mut index = [None; 3];
                    for (slot, part) in parts.iter().enumerate() {
                        if !part.is_empty() {
                            index[slot] = Some(part.parse::<i64>().map_err(|_| bad())?);
                        }
                    }
                    let Some(iv) = index[0] else { return Err(bad()) };
                    if iv > v_total || iv == 0 {
                        return Err(ImportError::IndexOutOfRange {
                            path: path.to_path_buf(),
                            location: format!("line {n}, face of object {object:?}"),
                            index: iv as u64,
                            count: v_total as u64,
                        });
                    }
                    if iv < 0 && v_seen + iv < 0 {
                        return Err(err(
                            n,
                            format!("relative vertex index {iv} reaches before the first vertex ({v_seen} precede it)"),
                        ));
                    }
                    // tobj only looks at texture and normal indices when the file has some.
                    for (slot, what, total, seen) in
                        [(1, "texture coordinate", vt_total, vt_seen), (2, "normal", vn_total, vn_seen)]
                    {
                        let Some(i) = index[slot] else { continue };
                        if total > 0 && (i == 0 || i > total || (i < 0 && seen + i < 0)) {
                            return Err(err(
                                n,
                                format!("{what} index {i} is out of range (the file has {total} {what}s)"),
                            ));
                        }
                    }
                }
                if corners == 0 {
                    return Err(err(n, "a face without vertices".to_string()));
                }
            }
            _ => {}
        }
    }
    Ok(scan)
}

/// What [`parse_mtl`] read from one MTL library.
struct MtlLibrary {
    /// Every `newmtl`, in order (tobj gives a duplicated name the later index).
    materials: Vec<MaterialDesc>,
    /// `map_*`, `bump`, `disp`, `decal` and `refl` statements, which are ignored.
    textures: usize,
    /// Malformed statements, one line each naming the line: ignored, with a warning.
    problems: Vec<String>,
}

/// The statements of one `newmtl` block that the Whitted model uses; `None` = not given.
#[derive(Default)]
struct MtlBlock {
    name: String,
    kd: Option<[f32; 3]>,
    ks: Option<[f32; 3]>,
    ke: Option<[f32; 3]>,
    tf: Option<[f32; 3]>,
    ns: Option<f32>,
    ni: Option<f32>,
    /// Dissolve: `d`, or `1 − Tr`; the later statement wins.
    d: Option<f32>,
    illum: Option<u32>,
}

impl MtlBlock {
    /// The mapping of `formats/vlf.md` §5.10 (OBJ).
    fn to_material(&self) -> MaterialDesc {
        let d = self.d.unwrap_or(1.0);
        let kd = self.kd.unwrap_or([0.8; 3]);
        let ks = self.ks.unwrap_or([0.0; 3]);
        let tf = self.tf.unwrap_or([1.0; 3]);
        let illum = self.illum.unwrap_or(2);
        MaterialDesc {
            name: self.name.clone(),
            diffuse: kd.map(|c| d * c),
            shininess: self.ns.unwrap_or(1.0).clamp(1.0, 4096.0),
            specular: if illum >= 2 { ks } else { [0.0; 3] },
            ior: self.ni.unwrap_or(1.0),
            reflection: if (3..=7).contains(&illum) { ks } else { [0.0; 3] },
            transmission: tf.map(|c| (1.0 - d) * c),
            emission: self.ke.unwrap_or([0.0; 3]),
        }
    }
}

/// Parses an MTL library: every `newmtl` and the statements of §5.10 (`Kd Ks Ke Tf Ns Ni d Tr
/// illum`). Other statements (`Ka`, PBR extensions, texture maps) are ignored; statements before
/// the first `newmtl` too. A malformed statement is skipped and described in `problems`; only a
/// `newmtl` without a name, which would renumber the materials, fails the library.
fn parse_mtl(text: &str) -> Result<MtlLibrary, String> {
    let mut library = MtlLibrary { materials: Vec::new(), textures: 0, problems: Vec::new() };
    let mut current: Option<MtlBlock> = None;
    for (n, line) in text.lines().enumerate() {
        let n = n + 1;
        let line = line.trim();
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        if keyword == "newmtl" {
            let name = line["newmtl".len()..].trim();
            if name.is_empty() {
                return Err(format!("line {n}: newmtl without a name"));
            }
            if let Some(done) = current.replace(MtlBlock { name: name.to_string(), ..Default::default() }) {
                library.materials.push(done.to_material());
            }
            continue;
        }
        if keyword.starts_with("map_") || matches!(keyword, "bump" | "disp" | "decal" | "refl") {
            library.textures += 1;
            continue;
        }
        let Some(block) = current.as_mut() else { continue };
        let args: Vec<&str> = words.collect();
        if let Err(problem) = mtl_statement(block, keyword, &args) {
            library.problems.push(format!("line {n}: {problem}: {line:?}"));
        }
    }
    if let Some(done) = current {
        library.materials.push(done.to_material());
    }
    Ok(library)
}

/// Applies one statement of a `newmtl` block, or says what is wrong with it.
fn mtl_statement(block: &mut MtlBlock, keyword: &str, args: &[&str]) -> Result<(), String> {
    let number = |s: &str| s.parse::<f32>().ok().filter(|v| v.is_finite());
    let scalar = |lo: f32, hi: f32| -> Result<f32, String> {
        match args {
            [v] => number(v)
                .filter(|v| (lo..=hi).contains(v))
                .ok_or_else(|| format!("{keyword} needs one number in [{lo}, {hi}]")),
            _ => Err(format!("{keyword} needs one number")),
        }
    };
    match keyword {
        "Kd" | "Ks" | "Ke" | "Tf" => {
            let values: Option<Vec<f32>> = args.iter().map(|a| number(a).filter(|v| *v >= 0.0)).collect();
            let colour = match values.as_deref() {
                Some(&[v]) => [v; 3],
                Some(&[r, g, b]) => [r, g, b],
                _ => {
                    return Err(format!(
                        "{keyword} needs one or three non-negative numbers (spectral and xyz colours are not supported)"
                    ));
                }
            };
            let slot = match keyword {
                "Kd" => &mut block.kd,
                "Ks" => &mut block.ks,
                "Ke" => &mut block.ke,
                _ => &mut block.tf,
            };
            *slot = Some(colour);
        }
        "Ns" => block.ns = Some(scalar(0.0, f32::MAX)?),
        "Ni" => block.ni = Some(scalar(1e-3, 1e3)?),
        "d" => {
            // `d -halo factor` makes dissolve depend on the view; we take the factor.
            let factor = match args {
                ["-halo", v] | [v] => number(v).filter(|v| (0.0..=1.0).contains(v)),
                _ => None,
            };
            block.d = Some(factor.ok_or("d needs one number in [0, 1]")?);
        }
        "Tr" => block.d = Some(1.0 - scalar(0.0, 1.0)?),
        "illum" => {
            let illum = match args {
                [v] => v.parse::<u32>().ok().filter(|i| *i <= 10),
                _ => None,
            };
            block.illum = Some(illum.ok_or("illum needs an integer from 0 to 10")?);
        }
        _ => {}
    }
    Ok(())
}

/// tobj's error with what it usually means.
fn tobj_message(e: tobj::LoadError) -> String {
    use tobj::LoadError as E;
    let hint = match e {
        E::ReadError => "; the file is not UTF-8 text",
        E::FaceVertexOutOfBounds => "; a face names a vertex that is defined only after the face's object ends",
        E::FaceColorOutOfBounds => "; vertex colours are given for some vertices but not for all",
        E::FaceTexCoordOutOfBounds | E::FaceNormalOutOfBounds => {
            "; a face names a missing texture coordinate or normal"
        }
        E::MaterialParseError => "; a usemtl line has no material name",
        _ => "",
    };
    format!("{e}{hint}")
}

fn quoted_list(names: &[&str]) -> String {
    const SHOWN: usize = 5;
    let mut s = names.iter().take(SHOWN).map(|n| format!("{n:?}")).collect::<Vec<_>>().join(", ");
    if names.len() > SHOWN {
        s.push_str(&format!(" and {} more", names.len() - SHOWN));
    }
    s
}
