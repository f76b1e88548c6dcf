//! Build-farm features end to end, through the real binary: sharded bakes in separate processes
//! merged into the single bake's bytes, every kind of bad shard set refused by name, concurrent
//! bakes sharing a cache directory, cache hits, `cache list/verify/prune`, and `--report`.
//! (`docs/build-farms.md` describes the features; `formats/vlf-shard.md` the shard files.)

#![forbid(unsafe_code)]

mod common;

use common::{BIN, DOCS, Run, SMALL, command, mesh, names_in, s, spawn, vlf, wait};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use vlf_runtime::{Field, hex};

fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// Bakes shards `0..n` of `inputs` with `params` into `dir/NAME-K.vlfs`, all at once in separate
/// processes, and returns their paths.
fn bake_shards(inputs: &[PathBuf], params: &[&str], n: u32, dir: &Path, name: &str) -> Vec<PathBuf> {
    let paths: Vec<PathBuf> = (0..n).map(|k| dir.join(format!("{name}-{k}.vlfs"))).collect();
    let children: Vec<_> = paths
        .iter()
        .enumerate()
        .map(|(k, path)| {
            let mut args: Vec<String> = vec!["bake".into()];
            args.extend(inputs.iter().map(|p| s(p).to_string()));
            args.extend(["-o".into(), s(path).into(), "--shard".into(), format!("{k}/{n}"), "--quiet".into()]);
            args.extend(params.iter().map(|p| p.to_string()));
            args.extend(["--report".into(), format!("{}.json", s(path))]);
            spawn(&args)
        })
        .collect();
    for child in children {
        wait(child).ok();
    }
    paths
}

fn merge_args(parts: &[&Path], output: &Path) -> Vec<String> {
    let mut args: Vec<String> = vec!["merge".into()];
    args.extend(parts.iter().map(|p| s(p).to_string()));
    args.extend(["-o".into(), s(output).into()]);
    args
}

/// The headline: four shards baked by four processes at once, with automatic parameters (which
/// every shard must choose alike), merge into exactly the bytes of the single bake.
#[test]
fn four_shards_in_four_processes_merge_to_the_single_bake() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let inputs = [mesh("bunny.obj"), mesh("Box.gltf")];
    // Automatic parameters under a small budget: 33 directions × 32² tiles for these inputs.
    let params = ["--max-bytes", "3MB"];
    let single = d.join("single.vlf");
    vlf(&["bake", s(&inputs[0]), s(&inputs[1]), "-o", s(&single), "--quiet", params[0], params[1]]).ok();
    let shards = bake_shards(&inputs, &params, 4, d, "part");

    let mut chosen = Vec::new();
    for (k, shard) in shards.iter().enumerate() {
        let report = read_json(&shard.with_extension("vlfs.json"));
        assert_eq!(report["output"]["kind"], "shard");
        assert_eq!(report["shard"]["index"], k as u64);
        assert_eq!(report["shard"]["count"], 4);
        assert_eq!(report["parameters"]["chosen"]["source"], "automatic");
        chosen.push(report["parameters"]["chosen"].clone());
        // A shard is not a field.
        let err = vlf(&["dump", s(shard)]);
        assert!(err.one_error_line().contains("shard"), "{}", err.stderr);
    }
    assert!(chosen.windows(2).all(|w| w[0] == w[1]), "shards chose different parameters: {chosen:?}");
    let ranges: Vec<(u64, u64)> = shards
        .iter()
        .map(|p| {
            let r = read_json(&p.with_extension("vlfs.json"));
            (r["shard"]["first_direction"].as_u64().unwrap(), r["shard"]["end_direction"].as_u64().unwrap())
        })
        .collect();
    let l = chosen[0]["directions"].as_u64().expect("the chosen direction count");
    let expected: Vec<(u64, u64)> = (0..4).map(|k| (k * l / 4, (k + 1) * l / 4)).collect();
    assert_eq!(ranges, expected, "{l} directions in 4 contiguous shards");

    // Any order of the arguments.
    let merged = d.join("merged.vlf");
    let report = d.join("merge.json");
    let parts = [&shards[2], &shards[0], &shards[3], &shards[1]].map(|p| p.as_path());
    let mut args = merge_args(&parts, &merged);
    args.extend(["--json".into(), "--report".into(), s(&report).into()]);
    let summary = vlf(&args).ok().json();
    let single_bytes = std::fs::read(&single).unwrap();
    assert!(std::fs::read(&merged).unwrap() == single_bytes, "the merged field differs from the single bake");
    let field = Field::open(&merged).unwrap();
    assert_eq!(summary["content_hash"], hex(&field.content_hash()));
    assert_eq!(summary["shards"], 4);
    let report = read_json(&report);
    assert_eq!(report["command"], "merge");
    assert_eq!(report["output"]["content_hash"], hex(&field.content_hash()));
    let parts: Vec<&str> = report["inputs"].as_array().unwrap().iter().map(|i| i["shard"].as_str().unwrap()).collect();
    assert_eq!(parts, ["0/4", "1/4", "2/4", "3/4"]);
    vlf(&["dump", s(&merged), "--verify", "--quiet"]).ok();
}

