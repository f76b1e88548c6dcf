//! `vlf-bake`: bake triangle meshes into visibility-field files, inspect and verify them, trace
//! batches of rays against them and render pictures of them. A thin layer over the `vlf_bake`,
//! `vlf_runtime` and `vlf_render` libraries.
//!
//! Exit codes: 0 success; 1 the command failed (one line on standard error says why); 2 the
//! command line was invalid. A closed output pipe (`vlf-bake dump f | head`) counts as success.

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Mutex;
use std::time::Instant;
use vlf_bake::params::{DEFAULT_LEAF_SIZE, DEFAULT_MAX_DEPTH, human_bytes};
use vlf_bake::{BakeConfig, DepthPolicy, Progress, generate, inspect};
use vlf_runtime::{Field, Hit, Ray};

#[derive(Parser)]
#[command(
    name = "vlf-bake",
    version,
    about = "Bake triangle meshes into visibility fields that load instantly, and inspect, verify and trace them.",
    long_about = "Bake triangle meshes (OBJ, glTF, GLB) into a visibility field: a precomputed, memory-mappable \
ray-tracing acceleration structure (Mortensen et al., \"A Visibility Field for Ray Tracing\"). A field is one \
versioned, content-hashed file; bakes are reproducible to the byte.\n\nTypical use:\n  vlf-bake bake scene.glb -o scene.vlf\n  vlf-bake dump scene.vlf --verify\n  vlf-bake render scene.vlf -o scene.png\n  vlf-bake pack scene.vlf -o scene.packed.vlf   (for transport; `unpack` restores it)\n  vlf-bake rays scene.vlf -o rays.bin && vlf-bake trace scene.vlf --rays rays.bin --out hits.bin --json"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Bake one or more meshes into a field file (or, with --shard, one shard of it).
    Bake(BakeArgs),
    /// Merge the shards of a sharded bake into the field a single bake writes, byte for byte.
    Merge(MergeArgs),
    /// List, verify or prune a bake cache directory.
    Cache(CacheArgs),
    /// Describe a field: header, parameters, sections, statistics; --verify checks every byte.
    Dump(DumpArgs),
    /// Compress a field for transport: sections stored as zstd frames (formats/vlf.md §8).
    Pack(PackArgs),
    /// Decompress a packed field back into the raw field, byte for byte.
    Unpack(UnpackArgs),
    /// Trace a file of rays against a field and write one hit record per ray.
    Trace(TraceArgs),
    /// Write a rays file of primary rays for a camera that frames a field's scene.
    Rays(RaysArgs),
    /// Render a picture of a field: Whitted ray tracing with shadows, mirrors and glass.
    Render(Box<RenderArgs>),
    /// Generate a test scene (the paper's random triangles, grids, slivers) as OBJ.
    Gen(GenArgs),
    /// Bake the bundled bunny in a room, dump and verify it, trace frames and render a picture.
    Demo(DemoArgs),
}

#[derive(Args)]
struct DemoArgs {
    /// The meshes to bake, repeatable (default: the bunny in the repository's fixtures, in the
    /// Cornell-like room whose glTF brings a camera and lights).
    #[arg(long, value_name = "MESH")]
    input: Vec<PathBuf>,
    /// Where to write the field, rays and hits.
    #[arg(long, default_value = "target/vlf-demo", value_name = "DIR")]
    output_dir: PathBuf,
}

#[derive(Args)]
struct BakeArgs {
    /// Input meshes: .obj, .gltf or .glb. Several inputs are baked into one field.
    #[arg(required = true, value_name = "INPUT")]
    inputs: Vec<PathBuf>,
    /// The field file to write (replaced atomically).
    #[arg(short, long, value_name = "FIELD")]
    output: PathBuf,
    /// Number of directions l; rounded up to the next lattice size 2N²+1 (3, 9, 19, 33, 51, ..., 2049, ...).
    /// Chosen automatically under --max-bytes if absent.
    #[arg(long, value_name = "L")]
    directions: Option<u32>,
    /// Tiles per side n of each direction's n×n beam grid. Chosen automatically if absent.
    #[arg(long, value_name = "N")]
    tiles: Option<u32>,
    /// BSP depth policy: target triangles per leaf.
    #[arg(long, default_value_t = DEFAULT_LEAF_SIZE, value_name = "K")]
    leaf_size: u32,
    /// BSP depth policy: largest depth of a tile's 1D BSP (0 = linear tiles, no BSP).
    #[arg(long, default_value_t = DEFAULT_MAX_DEPTH, value_name = "D")]
    max_depth: u32,
    /// Size budget for automatic parameters, and a ceiling for explicit ones: a bake with explicit
    /// parameters stops, leaving nothing behind, as soon as its field would exceed it (e.g. 4GiB, 512MiB, 1e9).
    #[arg(long, default_value = "4GiB", value_parser = parse_size, value_name = "SIZE")]
    max_bytes: u64,
    /// Automatic parameters aim at no more than this many bytes of field per triangle.
    #[arg(long, default_value = "16KiB", value_parser = parse_size, value_name = "SIZE")]
    max_bytes_per_triangle: u64,
    /// Worker threads (default: RAYON_NUM_THREADS, else all cores). The output does not depend on it.
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    /// No progress bar and no summary on success.
    #[arg(short, long)]
    quiet: bool,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
    /// Bake only shard K of N (K = 0..N-1): its share of the directions, into a shard file for
    /// `vlf-bake merge` (docs/build-farms.md).
    #[arg(long, value_name = "K/N")]
    shard: Option<vlf_bake::shard::ShardSpec>,
    #[command(flatten)]
    cache: CacheChoice,
    /// Write a JSON report (inputs, parameters, phase timings, peak memory, output, cache) to FILE.
    #[arg(long, value_name = "FILE.json")]
    report: Option<PathBuf>,
}

#[derive(Args)]
struct CacheChoice {
    /// Bake cache directory: reuse the field of unchanged inputs, store new ones
    /// (default: the VLF_CACHE_DIR environment variable).
    #[arg(long, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
    /// Do not use a cache, even if VLF_CACHE_DIR is set.
    #[arg(long, conflicts_with = "cache_dir")]
    no_cache: bool,
}

