//! The guarantees of `docs/reliability.md` that need the real `vlf-bake` binary:
//!
//! - bad meshes get exactly the error or warning the document's table lists, row by row (the
//!   table is read from the document, so it cannot go stale), and every fixture in
//!   `fixtures/meshes/bad/` has a row;
//! - `dump --verify` names the damage in a sample of damaged fields;
//! - a bake killed with `SIGKILL` midway leaves the previous field intact and a recognisable
//!   temporary file, which a later bake of the same path removes once its writer is gone;
//! - a bake that fails normally (a bad mesh, the size ceiling, a failing write, an unwritable
//!   directory, a directory as output) leaves the previous field and no temporary file;
//! - a field kept mapped while a bake renames a new one over its path keeps answering as before.

#![forbid(unsafe_code)]

mod common;

use common::{BIN, MESHES, Run, command, mesh, names_in, run, s, tempdir, vlf};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime};
use vlf_geom::{Camera, Hit, Ray};
use vlf_runtime::Field;

const DOC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/reliability.md");

/// `vlf-bake bake INPUT -o OUTPUT --directions 33 --tiles 16 --quiet EXTRA...`.
fn bake(input: &Path, output: &Path, extra: &[&str]) -> Run {
    run(command()
        .arg("bake")
        .arg(input)
        .arg("-o")
        .arg(output)
        .args(["--directions", "33", "--tiles", "16", "--quiet"])
        .args(extra))
}

