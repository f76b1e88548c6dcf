//! The command line as clap parses it: one struct of arguments per subcommand, with every flag's
//! help text. Values are parsed here ([`crate::values`]); what they mean is decided by the
//! commands and the libraries.

use crate::values::{
    MAX_BSP_DEPTH, MAX_DIRECTIONS, MAX_IMAGE_SIDE, MAX_THREADS, MAX_TILES, between, duration, parse_colour,
    parse_light, parse_png_path, parse_up, parse_vec3, real, size,
};
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;
use vlf_bake::generate;
use vlf_bake::params::{DEFAULT_LEAF_SIZE, DEFAULT_MAX_DEPTH};

#[derive(Parser)]
#[command(
    name = "vlf-bake",
    version,
    about = "Bake triangle meshes into visibility fields that load instantly, and inspect, verify and trace them.",
    long_about = "Bake triangle meshes (OBJ, glTF, GLB) into a visibility field: a precomputed, memory-mappable \
ray-tracing acceleration structure (Mortensen et al., \"A Visibility Field for Ray Tracing\"). A field is one \
versioned, content-hashed file; bakes are reproducible to the byte.\n\nTypical use:\n  vlf-bake bake scene.glb -o scene.vlf\n  vlf-bake dump scene.vlf --verify\n  vlf-bake render scene.vlf -o scene.png\n  vlf-bake pack scene.vlf -o scene.packed.vlf   (for transport; `unpack` restores it)\n  vlf-bake rays scene.vlf -o rays.bin && vlf-bake trace scene.vlf --rays rays.bin -o hits.bin --json"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
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

impl Command {
    /// Whether `--json` was given: a failure is then also reported on standard output, as one
    /// JSON object (`main`).
    pub fn json(&self) -> bool {
        match self {
            Command::Bake(a) => a.json,
            Command::Merge(a) => a.json,
            Command::Cache(a) => a.json,
            Command::Dump(a) => a.json,
            Command::Pack(a) => a.json,
            Command::Unpack(a) => a.json,
            Command::Trace(a) => a.json,
            Command::Rays(a) => a.json,
            Command::Render(a) => a.json,
            Command::Gen(a) => a.json,
            Command::Demo(_) => false,
        }
    }
}

#[derive(Args)]
pub struct DemoArgs {
    /// The meshes to bake, repeatable (default: the bunny in the repository's fixtures, in the
    /// Cornell-like room whose glTF brings a camera and lights).
    #[arg(long, value_name = "MESH")]
    pub input: Vec<PathBuf>,
    /// Where to write the field, rays and hits.
    #[arg(long, default_value = "target/vlf-demo", value_name = "DIR")]
    pub output_dir: PathBuf,
}

