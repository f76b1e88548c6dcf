//! What the tests of the `vlf-bake` binary share: running it as a user would ([`vlf`], [`run`],
//! [`spawn`]), what a finished run printed ([`Run`], with the assertions every test makes), and
//! the fixtures.
//!
//! Every run goes through [`Run::from_output`], which asserts that the process was not killed by a
//! signal, that its output is UTF-8 and that nothing it printed contains "panicked". Commands are
//! independent of the caller's environment: no `RAYON_NUM_THREADS`, no `VLF_CACHE_DIR`, and an
//! empty standard input.

// Each test crate uses its own subset of these helpers.
#![allow(dead_code)]

use serde_json::Value;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

/// The binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_vlf-bake");
/// The meshes of `fixtures/meshes/`.
pub const MESHES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/meshes/");
/// The repository's `docs/`.
pub const DOCS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/");

/// Small explicit parameters: 33 directions × 16² tiles.
pub const SMALL: [&str; 4] = ["--directions", "33", "--tiles", "16"];

/// A mesh of `fixtures/meshes/`.
pub fn mesh(name: &str) -> PathBuf {
    Path::new(MESHES).join(name)
}

pub fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().expect("create a temporary directory")
}

/// A path as a string argument (temporary directories and fixtures have UTF-8 paths).
pub fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// The names in a directory, sorted.
pub fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// What a finished `vlf-bake` process printed, and its exit code.
#[derive(Debug)]
pub struct Run {
    pub what: String,
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

impl Run {
    /// The run of `what` that ended with `out`; fails the test if it was killed by a signal, if
    /// its output is not UTF-8 or if it panicked.
    pub fn from_output(what: String, out: Output) -> Run {
        let stdout = String::from_utf8(out.stdout).expect("stdout is UTF-8");
        let stderr = String::from_utf8(out.stderr).expect("stderr is UTF-8");
        let Some(code) = out.status.code() else {
            panic!("`{what}` was killed by a signal ({})\nstdout: {stdout}\nstderr: {stderr}", out.status)
        };
        assert!(
            !stdout.contains("panicked") && !stderr.contains("panicked"),
            "`{what}` panicked (exit code {code}):\nstdout: {stdout}\nstderr: {stderr}"
        );
        Run { what, code, stdout, stderr }
    }

    /// Asserts exit code 0 and returns the run.
    pub fn ok(self) -> Run {
        assert_eq!(self.code, 0, "`{}` failed:\nstdout: {}\nstderr: {}", self.what, self.stdout, self.stderr);
        self
    }

    /// Asserts exit code `code` and returns the run.
    pub fn fails_with(self, code: i32) -> Run {
        assert_eq!(
            self.code, code,
            "`{}`: wrong exit code\nstdout: {}\nstderr: {}",
            self.what, self.stdout, self.stderr
        );
        self
    }

    /// Asserts exit code 1 with exactly one line on standard error, starting with `error:`, and
    /// returns that line.
    pub fn one_error_line(&self) -> &str {
        assert_eq!(
            self.code, 1,
            "`{}`: expected exit code 1\nstdout: {}\nstderr: {}",
            self.what, self.stdout, self.stderr
        );
        let lines: Vec<&str> = self.stderr.lines().collect();
        assert_eq!(lines.len(), 1, "`{}`: expected exactly one line on stderr, got:\n{}", self.what, self.stderr);
        assert!(
            lines[0].starts_with("error: "),
            "`{}`: the error line does not start with `error:`: {}",
            self.what,
            lines[0]
        );
        lines[0]
    }

    /// Asserts exit code 1 and one `error:` line on standard error that contains every phrase,
    /// and returns that line.
    pub fn fails_saying(&self, phrases: &[&str]) -> &str {
        let line = self.one_error_line();
        for phrase in phrases {
            assert!(line.contains(phrase), "`{}`: the error does not say `{phrase}`: {line}", self.what);
        }
        line
    }

    /// Standard output as one JSON value.
    pub fn json(&self) -> Value {
        serde_json::from_str(&self.stdout)
            .unwrap_or_else(|e| panic!("`{}`: stdout is not one JSON value ({e}):\n{}", self.what, self.stdout))
    }
}

/// `vlf-bake ARGS...` as text, for messages.
pub fn describe<S: AsRef<OsStr>>(args: impl IntoIterator<Item = S>) -> String {
    std::iter::once("vlf-bake".to_string())
        .chain(args.into_iter().map(|a| a.as_ref().to_string_lossy().into_owned()))
        .collect::<Vec<_>>()
        .join(" ")
}

/// A `vlf-bake` command independent of the caller's environment (threads, cache, input).
pub fn command() -> Command {
    let mut cmd = Command::new(BIN);
    cmd.env_remove("RAYON_NUM_THREADS").env_remove("VLF_CACHE_DIR").stdin(Stdio::null());
    cmd
}

/// Runs a prepared command to completion.
pub fn run(cmd: &mut Command) -> Run {
    let what = describe(cmd.get_args());
    let out = cmd.stdin(Stdio::null()).output().unwrap_or_else(|e| panic!("cannot run `{what}`: {e}"));
    Run::from_output(what, out)
}

/// Runs `vlf-bake ARGS...`.
pub fn vlf<S: AsRef<OsStr>>(args: &[S]) -> Run {
    run(command().args(args))
}

/// Starts `vlf-bake ARGS...` without waiting, its output captured.
pub fn spawn<S: AsRef<OsStr>>(args: &[S]) -> (String, Child) {
    let child = command().args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("spawn vlf-bake");
    (describe(args), child)
}

/// Waits for a process [`spawn`] started.
pub fn wait((what, child): (String, Child)) -> Run {
    Run::from_output(what, child.wait_with_output().expect("wait for vlf-bake"))
}

/// The temporary files of atomic writes in `dir` (`.NAME.XXXXXX.tmp`), by name.
pub fn temp_files_in(dir: &Path) -> Vec<String> {
    names_in(dir).into_iter().filter(|n| n.starts_with('.') && n.ends_with(".tmp")).collect()
}

/// Runs `vlf-bake ARGS...` through `sh -c 'ulimit LIMIT && exec ...'`: with a resource limit
/// (`-f BLOCKS`: file size; `-v KB`: address space) set in the process before it starts.
pub fn vlf_with_ulimit<S: AsRef<OsStr>>(limit: &str, args: &[S]) -> Run {
    let mut sh = Command::new("sh");
    sh.arg("-c").arg(format!("ulimit {limit} && exec \"$0\" \"$@\"")).arg(BIN).args(args);
    sh.env_remove("RAYON_NUM_THREADS").env_remove("VLF_CACHE_DIR");
    let what = format!("ulimit {limit}; {}", describe(args));
    let out = sh.stdin(Stdio::null()).output().unwrap_or_else(|e| panic!("cannot run `{what}`: {e}"));
    Run::from_output(what, out)
}

/// The bytes free for an unprivileged writer on the file system of `dir`, and its size.
#[cfg(unix)]
pub fn disk_space(dir: &Path) -> (u64, u64) {
    let s = rustix::fs::statvfs(dir).expect("statvfs");
    (s.f_bavail * s.f_frsize, s.f_blocks * s.f_frsize)
}

/// `MemAvailable` of `/proc/meminfo`, in bytes.
pub fn memory_available() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    line["MemAvailable:".len()..].trim().trim_end_matches("kB").trim().parse::<u64>().ok().map(|kb| kb * 1024)
}
