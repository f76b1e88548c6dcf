//! The C API from real C programs: compiles `examples/trace_rays.c` and `tests/c/api_test.c` with
//! the system C compiler (`$CC`, else `cc`) against `include/vlf.h`, links them with `libvlf.a`
//! and with `libvlf.so`, runs them, and holds every answer to the Rust API's on the same rays,
//! bit for bit.
//!
//! Cargo builds every crate type of this package's library before its integration tests, into
//! the directory holding the test executable (`target/<profile>/deps`), which is where the
//! libraries are found.

#![cfg(target_os = "linux")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use vlf_bake::generate::Rng;
use vlf_bake::{BakeConfig, DepthPolicy, NoProgress, import::import_paths};
use vlf_geom::{Camera, Hit, Ray};
use vlf_runtime::Field;

/// The libraries Rust's standard library needs when linked statically into a C program on Linux
/// (what `rustc --print native-static-libs` lists, less those the C compiler links anyway).
const STATIC_LIBS: [&str; 3] = ["-lpthread", "-ldl", "-lm"];

/// Warnings are errors: the header must compile cleanly under strict flags.
const STRICT: [&str; 4] = ["-Wall", "-Wextra", "-Werror", "-pedantic"];

fn crate_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The directory with `libvlf.a` and `libvlf.so`: next to this test's executable.
fn library_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    let deps = exe.parent().expect("executable directory").to_path_buf();
    for dir in [deps.clone(), deps.parent().unwrap_or(&deps).to_path_buf()] {
        if dir.join("libvlf.a").is_file() && dir.join("libvlf.so").is_file() {
            return dir;
        }
    }
    panic!(
        "libvlf.a and libvlf.so are not in {} or its parent: did cargo build the cdylib and staticlib?",
        deps.display()
    );
}

fn compiler() -> String {
    std::env::var("CC").ok().filter(|c| !c.is_empty()).unwrap_or_else(|| "cc".to_owned())
}

