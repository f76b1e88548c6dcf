//! The canonical scene a bake consumes: triangles in Morton order of their centroids (so that
//! triangles close in space are close in the file), relative to the scene's centre, with
//! provenance.
//!
//! Importers feed a [`SceneBuilder`] world-space triangles in f64; it validates every vertex
//! (finite, not huge), drops zero-area triangles with a count, and records where each kept
//! triangle came from, plus the materials, cameras and lights the inputs define. When the inputs
//! are done ([`SceneBuilder::finish`]) it places the scene: the centre of its box (kept in f64)
//! becomes the origin of the stored f32 triangles (`formats/vlf.md` §5.7), so a scene far from the
//! world's origin keeps the precision of its own size. A triangle that collapses to zero area in
//! f32 even so is dropped and counted as a loss of precision, and a triangle with the same
//! vertices as an earlier one is merged into it and counted; the rest are put in Morton order
//! ([`crate::order`]). The bytes of the resulting [`Scene`]
//! are what the SCENE's counts, TRIANGLES, PROVENANCE, SOURCES, INPUTS, STRINGS, MATERIALS,
//! CAMERAS and LIGHTS sections hold, and what the input hash covers.

use crate::params::count;
use std::collections::HashMap;
use std::path::PathBuf;
use vlf_format::{
    CameraRecord, DuplicateRecord, InputRecord, LightRecord, MaterialRecord, NO_INDEX, ProvenanceRecord, SourceRecord,
    TriangleRecord,
};

/// Coordinates beyond this magnitude are refused: rays are f32 records (`formats/rays.md`), which
/// cannot place an origin so far away with any precision.
pub const MAX_COORDINATE: f64 = 1.0e18;

/// Everything that can go wrong turning files into a scene. Each variant names the file and,
/// where it applies, the object and element at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImportError {
    #[error("cannot read {path}: {error}")]
    Io { path: PathBuf, error: std::io::Error },
    #[error("{path} is empty (0 bytes): there is no mesh to bake")]
    Empty { path: PathBuf },
    #[error("{path}: unknown mesh format (expected .obj, .gltf or .glb)")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: not a valid OBJ file: {message}")]
    Obj { path: PathBuf, message: String },
    #[error("{path}: not a valid glTF file: {message}")]
    Gltf { path: PathBuf, message: String },
    #[error("{path}: {source_name}, triangle {triangle}: vertex {vertex} has a non-finite coordinate {value:?}")]
    NonFinite { path: PathBuf, source_name: String, triangle: u64, vertex: usize, value: [f32; 3] },
    #[error(
        "{path}: {source_name}, triangle {triangle}: vertex {vertex} coordinate {} exceeds ±{max:e}, too large for f32 ray tracing",
        show_point(value)
    )]
    TooLarge { path: PathBuf, source_name: String, triangle: u64, vertex: usize, value: [f64; 3], max: f64 },
    #[error("{path}: {location}: index {index} is out of range (the mesh has {count} vertices)")]
    IndexOutOfRange { path: PathBuf, location: String, index: u64, count: u64 },
    #[error("{path}: {location} requires the unsupported extension {extension}")]
    UnsupportedExtension { path: PathBuf, location: String, extension: String },
    /// `detail` says why, when it is known: ": all 3 of its triangles have zero area".
    #[error("{what} contains no triangles to bake{detail}")]
    NoTriangles { what: String, detail: String },
    #[error("the scene has more than {max} triangles, the format's limit")]
    TooManyTriangles { max: u64 },
    /// Checked before the triangles are made: a file whose nodes instance its meshes into more
    /// triangles (with those of earlier inputs) than a field may hold.
    #[error(
        "{path}: its nodes instance {triangles} triangles{}, more than {max}, the format's limit",
        if *.earlier > 0 { format!(" (and the inputs before it {})", .earlier) } else { String::new() }
    )]
    InstancesTooManyTriangles { path: PathBuf, triangles: u64, earlier: u64, max: u64 },
    /// Checked before the triangles are made: a file whose nodes instance more triangles than
    /// this process can hold while importing them ([`IMPORT_BYTES_PER_TRIANGLE`] each).
    #[error("{path}: its nodes instance {triangles} triangles, which need {need} of memory to import, but {allowed}")]
    NotEnoughMemory { path: PathBuf, triangles: u64, need: String, allowed: String },
}

