//! `vlf-bake`: bake triangle meshes into visibility-field files, inspect and verify them, trace
//! batches of rays against them and render pictures of them. A thin layer over the `vlf_bake`,
//! `vlf_runtime` and `vlf_render` libraries: [`args`] parses, one function per subcommand in
//! [`commands`] calls the libraries and prints.
//!
//! Exit codes: 0 success; 1 the command failed (one line on standard error says why); 2 the
//! command line was invalid. A closed output pipe (`vlf-bake dump f | head`) counts as success.

#![forbid(unsafe_code)]

mod args;
mod commands;
mod progress;
mod values;

use anyhow::{Context, Result, bail};
use args::{Cli, Command};
use clap::Parser;
use std::process::ExitCode;

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

/// One library call per subcommand.
fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Bake(a) => with_threads(a.threads, || commands::bake::run(&a)),
        Command::Merge(a) => commands::merge::run(&a),
        Command::Cache(a) => commands::cache::run(&a),
        Command::Dump(a) => commands::dump::run(&a),
        Command::Pack(a) => with_threads(a.threads, || commands::pack::pack(&a)),
        Command::Unpack(a) => commands::pack::unpack(&a),
        Command::Trace(a) => with_threads(a.threads, || commands::trace::run(&a)),
        Command::Rays(a) => commands::rays::run(&a),
        Command::Render(a) => with_threads(a.threads, || commands::render::run(&a)),
        Command::Gen(a) => commands::gen_scene::run(&a),
        Command::Demo(a) => commands::demo::run(&a),
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
