//! `vlf-bake gen`: generate a test scene (the paper's random triangles, grids, slivers) as OBJ.

use crate::args::{GenArgs, SceneKind};
use anyhow::{Context, Result};
use vlf_bake::atomic::write_atomically;
use vlf_bake::generate;

/// `vlf-bake gen`: writes a generated scene as OBJ.
pub fn run(a: &GenArgs) -> Result<()> {
    let (name, tris) = match a.scene {
        SceneKind::Random => ("random", generate::random_cube(a.count, a.size, a.seed)),
        SceneKind::Grid => ("grid", generate::grid(a.count as u32, 4, 1.0)),
        SceneKind::Slivers => ("slivers", generate::slivers(a.count, a.seed)),
    };
    write_atomically(&a.output, |w| generate::write_obj(w, name, &tris))
        .with_context(|| format!("cannot write {}", a.output.display()))?;
    Ok(())
}
