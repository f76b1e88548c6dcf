//! Issue 11, items 5 and 6: sizes and thread counts beyond what the machine has are refused up
//! front, with one message naming the numbers, and nothing is left behind.
//!
//! No test here allocates, writes or waits for what it guards against: each command is refused
//! before its work (the checks are the point), so the huge outputs never exist.

#![forbid(unsafe_code)]

mod common;

use common::{Run, command, mesh, names_in, run, s, tempdir, vlf, vlf_with_ulimit};
use std::path::{Path, PathBuf};

/// Bakes the bunny with small parameters into `dir/bunny.vlf`.
fn bunny(dir: &Path) -> PathBuf {
    let field = dir.join("bunny.vlf");
    vlf(&["bake", s(&mesh("bunny.obj")), "-o", s(&field), "--directions", "33", "--tiles", "16", "-q"]).ok();
    field
}

/// Asserts a bad command line: exit 2 and clap's shape, the first line being `error: LINE`.
fn bad_usage(r: Run, line: &str) {
    let r = r.fails_with(2);
    assert_eq!(r.stderr.lines().next(), Some(format!("error: {line}").as_str()), "`{}`:\n{}", r.what, r.stderr);
    assert!(r.stderr.contains("For more information, try '--help'."), "`{}`:\n{}", r.what, r.stderr);
    assert_eq!(r.stdout, "");
}

/// `human_bytes` of the library, as the messages print sizes.
fn gib(bytes: u64) -> String {
    vlf_bake::params::human_bytes(bytes)
}

#[test]
fn rays_and_gen_beyond_the_disk_are_refused_before_writing() {
    let dir = tempdir();
    let field = bunny(dir.path());
    let out = dir.path().join("rays.bin");
    let o = s(&out);
    // The issue's command: 10¹⁰ rays (320 GB) do not fit the u32 ray count of a rays file.
    bad_usage(
        vlf(&["rays", s(&field), "--width", "100000", "--height", "100000", "-o", o]),
        "--width must be between 1 and 65535, got 100000",
    );
    bad_usage(
        vlf(&["rays", s(&field), "--height", "70000", "-o", o]),
        "--height must be between 1 and 65535, got 70000",
    );
    // The largest rays file there is: 128 GiB, refused where the disk has less room.
    let (free, size) = common::disk_space(dir.path());
    let needed = 65_535u64 * 65_535 * 32;
    let r = vlf(&["rays", s(&field), "--width", "65535", "--height", "65535", "-o", o]);
    if needed > free {
        let expected = format!(
            "error: the rays file of 65535×65535 rays needs {} but the file system of {} has ",
            gib(needed),
            dir.path().display()
        );
        assert!(r.one_error_line().starts_with(&expected), "{}", r.stderr);
    } else {
        println!("{} free: the 128 GiB rays file fits, so only the file size limit is tested", gib(free));
    }
    // A file size limit (ulimit -f, 512-byte blocks) is a limit too: 640×480 rays are 9.4 MiB.
    let r = vlf_with_ulimit("-f 1000", &["rays", s(&field), "-o", o]);
    assert_eq!(
        r.one_error_line(),
        "error: the rays file of 640×480 rays needs 9.4 MiB but this process may not write files over 500.0 KiB (ulimit -f)"
    );

    // gen: the issue's command overflows a field's triangle count; a grid of 100,000 cells per side
    // would be 8·10¹⁰ triangles.
    let obj = dir.path().join("scene.obj");
    bad_usage(
        vlf(&["gen", "random", "--count", "100000000000", "-o", s(&obj)]),
        "--count must be between 1 and 4294967295, got 100000000000",
    );
    bad_usage(
        vlf(&["gen", "grid", "--count", "100000", "-o", s(&obj)]),
        "--count must be between 1 and 23170 for a grid (cells per side: 4 layers of 2 × count² triangles, at most \
         4294967295), got 100000",
    );
    bad_usage(
        vlf(&["gen", "slivers", "--count", "0", "-o", s(&obj)]),
        "--count must be between 1 and 4294967295, got 0",
    );
    // The largest scenes there are take more than the whole file system: refused, not streamed.
    for (kind, count, triangles) in [("random", "4294967295", 4_294_967_295u64), ("grid", "23170", 4_294_791_200)] {
        let r = vlf(&["gen", kind, "--count", count, "-o", s(&obj)]);
        let line = r.one_error_line();
        let expected = format!("error: an OBJ of {triangles} {kind} triangles needs up to ");
        assert!(line.starts_with(&expected), "{line}");
        let needed =
            vlf_bake::generate::obj_bytes_at_most(kind, triangles, if kind == "grid" { 23170.0 } else { 1.05 });
        assert!(needed > size, "{kind}: {} fits a file system of {}", gib(needed), gib(size));
        assert!(
            line.contains(&format!("{} but the file system of {} has ", gib(needed), dir.path().display())),
            "{line}"
        );
    }
    assert_eq!(names_in(dir.path()), ["bunny.vlf"], "something was written");
}