/// More shards than directions: some shards hold none, and the merge still equals the bake.
#[test]
fn shards_without_directions_merge_too() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let inputs = [mesh("bunny.obj")];
    let params = ["--directions", "3", "--tiles", "8"];
    let single = d.join("single.vlf");
    vlf(&["bake", s(&inputs[0]), "-o", s(&single), "--quiet", params[0], params[1], params[2], params[3]]).ok();
    let shards = bake_shards(&inputs, &params, 5, d, "p");
    let merged = d.join("merged.vlf");
    let parts: Vec<&Path> = shards.iter().map(|p| p.as_path()).collect();
    vlf(&merge_args(&parts, &merged)).ok();
    assert!(std::fs::read(&merged).unwrap() == std::fs::read(&single).unwrap());
}

/// Flips one bit of a copy of `src` at `offset` into `dst`.
fn flipped(src: &Path, dst: &Path, offset: usize) -> PathBuf {
    let mut bytes = std::fs::read(src).unwrap();
    bytes[offset] ^= 0x10;
    std::fs::write(dst, bytes).unwrap();
    dst.to_path_buf()
}

/// Every kind of bad shard set is refused, with one error line naming the offending file(s), and
/// nothing is written.
#[test]
fn bad_shard_sets_are_refused_naming_the_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bunny = [mesh("bunny.obj")];
    let good = bake_shards(&bunny, &SMALL, 4, d, "good");
    let other_inputs = bake_shards(&[mesh("Box.gltf")], &SMALL, 4, d, "box");
    let other_params = bake_shards(&bunny, &["--directions", "33", "--tiles", "8"], 4, d, "tiles8");
    let other_count = bake_shards(&bunny, &SMALL, 3, d, "three");
    let field = d.join("field.vlf");
    vlf(&["bake", s(&bunny[0]), "-o", s(&field), "--quiet", SMALL[0], SMALL[1], SMALL[2], SMALL[3]]).ok();
    let len = std::fs::metadata(&good[1]).unwrap().len() as usize;
    let bulk_flip = flipped(&good[1], &d.join("bulk-flip.vlfs"), len - 100);
    let header_flip = flipped(&good[1], &d.join("header-flip.vlfs"), 20);
    let truncated = d.join("truncated.vlfs");
    std::fs::write(&truncated, &std::fs::read(&good[1]).unwrap()[..len / 2]).unwrap();
    let nope = d.join("nope.vlfs");
    let empty = d.join("empty.vlfs");
    std::fs::write(&empty, b"").unwrap();
    let [g0, g1, g2, g3] = [&good[0], &good[1], &good[2], &good[3]].map(|p| p.as_path());

    let cases: Vec<(&str, Vec<&Path>, Vec<&str>)> = vec![
        ("missing shard", vec![g0, g1, g3], vec!["shard 2/4 is missing", s(g0), s(g1), s(g3)]),
        ("two missing", vec![g3, g0], vec!["shards 1/4, 2/4 are missing"]),
        ("duplicated shard", vec![g0, g1, g2, g3, g2], vec!["shard 2/4 is given twice", s(g2)]),
        ("different inputs", vec![g0, g1, &other_inputs[2], g3], vec![s(&other_inputs[2]), "different inputs"]),
        ("different parameters", vec![g0, g1, &other_params[2], g3], vec![s(&other_params[2]), "different parameters"]),
        ("different count", vec![g0, g1, &other_count[2], g3], vec![s(&other_count[2]), "different splits"]),
        (
            "bit flip in a section",
            vec![g0, &bulk_flip, g2, g3],
            vec![s(&bulk_flip), "corrupt", "does not match its hash"],
        ),
        ("bit flip in the header", vec![g0, &header_flip, g2, g3], vec![s(&header_flip), "corrupt"]),
        ("truncated shard", vec![g0, &truncated, g2, g3], vec![s(&truncated), "truncated"]),
        ("empty file", vec![g0, &empty, g2, g3], vec![s(&empty), "not a VLF shard"]),
        ("a mesh", vec![g0, &bunny[0], g2, g3], vec![s(&bunny[0]), "not a VLF shard"]),
        ("a complete field", vec![g0, &field, g2, g3], vec![s(&field), "a complete field, not a shard"]),
        ("no such file", vec![g0, &nope, g2, g3], vec!["nope.vlfs"]),
    ];
    let out = d.join("out");
    std::fs::create_dir(&out).unwrap();
    let merged = out.join("merged.vlf");
    for (what, parts, expect) in cases {
        let r = vlf(&merge_args(&parts, &merged));
        let line = r.one_error_line();
        for e in expect {
            assert!(line.contains(e), "{what}: the error does not mention {e:?}: {line}");
        }
        assert!(names_in(&out).is_empty(), "{what}: merge left files behind: {:?}", names_in(&out));
    }
    // The good set still merges (nothing above damaged it).
    vlf(&merge_args(&[g3, g2, g1, g0], &merged)).ok();
    assert!(std::fs::read(&merged).unwrap() == std::fs::read(&field).unwrap());
}

