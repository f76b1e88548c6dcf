//! The scene file (`formats/scene.md`): JSON naming the fields to place, their transforms and
//! masks, and the edits to make to them. [`SceneFile::parse`] checks every key and value before
//! anything is opened; [`SceneFile::load`] then opens each field once, reads each mesh once,
//! makes the edits and builds the [`Scene`].
//!
//! Every error names the file, the instance (its index in `"instances"`) and the key.

use crate::affine::Affine;
use crate::edit::{EditedField, Object};
use crate::scene::Scene;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Value};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use vlf_runtime::{Field, FormatError, OpenError, OpenOptions};

/// The largest scene file read: JSON this long describes millions of instances.
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// The keys of an instance, in the order `formats/scene.md` gives them.
pub const INSTANCE_KEYS: [&str; 5] = ["field", "transform", "mask", "remove", "insert"];

/// A scene file, parsed and checked; paths resolved against the file's directory.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFile {
    /// The file, as given.
    pub path: PathBuf,
    /// `"instances"`, in order: entry `i` becomes the scene's instance `i`.
    pub instances: Vec<InstanceSpec>,
}

/// One entry of `"instances"`.
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceSpec {
    /// `"field"`, resolved.
    pub field: PathBuf,
    /// `"transform"`: the field's space to the world (identity when absent).
    pub transform: Affine,
    /// `"mask"` (`0xFFFFFFFF` when absent).
    pub mask: u32,
    /// `"remove"`: provenance object names whose triangles are removed.
    pub remove: Vec<String>,
    /// `"insert"`: meshes inserted into this instance's field.
    pub insert: Vec<InsertSpec>,
}

/// One entry of an instance's `"insert"`.
#[derive(Clone, Debug, PartialEq)]
pub struct InsertSpec {
    /// `"mesh"`, resolved.
    pub mesh: PathBuf,
    /// `"transform"`: the mesh's space to the field's (identity when absent).
    pub transform: Affine,
}

/// Why a scene file was refused. Each message is one line naming the file and, for a fault in an
/// instance, the instance and the key.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneFileError {
    /// The file cannot be read.
    #[error("cannot read scene file {path}: {error}")]
    Io {
        /// The scene file.
        path: PathBuf,
        /// What the system said.
        error: std::io::Error,
    },
    /// The file is larger than [`MAX_FILE_BYTES`].
    #[error("scene file {path} is {bytes} bytes, over the {max} a scene file may be", max = MAX_FILE_BYTES)]
    TooLarge {
        /// The scene file.
        path: PathBuf,
        /// Its size.
        bytes: u64,
    },
    /// The file is not JSON (or repeats a key in one object).
    #[error("scene file {path} is not valid JSON: {error}")]
    Json {
        /// The scene file.
        path: PathBuf,
        /// The parser's error, with its line and column.
        error: serde_json::Error,
    },
    /// The top level is wrong: not an object, no `"instances"`, or a key it does not know.
    #[error("scene file {path}: {message}")]
    TopLevel {
        /// The scene file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// An instance's key is unknown, or its value is wrong, or what it names cannot be used.
    #[error("scene file {path}: instance {index}: key \"{key}\": {message}")]
    Instance {
        /// The scene file.
        path: PathBuf,
        /// The instance's index in `"instances"`.
        index: usize,
        /// The key at fault.
        key: String,
        /// What is wrong.
        message: String,
    },
}

/// Reads a mesh file into triangles (world coordinates of the mesh's own space): the caller's
/// importer (the command line passes `vlf-bake`'s, which reads OBJ, glTF and GLB).
pub type MeshLoader<'a> = &'a dyn Fn(&Path) -> Result<Vec<[[f64; 3]; 3]>, String>;

struct Ctx<'a> {
    path: &'a Path,
    dir: &'a Path,
}

