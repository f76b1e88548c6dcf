//! Issue 11, items 7 and 8: the default camera frames the whole scene, one size flag keeps the
//! aspect ratio, impossible cameras and picture names are refused; and every command follows one
//! convention for exit codes, range messages, flag names, help and summaries.

#![forbid(unsafe_code)]

mod common;

use common::{Run, mesh, names_in, s, temp_files_in, tempdir, vlf};
use std::path::{Path, PathBuf};

/// Writes a closed box from `lo` to `hi` (12 triangles) as OBJ and bakes it with small
/// parameters; returns the field.
fn box_field(dir: &Path, name: &str, lo: [f32; 3], hi: [f32; 3]) -> PathBuf {
    let obj = dir.join(format!("{name}.obj"));
    let mut file = std::fs::File::create(&obj).unwrap();
    vlf_bake::generate::write_obj(&mut file, name, &vlf_bake::generate::closed_box(lo, hi)).unwrap();
    let field = dir.join(format!("{name}.vlf"));
    vlf(&["bake", s(&obj), "-o", s(&field), "--directions", "33", "--tiles", "16", "-q"]).ok();
    field
}

/// Writes the rays of `rays ARGS` and traces them: one hit flag per pixel, row by row.
fn hit_mask(dir: &Path, field: &Path, args: &[&str]) -> Vec<bool> {
    let (rays, hits) = (dir.join("mask.rays"), dir.join("mask.hits"));
    vlf(&[&["rays", s(field), "-q", "-o", s(&rays)], args].concat()).ok();
    vlf(&["trace", s(field), "--rays", s(&rays), "-o", s(&hits), "-q"]).ok();
    let bytes = std::fs::read(&hits).unwrap();
    bytes.chunks_exact(16).map(|h| u32::from_le_bytes(h[4..8].try_into().unwrap()) != u32::MAX).collect()
}

/// Asserts a bad command line: exit 2 and clap's shape, the first line being `error: LINE`.
fn bad_usage(r: Run, line: &str) {
    let r = r.fails_with(2);
    assert_eq!(r.stderr.lines().next(), Some(format!("error: {line}").as_str()), "`{}`:\n{}", r.what, r.stderr);
    assert!(r.stderr.contains("For more information, try '--help'."), "`{}`:\n{}", r.what, r.stderr);
    assert_eq!(r.stdout, "");
}

// ---------------------------------------------------------------------------------------------
// Item 7: the default camera

#[test]
fn a_long_thin_scene_is_seen_by_the_default_camera() {
    let dir = tempdir();
    let rod = box_field(dir.path(), "rod", [-500.0, -0.5, -0.5], [500.0, 0.5, 0.5]);
    // The issue: `rays --view outside` hit 11 of 262,144 rays. Now, seen end on: two thirds.
    let mask = hit_mask(dir.path(), &rod, &["--view", "outside"]);
    assert_eq!(mask.len(), 640 * 480);
    let hits = mask.iter().filter(|&&h| h).count();
    assert!(hits * 2 > mask.len(), "{hits} of {} outside rays hit the rod", mask.len());
    // ...and the picture is not empty: on black, most pixels are lit.
    let png = dir.path().join("rod.png");
    let args = ["render", s(&rod), "-o", s(&png), "--width", "64", "--samples", "1", "--background", "0,0,0", "-q"];
    vlf(&args).ok();
    let (w, h, rgb) = vlf_render::decode_png(&std::fs::read(&png).unwrap()).unwrap();
    assert_eq!((w, h), (64, 48));
    let lit = rgb.chunks_exact(3).filter(|p| p.iter().any(|&c| c > 0)).count();
    assert!(lit * 2 > (w * h) as usize, "{lit} of {} pixels show the rod", w * h);
}

