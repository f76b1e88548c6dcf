//! `vlf-bench`: the paper's experiments on this machine, written to `docs/benchmarks/`.
//!
//! ```sh
//! cargo run --release -p vlf-bench -- all          # Figures 3 and 4 and the parameter study
//! cargo run --release -p vlf-bench -- figure3 --sizes 1000,16000
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
    /// Scratch directory for baked fields (each is deleted after use).
    #[arg(long, default_value = "target/bench-work", global = true)]
    work: PathBuf,
    /// Timed runs per measurement, after a warm-up run.
    #[arg(long, default_value_t = 3, global = true)]
    repeats: usize,
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
    /// Everything, at the defaults above.
    All,
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
    let s = Settings {
        work: c.work,
        out: c.out,
        repeats: c.repeats,
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
        Command::All => {
            println!("{}", vlf_bench::experiments::figure3(&s, &[1_000, 4_000, 16_000, 64_000, 256_000, 1_000_000])?);
            println!("{}", vlf_bench::experiments::figure4(&s, 16_000, 120)?);
            println!("{}", params(&s, 100_000)?);
        }
    }
    Ok(())
}