#[test]
fn a_picture_beyond_the_memory_is_refused_before_rendering() {
    let dir = tempdir();
    let field = bunny(dir.path());
    let png = dir.path().join("big.png");
    // The issue's command, in an address space of 4 GiB: 20000×20000 pixels need about 20 GiB.
    let args = ["render", s(&field), "-o", s(&png), "--width", "20000", "--height", "20000"];
    let r = vlf_with_ulimit("-v 4194304", &args);
    let frame = vlf_render::Frame::bytes(20_000, 20_000);
    let picture = vlf_render::picture_bytes_at_most(20_000, 20_000, false);
    let expected = format!(
        "error: a 20000×20000 picture (frame {}, picture {}) needs {} of memory, but ",
        gib(frame),
        gib(picture),
        gib(frame + picture)
    );
    let line = r.one_error_line();
    assert!(line.starts_with(&expected), "{line}");
    assert!(line.ends_with(" may be used (what the address-space limit of 4.0 GiB (ulimit -v) leaves)"), "{line}");
    // Without a limit, the largest picture (65535² pixels, over 200 GiB with its work picture) is
    // more than this machine has.
    let work = dir.path().join("work.png");
    let args = ["render", s(&field), "-o", s(&png), "--width", "65535", "--height", "65535", "--work-image", s(&work)];
    let needed = vlf_render::Frame::bytes(65_535, 65_535) + vlf_render::picture_bytes_at_most(65_535, 65_535, true);
    let available = common::memory_available().expect("/proc/meminfo");
    let r = vlf(&args);
    assert!(needed > available, "{} needed, {} available", gib(needed), gib(available));
    let line = r.one_error_line();
    assert!(line.starts_with("error: a 65535×65535 picture (frame "), "{line}");
    assert!(
        line.contains(&format!(
            ", picture and work picture {}) needs {} of memory, but ",
            gib(needed - vlf_render::Frame::bytes(65_535, 65_535)),
            gib(needed)
        )),
        "{line}"
    );
    assert!(line.contains(" may be used (three quarters of the "), "{line}");
    assert_eq!(names_in(dir.path()), ["bunny.vlf"], "something was written");
}

