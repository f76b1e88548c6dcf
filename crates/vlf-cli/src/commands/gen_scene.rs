//! `vlf-bake gen`: generate a test scene (the paper's random triangles, grids, slivers) as OBJ,
//! streamed to its file: memory does not grow with the count, and a file the disk has no room for
//! is refused before anything is written.

use super::stdout_line;
use crate::args::{GenArgs, SceneKind};
use crate::distinct::{Writes, check_outputs};
use crate::limits::check_disk;
use crate::values::{MAX_TRIANGLES, between};
use anyhow::{Context, Result};
use std::io::Write;
use vlf_bake::atomic::write_atomically;
use vlf_bake::generate;
use vlf_bake::params::human_bytes;

/// Layers of a generated grid.
const GRID_LAYERS: u32 = 4;

/// The largest `--count` of a grid: `2 · count² · 4` triangles must stay within [`MAX_TRIANGLES`].
pub const MAX_GRID_CELLS: u64 = 23_170;

/// What `gen` prints, and its `--json` keys.
#[derive(serde::Serialize)]
struct GenSummary<'a> {
    output: &'a std::path::Path,
    scene: &'static str,
    triangles: u64,
    seed: u64,
    bytes: u64,
}

/// `vlf-bake gen`: writes a generated scene as OBJ and prints one summary line.
pub fn run(a: &GenArgs) -> Result<()> {
    // The range of --count depends on the scene: checked here, with the message of any range.
    let count = match a.scene {
        SceneKind::Grid => between(1, MAX_GRID_CELLS).check(
            "--count",
            &a.count,
            &format!(
                " for a grid (cells per side: {GRID_LAYERS} layers of 2 × count² triangles, at most {MAX_TRIANGLES})"
            ),
        ),
        SceneKind::Random | SceneKind::Slivers => between(1, MAX_TRIANGLES).check("--count", &a.count, ""),
    }?;
    let (name, triangles, max_abs) = match a.scene {
        SceneKind::Random => ("random", count, 1.0 + a.size),
        SceneKind::Slivers => ("slivers", count, 1.01),
        SceneKind::Grid => ("grid", 2 * count * count * GRID_LAYERS as u64, count as f64),
    };
    check_outputs(&[], &[("-o/--output", &a.output)], Writes::Through)?;
    let bound = generate::obj_bytes_at_most(name, triangles, max_abs);
    check_disk(&a.output, bound, true, &format!("an OBJ of {triangles} {name} triangles"))?;
    let bytes = write_atomically(&a.output, |w| {
        match a.scene {
            SceneKind::Random => {
                let tris = generate::random_cube_iter(triangles, a.size, a.seed);
                generate::write_obj_iter(w, name, triangles, tris)?
            }
            SceneKind::Slivers => {
                generate::write_obj_iter(w, name, triangles, generate::slivers_iter(triangles, a.seed))?
            }
            SceneKind::Grid => {
                let tris = generate::grid_iter(count as u32, GRID_LAYERS, 1.0);
                generate::write_obj_iter(w, name, triangles, tris)?
            }
        }
        w.flush()?;
        w.get_ref().metadata().map(|m| m.len())
    })
    .with_context(|| format!("cannot write {}", a.output.display()))?;
    let summary = GenSummary { output: &a.output, scene: name, triangles, seed: a.seed, bytes };
    if a.json {
        stdout_line(&serde_json::to_string(&summary)?)?;
    } else if !a.quiet {
        stdout_line(&format!(
            "generated {triangles} {name} triangles (seed {}) into {}: {} ({bytes} bytes)",
            a.seed,
            a.output.display(),
            human_bytes(bytes)
        ))?;
    }
    Ok(())
}