impl Ctx<'_> {
    fn fail(&self, index: usize, key: &str, message: impl Into<String>) -> SceneFileError {
        SceneFileError::Instance { path: self.path.into(), index, key: key.into(), message: message.into() }
    }

    fn top(&self, message: impl Into<String>) -> SceneFileError {
        SceneFileError::TopLevel { path: self.path.into(), message: message.into() }
    }

    fn resolve(&self, p: &str) -> PathBuf {
        self.dir.join(p)
    }

    fn string(&self, index: usize, key: &str, v: &Value, what: &str) -> Result<String, SceneFileError> {
        match v {
            Value::String(s) if !s.is_empty() => Ok(s.clone()),
            Value::String(_) => Err(self.fail(index, key, format!("{what} is an empty string"))),
            other => Err(self.fail(index, key, format!("{what} must be a string, not {}", kind(other)))),
        }
    }

    fn transform(&self, index: usize, key: &str, v: &Value, what: &str) -> Result<Affine, SceneFileError> {
        let Value::Array(items) = v else {
            return Err(self.fail(index, key, format!("{what} must be an array of 16 numbers, not {}", kind(v))));
        };
        if items.len() != 16 {
            return Err(self.fail(
                index,
                key,
                format!("{what} must be 16 numbers (a row-major 4×4 matrix), not {}", items.len()),
            ));
        }
        let mut m = [0.0; 16];
        for (k, item) in items.iter().enumerate() {
            m[k] = item
                .as_f64()
                .ok_or_else(|| self.fail(index, key, format!("{what}: element {k} is {}, not a number", kind(item))))?;
        }
        Affine::from_rows(&m).map_err(|e| self.fail(index, key, format!("{what} is not usable: {e}")))
    }
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

impl SceneFile {
    /// Reads and parses the scene file at `path` ([`SceneFile::parse`]).
    ///
    /// # Errors
    /// [`SceneFileError::Io`], [`SceneFileError::TooLarge`], and those of [`SceneFile::parse`].
    pub fn read(path: &Path) -> Result<SceneFile, SceneFileError> {
        let io = |error| SceneFileError::Io { path: path.into(), error };
        let bytes = std::fs::metadata(path).map_err(io)?.len();
        if bytes > MAX_FILE_BYTES {
            return Err(SceneFileError::TooLarge { path: path.into(), bytes });
        }
        // Only a regular file (a pipe would be waited on, `/dev/zero` read without end), and no
        // more than the limit, should it grow meanwhile.
        let raw = vlf_runtime::regular::read_regular_file(path, MAX_FILE_BYTES).map_err(io)?;
        let text = String::from_utf8(raw).map_err(|e| {
            io(std::io::Error::new(std::io::ErrorKind::InvalidData, format!("it is not UTF-8 text: {e}")))
        })?;
        SceneFile::parse(&text, path)
    }

    /// Parses the JSON `text` of the scene file at `path` (relative paths inside it are resolved
    /// against `path`'s directory) and checks every key and value: nothing is opened yet.
    ///
    /// # Errors
    /// [`SceneFileError::Json`] (including a key given twice in one object),
    /// [`SceneFileError::TopLevel`], [`SceneFileError::Instance`].
    pub fn parse(text: &str, path: &Path) -> Result<SceneFile, SceneFileError> {
        let mut de = serde_json::Deserializer::from_str(text);
        let json = de::Deserialize::deserialize(&mut de)
            .and_then(|v: Strict| de.end().map(|()| v.0))
            .map_err(|error| SceneFileError::Json { path: path.into(), error })?;
        let dir = path.parent().unwrap_or(Path::new(""));
        let ctx = Ctx { path, dir };
        let Value::Object(top) = json else {
            return Err(
                ctx.top(format!("the top level must be an object with the key \"instances\", not {}", kind(&json)))
            );
        };
        if let Some(k) = top.keys().find(|k| *k != "instances") {
            return Err(ctx.top(format!("unknown key \"{k}\" at the top level (the only one is \"instances\")")));
        }
        let Some(list) = top.get("instances") else {
            return Err(ctx.top("the key \"instances\" is missing"));
        };
        let Value::Array(list) = list else {
            return Err(ctx.top(format!("\"instances\" must be an array, not {}", kind(list))));
        };
        let instances = list.iter().enumerate().map(|(i, v)| instance(&ctx, i, v)).collect::<Result<_, _>>()?;
        Ok(SceneFile { path: path.into(), instances })
    }

    /// Opens every field (each path once, shared by its instances), reads every mesh (each
    /// once) with `meshes`, makes each instance's edits and builds the scene. An instance with
    /// edits gets its own copy of the field's edits (the mapping is still shared); instances
    /// without edits share one. Instance `i` of the file is the scene's instance `i`.
    ///
    /// # Errors
    /// [`SceneFileError::Instance`] naming the instance and the key: a field that cannot be
    /// opened (`field`), a name no triangle comes from (`remove`), a mesh that cannot be read or
    /// does not fit in the field's bounding sphere (`insert`).
    pub fn load(&self, meshes: MeshLoader<'_>) -> Result<Scene, SceneFileError> {
        self.load_with(meshes, &OpenOptions::new())
    }

