//! `vlf-bench`: the paper's experiments on this machine, written to `docs/benchmarks/`.
//!
//! ```sh
//! cargo run --release -p vlf-bench -- all          # Figures 3 and 4 and the parameter study
//! cargo run --release -p vlf-bench -- figure3 --sizes 1000,16000
//! cargo run --release -p vlf-bench --features embree,obvhs -- peers --quick --out target/peers/quick
//! ```

#![forbid(unsafe_code)]

use anyhow::Result;
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use vlf_bake::DepthPolicy;
use vlf_bench::Settings;

#[derive(Parser)]
#[command(
    name = "vlf-bench",
    about = "Reproduce the paper's experiments: the visibility field against a tuned CRT kd-tree (Figures 3 and 4), \
             their costs, and a parameter study. Writes markdown tables, SVG plots and raw JSON."
)]
struct Cli {
    #[command(flatten)]
    common: Common,
    #[command(subcommand)]
    command: Command,
}

#[derive(Args)]
struct Common {
    /// Where tables, plots and JSON go.
    #[arg(long, default_value = "docs/benchmarks", global = true)]
    out: PathBuf,
    /// Scratch directory for baked fields (each is deleted after use) [default: target/bench-work;
    /// for peers, target/peers].
    #[arg(long, global = true)]
    work: Option<PathBuf>,
    /// Timed runs per measurement, after a warm-up run [default: 3; for peers, 9 rounds; for
    /// dynamic, 5].
    #[arg(long, global = true)]
    repeats: Option<usize>,
    /// Width and height of each frame.
    #[arg(long, default_value_t = 512, global = true)]
    resolution: u32,
    /// Largest field to bake, in GiB.
    #[arg(long, default_value_t = 4.0, global = true)]
    max_field_gib: f64,
    /// No progress lines.
    #[arg(short, long, global = true)]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Figure 3: frame time against triangle count, outside and inside, CRT against six field variants.
    Figure3 {
        /// Scene sizes in triangles.
        #[arg(long, value_delimiter = ',', default_values_t = [1_000usize, 4_000, 16_000, 64_000, 256_000, 1_000_000])]
        sizes: Vec<usize>,
    },
    /// Figure 4: a walkthrough from outside to inside the 16K scene.
    Figure4 {
        #[arg(long, default_value_t = 16_000)]
        triangles: usize,
        #[arg(long, default_value_t = 120)]
        frames: usize,
    },
    /// The parameter study on the 100K scene.
    Params {
        #[arg(long, default_value_t = 100_000)]
        triangles: usize,
    },
    /// Time to first pixel: open each field and trace one ray in a new process, `--runs` times,
    /// with the file in the page cache (and with it evicted, with --cold). Prints a markdown
    /// table of medians and ranges; `docs/benchmarks/first-pixel.sh` runs it on a ~1 MiB field and
    /// on fields over 1 GiB.
    FirstPixel {
        /// Field files.
        #[arg(required = true)]
        fields: Vec<std::path::PathBuf>,
        /// New processes per field and cache state.
        #[arg(long, default_value_t = 21)]
        runs: usize,
        /// Also measure with the file evicted from the page cache before each run (Linux).
        #[arg(long)]
        cold: bool,
        /// How the measured process opens the field: `open` (`Field::open`) and/or `random`
        /// (the same with `madvise(MADV_RANDOM)` before the first read).
        #[arg(long, value_enum, value_delimiter = ',', default_values = ["open"])]
        access: Vec<vlf_bench::first_pixel::Access>,
        /// Also write every run as JSON to this file.
        #[arg(long)]
        json: Option<std::path::PathBuf>,
    },
    /// The measured process of `first-pixel` (internal).
    #[command(hide = true)]
    FirstPixelChild {
        field: std::path::PathBuf,
        #[arg(long, value_enum)]
        access: vlf_bench::first_pixel::Access,
    },
    /// The field against Embree (feature `embree`), obvhs (feature `obvhs`) and the kd-tree on the
    /// same scenes and rays (issue 12): Mrays/s at each thread count, build times and sizes, every
    /// contestant's hits checked against the brute force. Writes peers.md, peers.json and SVG plots
    /// to --out; `docs/benchmarks/peers.sh` installs what it needs and runs it. Exits nonzero if
    /// the field disagrees with the brute force.
    Peers(PeersArgs),
    /// Dynamic scenes (issue 13): instances of a field against Embree's two-level instancing,
    /// transform updates per frame against its top-level rebuild, and the paper's delete and
    /// reinsert; writes dynamic.md to --out.
    Dynamic(DynamicArgs),
    /// Everything, at the defaults above.
    All,
}