#[test]
fn a_wide_scene_is_framed_whole_in_tall_and_wide_pictures() {
    let dir = tempdir();
    let wide = box_field(dir.path(), "wide", [-10.0, -1.0, -1.0], [10.0, 1.0, 1.0]);
    for (width, height) in [(100usize, 300usize), (300, 100), (120, 90)] {
        let mask = hit_mask(dir.path(), &wide, &["--width", &width.to_string(), "--height", &height.to_string()]);
        let at = |x: usize, y: usize| mask[y * width + x];
        // Not cropped: no pixel on the picture's edge sees the scene.
        let edge =
            (0..width).any(|x| at(x, 0) || at(x, height - 1)) || (0..height).any(|y| at(0, y) || at(width - 1, y));
        assert!(!edge, "{width}×{height}: the scene touches the picture's edge");
        // Framed closely: it comes within a tenth of the picture's size of an edge (the camera looks
        // at the box's centre, so perspective may leave more room on the opposite side).
        let columns: Vec<usize> = (0..width).filter(|&x| (0..height).any(|y| at(x, y))).collect();
        let rows: Vec<usize> = (0..height).filter(|&y| (0..width).any(|x| at(x, y))).collect();
        let near = |v: &[usize], n: usize| {
            v.first().is_some_and(|&a| a < n / 10) || v.last().is_some_and(|&b| b >= n - n / 10)
        };
        assert!(near(&columns, width) || near(&rows, height), "{width}×{height}: the scene is framed loosely");
    }
}

#[test]
fn one_size_flag_keeps_four_to_three_for_rays_and_render() {
    let dir = tempdir();
    let field = box_field(dir.path(), "cube", [-1.0; 3], [1.0; 3]);
    let rays = dir.path().join("r.bin");
    for (flags, width, height) in [
        (&[][..], 640, 480),
        (&["--width", "800"][..], 800, 600),
        (&["--height", "300"][..], 400, 300),
        (&["--width", "30", "--height", "70"][..], 30, 70),
    ] {
        let j = vlf(&[&["rays", s(&field), "-o", s(&rays), "--json"], flags].concat()).ok().json();
        assert_eq!((j["width"].as_u64(), j["height"].as_u64()), (Some(width), Some(height)), "rays {flags:?}: {j}");
        assert_eq!(std::fs::metadata(&rays).unwrap().len(), width * height * 32);
        assert_eq!(j["bytes"].as_u64(), Some(width * height * 32));
        // render, at a tenth of the size for speed.
        let small: Vec<String> =
            flags.iter().map(|f| f.parse::<u64>().map_or(f.to_string(), |n| (n / 10).to_string())).collect();
        let small: Vec<&str> = small.iter().map(String::as_str).collect();
        let png = dir.path().join("p.png");
        let base = ["render", s(&field), "-o", s(&png), "--samples", "1", "--json"];
        let j = vlf(&[&base[..], &small].concat()).ok().json();
        let expected = if flags.is_empty() { (640, 480) } else { (width / 10, height / 10) };
        assert_eq!((j["width"].as_u64().unwrap(), j["height"].as_u64().unwrap()), expected, "render {small:?}: {j}");
    }
}

#[test]
fn impossible_cameras_and_picture_names_are_refused() {
    let dir = tempdir();
    let field = box_field(dir.path(), "cube", [-1.0; 3], [1.0; 3]);
    let png = dir.path().join("p.png");
    let render = |flags: &[&str]| vlf(&[&["render", s(&field), "-o", s(&png)][..], flags].concat());
    bad_usage(
        render(&["--up", "0,0,0"]),
        "invalid value '0,0,0' for '--up <X,Y,Z>': `0,0,0` is the zero vector, which points nowhere: give an up \
         direction such as 0,1,0",
    );
    bad_usage(
        render(&["--eye", "0,5,0", "--target", "0,0,0", "--up", "0,1,0"]),
        "--up 0,1,0 is along the line of sight from --eye to the target, so it gives the picture no up: give a \
         direction across it",
    );
    bad_usage(
        render(&["--eye", "0,-5,0", "--up", "0,2,0"]),
        "--up 0,2,0 is along the line of sight from --eye to the target, so it gives the picture no up: give a \
         direction across it",
    );
    // An eye whose line of sight overflows or underflows is named for that, not for its up.
    bad_usage(
        render(&["--eye", "1e308,0,0"]),
        "--eye 1e308,0.0,0.0 is too far from the target for double precision (their distance is inf): no line of \
         sight can be aimed; place them between about 1e-150 and 1e150 apart",
    );
    bad_usage(
        render(&["--eye", "1e-300,0,0", "--target", "0,0,0"]),
        "--eye 1e-300,0.0,0.0 is too close to the target for double precision (their distance is 0e0): no line \
         of sight can be aimed; place them between about 1e-150 and 1e150 apart",
    );
    for (flag, name) in [("-o", "x.jpg"), ("--output", "picture"), ("--work-image", "work.jpeg")] {
        let path = dir.path().join(name);
        let output = if flag == "--work-image" { s(&png) } else { s(&path) };
        let args = ["render", s(&field), flag, s(&path), "-o", output];
        let args = if flag == "--work-image" { &args[..] } else { &args[..4] };
        let r = vlf(args).fails_with(2);
        assert!(r.stderr.contains("does not end in .png: render writes PNG pictures only"), "{}", r.stderr);
    }
    assert_eq!(names_in(dir.path()), ["cube.obj", "cube.vlf"], "something was written");
}