/// A flipped bit anywhere in a shard (header, table, every section, padding) is caught by merge.
#[test]
fn a_flipped_bit_anywhere_in_a_shard_is_caught() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let shards = bake_shards(&[mesh("bunny.obj")], &["--directions", "9", "--tiles", "8"], 2, d, "s");
    let bytes = std::fs::read(&shards[1]).unwrap();
    let (_, table) = {
        let head = vlf_format::check_header(&bytes, bytes.len() as u64, &vlf_format::shard::SHARD_MAGIC).unwrap();
        let end = 128 + 72 * head.section_count as usize;
        (head, vlf_format::check_table(&bytes[..end], bytes.len() as u64).unwrap())
    };
    // The header, the table, the middle of every non-empty section, and every stretch of padding.
    let table_end = 128 + 72 * table.len() as u64;
    let mut offsets = vec![9, 100, table_end - 5];
    let mut end = table_end;
    for e in &table {
        if e.offset > end {
            offsets.push(end);
        }
        if e.raw_length > 0 {
            offsets.push(e.offset + e.raw_length / 2);
        }
        end = e.offset + e.raw_length;
    }
    assert!(offsets.len() > table.len() + 3, "the shard has padding to test");
    let merged = d.join("merged.vlf");
    for offset in offsets {
        let bad = flipped(&shards[1], &d.join("bad.vlfs"), offset as usize);
        let r = vlf(&merge_args(&[&shards[0], &bad], &merged));
        assert!(r.one_error_line().contains(s(&bad)), "flip at {offset}: {}", r.stderr);
        assert!(!merged.exists());
    }
}

/// Bakes with the cache in `cache` and a report, returning the report.
fn cached_bake(input: &Path, output: &Path, cache: &Path, extra: &[&str]) -> Value {
    let report = output.with_extension("json");
    let mut args = vec!["bake", s(input), "-o", s(output), "--cache-dir", s(cache), "--report", s(&report), "--quiet"];
    args.extend(SMALL);
    args.extend(extra);
    vlf(&args).ok();
    read_json(&report)
}

/// Two bakes of the same inputs at once against one cache directory both succeed with the same
/// bytes; the cache then holds one entry, and the next bake is a hit with the same bytes again.
#[test]
fn concurrent_bakes_share_a_cache_and_the_next_one_hits() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    let input = mesh("bunny.obj");
    let plain = d.join("plain.vlf");
    vlf(&["bake", s(&input), "-o", s(&plain), "--quiet", "--no-cache", SMALL[0], SMALL[1], SMALL[2], SMALL[3]]).ok();
    let outputs: Vec<PathBuf> = (0..3).map(|i| d.join(format!("concurrent-{i}.vlf"))).collect();
    let children: Vec<_> = outputs
        .iter()
        .map(|o| {
            let mut args = vec!["bake", s(&input), "-o", s(o), "--cache-dir", s(&cache), "--quiet"];
            args.extend(SMALL);
            spawn(&args)
        })
        .collect();
    for c in children {
        wait(c).ok();
    }
    let expected = std::fs::read(&plain).unwrap();
    for o in &outputs {
        assert!(std::fs::read(o).unwrap() == expected, "{} differs from the uncached bake", o.display());
    }
    let entries = names_in(&cache.join("v1"));
    assert_eq!(entries.len(), 1, "one entry and no temporary files: {entries:?}");

    let report = cached_bake(&input, &d.join("hit.vlf"), &cache, &[]);
    assert_eq!(report["cache"]["status"], "hit");
    assert_eq!(report["cache"]["stored"], false);
    assert_eq!(format!("{}.vlf", report["cache"]["key"].as_str().unwrap()), entries[0]);
    assert!(std::fs::read(d.join("hit.vlf")).unwrap() == expected);
    let phases: Vec<&str> = report["phases"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(phases, ["import", "prepare", "cache_key", "cache_lookup"], "a hit bakes nothing");

    // VLF_CACHE_DIR is the default; --no-cache turns it off.
    let env_run = command()
        .args(["bake", s(&input), "-o", s(&d.join("env.vlf")), "--json"])
        .args(SMALL)
        .env("VLF_CACHE_DIR", &cache)
        .output()
        .unwrap();
    assert_eq!(Run::from_output("bake with VLF_CACHE_DIR".into(), env_run).ok().json()["cache"], "hit");
    let off = command()
        .args(["bake", s(&input), "-o", s(&d.join("off.vlf")), "--json", "--no-cache"])
        .args(SMALL)
        .env("VLF_CACHE_DIR", &cache)
        .output()
        .unwrap();
    assert_eq!(Run::from_output("bake --no-cache".into(), off).ok().json()["cache"], "disabled");
}