impl CacheChoice {
    /// The cache to use, or why there is none. A cache directory that cannot be created is not
    /// an error (a cache only ever saves time): the bake goes on without it, with a warning unless
    /// `quiet`.
    fn resolve(&self, quiet: bool) -> (Option<vlf_bake::cache::Cache>, Option<String>) {
        let env = std::env::var_os(vlf_bake::cache::CACHE_DIR_ENV).filter(|v| !v.is_empty()).map(PathBuf::from);
        if self.no_cache {
            return (None, Some("--no-cache".into()));
        }
        match self.cache_dir.clone().or(env) {
            None => (None, Some(format!("no --cache-dir and no {}", vlf_bake::cache::CACHE_DIR_ENV))),
            Some(dir) => match vlf_bake::cache::Cache::open(&dir) {
                Ok(cache) => (Some(cache), None),
                Err(e) => {
                    let note = format!("not using the cache: {e}");
                    if !quiet {
                        eprintln!("warning: {note}");
                    }
                    (None, Some(note))
                }
            },
        }
    }
}

#[derive(Args)]
struct MergeArgs {
    /// The shard files of one bake, each once, in any order.
    #[arg(required = true, value_name = "SHARD")]
    parts: Vec<PathBuf>,
    /// The field file to write (replaced atomically).
    #[arg(short, long, value_name = "FIELD")]
    output: PathBuf,
    #[command(flatten)]
    cache: CacheChoice,
    /// Write a JSON report to FILE (the schema of `bake --report`).
    #[arg(long, value_name = "FILE.json")]
    report: Option<PathBuf>,
    /// No progress bar and no summary on success.
    #[arg(short, long)]
    quiet: bool,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct CacheArgs {
    #[command(subcommand)]
    action: CacheAction,
    /// The cache directory (default: the VLF_CACHE_DIR environment variable).
    #[arg(long, global = true, value_name = "DIR")]
    cache_dir: Option<PathBuf>,
    /// Print one JSON value instead of text.
    #[arg(long, global = true)]
    json: bool,
}

#[derive(Subcommand)]
enum CacheAction {
    /// List the entries, most recently used first.
    List,
    /// Check every byte of every entry (as `dump --verify`) and its key; remove the bad ones.
    Verify,
    /// Remove entries unused for longer than --max-age, then the least recently used ones until
    /// the cache fits in --max-size; and temporary files left by crashed bakes.
    Prune {
        /// Keep at most this many bytes (e.g. 20GiB).
        #[arg(long, value_parser = parse_size, value_name = "SIZE")]
        max_size: Option<u64>,
        /// Remove entries not used for this long (e.g. 30d, 12h, 90m).
        #[arg(long, value_parser = vlf_bake::cache::parse_duration, value_name = "DURATION")]
        max_age: Option<std::time::Duration>,
    },
}

#[derive(Args)]
struct DumpArgs {
    /// The field file. A packed field is decoded in memory first, which is not instant.
    field: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Recompute every hash and check every offset and index; exit 1 naming the first fault.
    #[arg(long)]
    verify: bool,
    /// No progress bar during --verify.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args)]
struct PackArgs {
    /// The raw field to pack.
    field: PathBuf,
    /// The packed field to write (replaced atomically). It is still a field: `dump`, `trace` and
    /// the runtime open it (decoding it in memory first).
    #[arg(short, long, value_name = "PACKED")]
    output: PathBuf,
    /// zstd level, from 1 (fastest) to 19 (smallest). The output does not depend on anything else.
    #[arg(long, default_value_t = vlf_bake::pack::DEFAULT_LEVEL, value_name = "N",
          value_parser = clap::value_parser!(i32).range(*vlf_bake::pack::LEVELS.start() as i64..=*vlf_bake::pack::LEVELS.end() as i64))]
    level: i32,
    /// Worker threads (default: RAYON_NUM_THREADS, else all cores); each compresses whole sections.
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    /// No progress bar and no summary on success.
    #[arg(short, long)]
    quiet: bool,
    /// Print the summary (sizes, ratio, MB/s, per-section codecs) as one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct UnpackArgs {
    /// The packed field.
    packed: PathBuf,
    /// The raw field to write (replaced atomically).
    #[arg(short, long, value_name = "FIELD")]
    output: PathBuf,
    /// No progress bar and no summary on success.
    #[arg(short, long)]
    quiet: bool,
    /// Print the summary (sizes, ratio, MB/s) as one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct TraceArgs {
    /// The field file.
    field: PathBuf,
    /// Rays: 32-byte little-endian records (formats/rays.md).
    #[arg(long, value_name = "FILE")]
    rays: PathBuf,
    /// Hits: 16-byte records, one per ray (formats/rays.md).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// Answer any-hit (shadow) queries instead of closest-hit.
    #[arg(long)]
    any_hit: bool,
    /// Print rays, hits, seconds (tracing only) and mrays_per_s as one JSON object.
    #[arg(long)]
    json: bool,
    /// Worker threads (default: RAYON_NUM_THREADS, else all cores).
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
}

#[derive(Clone, Copy, ValueEnum)]
enum View {
    /// From outside the scene's bounding sphere, framing all of it.
    Outside,
    /// From inside the scene, near its centre.
    Inside,
}

#[derive(Args)]
struct RaysArgs {
    /// The field whose bounding sphere the camera frames.
    field: PathBuf,
    /// The rays file to write.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    #[arg(long, value_enum, default_value = "outside")]
    view: View,
    #[arg(long, default_value_t = 512)]
    width: u32,
    #[arg(long, default_value_t = 512)]
    height: u32,
}

#[derive(Clone, Copy, ValueEnum)]
enum WorkArg {
    /// Ray/triangle tests.
    Tests,
    /// Tiles visited.
    Tiles,
    /// BSP leaves visited.
    Leaves,
    /// Rays traced.
    Rays,
}