    /// [`SceneFile::load`], opening the fields with `options`. A cap on the memory packed fields
    /// decode into ([`OpenOptions::max_unpacked_bytes`]) holds for all of the scene's packed
    /// fields together: each is opened with what the ones before it left.
    ///
    /// # Errors
    /// As [`SceneFile::load`].
    pub fn load_with(&self, meshes: MeshLoader<'_>, options: &OpenOptions) -> Result<Scene, SceneFileError> {
        let dir = self.path.parent().unwrap_or(Path::new(""));
        let ctx = Ctx { path: &self.path, dir };
        // One mapping per file, however its path is spelled (`a.vlf`, `./a.vlf`, a link).
        let key = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        let keys: Vec<PathBuf> = self.instances.iter().map(|spec| key(&spec.field)).collect();
        let mut opened: HashMap<&Path, Arc<Field>> = HashMap::new();
        let (limit, mut unpacked) = (options.unpacked_limit(), 0u64);
        for (i, spec) in self.instances.iter().enumerate() {
            if !opened.contains_key(keys[i].as_path()) {
                let mut these = options.clone();
                if let Some(limit) = limit {
                    these.max_unpacked_bytes(limit.saturating_sub(unpacked));
                }
                let f = these.open(&spec.field).map_err(|e| {
                    let before = match (&e, limit) {
                        (OpenError::Format { error: FormatError::UnpackedTooLarge { .. }, .. }, Some(limit))
                            if unpacked > 0 =>
                        {
                            format!(
                                " (the scene's packed fields opened before it take {unpacked} of the {limit} bytes \
                                 allowed for all of them)"
                            )
                        }
                        _ => String::new(),
                    };
                    ctx.fail(i, "field", format!("cannot open {}: {e}{before}", spec.field.display()))
                })?;
                if f.is_packed() {
                    unpacked = unpacked.saturating_add(f.len_bytes());
                }
                opened.insert(&keys[i], Arc::new(f));
            }
        }
        let mut read: HashMap<&Path, Vec<[[f64; 3]; 3]>> = HashMap::new();
        for (i, spec) in self.instances.iter().enumerate() {
            for (k, ins) in spec.insert.iter().enumerate() {
                if !read.contains_key(ins.mesh.as_path()) {
                    let tris = meshes(&ins.mesh).map_err(|e| ctx.fail(i, "insert", format!("[{k}]: {e}")))?;
                    read.insert(&ins.mesh, tris);
                }
            }
        }
        let mut scene = Scene::new();
        let mut shared = HashMap::new();
        let mut placed = Vec::with_capacity(self.instances.len());
        for (i, spec) in self.instances.iter().enumerate() {
            let base = opened[keys[i].as_path()].clone();
            let id = if spec.remove.is_empty() && spec.insert.is_empty() {
                *shared.entry(keys[i].as_path()).or_insert_with(|| scene.add_field(EditedField::new(base)))
            } else {
                let mut f = EditedField::new(base);
                for name in &spec.remove {
                    f.remove_object(Object::Name(name)).map_err(|e| ctx.fail(i, "remove", e.to_string()))?;
                }
                // Every insert of the instance in one pass over the field's tiles.
                let parts: Vec<(&[[[f64; 3]; 3]], &Affine)> =
                    spec.insert.iter().map(|ins| (read[ins.mesh.as_path()].as_slice(), &ins.transform)).collect();
                f.insert_all(&parts)
                    .map_err(|(k, e)| ctx.fail(i, "insert", format!("[{k}] {}: {e}", spec.insert[k].mesh.display())))?;
                scene.add_field(f)
            };
            placed.push((id, spec.transform, spec.mask));
        }
        // The hierarchy built once over every instance.
        scene.add_instances(&placed).map_err(|(i, e)| ctx.fail(i, "field", e.to_string()))?;
        Ok(scene)
    }
}