#[derive(Args)]
pub struct BakeArgs {
    /// Input meshes: .obj, .gltf or .glb. Several inputs are baked into one field.
    #[arg(required = true, value_name = "INPUT")]
    pub inputs: Vec<PathBuf>,
    /// The field file to write (replaced atomically).
    #[arg(short, long, value_name = "FIELD")]
    pub output: PathBuf,
    /// Number of directions l, 3 to 33554433; rounded up to the next lattice size 2N²+1 (3, 9, 19,
    /// 33, 51, ..., 2049, ...). Chosen automatically under --max-bytes if absent.
    #[arg(long, value_name = "L", value_parser = between(3, MAX_DIRECTIONS), allow_negative_numbers = true)]
    pub directions: Option<u32>,
    /// Tiles per side n of each direction's n×n beam grid, 1 to 65536. Chosen automatically if absent.
    #[arg(long, value_name = "N", value_parser = between(1, MAX_TILES), allow_negative_numbers = true)]
    pub tiles: Option<u32>,
    /// BSP depth policy: target triangles per leaf (at least 1).
    #[arg(long, default_value_t = DEFAULT_LEAF_SIZE, value_name = "K", value_parser = between(1, u32::MAX),
          allow_negative_numbers = true)]
    pub leaf_size: u32,
    /// BSP depth policy: largest depth of a tile's 1D BSP, 0 to 12, the format's limit (0 = linear
    /// tiles, no BSP).
    /// Not `render --bounces`, which once had this name.
    #[arg(long, default_value_t = DEFAULT_MAX_DEPTH, value_name = "D", value_parser = between(0, MAX_BSP_DEPTH),
          allow_negative_numbers = true)]
    pub max_depth: u32,
    /// Size budget for automatic parameters, and a ceiling for explicit ones: explicit parameters
    /// whose field cannot fit it (counting the tiles each triangle covers) are refused before
    /// baking, and a bake stops, leaving nothing behind, as soon as its field would exceed it
    /// (e.g. 4GiB, 512MiB, 1e9).
    #[arg(long, default_value = "4GiB", value_parser = size(), value_name = "SIZE", allow_negative_numbers = true)]
    pub max_bytes: u64,
    /// Automatic parameters aim at no more than this many bytes of field per triangle (any mesh
    /// gets at least 16 MiB, and 2.5 KiB for each of its first 100,000 triangles, less and less
    /// past them down to 1 KiB at 625,000, so that a few triangles always bake and small scenes
    /// get the directions that make them fast; --max-bytes caps both).
    #[arg(long, default_value = "1KiB", value_parser = size(), value_name = "SIZE", allow_negative_numbers = true)]
    pub max_bytes_per_triangle: u64,
    /// Worker threads, 1 to 1024; more than the cores available are reduced to them, with a warning
    /// (default: RAYON_NUM_THREADS, else all cores). The output does not depend on it.
    #[arg(long, value_name = "T", value_parser = between(1, MAX_THREADS), allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// No progress bar and no summary on success (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Bake only shard K of N (K = 0..N-1): its share of the directions, into a shard file for
    /// `vlf-bake merge` (docs/build-farms.md).
    #[arg(long, value_name = "K/N", allow_hyphen_values = true)]
    pub shard: Option<vlf_bake::shard::ShardSpec>,
    #[command(flatten)]
    pub cache: CacheChoice,
    /// Write a JSON report (inputs, parameters, phase timings, peak memory, output, cache) to FILE.
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
}

#[derive(Args)]
pub struct CacheChoice {
    /// Bake cache directory: reuse the field of unchanged inputs, store new ones
    /// (default: the VLF_CACHE_DIR environment variable).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Do not use a cache, even if VLF_CACHE_DIR is set.
    #[arg(long, conflicts_with = "cache_dir")]
    pub no_cache: bool,
}

#[derive(Args)]
pub struct MergeArgs {
    /// The shard files of one bake, each once, in any order.
    #[arg(required = true, value_name = "SHARD")]
    pub parts: Vec<PathBuf>,
    /// The field file to write (replaced atomically).
    #[arg(short, long, value_name = "FIELD")]
    pub output: PathBuf,
    #[command(flatten)]
    pub cache: CacheChoice,
    /// Write a JSON report to FILE (the schema of `bake --report`).
    #[arg(long, value_name = "FILE.json")]
    pub report: Option<PathBuf>,
    /// No progress bar and no summary on success (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct CacheArgs {
    #[command(subcommand)]
    pub action: CacheAction,
    /// The cache directory (default: the VLF_CACHE_DIR environment variable).
    #[arg(long, global = true, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Print one JSON value instead of text.
    #[arg(long, global = true)]
    pub json: bool,
}

#[derive(Subcommand)]
pub enum CacheAction {
    /// List the entries, most recently used first.
    List,
    /// Check every byte of every entry (as `dump --verify`) and its key; remove the bad ones.
    Verify,
    /// Remove entries unused for longer than --max-age, then the least recently used ones until
    /// the cache fits in --max-size; and temporary files left by crashed bakes. Needs one of the
    /// two, or both.
    #[command(group(clap::ArgGroup::new("limit").args(["max_size", "max_age"]).required(true).multiple(true)))]
    Prune {
        /// Keep at most this many bytes (e.g. 20GiB).
        #[arg(long, value_parser = size(), value_name = "SIZE", allow_negative_numbers = true)]
        max_size: Option<u64>,
        /// Remove entries not used for this long (e.g. 30d, 12h, 90m).
        #[arg(long, value_parser = duration(), value_name = "DURATION", allow_hyphen_values = true)]
        max_age: Option<std::time::Duration>,
    },
}

