//! The subcommands: one module each (`pack` holds `pack` and `unpack`), each with the one
//! function `main` calls for it, which turns the arguments into the libraries' terms, calls them
//! once, and prints what they return.

pub mod bake;
pub mod cache;
pub mod demo;
pub mod dump;
pub mod gen_scene;
pub mod merge;
pub mod pack;
pub mod picture;
pub mod rays;
pub mod render;
pub mod scene;
pub mod trace;

use crate::args::CacheChoice;
use anyhow::{Result, anyhow};
use std::io::Write;
use std::path::Path;
use vlf_bake::cache::Cache;
use vlf_bake::params::human_bytes;
use vlf_runtime::{Field, FormatError, OpenError, OpenOptions};

/// Prints one line (or several joined by newlines) on standard output and flushes it, so that a
/// closed pipe is reported here (and `main` treats it as success).
pub fn stdout_line(s: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{s}")?;
    out.flush()?;
    Ok(())
}

/// Opens the field at `path` for the commands that query or describe it, with the command line's
/// words for two faults the library names for programs:
///
/// - a packed field is decoded into memory, so it is held to the memory budget of every up-front
///   check (`vlf_bake::memory::budget`): a few hundred kilobytes of zstd frames can claim
///   gigabytes, refused before anything is allocated, naming `vlf-bake unpack`, which decodes to
///   disk;
/// - a pipe or a device cannot be mapped: the library's message advises reading the bytes into
///   memory and opening them with `from_bytes`, a remedy for a program, not for someone at a
///   shell.
pub fn open_field(path: &Path) -> Result<Field> {
    let (budget, why) = vlf_bake::memory::budget();
    OpenOptions::new().max_unpacked_bytes(budget).open(path).map_err(|e| {
        if let OpenError::Format { error: FormatError::UnpackedTooLarge { bytes, .. }, path } = &e {
            return anyhow!(
                "cannot open {}: it is a packed field that unpacks to {} in memory, but {} may be used ({why}); \
                 `vlf-bake unpack` decodes it to a file instead",
                path.display(),
                human_bytes(*bytes),
                human_bytes(budget)
            );
        }
        let special = match (&e, std::fs::metadata(path)) {
            (OpenError::Io { .. }, Ok(meta)) if !meta.is_dir() => vlf_runtime::regular::check_regular_file(&meta).err(),
            _ => None,
        };
        match special {
            Some(why) => {
                anyhow!("cannot read field {}: {why}, which cannot be mapped: copy it to a file first", path.display())
            }
            None => e.into(),
        }
    })
}

/// The cache to use for `--cache-dir` / `--no-cache` / `VLF_CACHE_DIR`, or why there is none. A
/// cache directory that cannot be created is not an error (a cache only ever saves time): the bake
/// goes on without it, with a warning (printed under `--quiet` too, as every warning is).
pub fn resolve_cache(choice: &CacheChoice) -> (Option<Cache>, Option<String>) {
    match vlf_bake::cache::resolve(choice.cache_dir.clone(), choice.no_cache, "--no-cache", "--cache-dir") {
        Ok(Ok(cache)) => (Some(cache), None),
        Ok(Err(note)) => {
            eprintln!("warning: {note}");
            (None, Some(note))
        }
        Err(note) => (None, Some(note)),
    }
}
