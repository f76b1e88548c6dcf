//! `vlf-bake`: bake triangle meshes into visibility-field files, inspect and verify them, trace
//! batches of rays against them and render pictures of them. A thin layer over the `vlf_bake`,
//! `vlf_runtime` and `vlf_render` libraries: [`args`] parses, one function per subcommand in
//! [`commands`] calls the libraries and prints.
//!
//! Exit codes: 0 success; 1 the command failed (one line on standard error says why); 2 the
//! command line was invalid (a value out of range included); 130, 143 and 129 interrupted by
//! SIGINT, SIGTERM and SIGHUP, after removing every temporary file ([`stop`]). A write past the
//! file size limit (`ulimit -f`) is an ordinary failure, exit 1, not death by SIGXFSZ. A closed
//! output pipe (`vlf-bake dump f | head`) counts as success. With `--json`, a failure (exit 1)
//! also prints one JSON object on standard output, `{"error": "<the line of standard error>"}`,
//! so that a tool reading the output always reads JSON.

#![forbid(unsafe_code)]

mod args;
mod commands;
mod distinct;
mod limits;
mod progress;
mod stop;
mod threads;
mod values;

use anyhow::Result;
use args::{Cli, Command};
use clap::{CommandFactory, FromArgMatches};
use std::process::ExitCode;
use values::BadUsage;

fn main() -> ExitCode {
    if let Err(e) = stop::install() {
        eprintln!("error: cannot install the handler of SIGINT, SIGTERM, SIGHUP and SIGXFSZ: {e}");
        return ExitCode::FAILURE;
    }
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.format(&mut Cli::command()).exit());
    // `bake`, or `cache prune`: a bad command line found later is printed with its usage.
    let mut path = Vec::new();
    let mut m = &matches;
    while let Some((name, sub)) = m.subcommand() {
        path.push(name.to_owned());
        m = sub;
    }
    let json = cli.command.json();
    let result = run(cli);
    // A signal or a failed worker is being handled: that thread ends the process.
    stop::wait_if_stopping();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => match e.downcast_ref::<BadUsage>() {
            Some(BadUsage(message)) => {
                let error = clap::Error::raw(clap::error::ErrorKind::ValueValidation, message);
                let mut cli = Cli::command();
                cli.build();
                let _ = error.format(subcommand(&mut cli, &path)).print();
                ExitCode::from(2)
            }
            None => {
                eprintln!("error: {e:#}");
                if json {
                    // Best effort: the failure is already on standard error and in the exit code.
                    let _ = commands::stdout_line(&serde_json::json!({ "error": format!("{e:#}") }).to_string());
                }
                ExitCode::FAILURE
            }
        },
    }
}

/// The subcommand of `cmd` at `path` (`["cache", "prune"]`), or `cmd` itself for an empty path.
fn subcommand<'a>(cmd: &'a mut clap::Command, path: &[String]) -> &'a mut clap::Command {
    let Some((name, rest)) = path.split_first() else { return cmd };
    if cmd.find_subcommand(name).is_none() {
        return cmd;
    }
    subcommand(cmd.find_subcommand_mut(name).expect("found above"), rest)
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}

/// One library call per subcommand, each on a pool of worker threads.
fn run(cli: Cli) -> Result<()> {
    use threads::with_threads;
    match cli.command {
        Command::Bake(a) => with_threads(a.threads, || commands::bake::run(&a)),
        Command::Merge(a) => with_threads(None, || commands::merge::run(&a)),
        Command::Cache(a) => with_threads(None, || commands::cache::run(&a)),
        Command::Dump(a) => with_threads(None, || commands::dump::run(&a)),
        Command::Pack(a) => with_threads(a.threads, || commands::pack::pack(&a)),
        Command::Unpack(a) => with_threads(None, || commands::pack::unpack(&a)),
        Command::Trace(a) => with_threads(a.threads, || commands::trace::run(&a)),
        Command::Rays(a) => commands::rays::run(&a),
        Command::Render(a) => with_threads(a.threads, || commands::render::run(&a)),
        Command::Gen(a) => commands::gen_scene::run(&a),
        Command::Demo(a) => with_threads(None, || commands::demo::run(&a)),
    }
}