#[derive(Args)]
struct PeersArgs {
    /// A quick run: 10K random triangles (fixed size) and the bunny, 128² primary rays, 16K
    /// incoherent rays; --sizes, --rules, --mesh and --sweep are ignored.
    #[arg(long)]
    quick: bool,
    /// Random scenes: triangle counts.
    #[arg(long, value_delimiter = ',', default_values_t = [10_000usize, 100_000, 1_000_000])]
    sizes: Vec<usize>,
    /// Random scenes: size rules (fixed: half-extent 0.05; density: 0.05·(10⁴/n)^(1/3)).
    #[arg(long, value_enum, value_delimiter = ',', default_values = ["fixed", "density"])]
    rules: Vec<Rule>,
    /// Leave out the bundled bunny.
    #[arg(long)]
    no_bunny: bool,
    /// Mesh files (OBJ or glTF) to add as scenes, e.g. a real scan.
    #[arg(long = "mesh")]
    meshes: Vec<PathBuf>,
    /// Incoherent rays per scene.
    #[arg(long, default_value_t = 262_144)]
    incoherent: usize,
    /// Thread counts to time at.
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 2])]
    threads: Vec<usize>,
    /// Rays per set checked against the brute force on scenes of --check-all-below triangles or more.
    #[arg(long, default_value_t = 4000)]
    check_rays: usize,
    /// Scenes with fewer triangles are checked on every ray.
    #[arg(long, default_value_t = 20_000)]
    check_all_below: usize,
    /// Relative t difference counted as rounding for Embree and obvhs.
    #[arg(long, default_value_t = 1e-4)]
    t_tolerance: f64,
    /// How the kd-tree's depth and leaf size are chosen.
    #[arg(long, value_enum, default_value = "tuned")]
    kd: vlf_bench::peers::KdChoice,
    /// Also bake each scene at the --sweep-params settings and time the field (speed against size).
    #[arg(long)]
    sweep: bool,
    /// The sweep's settings, DIRECTIONSxTILES.
    #[arg(long, value_delimiter = ',', default_values = ["9x32", "9x64", "19x64", "33x64", "33x128"], value_parser = parse_setting)]
    sweep_params: Vec<(u32, u32)>,
    /// Keep the baked fields in --work.
    #[arg(long)]
    keep_fields: bool,
    /// Run nothing: rewrite peers.md and the plots in --out from the peers.json of an earlier run.
    #[arg(long, value_name = "PEERS_JSON")]
    from_json: Option<PathBuf>,
}