#[derive(Args)]
pub struct DumpArgs {
    /// The field file. A packed field is decoded in memory first, which is not instant.
    pub field: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Recompute every hash and check every offset and index; exit 1 naming the first fault.
    #[arg(long)]
    pub verify: bool,
    /// No progress bar during --verify.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Args)]
pub struct PackArgs {
    /// The raw field to pack.
    pub field: PathBuf,
    /// The packed field to write (replaced atomically). It is still a field: `dump`, `trace` and
    /// the runtime open it (decoding it in memory first).
    #[arg(short, long, value_name = "PACKED")]
    pub output: PathBuf,
    /// zstd level, from 1 (fastest) to 19 (smallest). The output does not depend on anything else.
    #[arg(long, default_value_t = vlf_bake::pack::DEFAULT_LEVEL, value_name = "N", allow_negative_numbers = true,
          value_parser = between(*vlf_bake::pack::LEVELS.start(), *vlf_bake::pack::LEVELS.end()))]
    pub level: i32,
    /// Worker threads, 1 to 1024, at most the cores available (default: RAYON_NUM_THREADS, else all
    /// cores); each compresses whole sections.
    #[arg(long, value_name = "T", value_parser = between(1, MAX_THREADS), allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// No progress bar and no summary on success (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the summary (sizes, ratio, MB/s, per-section codecs) as one JSON object.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct UnpackArgs {
    /// The packed field.
    pub packed: PathBuf,
    /// The raw field to write (replaced atomically).
    #[arg(short, long, value_name = "FIELD")]
    pub output: PathBuf,
    /// No progress bar and no summary on success (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the summary (sizes, ratio, MB/s) as one JSON object.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct TraceArgs {
    /// The field file (or --scene).
    #[arg(required_unless_present = "scene", conflicts_with = "scene")]
    pub field: Option<PathBuf>,
    /// Trace against a scene file instead (formats/scene.md): fields placed by transforms, with
    /// edits. A hit's prim is the triangle's id in the hit instance's field.
    #[arg(long, value_name = "SCENE.json")]
    pub scene: Option<PathBuf>,
    /// With --scene: also write the hit instance of every ray, a little-endian u32 each
    /// (0xFFFFFFFF on a miss), in ray order.
    #[arg(long, value_name = "FILE", requires = "scene")]
    pub instance_ids: Option<PathBuf>,
    /// Rays: 32-byte little-endian records (formats/rays.md).
    #[arg(long, value_name = "FILE")]
    pub rays: PathBuf,
    /// The hits file to write: 16-byte records, one per ray (formats/rays.md). `--out` is an old
    /// spelling, still accepted.
    #[arg(short, long, value_name = "FILE", alias = "out")]
    pub output: PathBuf,
    /// Answer any-hit (shadow) queries instead of closest-hit.
    #[arg(long)]
    pub any_hit: bool,
    /// No summary on success (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print rays, hits, seconds (tracing only) and mrays_per_s as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Worker threads, 1 to 1024, at most the cores available (default: RAYON_NUM_THREADS, else
    /// all cores).
    #[arg(long, value_name = "T", value_parser = between(1, MAX_THREADS), allow_negative_numbers = true)]
    pub threads: Option<usize>,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum View {
    /// From outside the scene's bounding sphere, framing all of it.
    Outside,
    /// From inside the scene, near its centre.
    Inside,
}