#[test]
fn thread_counts_are_refused_above_1024_and_reduced_to_the_cores() {
    let dir = tempdir();
    let out = dir.path().join("out.vlf");
    let bunny = mesh("bunny.obj");
    let bake = |threads: &str| {
        run(command().arg("bake").arg(&bunny).arg("-o").arg(&out).args(["--directions", "33", "--tiles", "16"]).args([
            "--threads",
            threads,
            "-q",
        ]))
    };
    // The issue's commands: 100,000 threads hung the bake, 5,000 made it forty times slower.
    for t in ["100000", "5000", "1025", "0", "-1"] {
        bad_usage(bake(t), &format!("--threads must be between 1 and 1024, got {t}"));
        assert!(!out.exists());
    }
    // Up to 1024 is accepted and reduced to the cores, with one warning line; the field is the same.
    let cores = std::thread::available_parallelism().unwrap().get();
    let reference = dir.path().join("one.vlf");
    vlf(&["bake", s(&bunny), "-o", s(&reference), "--directions", "33", "--tiles", "16", "--threads", "1", "-q"]).ok();
    if cores < 1024 {
        let r = bake("1024").ok();
        assert_eq!(
            r.stderr,
            format!(
                "warning: --threads 1024 is more than the {cores} cores available; using {cores} (more threads than \
                 cores cannot speed up this work)\n"
            )
        );
        assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&reference).unwrap());
        // RAYON_NUM_THREADS gets the same treatment.
        let rays = dir.path().join("rays.bin");
        vlf(&["rays", s(&reference), "--width", "8", "--height", "8", "-q", "-o", s(&rays)]).ok();
        let hits = dir.path().join("hits.bin");
        let args = ["trace", s(&reference), "--rays", s(&rays), "-o", s(&hits), "--json"];
        let r = run(command().env("RAYON_NUM_THREADS", "1024").args(args)).ok();
        assert!(r.stderr.starts_with("warning: RAYON_NUM_THREADS=1024 is more than the "), "{}", r.stderr);
        assert_eq!(r.json()["threads"], cores);
    }
    // ...and the same range: what rayon would silently ignore is a bad command line.
    for bad in ["abc", "-1", "0", "100000"] {
        let r = run(command().env("RAYON_NUM_THREADS", bad).args(["bake", s(&bunny), "-o", s(&out)])).fails_with(2);
        let first = r.stderr.lines().next().unwrap_or_default();
        assert_eq!(first, format!("error: RAYON_NUM_THREADS must be between 1 and 1024, got {bad}"), "{}", r.stderr);
        assert!(r.stderr.contains("Usage: vlf-bake bake "), "{}", r.stderr);
    }
}

/// Starting the workers can fail (here: a cap on the processes of a user, `prlimit --nproc`); so
/// can a thread the bake starts later. Either is one error line and exit 1, never a hang or an
/// abort, and the temporary file is removed. Run as a user id of its own, since root ignores the
/// cap and the cap counts every process of the user.
#[cfg(unix)]
#[test]
fn failing_to_start_a_thread_is_an_error_not_a_hang() {
    use std::os::unix::fs::PermissionsExt;
    use std::os::unix::process::CommandExt;
    if rustix::process::getuid().as_raw() != 0 {
        println!("not root: cannot run as a user of its own; skipped");
        return;
    }
    let dir = tempdir();
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o777)).unwrap();
    let out = dir.path().join("scene.vlf");
    vlf(&["bake", s(&mesh("Box.gltf")), "-o", s(&out), "--directions", "3", "--tiles", "2", "-q"]).ok();
    let previous = std::fs::read(&out).unwrap();
    // 1: no thread at all; 2: the signal thread but no worker; 3: one worker of two; 4: both
    // workers, but not the bake's writer thread.
    for (processes, says) in [
        ("1", "error: cannot install the handler of SIGINT, SIGTERM, SIGHUP and SIGXFSZ: "),
        ("2", "error: cannot start 2 worker threads: "),
        ("3", "error: cannot start 2 worker threads: "),
        ("4", "error: internal error in thread vlf-worker-"),
    ] {
        let mut cmd = std::process::Command::new("prlimit");
        cmd.arg(format!("--nproc={processes}")).arg("--").arg(common::BIN);
        cmd.args([
            "bake",
            s(&mesh("bunny.obj")),
            "-o",
            s(&out),
            "--directions",
            "33",
            "--tiles",
            "16",
            "--threads",
            "2",
        ]);
        cmd.uid(54_321).gid(54_321).env_remove("RAYON_NUM_THREADS");
        let r = run(&mut cmd);
        let line = r.one_error_line();
        assert!(line.starts_with(says), "--nproc={processes}: {line}");
        assert_eq!(std::fs::read(&out).unwrap(), previous, "--nproc={processes}: the field changed");
        assert_eq!(names_in(dir.path()), ["scene.vlf"], "--nproc={processes}: left files behind");
    }
}