/// The key changes with anything that changes the output, and a hit is only ever the same bytes.
#[test]
fn the_cache_key_follows_the_inputs_and_the_request() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    let input = d.join("scene.obj");
    std::fs::copy(mesh("bunny.obj"), &input).unwrap();
    let first = cached_bake(&input, &d.join("a.vlf"), &cache, &[]);
    let other_request = cached_bake(&input, &d.join("b.vlf"), &cache, &["--leaf-size", "8"]);
    assert_eq!(other_request["cache"]["status"], "miss");
    assert_ne!(first["cache"]["key"], other_request["cache"]["key"]);
    // The same triangles from a file with other bytes (a comment) are other inputs: the field
    // records the file's hash.
    let mut text = std::fs::read(&input).unwrap();
    text.extend_from_slice(b"\n# edited\n");
    std::fs::write(&input, text).unwrap();
    let edited = cached_bake(&input, &d.join("c.vlf"), &cache, &[]);
    assert_eq!(edited["cache"]["status"], "miss");
    assert_ne!(first["cache"]["key"], edited["cache"]["key"]);
    assert_eq!(names_in(&cache.join("v1")).len(), 3);
}

/// A damaged entry is caught: at a hit (the header and table, and every section's hash), which
/// removes it and bakes again, and by `cache verify`, which removes it.
#[test]
fn damaged_cache_entries_are_caught_and_removed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    let input = mesh("bunny.obj");
    let report = cached_bake(&input, &d.join("a.vlf"), &cache, &[]);
    let entry = cache.join("v1").join(format!("{}.vlf", report["cache"]["key"].as_str().unwrap()));
    let good = std::fs::read(&entry).unwrap();

    // Header damage: the hit's checks refuse the entry, the bake proceeds and stores a new one.
    flipped(&entry, &entry, 60);
    let rebaked = d.join("b.vlf");
    let mut args = vec!["bake", s(&input), "-o", s(&rebaked), "--cache-dir", s(&cache)];
    args.extend(SMALL);
    let r = vlf(&args).ok();
    assert!(r.stderr.contains("warning: cache entry") && r.stderr.contains("was removed"), "{}", r.stderr);
    assert!(std::fs::read(&rebaked).unwrap() == good);
    assert!(std::fs::read(&entry).unwrap() == good, "the entry was stored again");

    // Damage inside a section, where the open checks do not look: the hit hashes every section,
    // so the damaged bytes never reach the output.
    for (offset, output) in [(good.len() - 200, "c.vlf"), (good.len() / 2, "d.vlf")] {
        flipped(&entry, &entry, offset);
        let output = d.join(output);
        let mut args = vec!["bake", s(&input), "-o", s(&output), "--cache-dir", s(&cache)];
        args.extend(SMALL);
        let r = vlf(&args).ok();
        assert!(r.stderr.contains("was removed") && r.stderr.contains("is corrupt"), "{}", r.stderr);
        assert!(std::fs::read(&output).unwrap() == good, "flipped byte {offset} reached the output");
        assert!(std::fs::read(&entry).unwrap() == good, "the entry was stored again");
    }

    // `cache verify` hashes every byte (and checks every offset and index) of every entry.
    vlf(&["cache", "verify", "--cache-dir", s(&cache)]).ok();
    flipped(&entry, &entry, good.len() - 200);
    let r = vlf(&["cache", "verify", "--cache-dir", s(&cache)]);
    assert!(r.one_error_line().contains("1 of 1 cache entries failed verification"), "{}", r.stderr);
    assert!(r.stdout.contains("removed"), "{}", r.stdout);
    assert!(!entry.exists());

    // A cache that cannot be used only costs the time it would have saved.
    let not_a_dir = d.join("file");
    std::fs::write(&not_a_dir, b"").unwrap();
    let report = cached_bake(&input, &d.join("e.vlf"), &not_a_dir.join("cache"), &[]);
    assert_eq!(report["cache"]["status"], "disabled");
    assert!(report["cache"]["note"].as_str().unwrap().contains("cannot create the cache directory"), "{report}");
    assert!(std::fs::read(d.join("e.vlf")).unwrap() == good);
}