#[derive(Args)]
pub struct RaysArgs {
    /// The field whose scene the camera frames.
    pub field: PathBuf,
    /// The rays file to write: one 32-byte record per pixel, row by row (formats/rays.md).
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Where the camera is: outside the scene framing all of it, or inside looking across it.
    #[arg(long, value_enum, default_value = "outside")]
    pub view: View,
    /// Image width in pixels, 1 to 65535 (default 640; with --height alone, 4:3 to it).
    #[arg(long, value_name = "PIXELS", value_parser = between(1, MAX_IMAGE_SIDE), allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Image height in pixels, 1 to 65535 (default 480; with --width alone, 3:4 of it).
    #[arg(long, value_name = "PIXELS", value_parser = between(1, MAX_IMAGE_SIDE), allow_negative_numbers = true)]
    pub height: Option<u32>,
    /// No summary on success (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the summary (output, rays, width, height, view, bytes) as one JSON object.
    #[arg(long)]
    pub json: bool,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum WorkArg {
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
pub struct RenderArgs {
    /// The field file (or --scene).
    #[arg(required_unless_present = "scene", conflicts_with = "scene")]
    pub field: Option<PathBuf>,
    /// Render a scene file instead (formats/scene.md): fields placed by transforms, with edits.
    #[arg(long, value_name = "SCENE.json")]
    pub scene: Option<PathBuf>,
    /// With --scene: render N frames (1 to 10000) into one animated PNG, the --move instances
    /// travelling along --path and turning by --spin from the first frame to the last.
    #[arg(long, value_name = "N", requires = "scene", value_parser = between(1u32, 10_000), allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// With --frames: an instance to move (its index in the scene file), repeatable (default:
    /// the last instance).
    #[arg(long = "move", value_name = "ID", requires = "frames", value_parser = between(0u32, u32::MAX - 1),
          allow_negative_numbers = true)]
    pub moves: Vec<u32>,
    /// With --frames: how far the moved instances travel by the last frame, DX,DY,DZ in world
    /// units (default: half the scene's width along x).
    #[arg(long, value_name = "DX,DY,DZ", value_parser = parse_vec3, allow_hyphen_values = true, requires = "frames")]
    pub path: Option<[f64; 3]>,
    /// With --frames: how far the moved instances turn by the last frame, in degrees about the
    /// --up axis through the centre of each (-36000 to 36000).
    #[arg(long, value_name = "DEGREES", default_value_t = 0.0, value_parser = real(-36000.0, 36000.0, (false, false)),
          allow_negative_numbers = true, requires = "frames")]
    pub spin: f64,
    /// With --frames: how long each frame shows, in milliseconds (1 to 60000).
    #[arg(long, value_name = "MS", default_value_t = 40, value_parser = between(1u16, 60_000), allow_negative_numbers = true,
          requires = "frames")]
    pub frame_ms: u16,
    /// The PNG to write (the name must end in .png).
    #[arg(short, long, value_name = "IMAGE.png", value_parser = parse_png_path)]
    pub output: PathBuf,
    /// Image width in pixels, 1 to 65535 (default 640, or from --height and the aspect ratio).
    #[arg(long, value_name = "PIXELS", value_parser = between(1, MAX_IMAGE_SIDE), allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Image height in pixels, 1 to 65535 (default: from the width and the field camera's aspect
    /// ratio, else 4:3).
    #[arg(long, value_name = "PIXELS", value_parser = between(1, MAX_IMAGE_SIDE), allow_negative_numbers = true)]
    pub height: Option<u32>,
    /// Frame the whole scene from outside, or look across it from inside (like `rays --view`).
    /// Default: the field's first glTF camera if it has one, else outside.
    #[arg(long, value_enum, conflicts_with_all = ["camera", "eye"])]
    pub view: Option<View>,
    /// Use the field's glTF camera number N (0 = first; `dump` counts them).
    #[arg(long, value_name = "N", conflicts_with = "eye", value_parser = between(0, u32::MAX as usize),
          allow_negative_numbers = true)]
    pub camera: Option<usize>,
    /// Place a pinhole camera at X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<[f64; 3]>,
    /// The point an --eye camera looks at (default: the centre of the scene).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true, requires = "eye")]
    pub target: Option<[f64; 3]>,
    /// The up direction of an --eye camera: not zero, and not along the line of sight.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_up, default_value = "0,1,0", allow_hyphen_values = true)]
    pub up: [f64; 3],
    /// Vertical field of view of an --eye camera, in degrees, between 0 and 180 (both excluded).
    #[arg(long, default_value_t = 50.0, value_name = "DEGREES", value_parser = real(0.0, 180.0, (true, true)),
          allow_negative_numbers = true)]
    pub fov: f64,
    /// A white point light at X,Y,Z with intensity I (irradiance I/d²); repeatable. Replaces the
    /// field's lights and the default key and fill lights.
    #[arg(long = "light", value_name = "X,Y,Z,I", value_parser = parse_light, allow_hyphen_values = true)]
    pub lights: Vec<[f64; 4]>,
    /// Ignore the field's glTF lights: light the scene with a key and a fill light around the camera.
    #[arg(long)]
    pub default_lights: bool,
    /// Reflection and refraction bounces after the primary ray, 0 to 64. `--max-depth` is an old
    /// spelling, still accepted (in `bake`, --max-depth is the BSP depth).
    #[arg(long, default_value_t = 5, value_name = "N", alias = "max-depth",
          value_parser = between(0, vlf_render::MAX_BOUNCES), allow_negative_numbers = true)]
    pub bounces: u32,
    /// Samples per pixel along each axis, 1 to 16 (2 = 4 rays per pixel, antialiased).
    #[arg(long, default_value_t = 2, value_name = "N", value_parser = between(1u32, 16), allow_negative_numbers = true)]
    pub samples: u32,
    /// Multiply the image's brightness (more than 0, at most 1000).
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", value_parser = real(0.0, 1000.0, (true, false)),
          allow_negative_numbers = true)]
    pub exposure: f64,
    /// Unshadowed light every surface receives, 0 to 1000.
    #[arg(long, default_value_t = 0.06, value_name = "IRRADIANCE", value_parser = real(0.0, 1000.0, (false, false)),
          allow_negative_numbers = true)]
    pub ambient: f64,
    /// A solid background colour R,G,B (linear, 0 to 1) instead of the sky gradient.
    #[arg(long, value_name = "R,G,B", value_parser = parse_colour, allow_hyphen_values = true)]
    pub background: Option<[f64; 3]>,
    /// Flat shading: no normals interpolated across edges.
    #[arg(long)]
    pub flat: bool,
    /// Also write a false-colour picture of the work per pixel (black = none, white = --work-max or
    /// more); the name must end in .png.
    #[arg(long, value_name = "IMAGE.png", value_parser = parse_png_path)]
    pub work_image: Option<PathBuf>,
    /// What the work picture shows, summed over every ray of the pixel.
    #[arg(long, value_enum, default_value = "tests")]
    pub work: WorkArg,
    /// The work at the top of the colour scale, at least 1 (default: the 99th percentile of the frame).
    #[arg(long, value_name = "COUNT", value_parser = between(1, u64::MAX), allow_negative_numbers = true)]
    pub work_max: Option<u64>,
    /// Worker threads, 1 to 1024, at most the cores available (default: RAYON_NUM_THREADS, else all
    /// cores). The picture does not depend on it.
    #[arg(long, value_name = "T", value_parser = between(1, MAX_THREADS), allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// No progress bar and no summary on success (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum SceneKind {
    /// The paper's scene: triangles with centres uniform in [-1,1]³, vertices within ±size of the centre.
    Random,
    /// Axis-aligned coplanar grids with shared edges (count = cells per side, 4 layers).
    Grid,
    /// Long thin slivers.
    Slivers,
}