/// A point as the file most likely wrote it: each coordinate as f32 (glTF and most OBJ files hold
/// f32), or in full where f32 cannot hold it (`1e308` is shown as such, not as `inf`).
fn show_point(p: &[f64; 3]) -> String {
    let show = |c: f64| if (c as f32).is_finite() { format!("{:?}", c as f32) } else { format!("{c:e}") };
    format!("[{}, {}, {}]", show(p[0]), show(p[1]), show(p[2]))
}

/// The most bytes of memory the import holds for one triangle, until [`SceneBuilder::finish`]
/// returns: its world-space vertices and provenance (80 bytes, reserved exactly before a glTF
/// file's triangles are made), then in `finish` its entry in the duplicate map (41 bytes, in a
/// table up to 16/7 times as large as its entries) and its stored record and provenance (44
/// bytes, in vectors up to twice as large as their contents).
pub const IMPORT_BYTES_PER_TRIANGLE: u64 = 80 + 41 * 16 / 7 + 2 * 44;

/// What an importer describes about one source of triangles.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SourceDesc {
    pub kind: u32,
    pub name: String,
    pub mesh: u32,
    pub primitive: u32,
    pub node: u32,
    pub material: u32,
}

impl SourceDesc {
    /// A source supplied by a program (generated scenes, tests).
    pub fn program(name: &str) -> Self {
        SourceDesc {
            kind: vlf_format::source_kind::PROGRAM,
            name: name.to_string(),
            mesh: 0,
            primitive: 0,
            node: NO_INDEX,
            material: NO_INDEX,
        }
    }
}

/// A material as an importer describes it, already mapped to the Whitted model of
/// `formats/vlf.md` §5.10 (linear RGB).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    pub name: String,
    pub diffuse: [f32; 3],
    pub shininess: f32,
    pub specular: [f32; 3],
    pub ior: f32,
    pub reflection: [f32; 3],
    pub transmission: [f32; 3],
    pub emission: [f32; 3],
}

impl MaterialDesc {
    /// Whether every value lies in the domain §5.10 requires (finite, colours non-negative,
    /// shininess non-negative, ior positive).
    pub fn is_valid(&self) -> bool {
        let colours = [self.diffuse, self.specular, self.reflection, self.transmission, self.emission];
        colours.iter().flatten().all(|c| c.is_finite() && *c >= 0.0)
            && self.shininess.is_finite()
            && self.shininess >= 0.0
            && self.ior.is_finite()
            && self.ior > 0.0
    }
}

/// Facts about an import that are not errors.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct ImportReport {
    /// Zero-area triangles dropped (zero area in the inputs' own f64 coordinates).
    pub dropped_degenerate: u64,
    /// Triangles dropped because they have zero area once stored in f32 relative to the scene's
    /// centre: a loss of precision (a triangle far smaller than the scene), not an input defect.
    pub dropped_precision: u64,
    /// Triangles with the same three stored vertices as an earlier triangle, merged into it.
    pub dropped_duplicates: u64,
    /// Point primitives skipped (glTF).
    pub skipped_points: u64,
    /// Line primitives skipped (glTF; OBJ `l` lines are ignored by the parser and not counted).
    pub skipped_lines: u64,
    /// Human-readable warnings, one line each.
    pub warnings: Vec<String>,
}

/// A scene ready to bake.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// The centre of the box around every input vertex, world units: the origin of `triangles`.
    pub center: [f64; 3],
    /// The triangles relative to `center`, as TRIANGLES stores them.
    pub triangles: Vec<TriangleRecord>,
    pub provenance: Vec<ProvenanceRecord>,
    pub sources: Vec<SourceRecord>,
    pub inputs: Vec<InputRecord>,
    pub strings: Vec<u8>,
    /// Sorted by (input, index), as MATERIALS requires.
    pub materials: Vec<MaterialRecord>,
    pub cameras: Vec<CameraRecord>,
    pub lights: Vec<LightRecord>,
    /// The triangles merged into an earlier one with the same vertices, and where they came from.
    pub duplicates: Vec<DuplicateRecord>,
    pub report: ImportReport,
}