/// Compiles C `sources` into `exe` with `args` (after the sources: libraries), or fails with the
/// compiler's output.
fn compile(std: &str, sources: &[&Path], args: &[&str], exe: &Path) {
    let cc = compiler();
    let mut cmd = Command::new(&cc);
    cmd.arg(format!("-std={std}")).args(STRICT).arg("-O1").arg("-I").arg(crate_dir().join("include"));
    cmd.args(sources).args(args).arg("-o").arg(exe);
    let out = cmd.output().unwrap_or_else(|e| panic!("cannot run the C compiler `{cc}` (set CC): {e}"));
    assert!(out.status.success(), "{cmd:?} failed:\n{}{}", text(&out.stdout), text(&out.stderr));
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Runs a program and returns its output, failing with its output if it exits non-zero.
fn run(cmd: &mut Command) -> Output {
    let out = cmd.output().unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    assert!(out.status.success(), "{cmd:?} exited with {}:\n{}{}", out.status, text(&out.stdout), text(&out.stderr));
    out
}

/// A field of the bunny, small enough to bake in well under a second.
fn bake_bunny(dir: &Path) -> PathBuf {
    let mesh = crate_dir().join("../../fixtures/meshes/bunny.obj");
    let scene = import_paths(&[mesh]).expect("import bunny.obj");
    let path = dir.join("bunny.vlf");
    let config = BakeConfig {
        directions: Some(33),
        tiles: Some(16),
        depth: DepthPolicy { leaf_size: 4, max_depth: 8 },
        ..BakeConfig::default()
    };
    vlf_bake::bake_scene(&scene, &config, &path, &NoProgress).expect("bake");
    path
}

fn to_f32(v: [f64; 3]) -> [f32; 3] {
    v.map(|c| c as f32)
}

/// Over 10,000 rays of every kind a renderer sends: primary rays from outside and from inside
/// the scene, random rays inside and around it, finite intervals, rays that miss the bounding
/// sphere, and invalid rays (which miss).
fn ray_mix(field: &Field) -> Vec<Ray> {
    let (c, r) = field.bounding_sphere();
    let mut rays = Camera::outside(c, r, 1.0).primary_rays(64, 64);
    rays.extend(Camera::inside(c, r, 1.0).primary_rays(64, 64));
    let mut rng = Rng::new(0x0c0a_f1e1d);
    let point =
        |scale: f64, rng: &mut Rng| -> [f64; 3] { std::array::from_fn(|i| c[i] + scale * r * rng.range(-1.0, 1.0)) };
    for i in 0..2_000 {
        let o = point(if i % 2 == 0 { 0.8 } else { 2.5 }, &mut rng);
        let target = point(0.6, &mut rng);
        rays.push(Ray::new(to_f32(o), to_f32(std::array::from_fn(|k| target[k] - o[k]))));
    }
    for _ in 0..1_000 {
        let o = point(1.2, &mut rng);
        let d = point(1.0, &mut rng).map(|x| x as f32);
        let tmin = rng.range(0.0, 0.5 * r) as f32;
        rays.push(Ray::with_interval(to_f32(o), d, tmin, tmin + rng.range(0.0, r) as f32));
    }
    for _ in 0..1_000 {
        // From outside the sphere, pointing away from it.
        let o = point(3.0, &mut rng);
        let away: [f64; 3] = std::array::from_fn(|k| o[k] - c[k]);
        if away.iter().map(|a| a * a).sum::<f64>() > 2.0 * r * r {
            rays.push(Ray::new(to_f32(o), to_f32(away)));
        }
    }
    let o = to_f32(c);
    rays.extend([
        Ray::new([f32::NAN, 0.0, 0.0], [0.0, 0.0, 1.0]),
        Ray::new(o, [0.0, 0.0, 0.0]),
        Ray::new(o, [f32::INFINITY, 0.0, 1.0]),
        Ray::with_interval(o, [0.0, 0.0, 1.0], 2.0, 1.0),
        Ray::with_interval(o, [0.0, 0.0, 1.0], 0.0, f32::NAN),
    ]);
    rays
}

fn hits_of(bytes: &[u8]) -> Vec<Hit> {
    assert_eq!(bytes.len() % 16, 0, "a hits file is a whole number of 16-byte records");
    bytes.chunks_exact(16).map(bytemuck::pod_read_unaligned).collect()
}

/// Every answer of a C run equals the Rust API's: the whole hit record bit for bit, and any-hit.
fn assert_same(label: &str, rays: &[Ray], want: &[Hit], want_any: &[bool], hits: &[u8], any: &[u8]) {
    let got = hits_of(hits);
    assert_eq!(got.len(), rays.len(), "{label}: one hit per ray");
    assert_eq!(any.len(), rays.len(), "{label}: one any-hit byte per ray");
    let mut bad = Vec::new();
    for i in 0..rays.len() {
        let (g, w) = (got[i], want[i]);
        let same = bytemuck::bytes_of(&g) == bytemuck::bytes_of(&w);
        if !same || any[i] != want_any[i] as u8 {
            bad.push(format!("ray {i} {:?}: C {g:?} any={}, Rust {w:?} any={}", rays[i], any[i], want_any[i]));
        }
    }
    assert!(
        bad.is_empty(),
        "{label}: {} of {} rays differ, e.g. {:#?}",
        bad.len(),
        rays.len(),
        &bad[..bad.len().min(5)]
    );
}

#[test]
fn c_programs_agree_with_the_rust_api() {
    let lib = library_dir();
    let work = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).expect("temp dir");
    let w = work.path();

    // The field, the rays, and the Rust API's answers.
    let field_path = bake_bunny(w);
    let field = Field::open(&field_path).expect("open");
    let rays = ray_mix(&field);
    assert!(rays.len() >= 10_000, "{} rays", rays.len());
    let rays_path = w.join("rays.bin");
    std::fs::write(&rays_path, bytemuck::cast_slice::<Ray, u8>(&rays)).expect("write rays");
    let want: Vec<Hit> = rays.iter().map(|r| Hit::record(field.closest_hit(r))).collect();
    let want_any: Vec<bool> = rays.iter().map(|r| field.any_hit(r)).collect();
    let hit_count = want.iter().filter(|h| h.prim != u32::MAX).count();
    // The mix must exercise both answers substantially.
    assert!(hit_count > rays.len() / 5 && hit_count < rays.len() * 4 / 5, "{hit_count} hits of {}", rays.len());

    // The example, statically linked and dynamically linked.
    let example = crate_dir().join("examples/trace_rays.c");
    let static_exe = w.join("trace_rays_static");
    let mut static_args = vec![lib.join("libvlf.a").to_str().expect("UTF-8 path").to_owned()];
    static_args.extend(STATIC_LIBS.map(String::from));
    compile("c99", &[&example], &static_args.iter().map(String::as_str).collect::<Vec<_>>(), &static_exe);
    let shared_exe = w.join("trace_rays_shared");
    let lib_arg = format!("-L{}", lib.display());
    let rpath = format!("-Wl,-rpath,{}", lib.display());
    compile("c99", &[&example], &[&lib_arg, "-l:libvlf.so", &rpath], &shared_exe);

    let runs: [(&str, &Path, &[&str]); 4] = [
        ("static, mapped, arrays", &static_exe, &[]),
        ("static, mapped, one ray at a time", &static_exe, &["--single"]),
        ("shared, from memory, arrays", &shared_exe, &["--memory"]),
        ("shared, mapped, one ray at a time", &shared_exe, &["--single"]),
    ];
    let hash = vlf_runtime::hex(&field.content_hash());
    for (i, (label, exe, flags)) in runs.iter().enumerate() {
        let hits_path = w.join(format!("hits{i}.bin"));
        let any_path = w.join(format!("any{i}.bin"));
        let out = run(Command::new(exe).args(*flags).arg(&field_path).arg(&rays_path).arg(&hits_path).arg(&any_path));
        let hits = std::fs::read(&hits_path).expect("read hits");
        let any = std::fs::read(&any_path).expect("read any-hits");
        assert_same(label, &rays, &want, &want_any, &hits, &any);
        let stdout = text(&out.stdout);
        let any_count = want_any.iter().filter(|&&a| a).count();
        assert!(
            stdout.contains(&format!("{} triangles, content hash {hash}", field.triangle_count()))
                && stdout.contains(&format!("rays: {}, closest hits: {hit_count}, any hits: {any_count}", rays.len())),
            "{label}: unexpected summary:\n{stdout}"
        );
        println!("{label}: {} rays, {hit_count} hits, identical to the Rust API", rays.len());
    }

    // A packed field (zstd sections) opens through the same calls, decoded at open: same answers.
    let packed = w.join("bunny.packed.vlf");
    vlf_bake::pack::pack_path(&field_path, &packed, 3, &NoProgress).expect("pack");
    for (label, flags) in [("static, packed, mapped", &[][..]), ("static, packed, from memory", &["--memory"][..])] {
        let (hits_path, any_path) = (w.join("hits-packed.bin"), w.join("any-packed.bin"));
        let out =
            run(Command::new(&static_exe).args(flags).arg(&packed).arg(&rays_path).arg(&hits_path).arg(&any_path));
        let (hits, any) = (std::fs::read(&hits_path).expect("hits"), std::fs::read(&any_path).expect("any"));
        assert_same(label, &rays, &want, &want_any, &hits, &any);
        assert!(text(&out.stdout).contains(&hash), "{label}: the packed field has the raw field's content hash");
    }

    // The example's failures: a missing field is one line on standard error and exit status 1.
    let out =
        Command::new(&static_exe).arg(w.join("missing.vlf")).arg(&rays_path).arg(w.join("h.bin")).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(
        text(&out.stderr).contains("VLF_ERR_IO") && text(&out.stderr).contains("missing.vlf"),
        "{}",
        text(&out.stderr)
    );
    let out = Command::new(&static_exe).arg("--bogus").output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn c_api_checks_pass() {
    let lib = library_dir();
    let work = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).expect("temp dir");
    let w = work.path();
    let field_path = bake_bunny(w);
    let field = Field::open(&field_path).expect("open");
    let exe = w.join("api_test");
    let source = crate_dir().join("tests/c/api_test.c");
    let archive = lib.join("libvlf.a");
    let mut args = vec![archive.to_str().expect("UTF-8 path"), "-pthread"];
    args.extend(STATIC_LIBS);
    compile("c11", &[&source], &args, &exe);
    // A glTF scene with materials, a camera and lights, and the bunny's field packed.
    let gltf = crate_dir().join("../../fixtures/meshes/cornell/cornell.gltf");
    let scene_path = w.join("cornell.vlf");
    let config = BakeConfig { directions: Some(9), tiles: Some(8), ..BakeConfig::default() };
    vlf_bake::bake_scene(&import_paths(&[gltf]).expect("import"), &config, &scene_path, &NoProgress).expect("bake");
    let scene = Field::open(&scene_path).expect("open");
    assert!(scene.materials().len() > 1 && scene.cameras().count() == 1 && scene.lights().count() > 1);
    let packed = w.join("bunny.packed.vlf");
    vlf_bake::pack::pack_path(&field_path, &packed, 3, &NoProgress).expect("pack");
    let (major, minor) = field.format_version();
    let p = field.parameters();
    let out = run(Command::new(&exe)
        .arg(&field_path)
        .arg(field.triangle_count().to_string())
        .arg(vlf_runtime::hex(&field.content_hash()))
        .arg("bunny.obj")
        .arg(env!("CARGO_PKG_VERSION"))
        .arg(format!("{major}.{minor}"))
        .arg(p.directions.to_string())
        .arg(p.tiles.to_string())
        .arg(&scene_path)
        .arg(scene.materials().len().to_string())
        .arg(scene.cameras().count().to_string())
        .arg(scene.lights().count().to_string())
        .arg(scene.cameras().next().unwrap().name)
        .arg(scene.material_index(0).map_or(u32::MAX, |i| i as u32).to_string())
        .arg(&packed)
        .arg(field.len_bytes().to_string()));
    let stdout = text(&out.stdout);
    println!("{stdout}{}", text(&out.stderr));
    assert!(stdout.contains(" passed, 0 failed"), "{stdout}");
}