#[derive(Args)]
struct DynamicArgs {
    /// Instances of the instanced field.
    #[arg(long, default_value_t = 1000)]
    instances: u32,
    /// Triangles of the instanced field.
    #[arg(long, default_value_t = 10_000)]
    mesh_triangles: usize,
    /// Incoherent rays per measurement.
    #[arg(long, default_value_t = 262_144)]
    incoherent: usize,
    /// Instances moved per frame.
    #[arg(long, default_value_t = 100)]
    updates: u32,
    /// Frames of updates.
    #[arg(long, default_value_t = 50)]
    frames: usize,
    /// Triangles of the edited field.
    #[arg(long, default_value_t = 100_000)]
    big_triangles: usize,
    /// Triangles of each object moved in it.
    #[arg(long, value_delimiter = ',', default_values_t = [1_000usize, 10_000])]
    objects: Vec<usize>,
    /// Moves of each object.
    #[arg(long, default_value_t = 10)]
    moves: usize,
    /// Directions and tiles of the edited field, DIRECTIONSxTILES.
    #[arg(long, default_value = "129x64", value_parser = parse_setting)]
    big_params: (u32, u32),
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Rule {
    Fixed,
    Density,
}

fn parse_setting(s: &str) -> Result<(u32, u32), String> {
    let (d, t) = s.split_once('x').ok_or_else(|| format!("{s:?} is not DIRECTIONSxTILES"))?;
    Ok((d.parse().map_err(|e| format!("{d:?}: {e}"))?, t.parse().map_err(|e| format!("{t:?}: {e}"))?))
}

fn peers(a: PeersArgs, c: &Common) -> Result<()> {
    use vlf_bench::peers::scenes::{SceneSpec, SizeRule};
    if let Some(json) = &a.from_json {
        let report: vlf_bench::peers::report::Report = serde_json::from_str(&std::fs::read_to_string(json)?)?;
        report.write(&c.out)?;
        println!("wrote {} from {}", c.out.join("peers.md").display(), json.display());
        return Ok(());
    }
    let rule = |r: Rule| match r {
        Rule::Fixed => SizeRule::Fixed,
        Rule::Density => SizeRule::Density,
    };
    let mut scenes = Vec::new();
    if !a.no_bunny {
        scenes.push(SceneSpec::bunny());
    }
    if a.quick {
        scenes.push(SceneSpec::Random { triangles: 10_000, rule: SizeRule::Fixed });
    } else {
        for &n in &a.sizes {
            for &r in &a.rules {
                scenes.push(SceneSpec::Random { triangles: n, rule: rule(r) });
            }
        }
        scenes.extend(a.meshes.iter().map(|p| SceneSpec::Mesh { path: p.clone() }));
    }
    let config = vlf_bench::peers::PeersConfig {
        scenes,
        work: c.work.clone().unwrap_or_else(|| "target/peers".into()),
        out: c.out.clone(),
        resolution: if a.quick { 128 } else { c.resolution },
        incoherent: if a.quick { 16_384 } else { a.incoherent },
        repeats: c.repeats.unwrap_or(9),
        threads: a.threads,
        check_rays: a.check_rays,
        check_all_below: a.check_all_below,
        t_tolerance: a.t_tolerance,
        kd: a.kd,
        sweep: if a.sweep && !a.quick { a.sweep_params } else { Vec::new() },
        keep_fields: a.keep_fields,
        command: std::iter::once("vlf-bench".to_string()).chain(std::env::args().skip(1)).collect::<Vec<_>>().join(" "),
        verbose: !c.quiet,
        quick: a.quick,
    };
    let report = vlf_bench::peers::run(&config)?;
    println!(
        "wrote {} ({} scenes, {:.0} s)",
        config.out.join("peers.md").display(),
        report.scenes.len(),
        report.total_seconds
    );
    Ok(())
}

fn params(s: &Settings, triangles: usize) -> Result<String> {
    let grid =
        [(129, 32), (129, 64), (129, 128), (513, 32), (513, 64), (513, 128), (2049, 32), (2049, 64), (2049, 128)];
    let policies = [
        DepthPolicy { leaf_size: 1, max_depth: 0 },
        DepthPolicy { leaf_size: 2, max_depth: 8 },
        DepthPolicy { leaf_size: 8, max_depth: 8 },
        DepthPolicy { leaf_size: 4, max_depth: 4 },
        DepthPolicy { leaf_size: 4, max_depth: 12 },
    ];
    vlf_bench::experiments::parameters(s, triangles, &grid, &policies, (513, 128))
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    let c = cli.common;
    if let Command::Peers(a) = cli.command {
        return peers(a, &c);
    }
    if let Command::Dynamic(a) = cli.command {
        let config = vlf_bench::dynamic::DynamicConfig {
            work: c.work.clone().unwrap_or_else(|| "target/bench-work".into()),
            repeats: c.repeats.unwrap_or(5),
            instances: a.instances,
            mesh_triangles: a.mesh_triangles,
            resolution: c.resolution,
            incoherent: a.incoherent,
            updates: a.updates,
            frames: a.frames,
            big_triangles: a.big_triangles,
            objects: a.objects,
            moves: a.moves,
            big_params: a.big_params,
            command: std::iter::once("vlf-bench".to_string())
                .chain(std::env::args().skip(1))
                .collect::<Vec<_>>()
                .join(" "),
            verbose: !c.quiet,
        };
        let md = vlf_bench::dynamic::run(&config)?;
        std::fs::create_dir_all(&c.out)?;
        std::fs::write(c.out.join("dynamic.md"), &md)?;
        print!("{md}");
        return Ok(());
    }
    let s = Settings {
        work: c.work.unwrap_or_else(|| "target/bench-work".into()),
        out: c.out,
        repeats: c.repeats.unwrap_or(3),
        resolution: c.resolution,
        max_field_bytes: (c.max_field_gib * (1u64 << 30) as f64) as u64,
        verbose: !c.quiet,
    };
    match cli.command {
        Command::Figure3 { sizes } => println!("{}", vlf_bench::experiments::figure3(&s, &sizes)?),
        Command::Figure4 { triangles, frames } => {
            println!("{}", vlf_bench::experiments::figure4(&s, triangles, frames)?)
        }
        Command::Params { triangles } => println!("{}", params(&s, triangles)?),
        Command::FirstPixel { fields, runs, cold, access, json } => {
            let series = vlf_bench::first_pixel::measure(&fields, &access, runs, cold, s.verbose)?;
            if let Some(path) = json {
                std::fs::write(&path, serde_json::to_string_pretty(&series)?)?;
            }
            print!("{}", vlf_bench::first_pixel::table(&series));
        }
        Command::FirstPixelChild { field, access } => vlf_bench::first_pixel::child(&field, access)?,
        Command::Peers(_) | Command::Dynamic(_) => unreachable!("handled above"),
        Command::All => {
            println!("{}", vlf_bench::experiments::figure3(&s, &[1_000, 4_000, 16_000, 64_000, 256_000, 1_000_000])?);
            println!("{}", vlf_bench::experiments::figure4(&s, 16_000, 120)?);
            println!("{}", params(&s, 100_000)?);
        }
    }
    Ok(())
}