impl Scene {
    /// A scene from bare triangles in world coordinates, for programs and tests: one input named
    /// `name`. Zero-area triangles are dropped and counted, like an importer does.
    pub fn from_triangles(name: &str, triangles: &[[[f32; 3]; 3]]) -> Result<Scene, ImportError> {
        let wide: Vec<[[f64; 3]; 3]> = triangles.iter().map(|t| t.map(|v| v.map(f64::from))).collect();
        Scene::from_triangles_f64(name, &wide)
    }

    /// [`Scene::from_triangles`] from f64 coordinates (a scene far from the origin).
    pub fn from_triangles_f64(name: &str, triangles: &[[[f64; 3]; 3]]) -> Result<Scene, ImportError> {
        let mut b = SceneBuilder::new();
        let input = b.begin_input(name, *blake3::hash(bytemuck::cast_slice(triangles)).as_bytes());
        let source = b.add_source(input, SourceDesc::program(name));
        for (i, t) in triangles.iter().enumerate() {
            b.push_triangle(source, i as u64, *t)?;
        }
        b.finish()
    }

    /// The vertices of every triangle as stored, relative to [`Scene::center`]: with
    /// `vlf_geom::BruteForce::relative(&vertices, scene.center)`, the brute-force reference of a
    /// field baked from this scene.
    pub fn vertices(&self) -> Vec<[[f32; 3]; 3]> {
        self.triangles.iter().map(|t| t.v).collect()
    }

    /// The vertices of every triangle in world coordinates (stored vertex + centre, in f64).
    pub fn world_vertices(&self) -> Vec<[[f64; 3]; 3]> {
        let c = self.center;
        self.triangles.iter().map(|t| t.v.map(|v| std::array::from_fn(|i| v[i] as f64 + c[i]))).collect()
    }

    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Reorders the triangles, with their provenance, along the Morton curve through their
    /// centroids ([`crate::order`]), and renames the kept triangle of every duplicate to match.
    fn put_in_morton_order(&mut self) {
        let order = crate::order::morton_order(&self.vertices());
        let mut new_id = vec![0u32; order.len()];
        for (k, &old) in order.iter().enumerate() {
            new_id[old as usize] = k as u32;
        }
        self.triangles = order.iter().map(|&old| self.triangles[old as usize]).collect();
        self.provenance = order.iter().map(|&old| self.provenance[old as usize]).collect();
        for d in &mut self.duplicates {
            d.triangle = new_id[d.triangle as usize];
        }
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}

/// Accumulates triangles from one or more inputs.
#[derive(Debug, Default)]
pub struct SceneBuilder {
    scene: Scene,
    /// The kept triangles in world coordinates, with their provenance, until [`Self::finish`]
    /// places them relative to the centre.
    world: Vec<([[f64; 3]; 3], ProvenanceRecord)>,
    /// Source path of each input, for error messages (never stored in the field).
    paths: Vec<PathBuf>,
}

impl SceneBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts an input file. Only the final component of `name` is stored.
    pub fn begin_input(&mut self, name: &str, file_hash: [u8; 32]) -> u32 {
        let base = std::path::Path::new(name).file_name().map_or(name.into(), |s| s.to_string_lossy());
        let (name_offset, name_length) = self.intern(&base);
        self.scene.inputs.push(InputRecord { name_offset, name_length, triangle_count: 0, file_hash });
        self.paths.push(PathBuf::from(name));
        (self.scene.inputs.len() - 1) as u32
    }