/// The all-hits and hit-count calls from C (`tests/c/all_hits_test.c`, linked with `libvlf.a`):
/// every ray's full list of hits, as C wrote it, equals the Rust API's bit for bit; the C program
/// checks the counts, the capped calls and the batch against it.
#[test]
fn c_all_hits_agree_with_the_rust_api() {
    let lib = library_dir();
    let work = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).expect("temp dir");
    let w = work.path();
    let field_path = bake_bunny(w);
    let field = Field::open(&field_path).expect("open");
    let rays = ray_mix(&field);
    let rays_path = w.join("rays.bin");
    std::fs::write(&rays_path, bytemuck::cast_slice::<Ray, u8>(&rays)).expect("write rays");
    let exe = w.join("all_hits_test");
    let archive = lib.join("libvlf.a");
    let mut args = vec![archive.to_str().expect("UTF-8 path")];
    args.extend(STATIC_LIBS);
    compile("c11", &[&crate_dir().join("tests/c/all_hits_test.c")], &args, &exe);
    let out_path = w.join("all_hits.bin");
    let out = run(Command::new(&exe).arg(&field_path).arg(&rays_path).arg("3").arg(&out_path));
    let stdout = text(&out.stdout);
    println!("{stdout}");
    assert!(stdout.contains(" passed, 0 failed"), "{stdout}{}", text(&out.stderr));
    let bytes = std::fs::read(&out_path).expect("read the C program's hits");
    let (mut at, mut several) = (0, 0);
    for (i, ray) in rays.iter().enumerate() {
        let want = field.view().all_hits(ray, usize::MAX);
        let count = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        at += 4;
        let got = hits_of(&bytes[at..at + 16 * count]);
        at += 16 * count;
        assert!(
            bytemuck::cast_slice::<Hit, u8>(&got) == bytemuck::cast_slice::<Hit, u8>(&want),
            "ray {i} {ray:?}: C {got:?}, Rust {want:?}"
        );
        several += (count > 1) as usize;
    }
    assert_eq!(at, bytes.len(), "nothing after the last ray");
    assert!(several > rays.len() / 10, "only {several} rays with several hits");
}