fn instance(ctx: &Ctx<'_>, i: usize, v: &Value) -> Result<InstanceSpec, SceneFileError> {
    let Value::Object(o) = v else {
        return Err(ctx.top(format!("instance {i} must be an object, not {}", kind(v))));
    };
    if let Some(k) = o.keys().find(|k| !INSTANCE_KEYS.contains(&k.as_str())) {
        return Err(ctx.fail(i, k, format!("unknown key (an instance has {})", quoted(&INSTANCE_KEYS))));
    }
    let field = match o.get("field") {
        Some(v) => ctx.resolve(&ctx.string(i, "field", v, "the field's path")?),
        None => return Err(ctx.fail(i, "field", "missing: every instance names its field")),
    };
    let transform = match o.get("transform") {
        Some(v) => ctx.transform(i, "transform", v, "the transform")?,
        None => Affine::IDENTITY,
    };
    let mask = match o.get("mask") {
        None => u32::MAX,
        Some(v) => v
            .as_u64()
            .and_then(|m| u32::try_from(m).ok())
            .ok_or_else(|| ctx.fail(i, "mask", format!("must be an integer from 0 to 4294967295, not {v}")))?,
    };
    let remove = match o.get("remove") {
        None => Vec::new(),
        Some(Value::Array(names)) => names
            .iter()
            .enumerate()
            .map(|(k, n)| ctx.string(i, "remove", n, &format!("element {k}")))
            .collect::<Result<_, _>>()?,
        Some(other) => {
            return Err(ctx.fail(i, "remove", format!("must be an array of object names, not {}", kind(other))));
        }
    };
    let insert = match o.get("insert") {
        None => Vec::new(),
        Some(Value::Array(items)) => {
            items.iter().enumerate().map(|(k, item)| insert(ctx, i, k, item)).collect::<Result<_, _>>()?
        }
        Some(other) => {
            return Err(ctx.fail(
                i,
                "insert",
                format!("must be an array of {{\"mesh\", \"transform\"}} objects, not {}", kind(other)),
            ));
        }
    };
    Ok(InstanceSpec { field, transform, mask, remove, insert })
}

fn insert(ctx: &Ctx<'_>, i: usize, k: usize, v: &Value) -> Result<InsertSpec, SceneFileError> {
    let Value::Object(o) = v else {
        return Err(ctx.fail(
            i,
            "insert",
            format!("element {k} must be an object with \"mesh\" and \"transform\", not {}", kind(v)),
        ));
    };
    if let Some(bad) = o.keys().find(|key| *key != "mesh" && *key != "transform") {
        return Err(ctx.fail(
            i,
            "insert",
            format!("element {k}: unknown key \"{bad}\" (an insertion has \"mesh\" and \"transform\")"),
        ));
    }
    let mesh = match o.get("mesh") {
        Some(m) => ctx.resolve(&ctx.string(i, "insert", m, &format!("element {k}: \"mesh\""))?),
        None => return Err(ctx.fail(i, "insert", format!("element {k}: \"mesh\" is missing"))),
    };
    let transform = match o.get("transform") {
        Some(t) => ctx.transform(i, "insert", t, &format!("element {k}: the transform"))?,
        None => Affine::IDENTITY,
    };
    Ok(InsertSpec { mesh, transform })
}

fn quoted(keys: &[&str]) -> String {
    keys.iter().map(|k| format!("\"{k}\"")).collect::<Vec<_>>().join(", ")
}

/// A JSON value whose objects may not repeat a key (serde_json keeps the last silently).
struct Strict(Value);

impl<'de> de::Deserialize<'de> for Strict {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Strict, D::Error> {
        d.deserialize_any(StrictVisitor).map(Strict)
    }
}

struct StrictVisitor;