// ---------------------------------------------------------------------------------------------
// Item 8: one convention

#[test]
fn out_of_range_values_are_bad_command_lines_with_one_message() {
    let dir = tempdir();
    let field = box_field(dir.path(), "cube", [-1.0; 3], [1.0; 3]);
    let bunny = mesh("bunny.obj");
    let out = dir.path().join("out.vlf");
    let png = dir.path().join("out.png");
    let bake = ["bake", s(&bunny), "-o", s(&out)];
    let render = ["render", s(&field), "-o", s(&png)];
    let rays = ["rays", s(&field), "-o", s(&png)];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        // The commands and their spellings.
        ([&bake[..], &["--tiles", "0"]].concat(), "--tiles must be between 1 and 65536, got 0"),
        ([&bake[..], &["--tiles", "-5"]].concat(), "--tiles must be between 1 and 65536, got -5"),
        ([&bake[..], &["--tiles=-5"]].concat(), "--tiles must be between 1 and 65536, got -5"),
        ([&bake[..], &["--tiles", "abc"]].concat(), "--tiles must be between 1 and 65536, got abc"),
        ([&bake[..], &["--tiles", "65537"]].concat(), "--tiles must be between 1 and 65536, got 65537"),
        ([&bake[..], &["--threads", "0"]].concat(), "--threads must be between 1 and 1024, got 0"),
        ([&bake[..], &["--directions", "2"]].concat(), "--directions must be between 3 and 33554433, got 2"),
        ([&bake[..], &["--max-depth", "13"]].concat(), "--max-depth must be between 0 and 12, got 13"),
        ([&bake[..], &["--leaf-size", "0"]].concat(), "--leaf-size must be between 1 and 4294967295, got 0"),
        ([&render[..], &["--samples", "0"]].concat(), "--samples must be between 1 and 16, got 0"),
        ([&render[..], &["--width", "0"]].concat(), "--width must be between 1 and 65535, got 0"),
        ([&render[..], &["--bounces", "65"]].concat(), "--bounces must be between 0 and 64, got 65"),
        ([&render[..], &["--max-depth", "65"]].concat(), "--bounces must be between 0 and 64, got 65"),
        ([&render[..], &["--fov", "180"]].concat(), "--fov must be between 0 (excluded) and 180 (excluded), got 180"),
        ([&render[..], &["--exposure", "0"]].concat(), "--exposure must be between 0 (excluded) and 1000, got 0"),
        ([&render[..], &["--ambient", "-1"]].concat(), "--ambient must be between 0 and 1000, got -1"),
        ([&rays[..], &["--width", "0"]].concat(), "--width must be between 1 and 65535, got 0"),
        (vec!["pack", s(&field), "-o", s(&out), "--level", "20"], "--level must be between 1 and 19, got 20"),
        (
            vec!["trace", s(&field), "--rays", s(&out), "-o", s(&out), "--threads", "x"],
            "--threads must be between 1 and 1024, got x",
        ),
        (vec!["gen", "random", "--count", "-3", "-o", s(&out)], "--count must be between 1 and 4294967295, got -3"),
        // Triangles smaller than f32 resolves near the cube's corners would all be dropped by a bake.
        (
            vec!["gen", "random", "--size", "1e-300", "-o", s(&out)],
            "--size must be between 0.00001 and 1000, got 1e-300",
        ),
        // A grid's range is its own, whichever end the value is off.
        (
            vec!["gen", "grid", "--count", "0", "-o", s(&out)],
            "--count must be between 1 and 23170 for a grid (cells per side: 4 layers of 2 × count² triangles, at \
             most 4294967295), got 0",
        ),
        (
            vec!["gen", "grid", "--count", "many", "-o", s(&out)],
            "--count must be between 1 and 23170 for a grid (cells per side: 4 layers of 2 × count² triangles, at \
             most 4294967295), got many",
        ),
        (
            vec!["cache", "prune", "--cache-dir", s(dir.path()), "--max-age", "-1d"],
            "--max-age must not be negative, got -1d",
        ),
        (
            vec!["cache", "prune", "--cache-dir", s(dir.path()), "--max-age", "99999999999999d"],
            "--max-age 99999999999999d is too large: the longest duration is 11574074074d (999999999993600 seconds, \
             about 31 million years)",
        ),
        // A shard's spelling: a leading `-` is a bad value, not an unknown flag; a count past u32
        // is out of range, not malformed.
        (
            [&bake[..], &["--shard", "-1/2"]].concat(),
            "invalid value '-1/2' for '--shard <K/N>': `-1/2` is not a shard: write K/N, shard K (counted from 0) \
             of N, e.g. 0/4 … 3/4",
        ),
        (
            [&bake[..], &["--shard", "0/4294967296"]].concat(),
            "invalid value '0/4294967296' for '--shard <K/N>': shard count 4294967296 in `0/4294967296` is \
             outside 1..=65536",
        ),
    ];
    for (args, line) in cases {
        bad_usage(vlf(&args), line);
    }
    // Sizes name the flag too.
    let r = vlf(&[&bake[..], &["--max-bytes", "banana"]].concat()).fails_with(2);
    assert!(r.stderr.starts_with("error: --max-bytes must be a size between 1 B and 16 EiB - 1 B"), "{}", r.stderr);
    // ...the whole range they give, in every unit up to EiB: a missing input (exit 1) shows the
    // size was accepted. Past it, a size is too large, not "not a positive size".
    let missing = ["bake", "missing.obj", "-o", s(&out), "--max-bytes"];
    for accepted in ["18446744073709551615", "15EiB", "1e18"] {
        vlf(&[&missing[..], &[accepted]].concat()).one_error_line();
    }
    for large in ["18446744073709551616", "16EiB", "1e30"] {
        let r = vlf(&[&missing[..], &[large]].concat()).fails_with(2);
        let says = format!("got {large}: `{large}` is too large: the largest size is 18446744073709551615 bytes");
        assert!(r.stderr.lines().next().unwrap_or_default().contains(&says), "{}", r.stderr);
    }
    // A duration that is not one says so, naming the forms it may take.
    let r = vlf(&["cache", "prune", "--cache-dir", s(dir.path()), "--max-age", "1e3"]).fails_with(2);
    assert!(
        r.stderr.contains("`1e3` is not a duration: write a number and a unit s, m, h, d or w, such as 30d"),
        "{}",
        r.stderr
    );
    assert_eq!(names_in(dir.path()), ["cube.obj", "cube.vlf"], "something was written");
}