/// The header also serves C++ (`extern "C"`, the `VlfStatus` enum with a fixed underlying type):
/// a translation unit that includes it and calls the API compiles cleanly as C++11 and C++17.
#[test]
fn header_compiles_as_cpp() {
    let work = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).expect("temp dir");
    let source = work.path().join("use_header.cpp");
    std::fs::write(
        &source,
        "#include \"vlf.h\"\n\
         static_assert(sizeof(VlfRay) == 32 && sizeof(VlfHit) == 16, \"rays.md records\");\n\
         int trace(const VlfField *field, const VlfRay *ray, VlfHit *hit) {\n\
         \x20   VlfStatus status = vlf_closest_hit(field, ray, hit);\n\
         \x20   return status == VLF_OK ? 0 : static_cast<int>(status);\n\
         }\n",
    )
    .expect("write C++ source");
    let cxx = std::env::var("CXX").ok().filter(|c| !c.is_empty()).unwrap_or_else(|| "c++".to_owned());
    for std in ["c++11", "c++17"] {
        let mut cmd = Command::new(&cxx);
        cmd.arg(format!("-std={std}")).args(STRICT).arg("-fsyntax-only").arg("-I").arg(crate_dir().join("include"));
        let out =
            cmd.arg(&source).output().unwrap_or_else(|e| panic!("cannot run the C++ compiler `{cxx}` (set CXX): {e}"));
        assert!(out.status.success(), "{cmd:?} failed:\n{}", text(&out.stderr));
    }
}

