//! Issue 11, item 4: Ctrl-C (SIGINT), SIGTERM or SIGHUP while a command writes leaves no temporary
//! file. The real binary is interrupted midway through a bake and through a streamed `gen`, and must
//! exit 130, 143 or 129 with one line on standard error, remove its temporary file, and leave the previous
//! output byte for byte. (SIGKILL, which nothing can catch, is `reliability.rs`'s.)

#![cfg(unix)]
#![forbid(unsafe_code)]

mod common;

use common::{Run, command, names_in, s, temp_files_in, tempdir, vlf};
use rustix::process::{Pid, Signal, kill_process};
use std::path::Path;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

/// Waits until `dir` holds a temporary file of at least `bytes` bytes, then sends `signal` to
/// `child` and waits for it.
fn interrupt_once_writing(what: &str, mut child: Child, dir: &Path, bytes: u64, signal: Signal) -> Run {
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        let big = temp_files_in(dir).iter().any(|n| std::fs::metadata(dir.join(n)).is_ok_and(|m| m.len() >= bytes));
        if big {
            break;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("`{what}` ended ({status}) before it could be interrupted");
        }
        assert!(Instant::now() < deadline, "`{what}` wrote no temporary file");
        std::thread::sleep(Duration::from_millis(2));
    }
    let pid = Pid::from_raw(child.id() as i32).expect("a process id");
    kill_process(pid, signal).expect("send the signal");
    Run::from_output(what.to_owned(), child.wait_with_output().expect("wait"))
}

/// Asserts the exit code and the one line of an interrupted run that had one temporary file.
fn assert_interrupted(r: &Run, code: i32, signal: &str, dir: &Path) {
    assert_eq!(r.code, code, "`{}`: exit code\n{}", r.what, r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "`{}`: one line on standard error:\n{}", r.what, r.stderr);
    let prefix = format!("error: interrupted by {signal}; removed the temporary file {}/.", dir.display());
    assert!(lines[0].starts_with(&prefix), "`{}`: {}", r.what, lines[0]);
    assert!(lines[0].ends_with(".tmp; the outputs keep their previous contents"), "`{}`: {}", r.what, lines[0]);
    assert_eq!(temp_files_in(dir), Vec::<String>::new(), "`{}` left a temporary file", r.what);
}

#[test]
fn ctrl_c_or_sigterm_during_a_bake_removes_its_temporary_file_and_keeps_the_previous_field() {
    let dir = tempdir();
    let out = dir.path().join("scene.vlf");
    vlf(&["bake", s(&common::mesh("bunny.obj")), "-o", s(&out), "--directions", "33", "--tiles", "16", "-q"]).ok();
    let previous = std::fs::read(&out).unwrap();
    // A bake of several seconds: 20,000 random triangles at 513 directions × 64² tiles.
    let scene = dir.path().join("random.obj");
    vlf(&["gen", "random", "--count", "20000", "-q", "-o", s(&scene)]).ok();
    for (signal, name, code) in [(Signal::INT, "SIGINT", 130), (Signal::TERM, "SIGTERM", 143)] {
        let args = ["bake", s(&scene), "-o", s(&out), "--directions", "513", "--tiles", "64", "-q"];
        let child = command().args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        let r = interrupt_once_writing(&common::describe(args), child, dir.path(), 1, signal);
        assert_interrupted(&r, code, name, dir.path());
        assert_eq!(r.stdout, "");
        assert!(std::fs::read(&out).unwrap() == previous, "{name}: the previous field changed");
        assert_eq!(names_in(dir.path()), ["random.obj", "scene.vlf"]);
    }
    vlf(&["dump", s(&out), "--verify"]).ok();
}

#[test]
fn ctrl_c_or_sigterm_during_gen_removes_its_temporary_file_and_keeps_the_previous_scene() {
    let dir = tempdir();
    let out = dir.path().join("big.obj");
    vlf(&["gen", "random", "--count", "10", "-q", "-o", s(&out)]).ok();
    let previous = std::fs::read(&out).unwrap();
    // SIGHUP (the terminal closed) goes the way of SIGTERM.
    for (signal, name, code) in
        [(Signal::TERM, "SIGTERM", 143), (Signal::INT, "SIGINT", 130), (Signal::HUP, "SIGHUP", 129)]
    {
        // Five million triangles stream out for seconds; interrupted after the first MiB.
        let args = ["gen", "random", "--count", "5000000", "-o", s(&out)];
        let child = command().args(args).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        let r = interrupt_once_writing(&common::describe(args), child, dir.path(), 1 << 20, signal);
        assert_interrupted(&r, code, name, dir.path());
        assert_eq!(std::fs::read(&out).unwrap(), previous, "{name}: the previous scene changed");
        assert_eq!(names_in(dir.path()), ["big.obj"]);
    }
}