    /// Adds a source of triangles within input `input`.
    pub fn add_source(&mut self, input: u32, desc: SourceDesc) -> u32 {
        let (name_offset, name_length) = self.intern(&desc.name);
        self.scene.sources.push(SourceRecord {
            input,
            kind: desc.kind,
            name_offset,
            name_length,
            mesh: desc.mesh,
            primitive: desc.primitive,
            node: desc.node,
            material: desc.material,
        });
        (self.scene.sources.len() - 1) as u32
    }

    /// Adds material number `index` of input `input` (the value its sources' `material` holds).
    /// Materials must be added input by input, in increasing index order within an input.
    pub fn add_material(&mut self, input: u32, index: u32, desc: &MaterialDesc) {
        debug_assert!(desc.is_valid(), "importers add only valid materials");
        debug_assert!(self.scene.materials.last().is_none_or(|m| (m.input, m.index) < (input, index)));
        let (name_offset, name_length) = self.intern(&desc.name);
        self.scene.materials.push(MaterialRecord {
            input,
            index,
            name_offset,
            name_length,
            diffuse: desc.diffuse,
            shininess: desc.shininess,
            specular: desc.specular,
            ior: desc.ior,
            reflection: desc.reflection,
            reserved0: 0,
            transmission: desc.transmission,
            reserved1: 0,
            emission: desc.emission,
            reserved2: 0,
        });
    }

    /// Adds a camera; `name` is interned and replaces the record's name fields.
    pub fn add_camera(&mut self, name: &str, mut camera: CameraRecord) {
        (camera.name_offset, camera.name_length) = self.intern(name);
        self.scene.cameras.push(camera);
    }

    /// Adds a light; `name` is interned and replaces the record's name fields.
    pub fn add_light(&mut self, name: &str, mut light: LightRecord) {
        (light.name_offset, light.name_length) = self.intern(name);
        self.scene.lights.push(light);
    }