/// `cache list` shows the entries; `cache prune` removes by age and then least recently used
/// first by size, and stale temporary files.
#[test]
fn cache_list_and_prune() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    let input = mesh("bunny.obj");
    let keys: Vec<String> = ["4", "8", "16"]
        .iter()
        .map(|leaf| {
            let r = cached_bake(&input, &d.join(format!("leaf{leaf}.vlf")), &cache, &["--leaf-size", leaf]);
            r["cache"]["key"].as_str().unwrap().to_string()
        })
        .collect();
    let path = |k: &str| cache.join("v1").join(format!("{k}.vlf"));
    let day = std::time::Duration::from_secs(86400);
    let now = std::time::SystemTime::now();
    // Ages: 10 days, 2 days, 1 day; then a hit makes the oldest the most recently used.
    for (key, days) in keys.iter().zip([10u32, 2, 1]) {
        std::fs::File::options().write(true).open(path(key)).unwrap().set_modified(now - day * days).unwrap();
    }
    cached_bake(&input, &d.join("again.vlf"), &cache, &["--leaf-size", "4"]);
    let stale = cache.join("v1").join(format!(".{}.vlf.abc123.tmp", keys[0]));
    std::fs::write(&stale, b"left by a crash").unwrap();
    std::fs::File::options().write(true).open(&stale).unwrap().set_modified(now - day).unwrap();

    let list = vlf(&["cache", "list", "--cache-dir", s(&cache), "--json"]).ok().json();
    let listed: Vec<&str> = list.as_array().unwrap().iter().map(|e| e["key"].as_str().unwrap()).collect();
    assert_eq!(listed, [&keys[0], &keys[2], &keys[1]], "most recently used first");
    assert!(list[0]["triangles"].as_u64() == Some(3674) && list[0]["inputs"][0] == "bunny.obj", "{list}");

    let size = |k: &str| std::fs::metadata(path(k)).unwrap().len();
    let pruned = vlf(&["cache", "prune", "--cache-dir", s(&cache), "--max-age", "36h", "--json"]).ok().json();
    assert_eq!(pruned["removed"], serde_json::json!([keys[1]]));
    assert_eq!(pruned["stale_temp_files"], 1);
    assert!(!stale.exists());
    // Room for one of the two left: the least recently used goes.
    let max_size = (size(&keys[0]) + size(&keys[2]) - 1).to_string();
    let pruned = vlf(&["cache", "prune", "--cache-dir", s(&cache), "--max-size", &max_size, "--json"]).ok().json();
    assert_eq!(pruned["removed"], serde_json::json!([keys[2]]), "the least recently used goes");
    assert_eq!(names_in(&cache.join("v1")), [format!("{}.vlf", keys[0])]);
    // Neither limit is a bad command line (exit 2), as is no cache directory at all.
    let r = vlf(&["cache", "prune", "--cache-dir", s(&cache)]).fails_with(2);
    assert!(r.stderr.starts_with("error: the following required arguments were not provided"), "{}", r.stderr);
    assert!(r.stderr.contains("--max-size <SIZE>|--max-age <DURATION>"), "{}", r.stderr);
    for action in ["list", "verify", "prune --max-age 1d"] {
        let args: Vec<&str> = ["cache"].into_iter().chain(action.split(' ')).collect();
        let r = vlf(&args).fails_with(2);
        let first = r.stderr.lines().next().unwrap_or_default();
        assert_eq!(first, "error: no cache directory: pass --cache-dir DIR or set VLF_CACHE_DIR", "{}", r.stderr);
    }
}

/// A farm's merged field goes into the cache, where a later plain bake of the same inputs finds it.
#[test]
fn merge_stores_the_field_a_later_bake_hits() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    let input = mesh("bunny.obj");
    let shards = bake_shards(std::slice::from_ref(&input), &SMALL, 2, d, "s");
    let merged = d.join("merged.vlf");
    let mut args = merge_args(&[&shards[0], &shards[1]], &merged);
    args.extend(["--cache-dir".into(), s(&cache).into(), "--report".into(), s(&d.join("merge.json")).into()]);
    vlf(&args).ok();
    let merge_report = read_json(&d.join("merge.json"));
    assert_eq!(merge_report["cache"]["status"], "store");
    assert_eq!(merge_report["cache"]["stored"], true);
    let report = cached_bake(&input, &d.join("bake.vlf"), &cache, &[]);
    assert_eq!(report["cache"]["status"], "hit");
    assert_eq!(report["cache"]["key"], merge_report["cache"]["key"]);
    assert!(std::fs::read(d.join("bake.vlf")).unwrap() == std::fs::read(&merged).unwrap());
}