#[derive(Args)]
struct RenderArgs {
    /// The field file.
    field: PathBuf,
    /// The PNG to write.
    #[arg(short, long, value_name = "IMAGE.png")]
    output: PathBuf,
    /// Image width in pixels.
    #[arg(long, default_value_t = 640)]
    width: u32,
    /// Image height (default: from the width and the field camera's aspect ratio, else 480).
    #[arg(long)]
    height: Option<u32>,
    /// Frame the whole scene from outside, or look across it from inside (like `rays --view`).
    /// Default: the field's first glTF camera if it has one, else outside.
    #[arg(long, value_enum, conflicts_with_all = ["camera", "eye"])]
    view: Option<View>,
    /// Use the field's glTF camera number N (0 = first; `dump` counts them).
    #[arg(long, value_name = "N", conflicts_with = "eye")]
    camera: Option<usize>,
    /// Place a pinhole camera at X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<[f64; 3]>,
    /// The point an --eye camera looks at (default: the centre of the scene).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true, requires = "eye")]
    target: Option<[f64; 3]>,
    /// The up direction of an --eye camera.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, default_value = "0,1,0", allow_hyphen_values = true)]
    up: [f64; 3],
    /// Vertical field of view of an --eye camera, in degrees.
    #[arg(long, default_value_t = 50.0, value_name = "DEGREES")]
    fov: f64,
    /// A white point light at X,Y,Z with intensity I (irradiance I/d²); repeatable. Replaces the
    /// field's lights and the default key and fill lights.
    #[arg(long = "light", value_name = "X,Y,Z,I", value_parser = parse_light, allow_hyphen_values = true)]
    lights: Vec<[f64; 4]>,
    /// Ignore the field's glTF lights: light the scene with a key and a fill light around the camera.
    #[arg(long)]
    default_lights: bool,
    /// Reflection and refraction bounces after the primary ray (at most 64).
    #[arg(long, default_value_t = 5)]
    max_depth: u32,
    /// Samples per pixel along each axis (2 = 4 rays per pixel, antialiased).
    #[arg(long, default_value_t = 2)]
    samples: u32,
    /// Multiply the image's brightness.
    #[arg(long, default_value_t = 1.0)]
    exposure: f64,
    /// Unshadowed light every surface receives.
    #[arg(long, default_value_t = 0.06)]
    ambient: f64,
    /// A solid background colour R,G,B (linear, 0 to 1) instead of the sky gradient.
    #[arg(long, value_name = "R,G,B", value_parser = parse_vec3)]
    background: Option<[f64; 3]>,
    /// Flat shading: no normals interpolated across edges.
    #[arg(long)]
    flat: bool,
    /// Also write a false-colour picture of the work per pixel (black = none, white = --work-max or more).
    #[arg(long, value_name = "IMAGE.png")]
    work_image: Option<PathBuf>,
    /// What the work picture shows, summed over every ray of the pixel.
    #[arg(long, value_enum, default_value = "tests")]
    work: WorkArg,
    /// The work at the top of the colour scale (default: the 99th percentile of the frame).
    #[arg(long, value_name = "COUNT")]
    work_max: Option<u64>,
    /// Worker threads (default: RAYON_NUM_THREADS, else all cores). The picture does not depend on it.
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    /// No progress bar and no summary on success.
    #[arg(short, long)]
    quiet: bool,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum SceneKind {
    /// The paper's scene: triangles with centres uniform in [-1,1]³, vertices within ±size of the centre.
    Random,
    /// Axis-aligned coplanar grids with shared edges (count = cells per side, 4 layers).
    Grid,
    /// Long thin slivers.
    Slivers,
}

#[derive(Args)]
struct GenArgs {
    #[arg(value_enum)]
    scene: SceneKind,
    /// Number of triangles (random, slivers) or cells per side (grid).
    #[arg(long, default_value_t = 10_000)]
    count: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Random scene: half-extent of each triangle around its centre.
    #[arg(long, default_value_t = generate::DEFAULT_TRIANGLE_SIZE)]
    size: f64,
    /// The OBJ file to write.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Bake(a) => with_threads(a.threads, || bake(&a)),
        Command::Merge(a) => merge(&a),
        Command::Cache(a) => cache(&a),
        Command::Dump(a) => dump(&a),
        Command::Pack(a) => with_threads(a.threads, || pack(&a)),
        Command::Unpack(a) => unpack(&a),
        Command::Trace(a) => with_threads(a.threads, || trace(&a)),
        Command::Rays(a) => rays(&a),
        Command::Render(a) => with_threads(a.threads, || render(&a)),
        Command::Gen(a) => gen_scene(&a),
        Command::Demo(a) => demo(&a),
    }
}

/// Runs `f` on a pool of `threads` workers, or on rayon's global pool (which honours
/// RAYON_NUM_THREADS) when `threads` is `None`.
fn with_threads<T: Send>(threads: Option<usize>, f: impl FnOnce() -> Result<T> + Send) -> Result<T> {
    match threads {
        None => f(),
        Some(0) => bail!("--threads must be at least 1"),
        Some(t) => {
            rayon::ThreadPoolBuilder::new().num_threads(t).build().context("cannot start worker threads")?.install(f)
        }
    }
}

/// Parses `4GiB`, `512MiB`, `100MB`, `1e9`, `123456`.
fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E').unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let value: f64 = num.trim().parse().map_err(|_| format!("`{s}` is not a size (try 4GiB, 512MiB or 1000000)"))?;
    let scale = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" => 1e3,
        "m" | "mb" => 1e6,
        "g" | "gb" => 1e9,
        "t" | "tb" => 1e12,
        "kib" => 1024.0,
        "mib" => 1024.0 * 1024.0,
        "gib" => 1024.0 * 1024.0 * 1024.0,
        "tib" => 1024.0f64.powi(4),
        other => return Err(format!("unknown size unit `{other}` in `{s}` (use B, KB, MB, GB, KiB, MiB, GiB)")),
    };
    let bytes = value * scale;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("`{s}` is not a positive size"));
    }
    Ok(bytes as u64)
}

/// Parses `x,y,z`.
fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let v = parse_numbers(s, 3)?;
    Ok([v[0], v[1], v[2]])
}

/// Parses `x,y,z,intensity`.
fn parse_light(s: &str) -> Result<[f64; 4], String> {
    let v = parse_numbers(s, 4)?;
    if v[3] < 0.0 {
        return Err(format!("`{s}`: the intensity must not be negative"));
    }
    Ok([v[0], v[1], v[2], v[3]])
}

fn parse_numbers(s: &str, count: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(|| format!("`{s}` is not {count} comma-separated numbers"))?;
    if v.len() != count {
        return Err(format!("`{s}` has {} numbers, expected {count} separated by commas", v.len()));
    }
    Ok(v)
}