/// Points, lights and colours name the component at fault: one that is a number but not a
/// finite one says so; a colour component outside 0 to 1 is out of range, negative ones included
/// (they used to be taken for flags).
#[test]
fn points_lights_and_colours_name_the_component_at_fault() {
    let dir = tempdir();
    let field = box_field(dir.path(), "cube", [-1.0; 3], [1.0; 3]);
    let png = dir.path().join("out.png");
    let render = ["render", s(&field), "-o", s(&png), "--width", "8"];
    for (extra, says) in [
        (
            ["--light", "0,0,0,1e309"],
            "'--light <X,Y,Z,I>': component 4 of `0,0,0,1e309`, 1e309, is not a finite number",
        ),
        (["--eye", "NaN,0,0"], "'--eye <X,Y,Z>': component 1 of `NaN,0,0`, NaN, is not a finite number"),
        (["--eye", "1,y,0"], "'--eye <X,Y,Z>': component 2 of `1,y,0`, `y`, is not a number"),
        (["--background", "-1,0,0"], "'--background <R,G,B>': component 1 of `-1,0,0`, -1, is outside 0 to 1"),
        (["--background", "2,0,0"], "'--background <R,G,B>': component 1 of `2,0,0`, 2, is outside 0 to 1"),
    ] {
        let r = vlf(&[&render[..], &extra].concat()).fails_with(2);
        let first = r.stderr.lines().next().unwrap_or_default();
        assert!(first.starts_with("error: invalid value") && first.contains(says), "`{}`:\n{}", r.what, r.stderr);
    }
    vlf(&[&render[..], &["--background", "0,0.5,1", "-q"]].concat()).ok();
}