/// The report has every documented key, with values that agree with the files.
#[test]
fn the_report_describes_the_bake() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = mesh("bunny.obj");
    let output = d.join("field.vlf");
    let report = cached_bake(&input, &output, &d.join("cache"), &["--threads", "2"]);
    assert_eq!(report["schema"], "vlf-bake-report/1");
    assert_eq!(report["command"], "bake");
    assert_eq!(report["format_version"], format!("{}.{}", vlf_format::VERSION_MAJOR, vlf_format::VERSION_MINOR));
    assert_eq!(report["baker_revision"], vlf_bake::BAKER_REVISION);
    assert_eq!(report["threads"], 2);
    let i = &report["inputs"][0];
    assert_eq!(i["path"], s(&input));
    assert_eq!(i["bytes"], std::fs::metadata(&input).unwrap().len());
    assert_eq!(i["blake3"], blake3::hash(&std::fs::read(&input).unwrap()).to_hex().as_str());
    let p = &report["parameters"];
    assert_eq!((p["requested"]["directions"].as_u64(), p["requested"]["tiles"].as_u64()), (Some(33), Some(16)));
    assert_eq!((p["chosen"]["directions"].as_u64(), p["chosen"]["tiles"].as_u64()), (Some(33), Some(16)));
    assert_eq!(p["chosen"]["source"], "requested");
    assert!(report["shard"].is_null());
    assert_eq!(report["cache"]["status"], "miss");
    assert_eq!(report["cache"]["stored"], true);
    let field = Field::open(&output).unwrap();
    let o = &report["output"];
    assert_eq!((o["kind"].as_str(), o["bytes"].as_u64()), (Some("field"), Some(field.len_bytes())));
    assert_eq!(o["content_hash"], hex(&field.content_hash()));
    assert_eq!(o["input_hash"], hex(&field.input_hash()));
    let phases: Vec<&str> = report["phases"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(phases, ["import", "prepare", "cache_key", "cache_lookup", "choose", "bake", "write", "cache_store"]);
    let sum: f64 = report["phases"].as_array().unwrap().iter().map(|p| p["seconds"].as_f64().unwrap()).sum();
    assert!(sum <= report["seconds"].as_f64().unwrap() + 1e-6);
    if cfg!(target_os = "linux") {
        assert!(report["peak_memory"]["bytes"].as_u64().unwrap() > 1 << 20, "{report}");
    }
}

/// The shell scripts of a YAML recipe: every literal block introduced by `run: |` (GitHub
/// Actions) or `- |` (a Kubernetes container's `args`), without its indentation.
fn shell_blocks(yaml: &str) -> Vec<String> {
    let lines: Vec<&str> = yaml.lines().collect();
    let indent = |l: &str| l.len() - l.trim_start().len();
    let mut blocks = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let t = line.trim();
        if !(t.ends_with("run: |") || t == "- |") {
            continue;
        }
        let body: Vec<&str> =
            lines[i + 1..].iter().take_while(|l| l.trim().is_empty() || indent(l) > indent(line)).copied().collect();
        let strip = body.iter().filter(|l| !l.trim().is_empty()).map(|l| indent(l)).min().unwrap_or(0);
        blocks.push(body.iter().map(|l| l.get(strip..).unwrap_or("")).collect::<Vec<_>>().join("\n"));
    }
    blocks
}

/// Runs `shell -c script` (or `shell script` for a file) in `dir` with `env`, `vlf-bake` on the
/// PATH, and asserts success.
fn run_shell(shell: &str, script: &str, is_file: bool, dir: &Path, env: &[(&str, String)]) {
    std::fs::create_dir_all(dir).unwrap();
    let bin_dir = Path::new(BIN).parent().unwrap();
    let path = std::env::join_paths(
        std::iter::once(bin_dir.to_path_buf())
            .chain(std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())),
    )
    .unwrap();
    let mut cmd = Command::new(shell);
    if is_file {
        cmd.arg(script)
    } else {
        cmd.arg("-c").arg(script)
    };
    cmd.current_dir(dir).env("PATH", path).env_remove("VLF_CACHE_DIR").env_remove("RAYON_NUM_THREADS");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.stdin(Stdio::null()).output().unwrap();
    let what = format!("{shell} in {} with {env:?}: {script}", dir.display());
    Run::from_output(what, out).ok();
}