/// A progress bar on standard error, drawn only when it is a terminal and not silenced.
struct Bar {
    enabled: bool,
    bar: Mutex<Option<ProgressBar>>,
}

impl Bar {
    fn new(quiet: bool) -> Self {
        Bar { enabled: !quiet && std::io::stderr().is_terminal(), bar: Mutex::new(None) }
    }
}

impl Progress for Bar {
    fn begin(&self, phase: &str, total: u64) {
        if !self.enabled {
            return;
        }
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template("{msg:>20} [{bar:40}] {pos}/{len} ({eta} left)")
                .expect("static template")
                .progress_chars("=> "),
        );
        bar.set_message(phase.to_string());
        *self.bar.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar);
    }

    fn advance(&self, done: u64) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            b.inc(done);
        }
    }

    fn end(&self) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            b.finish_and_clear();
        }
    }
}

fn stdout_line(s: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{s}")?;
    out.flush()?;
    Ok(())
}

fn bake(a: &BakeArgs) -> Result<()> {
    let config = BakeConfig {
        directions: a.directions,
        tiles: a.tiles,
        depth: DepthPolicy { leaf_size: a.leaf_size, max_depth: a.max_depth },
        max_bytes: a.max_bytes,
        max_bytes_per_triangle: a.max_bytes_per_triangle,
    };
    config.validate()?;
    let (cache, cache_note) = a.cache.resolve(a.quiet);
    let bar = Bar::new(a.quiet || a.json);
    let explain = |choice: &vlf_bake::Choice| {
        if choice.automatic {
            eprintln!("{}", choice.reason);
        }
    };
    let job = vlf_bake::job::BakeJob {
        inputs: &a.inputs,
        output: &a.output,
        config,
        shard: a.shard,
        cache,
        cache_note,
        on_choice: (!a.quiet && !a.json).then_some(&explain as &dyn Fn(&vlf_bake::Choice)),
    };
    let out = vlf_bake::job::run_bake_job(&job, &bar)?;
    if !a.quiet {
        for w in out.import.warnings.iter().chain(&out.warnings) {
            eprintln!("warning: {w}");
        }
    }
    if let Some(path) = &a.report {
        out.report.write(path).with_context(|| format!("cannot write the report {}", path.display()))?;
    }
    let summary = &out.summary;
    if a.json {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            #[serde(flatten)]
            summary: &'a vlf_bake::BakeSummary,
            import: &'a vlf_bake::ImportReport,
            cache: &'a str,
            #[serde(skip_serializing_if = "Option::is_none")]
            shard: Option<&'a vlf_bake::report::ShardInfo>,
        }
        let out = Out { summary, import: &out.import, cache: out.report.cache.status, shard: out.shard.as_ref() };
        stdout_line(&serde_json::to_string(&out)?)?;
    } else if !a.quiet {
        let s = summary;
        let what = match &out.shard {
            Some(sh) => format!(
                "shard {}/{} (directions {}..{} of {})",
                sh.index, sh.count, sh.first_direction, sh.end_direction, sh.direction_count
            ),
            None => format!("{} directions", s.directions),
        };
        let how = match &out.cache_hit {
            Some(entry) => format!("copied from the cache ({}) in {:.2} s", entry.display(), s.seconds),
            None => format!("in {:.2} s", s.seconds),
        };
        let mut text = format!(
            "baked {}: {} triangles, {what} × {}² tiles, {} ({} bytes) {how}\n  content hash {}\n  input hash   {}",
            s.output.display(),
            s.triangles,
            s.tile_resolution,
            human_bytes(s.bytes),
            s.bytes,
            s.content_hash,
            s.input_hash
        );
        let r = &out.import;
        if r.dropped_degenerate + r.skipped_points + r.skipped_lines > 0 {
            text.push_str(&format!(
                "\n  dropped {} degenerate triangles; skipped {} point and {} line primitives",
                r.dropped_degenerate, r.skipped_points, r.skipped_lines
            ));
        }
        stdout_line(&text)?;
    }
    Ok(())
}

fn merge(a: &MergeArgs) -> Result<()> {
    let (cache, cache_note) = a.cache.resolve(a.quiet);
    let bar = Bar::new(a.quiet || a.json);
    let out = vlf_bake::job::run_merge_job(&a.parts, &a.output, cache, cache_note, &bar)?;
    if !a.quiet {
        for w in &out.warnings {
            eprintln!("warning: {w}");
        }
    }
    if let Some(path) = &a.report {
        out.report.write(path).with_context(|| format!("cannot write the report {}", path.display()))?;
    }
    let s = &out.summary;
    if a.json {
        stdout_line(&serde_json::to_string(s)?)?;
    } else if !a.quiet {
        stdout_line(&format!(
            "merged {} shards into {}: {} directions × {}² tiles, {} ({} bytes) in {:.2} s\n  content hash {}\n  input hash   {}",
            s.shards,
            s.output.display(),
            s.directions,
            s.tile_resolution,
            human_bytes(s.bytes),
            s.bytes,
            s.check_seconds + s.copy_seconds,
            s.content_hash,
            s.input_hash
        ))?;
    }
    Ok(())
}

fn pack(a: &PackArgs) -> Result<()> {
    let bar = Bar::new(a.quiet || a.json);
    let s = vlf_bake::pack::pack_path(&a.field, &a.output, a.level, &bar)?;
    if a.json {
        stdout_line(&serde_json::to_string(&s)?)?;
    } else if !a.quiet {
        stdout_line(&format!(
            "packed {} into {}: {} to {} ({:.2}×) at zstd level {} in {:.2} s ({:.0} MB/s)\n  content hash {}\n  unpacks to   {}",
            s.input.display(),
            s.output.display(),
            human_bytes(s.raw_bytes),
            human_bytes(s.packed_bytes),
            s.ratio,
            s.level,
            s.seconds,
            s.mb_per_s,
            s.content_hash,
            s.raw_content_hash
        ))?;
    }
    Ok(())
}