#[test]
fn old_spellings_still_work_as_aliases() {
    let dir = tempdir();
    let field = box_field(dir.path(), "cube", [-1.0; 3], [1.0; 3]);
    let rays = dir.path().join("r.bin");
    vlf(&["rays", s(&field), "--width", "16", "--height", "12", "-q", "-o", s(&rays)]).ok();
    // trace: -o and --output like every other command, --out as before.
    let mut outputs = Vec::new();
    for flag in ["-o", "--output", "--out"] {
        let hits = dir.path().join(format!("hits{flag}.bin"));
        vlf(&["trace", s(&field), "--rays", s(&rays), flag, s(&hits), "-q"]).ok();
        outputs.push(std::fs::read(&hits).unwrap());
    }
    assert!(outputs[0].len() == 16 * 12 * 16 && outputs.iter().all(|o| *o == outputs[0]));
    // render: --bounces, and --max-depth as before.
    let mut pictures = Vec::new();
    for flag in ["--bounces", "--max-depth"] {
        let png = dir.path().join(format!("p{flag}.png"));
        vlf(&["render", s(&field), "-o", s(&png), "--width", "16", "--samples", "1", flag, "0", "-q"]).ok();
        pictures.push(std::fs::read(&png).unwrap());
    }
    assert_eq!(pictures[0], pictures[1]);
    assert_eq!(temp_files_in(dir.path()), Vec::<String>::new());
}

#[test]
fn rays_and_gen_print_one_summary_line_or_json_or_nothing() {
    let dir = tempdir();
    let field = box_field(dir.path(), "cube", [-1.0; 3], [1.0; 3]);
    let rays = dir.path().join("r.bin");
    let r = vlf(&["rays", s(&field), "--width", "8", "--height", "6", "-o", s(&rays)]).ok();
    assert_eq!(r.stdout, format!("wrote 48 rays (8×6, outside view) to {}: 1.5 KiB (1536 bytes)\n", rays.display()));
    assert_eq!(r.stderr, "");
    let j = vlf(&["rays", s(&field), "--view", "inside", "--width", "8", "-o", s(&rays), "--json"]).ok().json();
    assert_eq!(
        j,
        serde_json::json!({"output": s(&rays), "rays": 48, "width": 8, "height": 6, "view": "inside", "bytes": 1536})
    );
    assert_eq!(vlf(&["rays", s(&field), "-q", "-o", s(&rays)]).ok().stdout, "");

    let obj = dir.path().join("g.obj");
    let r = vlf(&["gen", "grid", "--count", "2", "-o", s(&obj)]).ok();
    let bytes = std::fs::metadata(&obj).unwrap().len();
    assert_eq!(
        r.stdout,
        format!(
            "generated 32 grid triangles (seed 1) into {}: {} ({bytes} bytes)\n",
            obj.display(),
            vlf_bake::params::human_bytes(bytes)
        )
    );
    let j = vlf(&["gen", "random", "--count", "7", "--seed", "3", "-o", s(&obj), "--json"]).ok().json();
    let bytes = std::fs::metadata(&obj).unwrap().len();
    assert_eq!(j, serde_json::json!({"output": s(&obj), "scene": "random", "triangles": 7, "seed": 3, "bytes": bytes}));
    assert_eq!(vlf(&["gen", "slivers", "--count", "5", "-q", "-o", s(&obj)]).ok().stdout, "");
}

