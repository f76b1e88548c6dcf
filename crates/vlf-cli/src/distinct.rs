//! Outputs that would overwrite an input or another output: `bake t.obj -o t.obj`, `trace f.vlf
//! --rays r.bin -o r.bin`, `render f.vlf -o p.png --work-image p.png`. Each is a bad command line
//! ([`BadUsage`], exit 2), found before any work starts: the atomic write would otherwise replace
//! the input with the output (or one output with another) and report success.
//!
//! Two paths are the same file if both name one existing regular file (the same device and inode
//! on Unix, however they are spelled: `./x`, a symbolic link, a hard link), or if neither exists
//! and they are the same path once made absolute, with `.` and `..` resolved and the directory's
//! symbolic links followed. Devices, pipes and directories are not compared: `/dev/null` may take
//! two outputs, and an input that is not a regular file is refused by its reader.

use crate::values::BadUsage;
use std::path::{Component, Path, PathBuf};

/// What a path names, for comparison.
#[derive(PartialEq, Eq)]
enum Identity {
    /// An existing regular file: its device and inode (Unix), or its canonical path.
    File(u64, u64, PathBuf),
    /// A path where nothing exists yet, normalised.
    Absent(PathBuf),
}

/// The identity of `path`, or `None` for something that is not data an output can destroy (a
/// device, a pipe, a directory).
fn identity(path: &Path) -> Option<Identity> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => {
            #[cfg(unix)]
            {
                use std::os::unix::fs::MetadataExt;
                Some(Identity::File(meta.dev(), meta.ino(), PathBuf::new()))
            }
            #[cfg(not(unix))]
            {
                let _ = meta;
                Some(Identity::File(0, 0, std::fs::canonicalize(path).unwrap_or_else(|_| normalised(path))))
            }
        }
        Ok(_) => None,
        Err(_) => Some(Identity::Absent(normalised(path))),
    }
}

/// `path` made absolute, `.` and `..` resolved, and its directory's links followed where it exists.
fn normalised(path: &Path) -> PathBuf {
    let absolute = std::env::current_dir().map(|d| d.join(path)).unwrap_or_else(|_| path.to_path_buf());
    let mut out = PathBuf::new();
    for c in absolute.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    match (out.parent().map(std::fs::canonicalize), out.file_name()) {
        (Some(Ok(dir)), Some(name)) => dir.join(name),
        _ => out,
    }
}

/// How a command writes its outputs, for [`check_outputs`].
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Writes {
    /// Files only: fields, shards and reports, made whole in a temporary file and renamed into
    /// place. An existing device or FIFO is refused.
    Files,
    /// Streams, written through an existing device or FIFO (`-o /dev/null`, a named pipe) and
    /// atomically to any other path: pictures, rays, hits, OBJ.
    Through,
}

/// Refuses an output that is the same file as one of `inputs` or as an earlier output (a
/// [`BadUsage`]); each path comes with the name of its flag or argument (`-o/--output`, `--rays`,
/// `INPUT`). Then refuses an output whose directory cannot take a new file
/// ([`crate::limits::check_writable`]) and, for [`Writes::Files`], an output that exists and is
/// not a regular file ([`crate::limits::check_regular_outputs`]): all before the work, so that no
/// command works for minutes, or writes one output, only to fail on another.
pub fn check_outputs(inputs: &[(&str, &Path)], outputs: &[(&str, &Path)], writes: Writes) -> anyhow::Result<()> {
    check_distinct(inputs, outputs)?;
    if writes == Writes::Files {
        crate::limits::check_regular_outputs(outputs)?;
    }
    crate::limits::check_writable(outputs)
}

/// The first half of [`check_outputs`].
fn check_distinct(inputs: &[(&str, &Path)], raw_outputs: &[(&str, &Path)]) -> Result<(), BadUsage> {
    // A flag is named with its path (`--rays r.bin`); an argument by its path alone (`t.obj`).
    let named = |list: &[(&str, &Path)]| -> Vec<(String, Option<Identity>)> {
        list.iter()
            .map(|(flag, p)| {
                let name =
                    if flag.starts_with('-') { format!("{flag} {}", p.display()) } else { p.display().to_string() };
                (name, identity(p))
            })
            .collect()
    };
    let (inputs, outputs) = (named(inputs), named(raw_outputs));
    for (k, ((name, id), (flag, _))) in outputs.iter().zip(raw_outputs).enumerate() {
        let Some(id) = id else { continue };
        let earlier = inputs.iter().map(|i| (i, "the input")).chain(outputs[..k].iter().map(|o| (o, "the output")));
        for ((other, other_id), role) in earlier {
            if other_id.as_ref() == Some(id) {
                return Err(BadUsage(format!(
                    "{name} is the same file as {role} {other}: writing it would destroy {role}; give {flag} another path"
                )));
            }
        }
    }
    Ok(())
}