    /// Adds triangle number `index` of `source`, in world coordinates. Refuses non-finite or huge
    /// coordinates; drops a zero-area triangle and counts it.
    pub fn push_triangle(&mut self, source: u32, index: u64, v: [[f64; 3]; 3]) -> Result<(), ImportError> {
        for (k, p) in v.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(ImportError::NonFinite {
                    path: self.source_path(source),
                    source_name: self.source_name(source),
                    triangle: index,
                    vertex: k,
                    // Shown as the file wrote it (glTF and most OBJ files hold f32).
                    value: p.map(|c| c as f32),
                });
            }
            if p.iter().any(|c| c.abs() > MAX_COORDINATE) {
                return Err(ImportError::TooLarge {
                    path: self.source_path(source),
                    source_name: self.source_name(source),
                    triangle: index,
                    vertex: k,
                    value: *p,
                    max: MAX_COORDINATE,
                });
            }
        }
        if zero_area(&v) {
            self.scene.report.dropped_degenerate += 1;
            return Ok(());
        }
        if self.world.len() as u64 >= u32::MAX as u64 {
            return Err(ImportError::TooManyTriangles { max: u32::MAX as u64 });
        }
        self.world.push((v, ProvenanceRecord { source, index: index.min(u32::MAX as u64) as u32 }));
        Ok(())
    }

    /// Reserves room for `additional` more triangles at once, instead of growing by doubling as
    /// they are pushed; `Err` if the memory cannot be had.
    pub fn try_reserve(&mut self, additional: usize) -> Result<(), std::collections::TryReserveError> {
        self.world.try_reserve_exact(additional)
    }

    /// Records a skipped point or line primitive.
    pub fn report_mut(&mut self) -> &mut ImportReport {
        &mut self.scene.report
    }

    /// Number of triangles kept so far.
    pub fn triangle_count(&self) -> usize {
        self.world.len()
    }

    /// The finished scene: placed relative to the centre of its box, triangles that collapse in
    /// f32 dropped and duplicates merged (both counted, with a warning). An error if no triangle
    /// is left.
    pub fn finish(mut self) -> Result<Scene, ImportError> {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (t, _) in &self.world {
            for v in t {
                for i in 0..3 {
                    lo[i] = lo[i].min(v[i]);
                    hi[i] = hi[i].max(v[i]);
                }
            }
        }
        let center: [f64; 3] = std::array::from_fn(|i| if lo[i] <= hi[i] { 0.5 * (lo[i] + hi[i]) } else { 0.0 });
        self.scene.center = center;
        // Key: the three stored vertices' bits, sorted, so any order of the same corners matches.
        let mut seen: HashMap<[[u32; 3]; 3], u32> = HashMap::with_capacity(self.world.len());
        let report = &mut self.scene.report;
        for (t, provenance) in std::mem::take(&mut self.world) {
            let stored = t.map(|v| std::array::from_fn(|i| (v[i] - center[i]) as f32));
            if vlf_geom::is_degenerate(stored[0], stored[1], stored[2]) {
                report.dropped_precision += 1;
                continue;
            }
            let mut key = stored.map(|v| v.map(f32::to_bits));
            key.sort_unstable();
            let id = self.scene.triangles.len() as u32;
            if let Some(&kept) = seen.get(&key) {
                report.dropped_duplicates += 1;
                let (source, index) = (provenance.source, provenance.index);
                self.scene.duplicates.push(DuplicateRecord { triangle: kept, source, index });
                continue;
            }
            seen.insert(key, id);
            let input = self.scene.sources[provenance.source as usize].input as usize;
            self.scene.inputs[input].triangle_count += 1;
            self.scene.triangles.push(TriangleRecord::new(stored[0], stored[1], stored[2]));
            self.scene.provenance.push(provenance);
        }
        if report.dropped_precision > 0 {
            report.warnings.push(format!(
                "{} collapsed to zero area when stored in f32 relative to the scene's centre (a loss of \
                 precision: too small for the scene's extent) and were dropped",
                count(report.dropped_precision, "triangle", "triangles")
            ));
        }
        if report.dropped_duplicates > 0 {
            report.warnings.push(format!(
                "{} the same three vertices as an earlier triangle and were merged into it \
                 (a ray cannot tell them apart; the field keeps where each came from)",
                count(report.dropped_duplicates, "triangle has", "triangles have")
            ));
        }
        if self.scene.triangles.is_empty() {
            let what = match self.paths.as_slice() {
                [one] => one.display().to_string(),
                _ => "the inputs".to_string(),
            };
            let detail = if report.dropped_precision > 0 {
                format!(
                    ": {} collapsed to zero area in f32 relative to the scene's centre",
                    count(report.dropped_precision, "triangle", "triangles")
                )
            } else {
                String::new()
            };
            return Err(ImportError::NoTriangles { what, detail });
        }
        self.scene.put_in_morton_order();
        // Sorted by the kept triangle (stable: import order among the duplicates of one).
        self.scene.duplicates.sort_by_key(|d| d.triangle);
        Ok(self.scene)
    }

    fn intern(&mut self, s: &str) -> (u32, u32) {
        let offset = self.scene.strings.len() as u32;
        self.scene.strings.extend_from_slice(s.as_bytes());
        (offset, s.len() as u32)
    }

    fn source_path(&self, source: u32) -> PathBuf {
        self.paths[self.scene.sources[source as usize].input as usize].clone()
    }

    fn source_name(&self, source: u32) -> String {
        let s = &self.scene.sources[source as usize];
        let name =
            std::str::from_utf8(&self.scene.strings[s.name_offset as usize..(s.name_offset + s.name_length) as usize])
                .unwrap_or("?");
        match s.kind {
            vlf_format::source_kind::GLTF_PRIMITIVE => {
                format!("mesh {} ({name:?}) primitive {} of node {}", s.mesh, s.primitive, s.node)
            }
            vlf_format::source_kind::OBJ_OBJECT => format!("object {name:?}"),
            _ => format!("source {name:?}"),
        }
    }
}

/// Whether a triangle has zero area in f64: its edge cross product is exactly zero.
fn zero_area(v: &[[f64; 3]; 3]) -> bool {
    let e1: [f64; 3] = std::array::from_fn(|i| v[1][i] - v[0][i]);
    let e2: [f64; 3] = std::array::from_fn(|i| v[2][i] - v[0][i]);
    let c = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    c == [0.0; 3]
}