#[derive(Args)]
pub struct GenArgs {
    /// Which scene: random triangles, grids or slivers.
    #[arg(value_enum)]
    pub scene: SceneKind,
    /// Number of triangles (random, slivers: 1 to 4294967295) or cells per side (grid: 1 to 23170,
    /// making 8 × count² triangles). Its range depends on the scene, so `gen` checks it.
    #[arg(long, default_value = "10000", value_name = "N", allow_hyphen_values = true)]
    pub count: String,
    /// Seed of the random scenes: the same seed gives the same file, byte for byte.
    #[arg(long, default_value_t = 1, value_name = "S", value_parser = between(0, u64::MAX), allow_negative_numbers = true)]
    pub seed: u64,
    /// Random scene: half-extent of each triangle around its centre (1e-5 to 1000: near the
    /// cube's corners f32 numbers are 1.2e-7 apart, and smaller triangles collapse to zero area,
    /// which a bake drops).
    #[arg(long, default_value_t = generate::DEFAULT_TRIANGLE_SIZE, value_name = "SIZE",
          value_parser = real(1e-5, 1000.0, (false, false)), allow_negative_numbers = true)]
    pub size: f64,
    /// The OBJ file to write.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// No summary on success (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the summary (output, scene, triangles, seed, bytes) as one JSON object.
    #[arg(long)]
    pub json: bool,
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// Every value parser gives the type its field holds (a mismatch panics only when a command
    /// is parsed, so each is parsed here with its defaults).
    #[test]
    fn every_subcommand_parses_with_its_defaults() {
        Cli::command().debug_assert();
        for args in [
            &["bake", "m.obj", "-o", "f.vlf"][..],
            &["merge", "a.vlfs", "-o", "f.vlf"],
            &["cache", "list"],
            &["cache", "prune", "--max-size", "1GiB"],
            &["dump", "f.vlf"],
            &["pack", "f.vlf", "-o", "p.vlf"],
            &["unpack", "p.vlf", "-o", "f.vlf"],
            &["trace", "f.vlf", "--rays", "r.bin", "-o", "h.bin"],
            &["trace", "--scene", "s.json", "--rays", "r.bin", "-o", "h.bin", "--instance-ids", "i.bin"],
            &[
                "render", "--scene", "s.json", "-o", "p.png", "--frames", "3", "--move", "1", "--path", "1,0,0",
                "--spin", "90",
            ],
            &["rays", "f.vlf", "-o", "r.bin"],
            &["render", "f.vlf", "-o", "p.png", "--work-image", "w.png", "--work-max", "9", "--camera", "0"],
            &["gen", "grid", "-o", "g.obj"],
            &["demo"],
        ] {
            let argv = std::iter::once("vlf-bake").chain(args.iter().copied());
            if let Err(e) = Cli::try_parse_from(argv) {
                panic!("{args:?}: {e}");
            }
        }
    }

    /// The range `bake --help` gives for --max-depth is the one its parser accepts.
    #[test]
    fn max_depth_help_gives_the_range_the_parser_accepts() {
        let cmd = Cli::command();
        let bake = cmd.find_subcommand("bake").unwrap();
        let arg = bake.get_arguments().find(|a| a.get_id() == "max_depth").unwrap();
        let help = arg.get_help().unwrap().to_string();
        assert!(help.contains(&format!("0 to {MAX_BSP_DEPTH},")), "{help}");
        let parse =
            |d: u32| Cli::try_parse_from(["vlf-bake", "bake", "m.obj", "-o", "f.vlf", "--max-depth", &d.to_string()]);
        assert!(parse(MAX_BSP_DEPTH).is_ok() && parse(MAX_BSP_DEPTH + 1).is_err());
    }

    /// The bake's flags default to the library's defaults, so the CLI, the C API and the Python
    /// package bake the same field from the same mesh.
    #[test]
    fn bake_defaults_are_the_library_defaults() {
        let Command::Bake(a) = Cli::try_parse_from(["vlf-bake", "bake", "m.obj", "-o", "f.vlf"]).unwrap().command
        else {
            panic!("not a bake");
        };
        let d = vlf_bake::BakeConfig::default();
        assert_eq!((a.max_bytes, a.max_bytes_per_triangle), (d.max_bytes, d.max_bytes_per_triangle));
        assert_eq!((a.leaf_size, a.max_depth), (d.depth.leaf_size, d.depth.max_depth));
        assert_eq!((a.directions, a.tiles), (d.directions, d.tiles));
    }
}
