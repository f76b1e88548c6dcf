//! The triangles a glTF scene expands to, counted before any of them is made. A few kilobytes of
//! JSON can instance one mesh from many nodes, and one accessor from many primitives: 100,000
//! primitives reusing a 1,000-triangle accessor are 10⁸ triangles, about 26 GB to import. The
//! count comes from the accessors' element counts alone, so a file that expands past the format's
//! limit or past the memory this process can still allocate is refused at once, naming the
//! numbers, instead of by the allocator's abort minutes later.

use super::accessor::{check_primitive, triangles};
use crate::memory;
use crate::params::human_bytes;
use crate::scene::{IMPORT_BYTES_PER_TRIANGLE, ImportError, SceneBuilder};
use ::gltf as gl;
use std::path::Path;

/// The most triangles a field holds: 2³² − 1 (triangle ids are u32).
const MAX_TRIANGLES: u64 = u32::MAX as u64;

/// The triangles the import will make of `primitive`, from its checked accessors' counts; none
/// for one it skips, and the import's own message for one it refuses.
fn primitive_triangles(primitive: &gl::Primitive, buffers: &[Vec<u8>]) -> Result<u64, String> {
    Ok(check_primitive(primitive, buffers)?.map_or(0, |checked| triangles(primitive.mode(), &checked)))
}

/// Counts the triangles the nodes of the glTF file at `path` `visits` (indices into `nodes`)
/// instance, and refuses them if a primitive's accessors are ones the import refuses, if with the
/// triangles `builder` holds they pass the format's limit, or if importing them needs more memory
/// than [`memory::budget`] allows; else reserves room for them in `builder`.
pub(super) fn check(
    builder: &mut SceneBuilder,
    path: &Path,
    nodes: &[gl::Node],
    meshes: usize,
    visits: &[usize],
    buffers: &[Vec<u8>],
) -> Result<(), ImportError> {
    // Each mesh counted once, however many nodes instance it.
    let mut per_mesh: Vec<Option<u64>> = vec![None; meshes];
    let mut triangles = 0u64;
    for mesh in visits.iter().filter_map(|&i| nodes.get(i).and_then(gl::Node::mesh)) {
        let Some(slot) = per_mesh.get_mut(mesh.index()) else { continue };
        let n = match *slot {
            Some(n) => n,
            None => {
                let mut n = 0u64;
                for p in mesh.primitives() {
                    let location = format!("mesh {} primitive {}", mesh.index(), p.index());
                    let message = |why| format!("{location}: {why}");
                    let made = primitive_triangles(&p, buffers)
                        .map_err(|why| ImportError::Gltf { path: path.to_path_buf(), message: message(why) })?;
                    n = n.saturating_add(made);
                }
                *slot.insert(n)
            }
        };
        triangles = triangles.saturating_add(n);
    }
    let path = path.to_path_buf();
    let earlier = builder.triangle_count() as u64;
    if triangles.saturating_add(earlier) > MAX_TRIANGLES {
        return Err(ImportError::InstancesTooManyTriangles { path, triangles, earlier, max: MAX_TRIANGLES });
    }
    let need = triangles.saturating_mul(IMPORT_BYTES_PER_TRIANGLE);
    let (budget, why) = memory::budget();
    let refuse = |allowed: String| ImportError::NotEnoughMemory {
        path: path.clone(),
        triangles,
        need: human_bytes(need),
        allowed,
    };
    if need > budget {
        return Err(refuse(format!("{} may be used ({why})", human_bytes(budget))));
    }
    builder.try_reserve(triangles as usize).map_err(|_| refuse("they cannot be allocated".to_string()))
}