/// `-h` prints one line per flag: its spelling, then its help. A flag without help text is its
/// spelling alone.
#[test]
fn every_flag_of_every_command_has_help() {
    let commands: [&[&str]; 13] = [
        &[],
        &["bake"],
        &["merge"],
        &["cache"],
        &["cache", "prune"],
        &["dump"],
        &["pack"],
        &["unpack"],
        &["trace"],
        &["rays"],
        &["render"],
        &["gen"],
        &["demo"],
    ];
    for command in commands {
        let r = vlf(&[command, &["-h"]].concat()).ok();
        let mut in_options = false;
        for line in r.stdout.lines() {
            if line.ends_with(':') && !line.starts_with(' ') {
                in_options = line == "Options:" || line == "Arguments:" || line == "Commands:";
                continue;
            }
            if !in_options || line.trim().is_empty() {
                continue;
            }
            // "  -o, --output <FILE>  The rays file ..." : the help follows two spaces; clap's own
            // notes (`[default: 512]`, `[possible values: ...]`) are not help.
            let text = line.trim_start();
            let mut help = text.split_once("  ").map(|(_, h)| h.to_owned()).unwrap_or_default();
            while let Some((start, end)) = help.find('[').zip(help.find(']')).filter(|(a, b)| a < b) {
                help.replace_range(start..=end, "");
            }
            let no_help = help.trim().is_empty();
            assert!(!no_help, "`vlf-bake {} -h`: no help for `{text}`\n{}", command.join(" "), r.stdout);
        }
    }
}