fn cache(a: &CacheArgs) -> Result<()> {
    let env = std::env::var_os(vlf_bake::cache::CACHE_DIR_ENV).filter(|v| !v.is_empty()).map(PathBuf::from);
    let Some(dir) = a.cache_dir.clone().or(env) else {
        bail!("no cache directory: pass --cache-dir DIR or set {}", vlf_bake::cache::CACHE_DIR_ENV)
    };
    if !dir.is_dir() {
        bail!("{} is not a directory", dir.display());
    }
    let cache = vlf_bake::cache::Cache::open(&dir)?;
    match &a.action {
        CacheAction::List => {
            let entries = cache.list().with_context(|| format!("cannot list {}", dir.display()))?;
            if a.json {
                return stdout_line(&serde_json::to_string_pretty(&entries)?);
            }
            let total: u64 = entries.iter().map(|e| e.bytes).sum();
            let mut text = format!("{} entries, {} in {}", entries.len(), human_bytes(total), dir.display());
            for e in &entries {
                let what = match (&e.field, &e.problem) {
                    (Some(f), _) => format!(
                        "{} triangles, {} directions × {}² tiles, format {}, from {}",
                        f.triangles,
                        f.directions,
                        f.tile_resolution,
                        f.format_version,
                        f.inputs.join(", ")
                    ),
                    (None, problem) => format!("unusable: {}", problem.as_deref().unwrap_or("unknown")),
                };
                text.push_str(&format!(
                    "\n  {}  {:>10}  used {} ago  {what}",
                    &e.key[..16],
                    human_bytes(e.bytes),
                    human_duration(e.age_seconds)
                ));
            }
            stdout_line(&text)
        }
        CacheAction::Verify => {
            let outcomes = cache.verify(&mut |_| {}).with_context(|| format!("cannot verify {}", dir.display()))?;
            let bad: Vec<_> = outcomes.iter().filter(|o| o.problem.is_some()).collect();
            if a.json {
                stdout_line(&serde_json::to_string_pretty(&outcomes)?)?;
            } else {
                let mut text = format!("{} entries verified, {} bad", outcomes.len(), bad.len());
                for o in &bad {
                    text.push_str(&format!("\n  {} removed: {}", o.key, o.problem.as_deref().unwrap_or_default()));
                }
                stdout_line(&text)?;
            }
            if !bad.is_empty() {
                bail!("{} of {} cache entries failed verification and were removed", bad.len(), outcomes.len());
            }
            Ok(())
        }
        CacheAction::Prune { max_size, max_age } => {
            if max_size.is_none() && max_age.is_none() {
                bail!("prune needs --max-size or --max-age (or both)");
            }
            let r = cache.prune(*max_size, *max_age).with_context(|| format!("cannot prune {}", dir.display()))?;
            if a.json {
                return stdout_line(&serde_json::to_string_pretty(&r)?);
            }
            stdout_line(&format!(
                "removed {} entries ({}) and {} stale temporary files; kept {} entries ({})",
                r.removed.len(),
                human_bytes(r.removed_bytes),
                r.stale_temp_files,
                r.kept,
                human_bytes(r.kept_bytes)
            ))
        }
    }
}

/// `3 d`, `5 h`, `12 min`, `40 s`.
fn human_duration(seconds: f64) -> String {
    match seconds {
        s if s >= 86400.0 => format!("{:.0} d", s / 86400.0),
        s if s >= 3600.0 => format!("{:.0} h", s / 3600.0),
        s if s >= 60.0 => format!("{:.0} min", s / 60.0),
        s => format!("{s:.0} s"),
    }
}

fn unpack(a: &UnpackArgs) -> Result<()> {
    let bar = Bar::new(a.quiet || a.json);
    let s = vlf_bake::pack::unpack_path(&a.packed, &a.output, &bar)?;
    if a.json {
        stdout_line(&serde_json::to_string(&s)?)?;
    } else if !a.quiet {
        stdout_line(&format!(
            "unpacked {} into {}: {} to {} in {:.2} s ({:.0} MB/s)\n  content hash {}",
            s.input.display(),
            s.output.display(),
            human_bytes(s.packed_bytes),
            human_bytes(s.raw_bytes),
            s.seconds,
            s.mb_per_s,
            s.content_hash
        ))?;
    }
    Ok(())
}

fn dump(a: &DumpArgs) -> Result<()> {
    let field = Field::open(&a.field)?;
    let info = match field.packed_layout() {
        Some(layout) => inspect::describe_packed(field.reader(), layout),
        None => inspect::describe(field.reader()),
    };
    let verified = if a.verify {
        if let Some(layout) = field.packed_layout() {
            // Opening decoded and hashed every section; the file's padding is all that is left.
            vlf_bake::pack::check_packed_file(&a.field, layout)
                .with_context(|| format!("{} failed verification", a.field.display()))?;
        }
        let bar = Bar::new(a.quiet || a.json);
        bar.begin("verifying", field.len_bytes());
        let mut last = 0;
        let t = Instant::now();
        let result = inspect::verify(field.reader(), &mut |done, _| {
            bar.advance(done - last);
            last = done;
        });
        bar.end();
        match result {
            Ok(r) => Some((r, t.elapsed().as_secs_f64())),
            Err(e) => bail!("{} failed verification: {e}", a.field.display()),
        }
    } else {
        None
    };
    if a.json {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            #[serde(flatten)]
            info: &'a inspect::Description,
            #[serde(skip_serializing_if = "Option::is_none")]
            verify: Option<serde_json::Value>,
        }
        let verify = verified.as_ref().map(|(r, secs)| {
            serde_json::json!({"ok": true, "bytes_hashed": r.bytes_hashed, "tiles": r.tiles, "triangle_ids": r.ids, "seconds": secs})
        });
        return stdout_line(&serde_json::to_string_pretty(&Out { info: &info, verify })?);
    }
    stdout_line(&describe_text(&info))?;
    if let Some((r, secs)) = verified {
        stdout_line(&format!(
            "verify: OK: {} hashed, {} tiles and {} triangle ids checked in {secs:.2} s",
            human_bytes(r.bytes_hashed),
            r.tiles,
            r.ids
        ))?;
    }
    Ok(())
}