impl<'de> Visitor<'de> for StrictVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.into()))
    }
    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut out = Vec::new();
        while let Some(Strict(v)) = seq.next_element()? {
            out.push(v);
        }
        Ok(Value::Array(out))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                return Err(de::Error::custom(format!("the key \"{key}\" appears twice in one object")));
            }
            let Strict(v) = map.next_value()?;
            out.insert(key, v);
        }
        Ok(Value::Object(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<SceneFile, String> {
        SceneFile::parse(text, Path::new("dir/scene.json")).map_err(|e| e.to_string())
    }

    #[test]
    fn a_full_instance_parses_with_paths_resolved() {
        let s = parse(
            r#"{"instances": [
                {"field": "room.vlf"},
                {"field": "sub/chair.vlf", "mask": 2,
                 "transform": [0,-1,0,5, 1,0,0,0, 0,0,2,1, 0,0,0,1],
                 "remove": ["Chair", "Lamp"],
                 "insert": [{"mesh": "box.obj"}, {"mesh": "/abs/b.glb", "transform": [1,0,0,0, 0,1,0,0, 0,0,1,0.5, 0,0,0,1]}]}
            ]}"#,
        )
        .unwrap();
        assert_eq!(s.instances.len(), 2);
        assert_eq!(s.instances[0].field, Path::new("dir/room.vlf"));
        assert_eq!((s.instances[0].mask, s.instances[0].transform), (u32::MAX, Affine::IDENTITY));
        let b = &s.instances[1];
        assert_eq!(b.field, Path::new("dir/sub/chair.vlf"));
        assert_eq!(b.mask, 2);
        assert_eq!(b.transform.point([1.0, 0.0, 0.0]), [5.0, 1.0, 1.0]);
        assert_eq!(b.remove, ["Chair", "Lamp"]);
        assert_eq!(b.insert[0].mesh, Path::new("dir/box.obj"));
        assert_eq!(b.insert[1].mesh, Path::new("/abs/b.glb"));
        assert_eq!(b.insert[1].transform.point([0.0; 3]), [0.0, 0.0, 0.5]);
    }

    #[test]
    fn every_fault_names_the_instance_and_the_key() {
        let cases: &[(&str, &[&str])] = &[
            (r#"[]"#, &["top level must be an object"]),
            (r#"{"instances": [], "extra": 1}"#, &["unknown key \"extra\""]),
            (r#"{}"#, &["\"instances\" is missing"]),
            (r#"{"instances": {}}"#, &["must be an array"]),
            (r#"{"instances": [{"field": "a", "scale": 2}]}"#, &["instance 0", "key \"scale\"", "unknown key"]),
            (r#"{"instances": [{"mask": 1}]}"#, &["instance 0", "key \"field\"", "missing"]),
            (r#"{"instances": [{"field": ""}]}"#, &["key \"field\"", "empty string"]),
            (r#"{"instances": [{"field": "a"}, {"field": 3}]}"#, &["instance 1", "key \"field\"", "must be a string"]),
            (r#"{"instances": [{"field": "a", "transform": [1,0,0]}]}"#, &["key \"transform\"", "16 numbers", "not 3"]),
            (
                r#"{"instances": [{"field": "a", "transform": [1,0,0,0, 0,1,0,0, 0,0,0,0, 0,0,0,1]}]}"#,
                &["key \"transform\"", "singular"],
            ),
            (
                r#"{"instances": [{"field": "a", "transform": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1]}]}"#,
                &["key \"transform\"", "last row"],
            ),
            (r#"{"instances": [{"field": "a", "transform": [1,0,0,0, 0,1,"x",0, 0,0,1,0, 0,0,0,1]}]}"#, &["element 6"]),
            (r#"{"instances": [{"field": "a", "mask": -1}]}"#, &["key \"mask\"", "0 to 4294967295"]),
            (r#"{"instances": [{"field": "a", "mask": 4294967296}]}"#, &["key \"mask\""]),
            (r#"{"instances": [{"field": "a", "mask": 1.5}]}"#, &["key \"mask\""]),
            (r#"{"instances": [{"field": "a", "remove": "Chair"}]}"#, &["key \"remove\"", "array of object names"]),
            (r#"{"instances": [{"field": "a", "remove": ["A", 2]}]}"#, &["key \"remove\"", "element 1"]),
            (
                r#"{"instances": [{"field": "a", "insert": [{"transform": []}]}]}"#,
                &["key \"insert\"", "\"mesh\" is missing"],
            ),
            (
                r#"{"instances": [{"field": "a", "insert": [{"mesh": "m", "at": 1}]}]}"#,
                &["key \"insert\"", "unknown key \"at\""],
            ),
            (r#"{"instances": [{"field": "a", "field": "b"}]}"#, &["appears twice", "line 1"]),
            (r#"{"instances": [{"field": "a"}]} x"#, &["not valid JSON"]),
            (r#"{"instances": [1]}"#, &["instance 0 must be an object"]),
        ];
        for (text, want) in cases {
            let e = parse(text).expect_err(text);
            assert!(e.contains("dir/scene.json"), "{e}");
            for w in *want {
                assert!(e.contains(w), "{text}: {e:?} lacks {w:?}");
            }
        }
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let text = format!("{{\"instances\": {}{}}}", "[".repeat(100_000), "]".repeat(100_000));
        assert!(parse(&text).unwrap_err().contains("not valid JSON"));
    }
}