/// The recipes of `docs/build-farms.md` are the files in `docs/farm/`, verbatim, and their shell
/// parts, run on this machine with the variables the schedulers would set, merge into the field a
/// single bake writes.
#[test]
fn the_build_farm_recipes_run_locally() {
    let doc = std::fs::read_to_string(Path::new(DOCS).join("build-farms.md")).unwrap();
    let farm = Path::new(DOCS).join("farm");
    let read = |name: &str| std::fs::read_to_string(farm.join(name)).unwrap();
    for name in [
        "github-actions.yml",
        "slurm/bake-shard.sbatch",
        "slurm/merge.sbatch",
        "slurm/submit.sh",
        "kubernetes/shards-job.yaml",
        "kubernetes/merge-job.yaml",
        "Dockerfile",
    ] {
        assert!(doc.contains(read(name).trim_end()), "docs/build-farms.md does not quote docs/farm/{name} verbatim");
    }

    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = s(&mesh("bunny_scene.glb")).to_string();
    let bake_args = "--directions 33 --tiles 16".to_string();
    let single = d.join("single.vlf");
    vlf(&["bake", &scene, "-o", s(&single), "--quiet", "--directions", "33", "--tiles", "16"]).ok();
    let expected = std::fs::read(&single).unwrap();
    let same = |field: &Path, recipe: &str| {
        assert!(std::fs::read(field).unwrap() == expected, "the {recipe} recipe's field differs from a single bake");
    };

    // GitHub Actions: each matrix job on its own runner, artifacts carried to the merge runner.
    let gh = read("github-actions.yml");
    assert!(gh.contains("shard: [0, 1, 2, 3]") && gh.contains("SHARDS: 4"), "the matrix and SHARDS disagree");
    let blocks = shell_blocks(&gh);
    assert_eq!(blocks.len(), 2, "a bake step and a merge step: {blocks:?}");
    let merge_runner = d.join("gh/merge");
    std::fs::create_dir_all(merge_runner.join("farm")).unwrap();
    for k in 0..4 {
        let runner = d.join(format!("gh/shard-{k}"));
        let env = [
            ("SCENE", scene.clone()),
            ("BAKE_ARGS", bake_args.clone()),
            ("SHARDS", "4".into()),
            ("SHARD", k.to_string()),
        ];
        run_shell("bash", &format!("set -eo pipefail\n{}", blocks[0]), false, &runner, &env);
        for f in std::fs::read_dir(runner.join("farm")).unwrap() {
            let f = f.unwrap();
            std::fs::copy(f.path(), merge_runner.join("farm").join(f.file_name())).unwrap();
        }
    }
    run_shell("bash", &format!("set -eo pipefail\n{}", blocks[1]), false, &merge_runner, &[]);
    same(&merge_runner.join("scene.vlf"), "GitHub Actions");
    assert_eq!(read_json(&merge_runner.join("farm/merge.json"))["inputs"].as_array().unwrap().len(), 4);

    // Slurm: the array tasks, then the merge, on a shared directory.
    let slurm = d.join("slurm");
    let out = slurm.join("farm").to_string_lossy().into_owned();
    assert!(read("slurm/bake-shard.sbatch").contains("#SBATCH --array=0-3"));
    for k in 0..4 {
        let env = [
            ("SCENE", scene.clone()),
            ("BAKE_ARGS", bake_args.clone()),
            ("OUT", out.clone()),
            ("SLURM_ARRAY_TASK_ID", k.to_string()),
            ("SLURM_ARRAY_TASK_COUNT", "4".into()),
        ];
        run_shell("bash", s(&farm.join("slurm/bake-shard.sbatch")), true, &slurm, &env);
    }
    run_shell("bash", s(&farm.join("slurm/merge.sbatch")), true, &slurm, &[("OUT", out.clone())]);
    same(&slurm.join("farm/scene.vlf"), "Slurm");

    // Kubernetes: the indexed pods, then the merge pod, on a shared volume.
    let shards_job = read("kubernetes/shards-job.yaml");
    assert!(shards_job.contains("completions: 4") && shards_job.contains(r#"{ name: SHARDS, value: "4" }"#));
    let k8s = d.join("k8s");
    let farm_dir = k8s.join("farm").to_string_lossy().into_owned();
    let [bake_script] = &shell_blocks(&shards_job)[..] else { panic!("one script in shards-job.yaml") };
    for k in 0..4 {
        let env = [
            ("SCENE", scene.clone()),
            ("BAKE_ARGS", bake_args.clone()),
            ("SHARDS", "4".into()),
            ("FARM_DIR", farm_dir.clone()),
            ("JOB_COMPLETION_INDEX", k.to_string()),
        ];
        run_shell("sh", bake_script, false, &k8s, &env);
    }
    let [merge_script] = &shell_blocks(&read("kubernetes/merge-job.yaml"))[..] else { panic!("one merge script") };
    run_shell("sh", merge_script, false, &k8s, &[("FARM_DIR", farm_dir.clone())]);
    same(&k8s.join("farm/scene.vlf"), "Kubernetes");
}

/// Rewrites the container `src` (magic `magic`) into `dst` with one more section, `extra`, placed
/// right after the section of kind `after`; a shard's SHARD record is updated to match.
fn with_extra_section(src: &Path, dst: &Path, magic: &[u8; 8], after: u32, extra: (u32, u32, &[u8])) {
    use vlf_format::shard::{SHARD_KIND, ShardRecord, is_per_direction, shared_hash};
    let bytes = std::fs::read(src).unwrap();
    let header = vlf_format::check_header(&bytes, bytes.len() as u64, magic).unwrap();
    let table =
        vlf_format::check_table(&bytes[..128 + 72 * header.section_count as usize], bytes.len() as u64).unwrap();
    let section = |e: &vlf_format::SectionEntry| &bytes[e.offset as usize..(e.offset + e.raw_length) as usize];
    let (kind, element_size, data) = extra;
    let extra_entry = vlf_format::SectionEntry {
        kind,
        codec: 0,
        offset: 0,
        stored_length: data.len() as u64,
        raw_length: data.len() as u64,
        element_size,
        reserved: 0,
        raw_hash: *blake3::hash(data).as_bytes(),
    };
    let mut shared = Vec::new();
    for e in table.iter().filter(|e| e.kind != SHARD_KIND && !is_per_direction(e.kind)) {
        shared.push(*e);
        if e.kind == after {
            shared.push(extra_entry);
        }
    }
    let file = std::fs::File::options().read(true).write(true).create(true).truncate(true).open(dst).unwrap();
    let mut f = vlf_format::FieldFile::create_with_magic(file, table.len() + 1, *magic).unwrap();
    for e in &table {
        if e.kind == SHARD_KIND {
            let mut record: ShardRecord = bytemuck::pod_read_unaligned(section(e));
            record.field_section_count += 1;
            record.shared_hash = shared_hash(&shared);
            f.append_kind(e.kind, e.element_size, bytemuck::bytes_of(&record)).unwrap();
        } else {
            f.append_kind(e.kind, e.element_size, section(e)).unwrap();
        }
        if e.kind == after {
            f.append_kind(kind, element_size, data).unwrap();
        }
    }
    f.finish(header.input_hash).unwrap();
}

/// A shared section of a kind this vlf-bake does not know (as a later format minor adds) flows
/// through merge unchanged: the merged field equals the single bake with the same section, and
/// opens as a field.
#[test]
fn merge_carries_sections_it_does_not_know() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = mesh("bunny.obj");
    let single = d.join("single.vlf");
    vlf(&["bake", s(&input), "-o", s(&single), "--quiet", SMALL[0], SMALL[1], SMALL[2], SMALL[3]]).ok();
    let shards = bake_shards(&[input], &SMALL, 3, d, "s");
    let strings = vlf_format::SectionKind::Strings as u32;
    let extra: (u32, u32, &[u8]) = (1234, 8, b"materials, cameras and lights: 48 bytes.........");
    let mut parts = Vec::new();
    for (k, shard) in shards.iter().enumerate() {
        let part = d.join(format!("extra-{k}.vlfs"));
        with_extra_section(shard, &part, &vlf_format::shard::SHARD_MAGIC, strings, extra);
        parts.push(part);
    }
    let expected = d.join("single-extra.vlf");
    with_extra_section(&single, &expected, &vlf_format::MAGIC, strings, extra);
    let merged = d.join("merged.vlf");
    let refs: Vec<&Path> = parts.iter().map(|p| p.as_path()).collect();
    vlf(&merge_args(&refs, &merged)).ok();
    assert!(std::fs::read(&merged).unwrap() == std::fs::read(&expected).unwrap());
    let field = Field::open(&merged).unwrap();
    let e = field.reader().table.iter().find(|e| e.kind == 1234).expect("the unknown section is in the field");
    assert_eq!(&field.reader().bytes[e.offset as usize..][..extra.2.len()], extra.2);
    vlf(&["dump", s(&merged), "--verify", "--quiet"]).ok();
}

/// Explicit parameters are held to --max-bytes: a single bake refuses a field over it, and so does
/// the merge of shards that each fit.
#[test]
fn merge_holds_explicit_parameters_to_max_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = mesh("bunny.obj");
    // A ceiling three quarters of the field: each half of it fits, the whole does not.
    let full = d.join("full.vlf");
    vlf(&["bake", s(&input), "-o", s(&full), "--directions", "33", "--tiles", "16", "--quiet"]).ok();
    let ceiling = (std::fs::metadata(&full).unwrap().len() * 3 / 4).to_string();
    let params = ["--directions", "33", "--tiles", "16", "--max-bytes", ceiling.as_str()];
    let single = vlf(&[
        "bake",
        s(&input),
        "-o",
        s(&d.join("single.vlf")),
        params[0],
        params[1],
        params[2],
        params[3],
        params[4],
        params[5],
    ]);
    assert!(single.one_error_line().contains("--max-bytes"), "{}", single.stderr);
    let shards = bake_shards(std::slice::from_ref(&input), &params, 2, d, "s");
    let out = d.join("out");
    std::fs::create_dir(&out).unwrap();
    let r = vlf(&merge_args(&[&shards[0], &shards[1]], &out.join("merged.vlf")));
    assert!(r.one_error_line().contains(&format!("over the --max-bytes ceiling of {ceiling} bytes")), "{}", r.stderr);
    assert!(names_in(&out).is_empty());
}