#[test]
fn trace_beyond_memory_or_the_disk_is_refused_before_reading_the_rays() {
    let dir = tempdir();
    let field = bunny(dir.path());
    let hits = dir.path().join("hits.bin");
    // A sparse rays file of 2³⁵ rays (1 TiB, no disk used): 2 TiB of memory to trace.
    let huge = dir.path().join("huge.rays");
    std::fs::File::create(&huge).unwrap().set_len(1 << 40).unwrap();
    let r = vlf(&["trace", s(&field), "--rays", s(&huge), "-o", s(&hits)]);
    let expected = format!(
        "error: tracing the 34359738368 rays of {} (64 bytes a ray) needs 2.0 TiB of memory, but ",
        huge.display()
    );
    assert!(r.one_error_line().starts_with(&expected), "{}", r.stderr);
    // The hits file past a file size limit (ulimit -f, 512-byte blocks): 640×480 rays, 4.7 MiB of hits.
    let rays = dir.path().join("rays.bin");
    vlf(&["rays", s(&field), "-q", "-o", s(&rays)]).ok();
    let r = vlf_with_ulimit("-f 5000", &["trace", s(&field), "--rays", s(&rays), "-o", s(&hits)]);
    assert_eq!(
        r.one_error_line(),
        format!(
            "error: the hits file {} of 307200 rays needs 4.7 MiB but this process may not write files over 2.4 MiB (ulimit -f)",
            hits.display()
        )
    );
    assert_eq!(names_in(dir.path()), ["bunny.vlf", "huge.rays", "rays.bin"], "left files behind");
}

// ---------------------------------------------------------------------------------------------
// The limits table of docs/reliability.md

/// The text inside a Markdown code span (`` `x` `` or ``` `` x `` ```).
fn code_span(cell: &str) -> &str {
    let cell = cell.trim();
    cell.strip_prefix("`` ")
        .and_then(|c| c.strip_suffix(" ``"))
        .or_else(|| cell.strip_prefix('`').and_then(|c| c.strip_suffix('`')))
        .unwrap_or_else(|| panic!("not a code span: {cell:?}"))
}

/// Bytes from a size as the messages print it (`741.7 GiB`), rounded down to the tenth.
fn size_of_text(text: &str) -> u64 {
    let (number, unit) = text.split_once(' ').unwrap();
    let scale = match unit {
        "GiB" => 1u64 << 30,
        "TiB" => 1 << 40,
        other => panic!("unit {other}"),
    };
    (number.parse::<f64>().unwrap() * scale as f64) as u64
}

#[test]
fn the_limits_table_is_what_the_commands_do() {
    let doc = std::fs::read_to_string(Path::new(common::DOCS).join("reliability.md")).unwrap();
    let (start, end) = (doc.find("<!-- limits:begin -->").unwrap(), doc.find("<!-- limits:end -->").unwrap());
    let rows: Vec<&str> = doc[start..end].lines().filter(|l| l.starts_with('|')).skip(2).collect();
    assert!(rows.len() >= 20, "only {} rows", rows.len());
    let dir = tempdir();
    let field = bunny(dir.path());
    std::fs::rename(&field, dir.path().join("field.vlf")).unwrap();
    let (free, _) = common::disk_space(dir.path());
    let memory = common::memory_available().unwrap() / 4 * 3;
    for row in rows {
        let cells: Vec<&str> = row.trim().trim_matches('|').split(" | ").collect();
        assert_eq!(cells.len(), 4, "case | command | exit | standard error: {row}");
        let command_line = code_span(cells[1]);
        let exit: i32 = cells[2].trim().parse().unwrap();
        let expected = code_span(cells[3]);
        // A message that goes on with this machine's numbers: run only where the machine has less
        // than the row needs (else the command would do the work for real).
        if let Some(prefix) = expected.strip_suffix('…') {
            let needs =
                prefix.split(" needs ").nth(1).unwrap().trim_start_matches("up to ").trim_start_matches("about ");
            let needed = size_of_text(&needs.split(' ').take(2).collect::<Vec<_>>().join(" "));
            let has = if prefix.contains(" of memory") { memory } else { free };
            if needed <= has {
                println!("skipped, this machine has room: {command_line}");
                continue;
            }
        }
        let mesh = mesh("bunny.obj");
        let args: Vec<&str> = command_line.split(' ').map(|a| if a == "MESH" { s(&mesh) } else { a }).collect();
        let r = run(command().current_dir(dir.path()).args(&args));
        assert_eq!(r.code, exit, "`{command_line}`: exit code\n{}", r.stderr);
        let first = r.stderr.lines().next().unwrap_or("");
        match expected.strip_suffix('…') {
            Some(prefix) => assert!(first.starts_with(prefix), "`{command_line}`:\n{first}\nnot\n{prefix}"),
            None => assert_eq!(first, expected, "`{command_line}`"),
        }
        assert_eq!(names_in(dir.path()), ["field.vlf"], "`{command_line}` left files behind");
    }
}

