//! The canonical scene a bake consumes: world-space triangles in import order, with provenance.
//!
//! Importers feed a [`SceneBuilder`]; it validates every vertex (finite, not huge), drops
//! zero-area triangles with a count, and records where each kept triangle came from, plus the
//! materials, cameras and lights the inputs define. The bytes of the resulting [`Scene`] are what
//! the TRIANGLES, PROVENANCE, SOURCES, INPUTS, STRINGS, MATERIALS, CAMERAS and LIGHTS sections
//! hold, and what the input hash covers.

use std::path::PathBuf;
use vlf_format::{
    CameraRecord, InputRecord, LightRecord, MaterialRecord, NO_INDEX, ProvenanceRecord, SourceRecord, TriangleRecord,
};

/// Coordinates beyond this magnitude are refused: the f32 kernel cannot resolve such scenes, and
/// products of coordinates would overflow f32.
pub const MAX_COORDINATE: f32 = 1.0e18;

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
        "{path}: {source_name}, triangle {triangle}: vertex {vertex} coordinate {value:?} exceeds ±{max:e}, too large for f32 ray tracing"
    )]
    TooLarge { path: PathBuf, source_name: String, triangle: u64, vertex: usize, value: [f32; 3], max: f32 },
    #[error("{path}: {location}: index {index} is out of range (the mesh has {count} vertices)")]
    IndexOutOfRange { path: PathBuf, location: String, index: u64, count: u64 },
    #[error("{path}: {location} requires the unsupported extension {extension}")]
    UnsupportedExtension { path: PathBuf, location: String, extension: String },
    /// `detail` says why, when it is known: ": all 3 of its triangles have zero area".
    #[error("{what} contains no triangles to bake{detail}")]
    NoTriangles { what: String, detail: String },
    #[error("the scene has more than {max} triangles, the format's limit")]
    TooManyTriangles { max: u64 },
}

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
    /// Zero-area triangles dropped.
    pub dropped_degenerate: u64,
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
    pub triangles: Vec<TriangleRecord>,
    pub provenance: Vec<ProvenanceRecord>,
    pub sources: Vec<SourceRecord>,
    pub inputs: Vec<InputRecord>,
    pub strings: Vec<u8>,
    /// Sorted by (input, index), as MATERIALS requires.
    pub materials: Vec<MaterialRecord>,
    pub cameras: Vec<CameraRecord>,
    pub lights: Vec<LightRecord>,
    pub report: ImportReport,
}

impl Scene {
    /// A scene from bare triangles, for programs and tests: one input named `name`. Zero-area
    /// triangles are dropped and counted, like an importer does.
    pub fn from_triangles(name: &str, triangles: &[[[f32; 3]; 3]]) -> Result<Scene, ImportError> {
        let mut b = SceneBuilder::new();
        let input = b.begin_input(name, *blake3::hash(bytemuck::cast_slice(triangles)).as_bytes());
        let source = b.add_source(input, SourceDesc::program(name));
        for (i, t) in triangles.iter().enumerate() {
            b.push_triangle(source, i as u64, *t)?;
        }
        b.finish()
    }

    /// The vertices of every triangle, for brute-force references.
    pub fn vertices(&self) -> Vec<[[f32; 3]; 3]> {
        self.triangles.iter().map(|t| [t.vertex(0), t.vertex(1), t.vertex(2)]).collect()
    }

    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}

/// Accumulates triangles from one or more inputs.
#[derive(Debug, Default)]
pub struct SceneBuilder {
    scene: Scene,
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

    /// Adds triangle number `index` of `source`. Refuses non-finite or huge coordinates; drops a
    /// zero-area triangle and counts it.
    pub fn push_triangle(&mut self, source: u32, index: u64, v: [[f32; 3]; 3]) -> Result<(), ImportError> {
        for (k, p) in v.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(ImportError::NonFinite {
                    path: self.source_path(source),
                    source_name: self.source_name(source),
                    triangle: index,
                    vertex: k,
                    value: *p,
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
        if vlf_geom::is_degenerate(v[0], v[1], v[2]) {
            self.scene.report.dropped_degenerate += 1;
            return Ok(());
        }
        if self.scene.triangles.len() as u64 >= u32::MAX as u64 {
            return Err(ImportError::TooManyTriangles { max: u32::MAX as u64 - 1 });
        }
        let input = self.scene.sources[source as usize].input as usize;
        self.scene.inputs[input].triangle_count += 1;
        self.scene.triangles.push(TriangleRecord::new(v[0], v[1], v[2]));
        self.scene.provenance.push(ProvenanceRecord { source, index: index.min(u32::MAX as u64) as u32 });
        Ok(())
    }

    /// Records a skipped point or line primitive.
    pub fn report_mut(&mut self) -> &mut ImportReport {
        &mut self.scene.report
    }

    /// Number of triangles kept so far.
    pub fn triangle_count(&self) -> usize {
        self.scene.triangles.len()
    }

    /// The finished scene; an error if it holds no triangle.
    pub fn finish(self) -> Result<Scene, ImportError> {
        if self.scene.triangles.is_empty() {
            let what = match self.paths.as_slice() {
                [one] => one.display().to_string(),
                _ => "the inputs".to_string(),
            };
            return Err(ImportError::NoTriangles { what, detail: String::new() });
        }
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
