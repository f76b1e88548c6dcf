//! `vlf-bake demo`: the other subcommands in a row on the bundled bunny in its room.

use super::stdout_line;
use crate::args::{BakeArgs, CacheChoice, DemoArgs, DumpArgs, RaysArgs, RenderArgs, TraceArgs, View, WorkArg};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use vlf_bake::params::{DEFAULT_LEAF_SIZE, DEFAULT_MAX_BYTES, DEFAULT_MAX_BYTES_PER_TRIANGLE, DEFAULT_MAX_DEPTH};

/// The bundled default meshes, found through the source tree this binary was built from: the
/// bunny, and the room around it whose glTF brings materials, a camera and lights.
const DEMO_MESHES: [&str; 2] = [
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/meshes/cornell/cornell.gltf"),
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/meshes/bunny.obj"),
];

/// The files the demo writes in its output directory.
const DEMO_FILES: [&str; 6] = ["demo.vlf", "outside.rays", "outside.hits", "inside.rays", "inside.hits", "demo.png"];

/// The outermost directory of `dir` (itself or an ancestor) that does not exist yet: the one
/// `create_dir_all(dir)` creates first, if any.
fn first_missing(dir: &Path) -> Option<PathBuf> {
    let mut missing = None;
    let mut next = Some(dir);
    while let Some(d) = next.filter(|d| !d.as_os_str().is_empty() && std::fs::symlink_metadata(d).is_err()) {
        missing = Some(d.to_path_buf());
        next = d.parent();
    }
    missing
}

/// `vlf-bake demo`: bake, dump, trace and render, as a user would, each step announced. If a step
/// fails, the output directory is removed again when the demo created it (with the files it
/// wrote there, and nothing else), so that a failed demo leaves nothing behind.
pub fn run(a: &DemoArgs) -> Result<()> {
    let inputs: Vec<PathBuf> =
        if a.input.is_empty() { DEMO_MESHES.iter().map(PathBuf::from).collect() } else { a.input.clone() };
    if let Some(missing) = inputs.iter().find(|i| !i.exists()) {
        bail!("demo mesh {} not found; pass --input MESH", missing.display());
    }
    if std::fs::metadata(&a.output_dir).is_ok_and(|m| !m.is_dir()) {
        bail!(
            "--output-dir {} exists and is not a directory: give a directory, or a path to create one",
            a.output_dir.display()
        );
    }
    let created = first_missing(&a.output_dir);
    std::fs::create_dir_all(&a.output_dir).with_context(|| format!("cannot create {}", a.output_dir.display()))?;
    let result = steps(a, inputs);
    if let (Err(_), Some(top)) = (&result, created) {
        for name in DEMO_FILES {
            let _ = std::fs::remove_file(a.output_dir.join(name));
        }
        // Only empty directories go: from the output directory up to the first one created.
        for dir in a.output_dir.ancestors() {
            if std::fs::remove_dir(dir).is_err() || dir == top {
                break;
            }
        }
    }
    result
}

/// The demo's steps, in its output directory.
fn steps(a: &DemoArgs, inputs: Vec<PathBuf>) -> Result<()> {
    let field_path = a.output_dir.join("demo.vlf");
    let names: Vec<String> = inputs.iter().map(|i| i.display().to_string()).collect();
    stdout_line(&format!("1. bake {} (parameters chosen automatically)", names.join(" ")))?;
    super::bake::run(&BakeArgs {
        inputs,
        output: field_path.clone(),
        directions: None,
        tiles: None,
        leaf_size: DEFAULT_LEAF_SIZE,
        max_depth: DEFAULT_MAX_DEPTH,
        max_bytes: DEFAULT_MAX_BYTES,
        max_bytes_per_triangle: DEFAULT_MAX_BYTES_PER_TRIANGLE,
        threads: None,
        quiet: false,
        json: false,
        shard: None,
        cache: CacheChoice { cache_dir: None, no_cache: true },
        report: None,
    })?;
    stdout_line(&format!("\n2. dump {} --verify", field_path.display()))?;
    super::dump::run(&DumpArgs { field: field_path.clone(), json: false, verify: true, quiet: false })?;
    for (view, name) in [(View::Outside, "outside"), (View::Inside, "inside")] {
        let rays_path = a.output_dir.join(format!("{name}.rays"));
        let hits_path = a.output_dir.join(format!("{name}.hits"));
        stdout_line(&format!("\n3. trace 512×512 primary rays from {name} the scene"))?;
        super::rays::run(&RaysArgs {
            field: field_path.clone(),
            output: rays_path.clone(),
            view,
            width: Some(512),
            height: Some(512),
            quiet: true,
            json: false,
        })?;
        super::trace::run(&TraceArgs {
            field: Some(field_path.clone()),
            scene: None,
            instance_ids: None,
            rays: rays_path,
            output: hits_path,
            any_hit: false,
            quiet: false,
            json: false,
            threads: None,
        })?;
    }
    let picture = a.output_dir.join("demo.png");
    stdout_line(&format!("\n4. render {} -o {}", field_path.display(), picture.display()))?;
    super::render::run(&RenderArgs {
        field: Some(field_path),
        scene: None,
        frames: None,
        moves: Vec::new(),
        path: None,
        spin: 0.0,
        frame_ms: 40,
        output: picture.clone(),
        width: None,
        height: None,
        view: None,
        camera: None,
        eye: None,
        target: None,
        up: [0.0, 1.0, 0.0],
        fov: 50.0,
        lights: Vec::new(),
        default_lights: false,
        bounces: 5,
        samples: 2,
        exposure: 1.0,
        ambient: 0.06,
        background: None,
        flat: false,
        work_image: None,
        work: WorkArg::Tests,
        work_max: None,
        threads: None,
        quiet: false,
        json: false,
    })?;
    stdout_line(&format!("\nfiles are in {}; the picture is {}", a.output_dir.display(), picture.display()))
}