/// Writes `dir/NAME.gltf` and its buffer `dir/NAME.bin`: `nodes` nodes each instancing one mesh of
/// `primitives` primitives, all reading the same accessors. `sparse` makes the positions 2²⁴ − 1
/// zeros from a sparse accessor of 16 bytes (5,592,405 triangles a primitive, every one of zero
/// area); else they are 256 points of a circle read by a 1,002-index strip (1,000 triangles).
fn expanding_gltf(dir: &Path, name: &str, nodes: usize, primitives: usize, sparse: bool) -> PathBuf {
    let (buffer, accessors, views, mode) = if sparse {
        let mut bin = vec![0u8; 4];
        bin.extend([1.0f32, 2.0, 3.0].iter().flat_map(|c| c.to_le_bytes()));
        let accessors = r#"[{"componentType":5126,"count":16777215,"type":"VEC3","sparse":{"count":1,
            "indices":{"bufferView":0,"componentType":5121},"values":{"bufferView":1}}}]"#;
        (bin, accessors, r#"[{"buffer":0,"byteLength":1},{"buffer":0,"byteOffset":4,"byteLength":12}]"#, 4)
    } else {
        let mut bin: Vec<u8> = (0..256)
            .flat_map(|k| {
                let a = k as f32 * std::f32::consts::TAU / 256.0;
                [a.cos(), a.sin(), 0.0].into_iter().flat_map(f32::to_le_bytes)
            })
            .collect();
        bin.extend((0..1002u32).map(|k| (k % 256) as u8));
        let accessors = r#"[{"bufferView":0,"componentType":5126,"count":256,"type":"VEC3"},
            {"bufferView":1,"componentType":5121,"count":1002,"type":"SCALAR"}]"#;
        (bin, accessors, r#"[{"buffer":0,"byteLength":3072},{"buffer":0,"byteOffset":3072,"byteLength":1002}]"#, 5)
    };
    let indices = if sparse { "" } else { r#","indices":1"# };
    let primitive = format!(r#"{{"attributes":{{"POSITION":0}}{indices},"mode":{mode}}}"#);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],
        "meshes":[{{"primitives":[{}]}}],"accessors":{accessors},"bufferViews":{views},
        "buffers":[{{"uri":"{name}.bin","byteLength":{}}}]}}"#,
        (0..nodes).map(|k| k.to_string()).collect::<Vec<_>>().join(","),
        vec![r#"{"mesh":0}"#; nodes].join(","),
        vec![primitive; primitives].join(","),
        buffer.len()
    );
    std::fs::write(dir.join(format!("{name}.bin")), &buffer).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, json).unwrap();
    path
}

#[test]
fn a_gltf_that_instances_more_triangles_than_fit_is_refused_before_importing() {
    let dir = tempdir();
    let out = dir.path().join("out.vlf");
    // 45 nodes × 40 primitives × 5,592,405 triangles: 10¹⁰ triangles from 4 KB of JSON.
    let huge = expanding_gltf(dir.path(), "huge", 45, 40, true);
    assert!(std::fs::metadata(&huge).unwrap().len() < 8 << 10);
    let start = std::time::Instant::now();
    let r = vlf_with_ulimit("-v 4194304", &["bake", s(&huge), "-o", s(&out), "--directions", "33", "--tiles", "16"]);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert_eq!(
        r.one_error_line(),
        format!(
            "error: {}: its nodes instance 10066329000 triangles, more than 4294967295, the format's limit",
            huge.display()
        )
    );
    assert!(start.elapsed().as_secs() < 10, "refused after {:?}", start.elapsed());
    // The review's case: 1,000 nodes × 100 primitives reuse one 1,000-triangle strip, 10⁸
    // triangles (about 26 GB to import) from 20 KB, in an address space of 4 GiB.
    let many = expanding_gltf(dir.path(), "many", 1000, 100, false);
    assert!(std::fs::metadata(&many).unwrap().len() < 32 << 10);
    let start = std::time::Instant::now();
    let r = vlf_with_ulimit("-v 4194304", &["bake", s(&many), "-o", s(&out), "--directions", "33", "--tiles", "16"]);
    assert_eq!(r.code, 1, "{}", r.stderr);
    let need = gib(100_000_000 * vlf_bake::scene::IMPORT_BYTES_PER_TRIANGLE);
    let expected = format!(
        "error: {}: its nodes instance 100000000 triangles, which need {need} of memory to import, but ",
        many.display()
    );
    let line = r.one_error_line();
    assert!(
        line.starts_with(&expected)
            && line.ends_with(" may be used (what the address-space limit of 4.0 GiB (ulimit -v) leaves)"),
        "{line}"
    );
    assert!(start.elapsed().as_secs() < 10, "refused after {:?}", start.elapsed());
    assert_eq!(names_in(dir.path()), ["huge.bin", "huge.gltf", "many.bin", "many.gltf"], "something was written");
}