/// An output that is an input or another output would replace it (the atomic write succeeds, and
/// the input is gone): a bad command line naming both flags and paths, before any work. Files
/// are compared by identity, so `./x`, `sub/../x` and a symbolic link are caught too; paths where
/// nothing exists yet, by their normalised spelling.
#[test]
fn an_output_that_is_an_input_or_another_output_is_a_bad_command_line() {
    let dir = tempdir();
    let d = dir.path();
    let in_dir = |args: &[&str]| common::run(common::command().current_dir(d).args(args));
    std::fs::write(d.join("t2.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    box_field(d, "bunny", [-1.0; 3], [1.0; 3]);
    in_dir(&["rays", "bunny.vlf", "-o", "r.bin", "--width", "8", "--height", "8", "-q"]).ok();
    in_dir(&["pack", "bunny.vlf", "-o", "p.vlf", "-q"]).ok();
    for k in 0..2 {
        let shard = format!("{k}/2");
        let out = format!("s{k}.vlfs");
        in_dir(&["bake", "t2.obj", "-o", &out, "--shard", &shard, "--directions", "9", "--tiles", "2", "-q"]).ok();
    }
    std::fs::create_dir(d.join("sub")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("bunny.vlf", d.join("link.vlf")).unwrap();
    let before: Vec<(String, Vec<u8>)> = names_in(d)
        .into_iter()
        .filter(|n| n != "sub")
        .map(|n| (n.clone(), std::fs::read(d.join(&n)).unwrap()))
        .collect();
    let same =
        |a: &str, b: &str, role: &str| format!("{a} is the same file as the {role} {b}: writing it would destroy");
    let mut cases: Vec<(Vec<&str>, String)> = vec![
        (vec!["bake", "t2.obj", "-o", "t2.obj"], same("-o/--output t2.obj", "t2.obj", "input")),
        (
            vec!["trace", "bunny.vlf", "--rays", "r.bin", "-o", "./bunny.vlf"],
            same("-o/--output ./bunny.vlf", "bunny.vlf", "input"),
        ),
        (
            vec!["trace", "bunny.vlf", "--rays", "r.bin", "-o", "r.bin"],
            same("-o/--output r.bin", "--rays r.bin", "input"),
        ),
        (vec!["merge", "s0.vlfs", "s1.vlfs", "-o", "s0.vlfs"], same("-o/--output s0.vlfs", "s0.vlfs", "input")),
        (
            vec!["bake", "t2.obj", "-o", "f.vlf", "--report", "f.vlf"],
            same("--report f.vlf", "-o/--output f.vlf", "output"),
        ),
        (
            vec!["render", "bunny.vlf", "-o", "same.png", "--work-image", "sub/../same.png"],
            same("--work-image sub/../same.png", "-o/--output same.png", "output"),
        ),
        (vec!["pack", "bunny.vlf", "-o", "bunny.vlf"], same("-o/--output bunny.vlf", "bunny.vlf", "input")),
        (vec!["unpack", "p.vlf", "-o", "sub/../p.vlf"], same("-o/--output sub/../p.vlf", "p.vlf", "input")),
        (vec!["rays", "bunny.vlf", "-o", "bunny.vlf"], same("-o/--output bunny.vlf", "bunny.vlf", "input")),
    ];
    #[cfg(unix)]
    cases.push((vec!["pack", "bunny.vlf", "-o", "link.vlf"], same("-o/--output link.vlf", "bunny.vlf", "input")));
    for (args, says) in cases {
        let r = in_dir(&args).fails_with(2);
        let first = r.stderr.lines().next().unwrap_or_default();
        assert!(first.starts_with(&format!("error: {says}")), "`{}`:\n{}", r.what, r.stderr);
        // The usage of the subcommand, not of `vlf-bake <COMMAND>`.
        assert!(r.stderr.contains(&format!("Usage: vlf-bake {} ", args[0])), "`{}`:\n{}", r.what, r.stderr);
        let after: Vec<(String, Vec<u8>)> = names_in(d)
            .into_iter()
            .filter(|n| n != "sub")
            .map(|n| (n.clone(), std::fs::read(d.join(&n)).unwrap()))
            .collect();
        assert!(after == before, "`{}` changed or wrote files", r.what);
    }
    // Two outputs on a device are no loss: both go to /dev/null.
    #[cfg(unix)]
    in_dir(&["render", "bunny.vlf", "-o", "/dev/null", "--work-image", "/dev/null", "--width", "8", "-q"]).ok();
}

/// An output that cannot be written (its directory missing, a directory itself, a file system
/// that takes no new file) fails before the work, naming its flag, and no other output is
/// written: a bake used to import and bake first, and `--report` or `--work-image` into a
/// missing directory failed only after the field or the picture was written.
#[test]
fn an_output_that_cannot_be_written_fails_before_the_work_and_writes_nothing() {
    let dir = tempdir();
    let d = dir.path();
    let in_dir = |args: &[&str]| common::run(common::command().current_dir(d).args(args));
    std::fs::write(d.join("t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    box_field(d, "box", [-1.0; 3], [1.0; 3]);
    in_dir(&["rays", "box.vlf", "-o", "r.bin", "--width", "8", "--height", "8", "-q"]).ok();
    std::fs::create_dir(d.join("sub")).unwrap();
    let before = names_in(d);
    let cases: [(&[&str], &[&str]); 6] = [
        (&["bake", "t.obj", "-o", "nodir/x.vlf"], &["-o/--output nodir/x.vlf", "nodir"]),
        (&["bake", "t.obj", "-o", "sub"], &["-o/--output sub", "is a directory"]),
        (&["bake", "t.obj", "-o", "f.vlf", "--report", "nodir/r.json"], &["--report nodir/r.json"]),
        (&["render", "box.vlf", "-o", "x.png", "--work-image", "nodir/w.png", "--width", "8"], &["--work-image"]),
        (&["trace", "box.vlf", "--rays", "r.bin", "-o", "nodir/h.bin"], &["-o/--output nodir/h.bin"]),
        (&["pack", "box.vlf", "-o", "nodir/p.vlf"], &["-o/--output nodir/p.vlf"]),
    ];
    for (args, says) in cases {
        let r = in_dir(args).fails_with(1);
        r.fails_saying(says);
        assert_eq!(names_in(d), before, "`{}` wrote a file", r.what);
    }
}

/// An output that must be a file (a field, a shard, a report) but is an existing device is
/// refused before any work, naming its flag: `bake -o /dev/null` used to import and choose the
/// parameters first (12 s on a large mesh), and `--report /dev/full` to bake and commit the field
/// before failing on the report. Outputs written through a device (pictures, rays, hits, OBJ) are
/// not refused.
#[cfg(unix)]
#[test]
fn a_file_output_that_is_a_device_is_refused_before_the_work() {
    let dir = tempdir();
    let d = dir.path();
    let in_dir = |args: &[&str]| common::run(common::command().current_dir(d).args(args));
    std::fs::write(d.join("t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    box_field(d, "box", [-1.0; 3], [1.0; 3]);
    in_dir(&["pack", "box.vlf", "-o", "p.vlf", "-q"]).ok();
    let before = names_in(d);
    let device = |flag: &str, path: &str| {
        format!("error: cannot write {flag} {path}: it is a character device, not a regular file")
    };
    let cases: [(&[&str], String); 7] = [
        (&["bake", "t.obj", "-o", "/dev/null"], device("-o/--output", "/dev/null")),
        (&["bake", "t.obj", "-o", "/dev/full", "--shard", "0/2"], device("-o/--output", "/dev/full")),
        (&["bake", "t.obj", "-o", "f.vlf", "--report", "/dev/full"], device("--report", "/dev/full")),
        (&["merge", "box.vlf", "-o", "/dev/null"], device("-o/--output", "/dev/null")),
        (&["merge", "box.vlf", "-o", "f.vlf", "--report", "/dev/full"], device("--report", "/dev/full")),
        (&["pack", "box.vlf", "-o", "/dev/null"], device("-o/--output", "/dev/null")),
        (&["unpack", "p.vlf", "-o", "/dev/null"], device("-o/--output", "/dev/null")),
    ];
    for (args, says) in cases {
        // One line: the automatic choice of parameters was not even announced.
        let r = in_dir(args);
        assert!(r.one_error_line().starts_with(&says), "`{}`:\n{}", r.what, r.stderr);
        assert_eq!(names_in(d), before, "`{}` wrote a file", r.what);
    }
    // Streams still go through a device.
    in_dir(&["gen", "grid", "--count", "2", "-o", "/dev/null", "-q"]).ok();
    in_dir(&["rays", "box.vlf", "-o", "/dev/null", "--width", "8", "--height", "8", "-q"]).ok();
}

/// A directory named on the command line that is missing, or is a file, is named for which.
#[test]
fn directories_that_are_missing_or_files_say_which() {
    let dir = tempdir();
    let d = dir.path();
    let file = d.join("file.txt");
    std::fs::write(&file, "x").unwrap();
    let missing = d.join("nonexist");
    vlf(&["cache", "list", "--cache-dir", s(&missing)])
        .fails_saying(&[&format!("the cache directory {} does not exist", s(&missing))]);
    vlf(&["cache", "list", "--cache-dir", s(&file)])
        .fails_saying(&[&format!("the cache directory {} is not a directory", s(&file))]);
    vlf(&["demo", "--output-dir", s(&file)])
        .fails_saying(&[&format!("--output-dir {} exists and is not a directory", s(&file))]);
    assert_eq!(names_in(d), ["file.txt"]);
}

#[test]
fn a_failure_with_json_prints_its_error_as_one_json_object() {
    let dir = tempdir();
    let field = box_field(dir.path(), "box", [-1.0; 3], [1.0; 3]);
    // A byte flipped in the middle of the file: opening checks the header, --verify the hashes.
    let bad = dir.path().join("bad.vlf");
    let mut bytes = std::fs::read(&field).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    std::fs::write(&bad, &bytes).unwrap();
    let missing = dir.path().join("missing.rays");
    let out = dir.path().join("hits.bin");
    for args in [
        vec!["dump", s(&bad), "--verify", "--json"],
        vec!["dump", "no-such-field.vlf", "--json"],
        vec!["trace", s(&field), "--rays", s(&missing), "-o", s(&out), "--json"],
        vec!["cache", "list", "--cache-dir", s(&field), "--json"],
    ] {
        let r = vlf(&args);
        let line = r.one_error_line().to_owned();
        let j = r.json();
        assert_eq!(j, serde_json::json!({ "error": &line["error: ".len()..] }), "`{}`", r.what);
    }
    // Without --json, standard output stays empty; a bad command line is not JSON either.
    let r = vlf(&["dump", s(&bad), "--verify", "-q"]);
    r.fails_saying(&["failed verification"]);
    assert_eq!(r.stdout, "");
    bad_usage(vlf(&["dump", s(&field), "--json", "--no-such-flag"]), "unexpected argument '--no-such-flag' found");
}