fn describe_text(d: &inspect::Description) -> String {
    let st = &d.statistics;
    let mut s = String::new();
    let mut line = |t: String| {
        s.push_str(&t);
        s.push('\n');
    };
    line(format!("VLF field, format {}, {} ({} bytes)", d.format_version, human_bytes(d.file_bytes), d.file_bytes));
    line(format!("  content hash  {}", d.content_hash));
    line(format!("  input hash    {}", d.input_hash));
    if let Some(p) = &d.packed {
        line(format!(
            "  packed        zstd, {:.2}× smaller than the raw field of {} ({} bytes)",
            p.ratio,
            human_bytes(p.unpacked_bytes),
            p.unpacked_bytes
        ));
        line(format!("  unpacks to    content hash {}", p.unpacked_content_hash));
    }
    line("scene".into());
    line(format!("  triangles     {} ({} degenerate dropped at import)", d.triangle_count, d.dropped_degenerate));
    line(format!(
        "  sphere        centre ({:.6}, {:.6}, {:.6}), radius {:.6}",
        d.center[0], d.center[1], d.center[2], d.radius
    ));
    line(format!("  bounds        {:?} .. {:?}", d.aabb_min, d.aabb_max));
    for i in &d.inputs {
        line(format!("  input         {} ({} triangles, blake3 {})", i.name, i.triangles, &i.file_hash[..16]));
    }
    line(format!(
        "  rendering     {} materials, {} cameras, {} lights ({} sources)",
        d.materials, d.cameras, d.lights, d.sources
    ));
    line("parameters".into());
    let req = |v: Option<u32>| v.map_or("automatic".to_string(), |v| format!("requested {v}"));
    line(format!(
        "  directions    {} (lattice N = {}; {})",
        d.direction_count,
        d.lattice_n,
        req(d.requested_directions)
    ));
    line(format!("  tiles         {}² ({})", d.tile_resolution, req(d.requested_tiles)));
    line(format!("  bsp policy    leaf size {}, max depth {}", d.leaf_size, d.max_depth));
    line(format!(
        "  budget        {} ({} per triangle for automatic parameters)",
        human_bytes(d.max_bytes),
        human_bytes(d.max_bytes_per_triangle)
    ));
    line(format!("  margin        {:.3e} (world units)", d.margin));
    line(format!("  worst angle   {:.3}° between a ray and its chosen direction", d.worst_direction_angle_deg));
    line("statistics".into());
    line(format!(
        "  triangles/tile mean {:.2} ({:.2} over non-empty tiles), max {}; {:.1}% of {} tiles empty",
        st.mean_triangles_per_tile,
        st.mean_triangles_per_nonempty_tile,
        st.max_triangles_per_tile,
        100.0 * st.empty_tile_share,
        st.tiles
    ));
    line(format!(
        "  leaf depths   mean {:.2} over non-empty tiles, max {}; histogram {:?}",
        st.mean_depth_nonempty, st.max_depth_used, st.depth_histogram
    ));
    line(format!("  ids           {} in {} leaves", st.triangle_ids, st.leaves));
    line("sections".into());
    if d.packed.is_some() {
        line(format!(
            "  {:<13} {:>5} {:>14} {:>14} {:>14} {:>7} {:>12}  {}",
            "kind", "codec", "offset", "stored", "raw", "ratio", "elements", "blake3 (raw)"
        ));
        for e in &d.sections {
            line(format!(
                "  {:<13} {:>5} {:>14} {:>14} {:>14} {:>6.2}× {:>12}  {}",
                e.name,
                e.codec,
                e.offset,
                e.stored_length,
                e.raw_length,
                e.raw_length as f64 / e.stored_length.max(1) as f64,
                e.elements,
                &e.raw_hash[..16]
            ));
        }
    } else {
        line(format!(
            "  {:<13} {:>5} {:>14} {:>14} {:>12}  {}",
            "kind", "codec", "offset", "bytes", "elements", "blake3"
        ));
        for e in &d.sections {
            line(format!(
                "  {:<13} {:>5} {:>14} {:>14} {:>12}  {}",
                e.name,
                e.codec,
                e.offset,
                e.stored_length,
                e.elements,
                &e.raw_hash[..16]
            ));
        }
    }
    s.pop();
    s
}

fn read_rays(path: &Path) -> Result<Vec<Ray>> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read rays file {}", path.display()))?;
    if bytes.len() % size_of::<Ray>() != 0 {
        bail!(
            "rays file {} is {} bytes, not a multiple of the 32-byte ray record (formats/rays.md)",
            path.display(),
            bytes.len()
        );
    }
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

fn trace(a: &TraceArgs) -> Result<()> {
    let field = Field::open(&a.field)?;
    let rays = read_rays(&a.rays)?;
    let mut hits = vec![Hit::MISS; rays.len()];
    let start = Instant::now();
    if a.any_hit {
        use rayon::prelude::*;
        let view = field.view();
        rays.par_iter().zip(hits.par_iter_mut()).with_min_len(256).for_each(|(r, h)| {
            *h = Hit::record(view.any_hit_counted(r, &mut ()));
        });
    } else {
        field.par_closest_hits(&rays, &mut hits);
    }
    let seconds = start.elapsed().as_secs_f64();
    vlf_bake::atomic::write_atomically(&a.out, |w| w.write_all(bytemuck::cast_slice(&hits)))
        .with_context(|| format!("cannot write hits file {}", a.out.display()))?;
    let hit_count = hits.iter().filter(|h| h.prim != u32::MAX).count();
    let invalid = rays.iter().filter(|r| !r.is_valid()).count();
    let mrays = rays.len() as f64 / seconds.max(1e-12) / 1e6;
    if a.json {
        stdout_line(
            &serde_json::json!({
                "rays": rays.len(), "hits": hit_count, "invalid": invalid,
                "seconds": seconds, "mrays_per_s": mrays,
                "threads": rayon::current_num_threads(), "any_hit": a.any_hit,
            })
            .to_string(),
        )
    } else {
        stdout_line(&format!(
            "traced {} rays ({} hits, {invalid} invalid) in {seconds:.3} s: {mrays:.2} Mrays/s on {} threads",
            rays.len(),
            hit_count,
            rayon::current_num_threads()
        ))
    }
}