#[test]
fn a_scene_that_flattens_past_the_memory_is_refused_before_rendering() {
    let dir = tempdir();
    let field = bunny(dir.path());
    let triangles = vlf_runtime::Field::open(&field).unwrap().triangle_count() as u64;
    let png = dir.path().join("out.png");
    let scene_of = |name: &str, instances: u64| {
        let path = dir.path().join(name);
        let one = r#"{"field":"bunny.vlf"}"#;
        std::fs::write(&path, format!(r#"{{"instances":[{}]}}"#, vec![one; instances as usize].join(","))).unwrap();
        path
    };
    // The review's case, in an address space of 4 GiB: 20,000 bunnies flattened for the renderer
    // are 7·10⁷ triangles, about 12.6 GiB with smoothing.
    let many = scene_of("many.json", 20_000);
    let start = std::time::Instant::now();
    let r = vlf_with_ulimit(
        "-v 4194304",
        &["render", "--scene", s(&many), "-o", s(&png), "--width", "64", "--height", "64"],
    );
    assert_eq!(r.code, 1, "{}", r.stderr);
    let expected = format!(
        "error: scene file {}: its 20000 instances hold {} triangles; copying them to world space for the renderer \
         needs {} of memory, but ",
        many.display(),
        20_000 * triangles,
        gib(20_000 * triangles * 184)
    );
    let line = r.one_error_line();
    assert!(
        line.starts_with(&expected)
            && line.ends_with(" may be used (what the address-space limit of 4.0 GiB (ulimit -v) leaves)"),
        "{line}"
    );
    assert!(start.elapsed().as_secs() < 20, "refused after {:?}", start.elapsed());
    assert_eq!(names_in(dir.path()), ["bunny.vlf", "many.json"], "something was written");
}

/// `packed` with one more section: of kind 99 (unknown: readers skip it), compressed, claiming
/// `claim` decoded bytes from the fewest stored bytes the format allows (garbage: nothing gets to
/// decode it), laid out canonically with a valid content hash.
fn with_unpacking_bomb(packed: &Path, claim: u64) -> PathBuf {
    use vlf_format::pack::{head_bytes, lay_out};
    let bytes = std::fs::read(packed).unwrap();
    let (header, mut table) = vlf_format::parse_head(&bytes, bytes.len() as u64).unwrap();
    let mut sections: Vec<Vec<u8>> =
        table.iter().map(|e| bytes[e.offset as usize..(e.offset + e.stored_length) as usize].to_vec()).collect();
    let stored = claim.div_ceil(vlf_format::MAX_ZSTD_EXPANSION);
    let bomb = vlf_format::SectionEntry {
        kind: 99,
        codec: vlf_format::codec::ZSTD,
        stored_length: stored,
        raw_length: claim,
        element_size: 1,
        raw_hash: [0; 32],
        ..table[0]
    };
    table.push(bomb);
    sections.push(vec![0x5a; stored as usize]);
    let header = lay_out(&header, &mut table).unwrap();
    let mut out = head_bytes(&header, &table);
    for (e, data) in table.iter().zip(&sections) {
        out.resize(e.offset as usize, 0);
        out.extend_from_slice(data);
    }
    let path = packed.with_file_name("bomb.vlf");
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn a_packed_field_that_unpacks_past_the_memory_is_refused_before_decoding() {
    // A few hundred kilobytes of zstd frames may claim tens of gigabytes: an adversarial sweep
    // found `dump`, `trace` and `render` killed at 8 GB on a 674 KB field. Every command that
    // decodes a field in memory holds it to the memory budget first.
    let dir = tempdir();
    let field = bunny(dir.path());
    let packed = dir.path().join("packed.vlf");
    vlf(&["pack", s(&field), "-o", s(&packed), "-q"]).ok();
    let budget = common::memory_available().unwrap() / 4 * 3;
    let claim = 2 * budget;
    let bomb = with_unpacking_bomb(&packed, claim);
    let rays = dir.path().join("rays.bin");
    vlf(&["rays", s(&field), "--width", "4", "--height", "4", "-o", s(&rays)]).ok();
    let png = dir.path().join("out.png");
    let hits = dir.path().join("hits.bin");
    for args in [
        vec!["dump", s(&bomb)],
        vec!["dump", s(&bomb), "--json"],
        vec!["trace", s(&bomb), "--rays", s(&rays), "-o", s(&hits)],
        vec!["render", s(&bomb), "-o", s(&png), "--width", "16", "--height", "16"],
        vec!["rays", s(&bomb), "-o", s(&rays)],
    ] {
        let r = vlf(&args);
        let expected = format!(
            "cannot open {}: it is a packed field that unpacks to {} in memory, but ",
            bomb.display(),
            gib(claim)
        );
        if args.contains(&"--json") {
            let r = r.fails_with(1);
            let j: serde_json::Value = serde_json::from_str(r.stdout.trim()).unwrap();
            assert!(j["error"].as_str().unwrap().starts_with(&expected), "{j}");
            continue;
        }
        let line = r.one_error_line();
        assert!(line.starts_with(&format!("error: {expected}")), "{}: {line}", args[0]);
        assert!(line.ends_with("`vlf-bake unpack` decodes it to a file instead"), "{line}");
    }
    // A scene file's fields are held to the budget (together:
    // `a_scene_files_packed_fields_share_one_memory_budget`).
    let scene = dir.path().join("scene.json");
    std::fs::write(&scene, r#"{"instances": [{"field": "packed.vlf"}, {"field": "bomb.vlf"}]}"#).unwrap();
    let line = vlf(&["trace", "--scene", s(&scene), "--rays", s(&rays), "-o", s(&hits)]).one_error_line().to_string();
    assert!(
        line.contains("instance 1: key \"field\"")
            && line.contains("unpacks to")
            && line.contains("more than the limit"),
        "{line}"
    );
}

#[test]
fn a_scene_files_packed_fields_share_one_memory_budget() {
    // Each packed field of a scene is decoded into memory: held to the budget one by one, a scene
    // of many could claim the budget many times over.
    let dir = tempdir();
    let packed = dir.path().join("a.vlf");
    vlf(&["pack", s(&bunny(dir.path())), "-o", s(&packed), "-q"]).ok();
    std::fs::copy(&packed, dir.path().join("b.vlf")).unwrap();
    let each = vlf_runtime::Field::open(&packed).unwrap().len_bytes();
    let scene = dir.path().join("scene.json");
    // `a.vlf` twice: one field, decoded once, counted once.
    std::fs::write(&scene, r#"{"instances": [{"field": "a.vlf"}, {"field": "a.vlf"}, {"field": "b.vlf"}]}"#).unwrap();
    let no_meshes = |p: &Path| -> Result<Vec<[[f64; 3]; 3]>, String> { panic!("no mesh is inserted: {p:?}") };
    let load = |limit: u64| {
        let file = vlf_scene::SceneFile::read(&scene).unwrap();
        file.load_with(&no_meshes, vlf_runtime::OpenOptions::new().max_unpacked_bytes(limit)).map(|_| ())
    };
    load(2 * each).unwrap();
    let e = load(2 * each - 1).unwrap_err().to_string();
    assert!(
        e.contains("instance 2: key \"field\"")
            && e.contains(&format!("unpacks to {each} bytes, more than the limit of {} bytes", each - 1))
            && e.contains(&format!("opened before it take {each} of the {} bytes allowed", 2 * each - 1)),
        "{e}"
    );
    // One field alone within the limit opens.
    std::fs::write(&scene, r#"{"instances": [{"field": "b.vlf"}]}"#).unwrap();
    load(each).unwrap();
}
