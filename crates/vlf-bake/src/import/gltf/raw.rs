//! What the import reads from the glTF JSON itself, where the typed document drops it: the
//! extensions on primitives, accessors, buffer views and nodes, and a node's transform as written.
//!
//! Only that is kept. The whole document as a `serde_json::Value` took about 830 bytes a node (a
//! B-tree node for each JSON object), 830 MB for a chain of a million nodes holding one triangle,
//! on top of the typed document's 250 bytes a node; here a node is one byte, whether it uses
//! `EXT_mesh_gpu_instancing`. The meshes, accessors and buffer views stay JSON values (their
//! size follows the file's arrays of them, not its nodes). A node's transform as written is
//! looked up again only for an error message ([`raw_node`]), keeping nothing else.

use serde::Deserialize;
use serde::de::{DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde_json::Value;
use std::fmt;

/// The parts of the glTF JSON the import reads raw.
#[derive(Default, Deserialize)]
#[serde(default)]
pub(super) struct Raw {
    #[serde(rename = "extensionsRequired")]
    extensions_required: Value,
    meshes: Value,
    accessors: Value,
    #[serde(rename = "bufferViews")]
    buffer_views: Value,
    pub nodes: Vec<RawNode>,
}

impl Raw {
    /// The top-level property `name` of the document, as [`Value::get`] would give it, for those
    /// kept: `extensionsRequired`, `meshes`, `accessors`, `bufferViews` (null when absent).
    pub fn get(&self, name: &str) -> Option<&Value> {
        match name {
            "extensionsRequired" => Some(&self.extensions_required),
            "meshes" => Some(&self.meshes),
            "accessors" => Some(&self.accessors),
            "bufferViews" => Some(&self.buffer_views),
            _ => None,
        }
    }
}

/// A node, as far as the import reads it raw: whether it uses `EXT_mesh_gpu_instancing`.
#[derive(Default, Deserialize)]
#[serde(default)]
pub(super) struct RawNode {
    extensions: Option<NodeExtensions>,
}

#[derive(Default, Deserialize)]
#[serde(default)]
struct NodeExtensions {
    #[serde(rename = "EXT_mesh_gpu_instancing")]
    instancing: Option<IgnoredAny>,
}

impl RawNode {
    pub fn uses_gpu_instancing(&self) -> bool {
        self.extensions.as_ref().is_some_and(|e| e.instancing.is_some())
    }
}

/// Node `index` of the glTF JSON `json` as written, for a message; the rest of the document is
/// skipped as it is read, not kept.
pub(super) fn raw_node(json: &[u8], index: usize) -> Option<Value> {
    let mut deserializer = serde_json::Deserializer::from_slice(json);
    Document(index).deserialize(&mut deserializer).ok().flatten()
}

/// Finds node `.0` in a document.
struct Document(usize);

impl<'de> DeserializeSeed<'de> for Document {
    type Value = Option<Value>;
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<Self::Value, D::Error> {
        deserializer.deserialize_map(self)
    }
}

impl<'de> Visitor<'de> for Document {
    type Value = Option<Value>;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a glTF document")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut found = None;
        while let Some(key) = map.next_key::<std::borrow::Cow<str>>()? {
            if key == "nodes" {
                found = map.next_value_seed(Nth(self.0))?;
            } else {
                map.next_value::<IgnoredAny>()?;
            }
        }
        Ok(found)
    }
}

/// Finds element `.0` in an array.
struct Nth(usize);

impl<'de> DeserializeSeed<'de> for Nth {
    type Value = Option<Value>;
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<Self::Value, D::Error> {
        deserializer.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for Nth {
    type Value = Option<Value>;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("an array")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        for _ in 0..self.0 {
            if seq.next_element::<IgnoredAny>()?.is_none() {
                return Ok(None);
            }
        }
        let found = seq.next_element::<Value>()?;
        while seq.next_element::<IgnoredAny>()?.is_some() {}
        Ok(found)
    }
}