fn rays(a: &RaysArgs) -> Result<()> {
    if a.width == 0 || a.height == 0 {
        bail!("--width and --height must be positive");
    }
    let field = Field::open(&a.field)?;
    let (center, radius) = field.bounding_sphere();
    let aspect = a.width as f64 / a.height as f64;
    let camera = match a.view {
        View::Outside => vlf_geom::Camera::outside(center, radius, aspect),
        View::Inside => vlf_geom::Camera::inside(center, radius, aspect),
    };
    let rays = camera.primary_rays(a.width, a.height);
    vlf_bake::atomic::write_atomically(&a.output, |w| w.write_all(bytemuck::cast_slice(&rays)))
        .with_context(|| format!("cannot write rays file {}", a.output.display()))?;
    Ok(())
}

/// What `render` prints, and its `--json` keys.
#[derive(serde::Serialize)]
struct RenderSummary {
    output: PathBuf,
    width: u32,
    height: u32,
    samples_per_pixel: u32,
    camera: String,
    lights: String,
    light_count: usize,
    seconds: f64,
    rays: RaysSummary,
    mrays_per_s: f64,
    work: WorkSummary,
    #[serde(skip_serializing_if = "Option::is_none")]
    work_image: Option<WorkImageSummary>,
    threads: usize,
}

#[derive(serde::Serialize)]
struct RaysSummary {
    primary: u64,
    shadow: u64,
    reflection: u64,
    refraction: u64,
    total: u64,
}

#[derive(serde::Serialize)]
struct WorkSummary {
    rays_reaching_the_scene: u64,
    tiles: u64,
    leaves: u64,
    triangle_tests: u64,
}

#[derive(serde::Serialize)]
struct WorkImageSummary {
    path: PathBuf,
    metric: &'static str,
    scale_max: u64,
    max: u64,
    mean: f64,
}

fn render(a: &RenderArgs) -> Result<()> {
    use vlf_render::{Background, Light, Scene, SceneOptions, Settings, View as Camera, WorkMetric};
    if a.width == 0 || a.height == Some(0) {
        bail!("--width and --height must be positive");
    }
    if a.samples == 0 || a.samples > 16 {
        bail!("--samples must be between 1 and 16 (it is per axis: 16 = 256 rays per pixel)");
    }
    if a.max_depth > vlf_render::MAX_BOUNCES {
        bail!("--max-depth must be at most {}", vlf_render::MAX_BOUNCES);
    }
    if !(a.fov > 0.0 && a.fov < 180.0) {
        bail!("--fov must be between 0 and 180 degrees");
    }
    if !(a.exposure.is_finite() && a.exposure > 0.0) {
        bail!("--exposure must be positive");
    }
    if !(a.ambient.is_finite() && a.ambient >= 0.0) {
        bail!("--ambient must not be negative");
    }
    let field = Field::open(&a.field)?;
    let (center, radius) = field.bounding_sphere();
    let cameras: Vec<_> = field.cameras().collect();

    // The camera: flags, else the field's, else a framing; the image height follows a field
    // camera's aspect ratio unless given.
    let field_camera = match (a.camera, a.view, a.eye) {
        (Some(n), _, _) => Some(n),
        (None, None, None) if !cameras.is_empty() => Some(0),
        _ => None,
    };
    let chosen = field_camera
        .map(|n| {
            cameras
                .get(n)
                .ok_or_else(|| anyhow::anyhow!("--camera {n}: {} has {} camera(s)", a.field.display(), cameras.len()))
        })
        .transpose()?;
    let camera_aspect = chosen.and_then(|c| match c.projection {
        vlf_runtime::CameraProjection::Perspective { aspect_ratio, .. } => aspect_ratio.map(f64::from),
        vlf_runtime::CameraProjection::Orthographic { xmag, ymag } => Some(xmag as f64 / ymag as f64),
    });
    let height = a.height.unwrap_or_else(|| match camera_aspect {
        Some(r) if r.is_finite() && r > 0.0 => ((a.width as f64 / r).round() as u32).clamp(1, 1 << 16),
        _ => 480,
    });
    let aspect = a.width as f64 / height as f64;
    let (view, camera_name) = match (chosen, a.eye) {
        (Some(c), _) => {
            let n = field_camera.unwrap_or(0);
            let view = Camera::from_scene_camera(c, aspect).ok_or_else(|| {
                anyhow::anyhow!("camera {n} of {} cannot be used: its frame is degenerate", a.field.display())
            })?;
            (view, format!("field camera {n} {:?}", c.name))
        }
        (None, Some(eye)) => {
            let target = a.target.unwrap_or(center);
            if eye == target {
                bail!("--eye and --target are the same point");
            }
            (Camera::look_at(eye, target, a.up, a.fov, aspect), format!("eye {eye:?} looking at {target:?}"))
        }
        (None, None) => match a.view.unwrap_or(View::Outside) {
            View::Outside => (Camera::outside(center, radius, aspect), "outside (framing the scene)".to_string()),
            View::Inside => (Camera::inside(center, radius, aspect), "inside (across the scene)".to_string()),
        },
    };

    let field_lights: Vec<Light> = field.lights().filter_map(|l| Light::from_scene_light(&l)).collect();
    let (lights, lights_name) = if !a.lights.is_empty() {
        (a.lights.iter().map(|l| Light::point([l[0], l[1], l[2]], l[3])).collect(), "from --light")
    } else if !field_lights.is_empty() && !a.default_lights {
        (field_lights, "the field's")
    } else {
        (vlf_render::default_lights(&view, center, radius), "default key and fill")
    };

    let settings = Settings {
        width: a.width,
        height,
        samples: a.samples,
        max_depth: a.max_depth,
        ambient: a.ambient,
        background: a.background.map_or(Background::Sky, Background::Solid),
    };
    let options = SceneOptions { smooth: !a.flat, ..SceneOptions::default() };
    let scene = Scene::from_field(&field, &options);
    let bar = Bar::new(a.quiet || a.json);
    bar.begin("rendering rows", height as u64);
    let start = Instant::now();
    let frame = vlf_render::render(field.view(), &scene, &view, &lights, &settings, &|rows| bar.advance(rows));
    let seconds = start.elapsed().as_secs_f64();
    bar.end();

    let png = vlf_render::encode_png(frame.width, frame.height, &vlf_render::to_srgb8(&frame, a.exposure))?;
    vlf_bake::atomic::write_atomically(&a.output, |w| w.write_all(&png))
        .with_context(|| format!("cannot write {}", a.output.display()))?;
    let work_image = match &a.work_image {
        None => None,
        Some(path) => {
            let metric = match a.work {
                WorkArg::Tests => WorkMetric::TriangleTests,
                WorkArg::Tiles => WorkMetric::Cells,
                WorkArg::Leaves => WorkMetric::Leaves,
                WorkArg::Rays => WorkMetric::Rays,
            };
            let image = vlf_render::work_image(&frame, metric, a.work_max);
            let png = vlf_render::encode_png(frame.width, frame.height, &image.rgb)?;
            vlf_bake::atomic::write_atomically(path, |w| w.write_all(&png))
                .with_context(|| format!("cannot write {}", path.display()))?;
            Some(WorkImageSummary {
                path: path.clone(),
                metric: metric.describe(),
                scale_max: image.scale_max,
                max: image.max,
                mean: image.mean,
            })
        }
    };
    let r = frame.rays;
    let summary = RenderSummary {
        output: a.output.clone(),
        width: frame.width,
        height: frame.height,
        samples_per_pixel: a.samples * a.samples,
        camera: camera_name,
        lights: lights_name.to_string(),
        light_count: lights.len(),
        seconds,
        rays: RaysSummary {
            primary: r.primary,
            shadow: r.shadow,
            reflection: r.reflection,
            refraction: r.refraction,
            total: r.total(),
        },
        mrays_per_s: r.total() as f64 / seconds.max(1e-12) / 1e6,
        work: WorkSummary {
            rays_reaching_the_scene: frame.total_work.rays,
            tiles: frame.total_work.cells,
            leaves: frame.total_work.leaves,
            triangle_tests: frame.total_work.triangle_tests,
        },
        work_image,
        threads: rayon::current_num_threads(),
    };
    if a.json {
        return stdout_line(&serde_json::to_string(&summary)?);
    }
    if a.quiet {
        return Ok(());
    }
    let s = &summary;
    let mut text = format!(
        "rendered {} ({}×{}, {} samples per pixel) in {:.2} s: {} rays ({} primary, {} shadow, {} reflected, {} refracted), {:.2} Mrays/s on {} threads\n  camera {}; {} light(s), {}",
        s.output.display(),
        s.width,
        s.height,
        s.samples_per_pixel,
        s.seconds,
        s.rays.total,
        s.rays.primary,
        s.rays.shadow,
        s.rays.reflection,
        s.rays.refraction,
        s.mrays_per_s,
        s.threads,
        s.camera,
        s.light_count,
        s.lights
    );
    if let Some(w) = &s.work_image {
        text.push_str(&format!(
            "\n  work picture {}: {} per pixel, black = 0 to white = {} (largest {}, mean {:.1})",
            w.path.display(),
            w.metric,
            w.scale_max,
            w.max,
            w.mean
        ));
    }
    stdout_line(&text)
}