/// The temporary files of writes of `dir/NAME`: `.NAME.XXXXXX.tmp`.
fn temp_files(dir: &Path, name: &str) -> Vec<PathBuf> {
    let prefix = format!(".{name}.");
    names_in(dir)
        .into_iter()
        .filter(|n| n.strip_prefix(&prefix).and_then(|r| r.strip_suffix(".tmp")).is_some_and(|r| r.len() == 6))
        .map(|n| dir.join(n))
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Bad meshes: the table in docs/reliability.md

/// One row of the bad-mesh table.
#[derive(Debug)]
struct Row {
    input: String,
    exit: i32,
    stderr: Vec<String>,
}

/// The text inside a Markdown code span (`` `x` `` or ``` `` x `` ```).
fn code_span(cell: &str) -> &str {
    let cell = cell.trim();
    cell.strip_prefix("`` ")
        .and_then(|c| c.strip_suffix(" ``"))
        .or_else(|| cell.strip_prefix('`').and_then(|c| c.strip_suffix('`')))
        .unwrap_or_else(|| panic!("not a code span: {cell:?}"))
}

/// The rows of the table between `<!-- bad-meshes:begin -->` and `<!-- bad-meshes:end -->`.
fn bad_mesh_table() -> Vec<Row> {
    let doc = std::fs::read_to_string(DOC).unwrap();
    let start = doc.find("<!-- bad-meshes:begin -->").expect("the table's begin marker");
    let end = doc.find("<!-- bad-meshes:end -->").expect("the table's end marker");
    let rows: Vec<&str> = doc[start..end].lines().filter(|l| l.starts_with('|')).skip(2).collect();
    rows.iter()
        .map(|line| {
            let cells: Vec<&str> = line.trim().trim_matches('|').split(" | ").collect();
            assert_eq!(cells.len(), 4, "a row needs case | input | exit | standard error: {line}");
            Row {
                input: code_span(cells[1]).to_string(),
                exit: cells[2].trim().parse().unwrap_or_else(|_| panic!("exit code: {line}")),
                stderr: cells[3].split("<br>").map(|s| code_span(s).to_string()).collect(),
            }
        })
        .collect()
}

#[test]
fn bad_meshes_get_exactly_the_errors_and_warnings_the_docs_table_lists() {
    let rows = bad_mesh_table();
    assert!(rows.len() >= 30, "only {} rows", rows.len());
    let dir = tempdir();
    let out = dir.path().join("out.vlf");
    for row in &rows {
        // Paths relative to fixtures/meshes, as the table shows them.
        let r = run(command().current_dir(MESHES).args(["bake", &row.input, "-o"]).arg(&out).args([
            "--directions",
            "3",
            "--tiles",
            "2",
        ]));
        assert_eq!(r.code, row.exit, "{}: exit code\n{}", row.input, r.stderr);
        assert_eq!(r.stderr.lines().collect::<Vec<_>>(), row.stderr, "{}: standard error", row.input);
        if row.exit == 0 {
            Field::open(&out).unwrap();
            std::fs::remove_file(&out).unwrap();
        }
        assert_eq!(names_in(dir.path()), Vec::<String>::new(), "{}: left files behind", row.input);
    }
    // Every bad input the repository ships is in the table.
    for name in names_in(&mesh("bad")) {
        let input = format!("bad/{name}");
        assert!(rows.iter().any(|r| r.input == input), "{input} has no row in docs/reliability.md");
    }
}

/// `--quiet` hides the progress bar and the summary, not warnings: the dropped triangles of the
/// table's rows and a missing material library are still reported, on standard error only.
#[test]
fn quiet_bakes_still_print_their_warnings() {
    let dir = tempdir();
    let out = dir.path().join("out.vlf");
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let missing_mtl = dir.path().join("missing_mtl.obj");
    std::fs::write(&missing_mtl, format!("mtllib missing.mtl\n{triangle}")).unwrap();
    for (input, says) in [
        (mesh("bad/degenerate.obj"), "dropped 2 degenerate (zero-area) triangles"),
        (mesh("bad/degenerate.gltf"), "dropped 2 degenerate (zero-area) triangles"),
        (missing_mtl, "missing.mtl"),
    ] {
        // (`bake` gives --quiet.)
        let r = bake(&input, &out, &[]).ok();
        assert_eq!(r.stdout, "", "`{}`", r.what);
        let lines: Vec<&str> = r.stderr.lines().collect();
        assert!(
            !lines.is_empty() && lines.iter().all(|l| l.starts_with("warning: ")) && r.stderr.contains(says),
            "`{}`: {}",
            r.what,
            r.stderr
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Damaged fields through `dump --verify`

#[test]
fn dump_verify_names_the_damage_in_a_sample_of_damaged_fields() {
    let dir = tempdir();
    let good = dir.path().join("good.vlf");
    run(command().arg("bake").arg(mesh("Box.gltf")).arg("-o").arg(&good).args([
        "--directions",
        "3",
        "--tiles",
        "2",
        "-q",
    ]))
    .ok();
    let verified = vlf(&[OsStr::new("dump"), good.as_os_str(), OsStr::new("--verify")]).ok();
    assert!(verified.stdout.contains("verify: OK"), "{}", verified.stdout);

    let info: serde_json::Value =
        serde_json::from_str(&vlf(&[OsStr::new("dump"), good.as_os_str(), OsStr::new("--json")]).ok().stdout).unwrap();
    let sections: Vec<(String, u64, u64)> = info["sections"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            (
                s["name"].as_str().unwrap().to_string(),
                s["offset"].as_u64().unwrap(),
                s["stored_length"].as_u64().unwrap(),
            )
        })
        .collect();
    let table_end = 128 + 72 * sections.len() as u64;
    let mut cases: Vec<(u64, String)> = vec![
        (1, "bad magic".into()),
        (8, "format version 3.".into()),
        (16, "the file is truncated".into()),
        (40, "`flags` must be zero".into()),
        (60, "content hash mismatch".into()),
        (100, "content hash mismatch".into()),
        (table_end - 30, "content hash mismatch".into()),
    ];
    for (name, offset, len) in &sections {
        cases.push((offset + len / 2, format!("section {name} is corrupt")));
    }
    // A padding byte: the first gap between the table or a section and the next section.
    let mut end = table_end;
    for (_, offset, len) in &sections {
        if *offset > end {
            cases.push((end, format!("padding byte at offset {end} is 0x01")));
            break;
        }
        end = offset + len;
    }
    let bytes = std::fs::read(&good).unwrap();
    let bad = dir.path().join("bad.vlf");
    for (at, phrase) in cases {
        let mut damaged = bytes.clone();
        damaged[at as usize] ^= 0x01;
        std::fs::write(&bad, &damaged).unwrap();
        let r = vlf(&[OsStr::new("dump"), bad.as_os_str(), OsStr::new("--verify")]);
        r.fails_saying(&["bad.vlf", &phrase]);
        assert!(!r.stdout.contains("verify: OK"), "{}", r.stdout);
    }
}

// ---------------------------------------------------------------------------------------------
// Crash safety

/// `vlf-bake gen random --count COUNT -o DIR/random.obj`: the scene's path.
fn random_scene(dir: &Path, count: u32) -> PathBuf {
    let scene = dir.join("random.obj");
    vlf(&["gen", "random", "--count", &count.to_string(), "-o", s(&scene)]).ok();
    scene
}

/// Pretends a file was last modified `age` ago.
fn age(path: &Path, age: Duration) {
    let file = std::fs::File::options().write(true).open(path).unwrap();
    file.set_modified(SystemTime::now() - age).unwrap();
}

#[cfg(unix)]
#[test]
fn a_bake_killed_midway_leaves_the_previous_field_intact_and_its_temporary_file_is_cleaned_up_later() {
    use std::os::unix::process::ExitStatusExt;
    let dir = tempdir();
    let out = dir.path().join("scene.vlf");
    bake(&mesh("bunny.obj"), &out, &[]).ok();
    let previous = std::fs::read(&out).unwrap();

    // A bake that writes a few hundred MiB, killed once its temporary file holds 16 MiB.
    let scene = random_scene(dir.path(), 20000);
    let mut child = command()
        .arg("bake")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["--directions", "513", "--tiles", "64", "--quiet"])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(300);
    let temp = loop {
        if let Some(t) = temp_files(dir.path(), "scene.vlf").pop()
            && std::fs::metadata(&t).map_or(0, |m| m.len()) >= 16 << 20
        {
            break t;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the bake ended ({status}) before it could be killed midway");
        }
        assert!(Instant::now() < deadline, "the bake made no progress");
        std::thread::sleep(Duration::from_millis(2));
    };
    child.kill().unwrap();
    assert_eq!(child.wait().unwrap().signal(), Some(9), "not killed by SIGKILL");

    // The path holds the previous field, byte for byte, and it opens and verifies.
    assert!(std::fs::read(&out).unwrap() == previous, "the previous field changed");
    Field::open(&out).unwrap();
    vlf(&[OsStr::new("dump"), out.as_os_str(), OsStr::new("--verify")]).ok();
    // Left behind: the temporary file, by its name, and nothing else (spill files are anonymous).
    let temp_name = temp.file_name().unwrap().to_str().unwrap().to_string();
    assert_eq!(names_in(dir.path()), [temp_name.as_str(), "random.obj", "scene.vlf"]);

    // A later bake of the same path leaves a leftover younger than a minute alone (its writer may
    // have only just created it)...
    bake(&mesh("Box.gltf"), &out, &[]).ok();
    assert!(temp.exists(), "a young temporary file was removed");
    // ...and removes it once older, because no process holds its lock. Left alone: an old one a
    // live writer holds locked, another path's, and names of another shape.
    let locked = dir.path().join(".scene.vlf.AbC123.tmp");
    let holder = std::fs::File::create(&locked).unwrap();
    rustix::fs::flock(&holder, rustix::fs::FlockOperation::NonBlockingLockExclusive).unwrap();
    let others =
        [".other.vlf.XyZ789.tmp", ".scene.vlf.partial.tmp", "scene.vlf.AbC123.tmp"].map(|n| dir.path().join(n));
    for p in &others {
        std::fs::write(p, b"not mine").unwrap();
    }
    for p in others.iter().chain([&temp, &locked]) {
        age(p, Duration::from_secs(120));
    }
    bake(&mesh("Box.gltf"), &out, &[]).ok();
    assert!(!temp.exists(), "the stale temporary file of the killed bake is still there");
    assert!(locked.exists(), "a locked temporary file (a live writer's) was removed");
    for p in &others {
        assert!(p.exists(), "{} was removed", p.display());
    }
    drop(holder);
}

/// Every normal failure leaves `dir/scene.vlf` as it was and no temporary file.
#[test]
fn failed_bakes_leave_the_previous_field_and_no_temporary_files() {
    let dir = tempdir();
    let out = dir.path().join("scene.vlf");
    bake(&mesh("Box.gltf"), &out, &[]).ok();
    let previous = std::fs::read(&out).unwrap();
    let bunny = mesh("bunny.obj");
    let mut failures = vec![
        ("a bad mesh", bake(&mesh("bad/nan_vertex.obj"), &out, &[]), vec!["nan_vertex.obj", "non-finite"]),
        (
            "a bad mesh after a good one",
            run(command()
                .arg("bake")
                .arg(&bunny)
                .arg(mesh("bad/degenerate.gltf"))
                .arg(mesh("bad/draco.gltf"))
                .arg("-o")
                .arg(&out)),
            vec!["draco.gltf"],
        ),
        // 33 directions × 16² of the bunny take 2.5 MB; the lower bound checked before the bake
        // is 0.8 MB, so the ceiling is found exceeded while the field is being written.
        (
            "the --max-bytes ceiling, exceeded midway",
            bake(&bunny, &out, &["--max-bytes", "1500000"]),
            vec!["--max-bytes ceiling of 1500000 bytes"],
        ),
        ("a directory as the output", bake(&bunny, dir.path(), &[]), vec!["is a directory"]),
    ];
    // A write that fails midway: the file size limit (512-byte blocks in POSIX sh) stops the
    // field at 512 KiB. SIGXFSZ is left at its default action (death), as a shell leaves it: the
    // binary itself must catch it so that the write fails with EFBIG.
    #[cfg(unix)]
    failures.push((
        "a write that fails midway",
        run(Command::new("sh")
            .args(["-c", r#"ulimit -f 1024; exec "$0" "$@""#, BIN, "bake"])
            .arg(&bunny)
            .arg("-o")
            .arg(&out)
            .args(["--directions", "33", "--tiles", "16", "--quiet"])),
        vec!["cannot write", "scene.vlf", "File too large"],
    ));
    for (what, r, phrases) in failures {
        r.fails_saying(&phrases);
        assert!(std::fs::read(&out).unwrap() == previous, "{what}: the previous field changed");
        assert_eq!(names_in(dir.path()), ["scene.vlf"], "{what}: files left behind");
    }
}

/// Every command that writes a file, stopped midway by the file size limit (`ulimit -f`, with
/// SIGXFSZ at its default action, death, as a shell leaves it): one line naming the output and
/// "File too large", exit 1, and no temporary file, not a process killed by SIGXFSZ with its
/// temporary file left behind.
#[cfg(unix)]
#[test]
fn a_write_past_the_file_size_limit_fails_with_one_line_and_leaves_no_temporary_file() {
    let dir = tempdir();
    let field = dir.path().join("scene.vlf");
    bake(&mesh("bunny.obj"), &field, &[]).ok();
    let packed = dir.path().join("packed.vlf");
    vlf(&["pack", s(&field), "-o", s(&packed), "-q"]).ok();
    let rays = dir.path().join("rays.bin");
    vlf(&["rays", s(&field), "-o", s(&rays), "--width", "64", "--height", "64", "-q"]).ok();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let o = |name: &str| out.join(name).to_str().unwrap().to_string();
    let bunny = mesh("bunny.obj");
    // 10 KiB: less than each of these outputs (a 64×64 hits file is 64 KiB). Each fails as it
    // writes, except `trace`, whose output's size follows from its input's: it is refused first.
    let cases: [(Vec<String>, &str); 5] = [
        (
            vec![
                "bake".into(),
                s(&bunny).into(),
                "-o".into(),
                o("b.vlf"),
                "--directions".into(),
                "33".into(),
                "--tiles".into(),
                "16".into(),
            ],
            "b.vlf",
        ),
        (vec!["pack".into(), s(&field).into(), "-o".into(), o("p.vlf")], "out"),
        (vec!["unpack".into(), s(&packed).into(), "-o".into(), o("u.vlf")], "u.vlf"),
        (vec!["trace".into(), s(&field).into(), "--rays".into(), s(&rays).into(), "-o".into(), o("h.bin")], "h.bin"),
        (vec!["render".into(), s(&field).into(), "-o".into(), o("x.png"), "--width".into(), "320".into()], "x.png"),
    ];
    for (args, name) in cases {
        let mut args = args;
        args.push("-q".into());
        let r = common::vlf_with_ulimit("-f 20", &args);
        let why = if args[0] == "trace" { "may not write files over 10.0 KiB (ulimit -f)" } else { "File too large" };
        r.fails_saying(&[why, name]);
        assert_eq!(names_in(&out), Vec::<String>::new(), "`{}` left files behind", r.what);
    }
}

/// The uid this process runs as (the owner of a file it creates).
#[cfg(unix)]
fn my_uid(dir: &Path) -> u32 {
    use std::os::unix::fs::MetadataExt;
    let probe = dir.join("uid-probe");
    std::fs::write(&probe, b"").unwrap();
    let uid = std::fs::metadata(&probe).unwrap().uid();
    std::fs::remove_file(&probe).unwrap();
    uid
}

#[cfg(unix)]
#[test]
fn an_unwritable_output_directory_is_an_error_and_is_left_as_it_was() {
    use std::os::unix::fs::PermissionsExt;
    use std::os::unix::process::CommandExt;
    let dir = tempdir();
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
    let locked = dir.path().join("read-only");
    std::fs::create_dir(&locked).unwrap();
    let out = locked.join("scene.vlf");
    bake(&mesh("Box.gltf"), &out, &[]).ok();
    let previous = std::fs::read(&out).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();

    let mut cmd = command();
    cmd.arg("bake").arg(mesh("bunny.obj")).arg("-o").arg(&out).args(["--directions", "33", "--tiles", "16"]);
    // Root writes anywhere: bake as `nobody` instead.
    if my_uid(dir.path()) == 0 {
        cmd.uid(65534).gid(65534);
    }
    let r = run(&mut cmd);
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
    r.fails_saying(&["cannot write", "scene.vlf", "Permission denied"]);
    assert!(std::fs::read(&out).unwrap() == previous);
    assert_eq!(names_in(&locked), ["scene.vlf"]);
}

// ---------------------------------------------------------------------------------------------
// Inputs that are not regular files

/// Runs `vlf-bake ARGS...` in `dir` with at most 4 GiB of address space, killing it if it has not
/// ended within a minute: a read of `/dev/zero` then fails fast instead of filling the memory of
/// the machine, and a wait on a pipe fails the test instead of hanging it.
#[cfg(unix)]
fn run_bounded(dir: &Path, args: &[&str]) -> Run {
    let what = common::describe(args);
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(r#"ulimit -v 4194304 && exec "$0" "$@""#)
        .arg(BIN)
        .args(args)
        .current_dir(dir)
        .env_remove("RAYON_NUM_THREADS")
        .env_remove("VLF_CACHE_DIR")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(60);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("`{what}` hung (killed after a minute)");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    Run::from_output(what, child.wait_with_output().unwrap())
}

/// Every input a command reads (meshes, OBJ material libraries, external glTF buffers, rays
/// files, scene files and the meshes they insert, fields, shards) must be a regular file: a directory, a pipe or
/// a device is refused at once, in one line naming the path and what it is. Before, `/dev/zero`
/// was read until memory ran out and a pipe was waited on forever.
#[cfg(unix)]
#[test]
fn inputs_that_are_not_regular_files_are_refused_by_what_they_are() {
    let dir = tempdir();
    let d = dir.path();
    bake(&mesh("bunny.obj"), &d.join("f.vlf"), &[]).ok();
    vlf(&["rays", s(&d.join("f.vlf")), "-o", s(&d.join("r.bin")), "--width", "8", "--height", "8", "-q"]).ok();
    assert!(Command::new("mkfifo").arg(d.join("pipe.obj")).status().unwrap().success());
    std::fs::create_dir(d.join("dir.obj")).unwrap();
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::fs::write(d.join("zero_mtl.obj"), format!("mtllib /dev/zero\n{triangle}")).unwrap();
    std::fs::write(d.join("pipe_mtl.obj"), format!("mtllib pipe.obj\n{triangle}")).unwrap();
    std::fs::write(d.join("missing_mtl.obj"), format!("mtllib missing.mtl\n{triangle}")).unwrap();
    let gltf = |uri: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"uri":"{uri}","byteLength":36}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],"accessors":[{{"bufferView":0,"componentType":5126,
            "count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],"meshes":[{{"primitives":[{{"attributes":
            {{"POSITION":0}}}}]}}],"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#
        )
    };
    std::fs::write(d.join("zero_uri.gltf"), gltf("file:///dev/zero")).unwrap();
    std::fs::write(d.join("zero_path.gltf"), gltf("/dev/zero")).unwrap();
    std::fs::write(d.join("s.json"), r#"{"instances":[{"field":"f.vlf","insert":[{"mesh":"/dev/zero"}]}]}"#).unwrap();
    let dev = "it is a character device, not a regular file";
    let fifo = "it is a pipe (FIFO), not a regular file";
    let hits = ["-o", "h.bin"];
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (vec!["bake", "pipe.obj", "-o", "o.vlf"], vec!["cannot read pipe.obj: ", fifo]),
        (vec!["bake", "/dev/zero", "-o", "o.vlf"], vec!["cannot read /dev/zero: ", dev]),
        (vec!["bake", "dir.obj", "-o", "o.vlf"], vec!["cannot read dir.obj: it is a directory, not a regular file"]),
        (vec!["bake", "zero_mtl.obj", "-o", "o.vlf"], vec!["zero_mtl.obj", "material library \"/dev/zero\"", dev]),
        (vec!["bake", "pipe_mtl.obj", "-o", "o.vlf"], vec!["pipe_mtl.obj", "material library \"pipe.obj\"", fifo]),
        (vec!["bake", "zero_uri.gltf", "-o", "o.vlf"], vec!["zero_uri.gltf", "buffer 0", "(/dev/zero)", dev]),
        (vec!["bake", "zero_path.gltf", "-o", "o.vlf"], vec!["zero_path.gltf", "buffer 0", "(/dev/zero)", dev]),
        ([&["trace", "f.vlf", "--rays", "/dev/zero"][..], &hits].concat(), vec!["rays file /dev/zero: ", dev]),
        ([&["trace", "f.vlf", "--rays", "pipe.obj"][..], &hits].concat(), vec!["rays file pipe.obj: ", fifo]),
        (
            [&["trace", "--scene", "/dev/zero", "--rays", "r.bin"][..], &hits].concat(),
            vec!["scene file /dev/zero: ", dev],
        ),
        (
            [&["trace", "--scene", "s.json", "--rays", "r.bin"][..], &hits].concat(),
            vec!["s.json", "instance 0", "insert", "/dev/zero: ", dev],
        ),
        (
            [&["trace", "--scene", "pipe.obj", "--rays", "r.bin"][..], &hits].concat(),
            vec!["scene file pipe.obj: ", fifo],
        ),
        (vec!["merge", "pipe.obj", "-o", "o.vlf"], vec!["cannot read pipe.obj: ", fifo]),
        // In the command line's words: not the library's advice to open the bytes with from_bytes.
        (
            vec!["dump", "pipe.obj"],
            vec!["cannot read field pipe.obj: ", fifo, "cannot be mapped: copy it to a file first"],
        ),
        (vec!["dump", "/dev/zero"], vec!["cannot read field /dev/zero: ", dev, "copy it to a file first"]),
    ];
    for (args, phrases) in cases {
        let args = [&args[..], &["--directions", "3", "--tiles", "2"][..]].concat();
        let args = if args[0] == "bake" { args } else { args[..args.len() - 4].to_vec() };
        run_bounded(d, &args).fails_saying(&phrases);
        assert!(!d.join("o.vlf").exists() && !d.join("h.bin").exists(), "{args:?} wrote an output");
    }
    // An external buffer is read up to its byteLength, however long its file: here 36 bytes of a
    // 16 GiB sparse file, which the 4 GiB of address space could not hold.
    let big = std::fs::File::create(d.join("big.bin")).unwrap();
    let triangle: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.].iter().flat_map(|c| c.to_le_bytes()).collect();
    std::io::Write::write_all(&mut &big, &triangle).unwrap();
    big.set_len(16 << 30).unwrap();
    std::fs::write(d.join("big.gltf"), gltf("big.bin")).unwrap();
    run_bounded(d, &["bake", "big.gltf", "-o", "o.vlf", "--directions", "3", "--tiles", "2", "-q"]).ok();
    std::fs::remove_file(d.join("o.vlf")).unwrap();
    // A missing material library stays a warning: the mesh bakes without its materials.
    let r = run_bounded(d, &["bake", "missing_mtl.obj", "-o", "o.vlf", "--directions", "3", "--tiles", "2"]).ok();
    assert!(r.stderr.contains("material library \"missing.mtl\": cannot read it"), "{}", r.stderr);
}