/// `tests/c/scene_test.c`'s records for `rays` in `scene`: per ray the closest hit over every
/// instance (16 bytes), its instance (4 bytes) and the any-hit byte under `any_mask`.
fn scene_records(scene: &vlf_scene::Scene, rays: &[Ray], any_mask: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity(rays.len() * 21);
    for ray in rays {
        let h = scene.closest_hit(ray, u32::MAX);
        out.extend_from_slice(bytemuck::bytes_of(&Hit::record(h.map(|h| h.hit))));
        out.extend_from_slice(&h.map_or(u32::MAX, |h| h.instance).to_le_bytes());
        out.push(scene.any_hit(ray, any_mask) as u8);
    }
    out
}

#[test]
fn c_scene_api_agrees_with_the_rust_api() {
    use vlf_scene::{Affine, EditedField, Scene};
    let lib = library_dir();
    let work = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).expect("temp dir");
    let w = work.path();
    let field_path = bake_bunny(w);
    let field = std::sync::Arc::new(Field::open(&field_path).expect("open"));
    let (c, r) = field.bounding_sphere();
    let count = field.triangle_count();
    // The field's rays, and as many around the mirrored instance (x ↦ -2x + 3r, z ↦ z/2).
    let mut rays = ray_mix(&field);
    let m = [-2.0 * c[0] + 3.0 * r, c[1], 0.5 * c[2]];
    let mut rng = Rng::new(13);
    for _ in 0..4_000 {
        let o: [f64; 3] = std::array::from_fn(|k| m[k] + 3.0 * r * rng.range(-1.0, 1.0));
        let t: [f64; 3] = std::array::from_fn(|k| m[k] + 0.8 * r * rng.range(-1.0, 1.0));
        rays.push(Ray::new(to_f32(o), to_f32(std::array::from_fn(|k| t[k] - o[k]))));
    }
    let rays_path = w.join("rays.bin");
    std::fs::write(&rays_path, bytemuck::cast_slice::<Ray, u8>(&rays)).expect("write rays");

    let exe = w.join("scene_test");
    let archive = lib.join("libvlf.a");
    let mut args = vec![archive.to_str().expect("UTF-8 path")];
    args.extend(STATIC_LIBS);
    compile("c11", &[&crate_dir().join("tests/c/scene_test.c")], &args, &exe);
    let (before, after) = (w.join("before.bin"), w.join("after.bin"));
    let out = run(Command::new(&exe).arg(&field_path).arg(&rays_path).arg(&before).arg(&after));
    let stdout = text(&out.stdout);
    assert!(stdout.contains(" passed, 0 failed"), "{stdout}{}", text(&out.stderr));

    // The same scene and the same edits through the Rust API.
    let rows = |v: [f64; 12]| {
        Affine::from_rows(&[
            v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11], 0.0, 0.0, 0.0, 1.0,
        ])
        .unwrap()
    };
    let mut scene = Scene::new();
    let id = scene.add_field(EditedField::new(field.clone()));
    let a = scene.add_instance(id, Affine::IDENTITY, 1).unwrap();
    let b = scene.add_instance(id, rows([-2.0, 0.0, 0.0, 3.0 * r, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0]), 2).unwrap();
    let want_before = scene_records(&scene, &rays, 2);
    scene.set_transform(a, rows([1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.5 * r, 0.0, 0.0, 1.0, 0.0])).unwrap();
    scene.set_mask(b, 3).unwrap();
    scene.edit(id, |f| f.remove(&[0, 1, 1])).unwrap().unwrap();
    let t0 = [c, [c[0] + 0.5 * r, c[1], c[2]], [c[0], c[1] + 0.5 * r, c[2]]];
    let t1 = [
        [c[0], c[1], c[2] + 0.25 * r],
        [c[0] + 0.25 * r, c[1], c[2] + 0.25 * r],
        [c[0], c[1] + 0.25 * r, c[2] + 0.5 * r],
    ];
    scene.edit(id, |f| f.insert(&[t0], &Affine::IDENTITY)).unwrap().unwrap();
    scene.edit(id, |f| f.insert(&[t1], &Affine::translation([0.0, 0.25 * r, 0.0]))).unwrap().unwrap();
    let want_after = scene_records(&scene, &rays, 1);

    for (label, path, want) in [("before the edits", &before, &want_before), ("after the edits", &after, &want_after)] {
        let got = std::fs::read(path).expect("read records");
        assert_eq!(got.len(), want.len(), "{label}: one record per ray");
        let differ = got.chunks_exact(21).zip(want.chunks_exact(21)).filter(|(g, w)| g != w).count();
        assert_eq!(differ, 0, "{label}: {differ} of {} rays differ between C and Rust", rays.len());
        // Both instances are hit, and after the edits the inserted triangles too.
        let instance_of = |rec: &[u8]| u32::from_le_bytes(rec[16..20].try_into().unwrap());
        let prim_of = |rec: &[u8]| u32::from_le_bytes(rec[4..8].try_into().unwrap());
        let on = |k: u32| want.chunks_exact(21).filter(|rec| instance_of(rec) == k).count();
        assert!(on(0) > 500 && on(1) > 500, "{label}: {} and {} hits on the two instances", on(0), on(1));
        if path == &after {
            let inserted =
                want.chunks_exact(21).filter(|rec| prim_of(rec) >= count && prim_of(rec) != u32::MAX).count();
            assert!(inserted > 20, "{label}: {inserted} hits on inserted triangles");
        }
        println!("{label}: {} rays, C and Rust identical", rays.len());
    }
}