fn gen_scene(a: &GenArgs) -> Result<()> {
    let (name, tris) = match a.scene {
        SceneKind::Random => ("random", generate::random_cube(a.count, a.size, a.seed)),
        SceneKind::Grid => ("grid", generate::grid(a.count as u32, 4, 1.0)),
        SceneKind::Slivers => ("slivers", generate::slivers(a.count, a.seed)),
    };
    vlf_bake::atomic::write_atomically(&a.output, |w| generate::write_obj(w, name, &tris))
        .with_context(|| format!("cannot write {}", a.output.display()))?;
    Ok(())
}

/// The bundled default meshes, found through the source tree this binary was built from: the
/// bunny, and the room around it whose glTF brings materials, a camera and lights.
const DEMO_MESHES: [&str; 2] = [
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/meshes/cornell/cornell.gltf"),
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/meshes/bunny.obj"),
];

fn demo(a: &DemoArgs) -> Result<()> {
    let inputs: Vec<PathBuf> =
        if a.input.is_empty() { DEMO_MESHES.iter().map(PathBuf::from).collect() } else { a.input.clone() };
    if let Some(missing) = inputs.iter().find(|i| !i.exists()) {
        bail!("demo mesh {} not found; pass --input MESH", missing.display());
    }
    std::fs::create_dir_all(&a.output_dir).with_context(|| format!("cannot create {}", a.output_dir.display()))?;
    let field_path = a.output_dir.join("demo.vlf");
    let names: Vec<String> = inputs.iter().map(|i| i.display().to_string()).collect();
    stdout_line(&format!("1. bake {} (parameters chosen automatically)", names.join(" ")))?;
    bake(&BakeArgs {
        inputs,
        output: field_path.clone(),
        directions: None,
        tiles: None,
        leaf_size: DEFAULT_LEAF_SIZE,
        max_depth: DEFAULT_MAX_DEPTH,
        max_bytes: vlf_bake::params::DEFAULT_MAX_BYTES,
        max_bytes_per_triangle: vlf_bake::params::DEFAULT_MAX_BYTES_PER_TRIANGLE,
        threads: None,
        quiet: false,
        json: false,
        shard: None,
        cache: CacheChoice { cache_dir: None, no_cache: true },
        report: None,
    })?;
    stdout_line(&format!("\n2. dump {} --verify", field_path.display()))?;
    dump(&DumpArgs { field: field_path.clone(), json: false, verify: true, quiet: false })?;
    for (view, name) in [(View::Outside, "outside"), (View::Inside, "inside")] {
        let rays_path = a.output_dir.join(format!("{name}.rays"));
        let hits_path = a.output_dir.join(format!("{name}.hits"));
        stdout_line(&format!("\n3. trace 512×512 primary rays from {name} the scene"))?;
        rays(&RaysArgs { field: field_path.clone(), output: rays_path.clone(), view, width: 512, height: 512 })?;
        trace(&TraceArgs {
            field: field_path.clone(),
            rays: rays_path,
            out: hits_path,
            any_hit: false,
            json: false,
            threads: None,
        })?;
    }
    let picture = a.output_dir.join("demo.png");
    stdout_line(&format!("\n4. render {} -o {}", field_path.display(), picture.display()))?;
    render(&RenderArgs {
        field: field_path,
        output: picture.clone(),
        width: 640,
        height: None,
        view: None,
        camera: None,
        eye: None,
        target: None,
        up: [0.0, 1.0, 0.0],
        fov: 50.0,
        lights: Vec::new(),
        default_lights: false,
        max_depth: 5,
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