// ---------------------------------------------------------------------------------------------
// A field kept mapped while a bake replaces it

fn answers(field: &Field, rays: &[Ray]) -> Vec<Option<[u32; 4]>> {
    let bits = |h: Hit| [h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()];
    rays.iter().map(|r| field.closest_hit(r).map(bits)).collect()
}

#[test]
fn a_mapped_field_keeps_answering_as_before_while_a_bake_renames_a_new_one_over_it() {
    let dir = tempdir();
    let out = dir.path().join("scene.vlf");
    bake(&mesh("bunny.obj"), &out, &[]).ok();
    let old = Field::open(&out).unwrap();
    let old_hash = old.content_hash();
    let (c, r) = old.bounding_sphere();
    let mut rays = Camera::outside(c, r, 1.0).primary_rays(48, 48);
    rays.extend(Camera::inside(c, r, 1.0).primary_rays(48, 48));
    let before = answers(&old, &rays);
    assert!(before.iter().filter(|h| h.is_some()).count() > 1000);

    // Another scene is baked over the path while this process keeps querying the old mapping.
    let scene = random_scene(dir.path(), 5000);
    let mut child = command()
        .arg("bake")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["--directions", "129", "--tiles", "32", "--quiet"])
        .stdin(Stdio::null())
        .spawn()
        .unwrap();
    let mut during = 0;
    let status = loop {
        assert!(answers(&old, &rays) == before, "the mapped field answered differently during the bake");
        during += 1;
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
    };
    assert!(status.success(), "{status}");
    assert!(answers(&old, &rays) == before, "the mapped field answered differently after the rename");
    assert_eq!(old.content_hash(), old_hash);
    println!("{during} frames traced on the old field while the new one was baked");

    // Opening the path again gives the new field.
    let new = Field::open(&out).unwrap();
    assert_ne!(new.content_hash(), old_hash);
    assert_eq!(new.triangle_count(), 5000);
    assert_eq!(names_in(dir.path()), ["random.obj", "scene.vlf"]);
}
