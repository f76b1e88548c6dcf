//! The bodies of the fuzz targets in `fuzz/fuzz_targets/` (`docs/fuzzing.md`), kept here so that
//! `tests/fuzz_regressions.rs` replays the seed corpus and every input the fuzzer ever found
//! through exactly the code the fuzzer ran, in the ordinary `cargo test --workspace`.
//!
//! Each function takes arbitrary bytes and either returns normally or panics; a panic is a bug in
//! the library (or a broken invariant asserted here), never an acceptable answer to bad input.

use std::io;
use std::path::Path;
use vlf_bake::import::import_bytes;
use vlf_bake::{Scene, SceneBuilder};
use vlf_format::{CONTENT_HASH_RANGE, HEADER_SIZE, Header, MAX_SECTIONS, SectionEntry, TABLE_ENTRY_SIZE, codec};
use vlf_geom::{Hit, Ray, TraceStats, TriRay};
use vlf_runtime::{Field, FieldView, Interleave};

/// At most this many rays are decoded from the bytes after a field.
const MAX_TAIL_RAYS: usize = 64;

/// Target `field_open`: the bytes as a field file, exactly as a renderer or `vlf-bake dump` gets
/// them. The field is `data[..file_length]` (the header's own length field) when that fits, and
/// the 32-byte records after it are extra rays; otherwise all of `data` is the field. If it opens,
/// every query runs on it ([`exercise`]).
pub fn field_open(data: &[u8]) {
    let (field, tail) = split_field(data);
    open_and_exercise(field, tail);
}

/// Target `field_resealed`: like [`field_open`], but first makes the bytes pass the open checks'
/// hashes: `file_length` is set to the field's length, every raw section's `raw_hash` to the BLAKE3
/// of the bytes it covers, and the content hash recomputed ([`reseal`]). So the fuzzer's mutations
/// of section payloads, counts and offsets reach the structural checks, the queries and the full
/// verifier instead of stopping at a hash mismatch: a field that lies but is well hashed.
pub fn field_resealed(data: &[u8]) {
    let (field, tail) = split_field(data);
    let mut field = field.to_vec();
    reseal(&mut field);
    open_and_exercise(&field, tail);
}

/// Target `import_obj`: the bytes up to the first NUL as an OBJ file, the rest (if any) as the
/// material library every `mtllib` line names. Imported as `fuzz.obj` and again under a name
/// without an extension (the format sniffing of `vlf-bake bake`).
pub fn import_obj(data: &[u8]) {
    let (obj, mtl) = split_at_nul(data);
    import_and_check("fuzz.obj", obj, mtl);
    import_and_check("fuzz", obj, mtl);
}

/// Target `import_gltf`: bytes that start with the GLB magic as a `.glb` file; otherwise the bytes
/// up to the first NUL as `.gltf` JSON and the rest (if any) as the external file every buffer URI
/// names.
pub fn import_gltf(data: &[u8]) {
    if data.starts_with(b"glTF") {
        import_and_check("fuzz.glb", data, None);
    } else {
        let (json, external) = split_at_nul(data);
        import_and_check("fuzz.gltf", json, external);
    }
}

/// Splits fuzz input into the field and the bytes after it (see [`field_open`]).
fn split_field(data: &[u8]) -> (&[u8], &[u8]) {
    let declared = data.get(16..24).map(|b| u64::from_le_bytes(b.try_into().expect("eight bytes")));
    match declared {
        Some(len) if len >= HEADER_SIZE as u64 && len <= data.len() as u64 => data.split_at(len as usize),
        _ => (data, &[]),
    }
}

fn split_at_nul(data: &[u8]) -> (&[u8], Option<&[u8]>) {
    match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], Some(&data[i + 1..])),
        None => (data, None),
    }
}

/// Makes `bytes` pass the hash checks of `Field::open`, leaving every other byte as it is: sets
/// `file_length`, the `raw_hash` of every raw section whose bytes lie inside the file, and the
/// content hash. Entries that do not fit, and compressed sections, are left alone.
pub fn reseal(bytes: &mut [u8]) {
    if bytes.len() < HEADER_SIZE {
        return;
    }
    let len = bytes.len() as u64;
    let mut header: Header = bytemuck::pod_read_unaligned(&bytes[..HEADER_SIZE]);
    header.file_length = len;
    bytes[..HEADER_SIZE].copy_from_slice(bytemuck::bytes_of(&header));
    let count = header.section_count.min(MAX_SECTIONS) as usize;
    for i in 0..count {
        let at = HEADER_SIZE + i * TABLE_ENTRY_SIZE;
        let Some(raw) = bytes.get(at..at + TABLE_ENTRY_SIZE) else { break };
        let mut entry: SectionEntry = bytemuck::pod_read_unaligned(raw);
        let end = entry.offset.checked_add(entry.stored_length).filter(|&end| end <= len);
        if let (Some(end), codec::RAW) = (end, entry.codec) {
            entry.raw_hash = *blake3::hash(&bytes[entry.offset as usize..end as usize]).as_bytes();
            bytes[at..at + TABLE_ENTRY_SIZE].copy_from_slice(bytemuck::bytes_of(&entry));
        }
    }
    let table_end = HEADER_SIZE + count * TABLE_ENTRY_SIZE;
    if header.section_count as usize == count && table_end <= bytes.len() {
        let hash = vlf_format::content_hash(&bytes[..table_end]);
        bytes[CONTENT_HASH_RANGE].copy_from_slice(&hash);
    }
}

fn open_and_exercise(field: &[u8], tail: &[u8]) {
    // Borrowed bytes at whatever alignment the fuzzer's buffer has: opens or says why not.
    if let Err(e) = FieldView::from_bytes(field) {
        let _ = e.to_string();
    }
    match Field::from_bytes(field) {
        Ok(f) => exercise(&f, tail),
        Err(e) => {
            let _ = e.to_string();
        }
    }
}

/// Everything a user of an opened field can do, on a field that may lie anywhere past its header
/// and table: `dump` (describe), `dump --verify`, and every query on a fixed set of nasty rays, rays
/// aimed at the field's own triangles and the rays in `tail`. Asserts what must hold whatever the
/// file says.
pub fn exercise(field: &Field, tail: &[u8]) {
    let reader = field.reader();
    let description = vlf_bake::inspect::describe(reader);
    serde_json::to_string(&description).expect("a description serialises");
    let verified = vlf_bake::inspect::verify(reader, &mut |_, _| {});
    if let Err(e) = &verified {
        let _ = e.to_string();
    }

    let mut rays = nasty_rays(field);
    rays.extend(tail.chunks_exact(size_of::<Ray>()).take(MAX_TAIL_RAYS).map(bytemuck::pod_read_unaligned::<Ray>));
    for ray in &rays {
        check_queries(field, ray);
    }
    let mut hits = vec![Hit::MISS; rays.len()];
    field.closest_hits(&rays, &mut hits);
    let mut any = vec![false; rays.len()];
    field.any_hits(&rays, &mut any);
    for ((ray, hit), any) in rays.iter().zip(&hits).zip(&any) {
        assert_eq!(*hit, Hit::record(field.closest_hit(ray)), "batch and single closest hit differ for {ray:?}");
        assert_eq!(*any, field.any_hit(ray), "batch and single any hit differ for {ray:?}");
    }
    // The interleaved batch, which the calls above leave out on a field this small.
    let mut closest = vec![None; rays.len()];
    field.view().closest_hits_in(&rays, &mut closest, Interleave::Always);
    field.view().any_hits_in(&rays, &mut any, Interleave::Always);
    for ((ray, hit), any) in rays.iter().zip(&closest).zip(&any) {
        assert_eq!(*hit, field.closest_hit(ray), "interleaved and single closest hit differ for {ray:?}");
        assert_eq!(*any, field.any_hit(ray), "interleaved and single any hit differ for {ray:?}");
    }
    for id in [0, 1, field.triangle_count().saturating_sub(1), field.triangle_count(), u32::MAX] {
        let _ = field.provenance(id);
        let _ = field.triangle(id);
    }
    let _ = (field.content_hash(), field.input_hash(), field.bounding_sphere(), field.len_bytes());
    let _ = (field.direction_count(), field.tile_resolution());
}

/// One ray through every query entry point, with the invariants that hold for any file.
fn check_queries(field: &Field, ray: &Ray) {
    let view = field.view();
    let closest = field.closest_hit(ray);
    let any = field.any_hit(ray);
    // On a file that keeps the format's promises the two agree (the oracle suites check both
    // against the brute force), but an any-hit search may walk a segment from its far end
    // (`vlf-runtime`'s `Setup::for_any_hit`), so on a file that lies they may see different
    // leaves. Whatever the file, a hit either reports is one: the kernel confirms it below.
    let mut stats = TraceStats::default();
    assert_eq!(view.closest_hit_counted(ray, &mut stats), closest, "counting changed the answer for {ray:?}");
    let first = view.any_hit_counted(ray, &mut stats);
    assert_eq!(first.is_some(), any, "any_hit_counted disagrees with any_hit for {ray:?}");
    // The work is bounded by the file, whatever it claims: a ray crosses at most 2n + 1 tiles, and
    // visits in each at most the leaves a block may hold.
    let n = field.tile_resolution() as u64;
    assert!(stats.cells <= stats.rays * (2 * n + 1), "{} tiles visited by {} rays, n = {n}", stats.cells, stats.rays);
    let max_leaves = vlf_format::block::MAX_LEAVES as u64;
    assert!(
        stats.leaves <= stats.cells * max_leaves,
        "{} leaves visited in {} tiles, but a block holds at most {max_leaves}: {ray:?}",
        stats.leaves,
        stats.cells
    );
    for hit in closest.iter().chain(&first) {
        let tri = field.triangle_local(hit.prim);
        assert!(tri.is_some(), "hit names triangle {} of {}", hit.prim, field.triangle_count());
        assert!(ray.tmin <= hit.t && hit.t <= ray.tmax, "hit t = {} outside [{}, {}]", hit.t, ray.tmin, ray.tmax);
        // The hit is the kernel's answer for that triangle.
        let c = tri.and_then(|tri| TriRay::relative(ray, field.origin()).candidate(&tri));
        assert_eq!(
            c.map(|c| c.t as f32),
            Some(hit.t),
            "{ray:?} reports a hit on {} that the kernel does not",
            hit.prim
        );
        let _ = field.provenance(hit.prim);
    }
    if !ray.is_valid() {
        assert!(closest.is_none(), "an invalid ray hit something: {ray:?}");
    }
    let mut ids_seen = 0usize;
    view.for_each_leaf(ray, &mut (), |ids, _| {
        ids_seen += ids.len();
        false
    });
    let _ = view.select_direction(ray.dir.map(f64::from));
}

/// Rays that stress the query's arithmetic, placed around the field's own bounding sphere and
/// triangles (as the file states them, lies included).
fn nasty_rays(field: &Field) -> Vec<Ray> {
    let (c, r) = field.bounding_sphere();
    let f = |v: f64| v as f32;
    let at = |k: [f64; 3]| [f(c[0] + k[0] * r), f(c[1] + k[1] * r), f(c[2] + k[2] * r)];
    let centre = at([0.0; 3]);
    let (nan, inf, big) = (f32::NAN, f32::INFINITY, f32::MAX);
    let mut rays = Vec::new();
    // Towards the centre from outside along the axes and a diagonal; outward from the centre.
    for axis in 0..3 {
        for s in [-3.0f64, 3.0] {
            let mut k = [0.0; 3];
            k[axis] = s;
            let mut d = [0.0f32; 3];
            d[axis] = -s.signum() as f32;
            rays.push(Ray::new(at(k), d));
            rays.push(Ray::new(centre, d.map(|v| -v)));
        }
    }
    rays.push(Ray::new(at([2.0, 2.0, 2.0]), [-1.0, -1.0, -1.0]));
    rays.push(Ray::new(at([-2.0, 1.0, 0.5]), [1.0, -0.5, -0.25]));
    // Grazing the sphere and its grown rim; equator and near-axis directions of the lattice.
    for g in [1.0 - 1e-7, 1.0, 1.0 + 1e-6, 1.0 + 1e-3] {
        rays.push(Ray::new(at([g, 0.0, -3.0]), [0.0, 0.0, 1.0]));
        rays.push(Ray::new(at([0.0, -3.0, g]), [0.0, 1.0, 0.0]));
    }
    for d in [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 0.0, -0.0], [1e-45, 0.0, 0.0]] {
        rays.push(Ray::new(at([-2.0 * d[0] as f64, -2.0 * d[1] as f64, 0.0]), d));
    }
    rays.push(Ray::new(at([0.0, 0.0, -3.0]), [1e-45, -1e-45, 1.0]));
    rays.push(Ray::new(at([0.0, 0.0, 3.0]), [0.0, 0.0, -1e-38]));
    // Parallel to stored directions, both ways.
    for w in field.reader().directions.iter().take(4) {
        let d = [w[0], w[1], w[2]];
        rays.push(Ray::new(at([0.1, -0.2, 0.0]), d));
        rays.push(Ray::new(at([0.1, -0.2, 0.0]), d.map(|v| -v)));
    }
    // Huge origins and directions.
    rays.push(Ray::new([1e30, 0.0, 0.0], [-1.0, 0.0, 0.0]));
    rays.push(Ray::new([big, big, big], [-1.0, -1.0, -1.0]));
    rays.push(Ray::new([-big, 0.0, big], [1.0, 0.0, -1.0]));
    rays.push(Ray::new(centre, [big, big, -big]));
    rays.push(Ray::new(at([-3.0, 0.0, 0.0]), [big, 1.0, 0.0]));
    // Invalid: NaN, infinities, zero direction, empty or NaN intervals.
    rays.push(Ray::new([nan, 0.0, 0.0], [0.0, 0.0, 1.0]));
    rays.push(Ray::new(centre, [nan, nan, nan]));
    rays.push(Ray::new([inf, 0.0, 0.0], [-1.0, 0.0, 0.0]));
    rays.push(Ray::new(centre, [0.0, -inf, 0.0]));
    rays.push(Ray::new(centre, [0.0, 0.0, 0.0]));
    rays.push(Ray::new(centre, [-0.0, -0.0, -0.0]));
    rays.push(Ray::with_interval(at([0.0, 0.0, -3.0]), [0.0, 0.0, 1.0], 5.0, 1.0));
    rays.push(Ray::with_interval(at([0.0, 0.0, -3.0]), [0.0, 0.0, 1.0], nan, inf));
    rays.push(Ray::with_interval(at([0.0, 0.0, -3.0]), [0.0, 0.0, 1.0], 0.0, nan));
    // Valid but odd intervals.
    rays.push(Ray::with_interval(at([0.0, 0.0, -3.0]), [0.0, 0.0, 1.0], -inf, inf));
    rays.push(Ray::with_interval(at([0.0, 0.0, -3.0]), [0.0, 0.0, 1.0], 3.0 * r as f32, 3.0 * r as f32));
    rays.push(Ray::with_interval(at([0.0, 0.0, -3.0]), [0.0, 0.0, 1.0], 0.0, 0.0));
    rays.push(Ray::with_interval(at([0.0, 0.0, 3.0]), [0.0, 0.0, -1.0], -inf, -1.0));
    // Aimed at the vertices, an edge midpoint and the centroid of the first triangles, from outside
    // and from inside the sphere.
    for id in 0..field.triangle_count().min(3) {
        let t = field.triangle(id).expect("id below the count").map(|v| v.map(|c| c as f32));
        let mid = |a: [f32; 3], b: [f32; 3]| [0, 1, 2].map(|i| 0.5 * (a[i] + b[i]));
        let centroid = [0, 1, 2].map(|i| (t[0][i] + t[1][i] + t[2][i]) / 3.0);
        for target in [t[0], t[1], t[2], mid(t[0], t[1]), centroid] {
            for o in [at([-2.5, 1.5, 2.0]), at([0.3, -0.2, 0.1])] {
                rays.push(Ray::new(o, [0, 1, 2].map(|i| target[i] - o[i])));
            }
        }
    }
    rays
}

/// Imports `bytes` as the file `name`; `external` serves every file it refers to. Asserts that an
/// imported scene holds what a bake relies on.
fn import_and_check(name: &str, bytes: &[u8], external: Option<&[u8]>) {
    let read_file = |_: &Path| match external {
        Some(b) => Ok(b.to_vec()),
        None => Err(io::Error::new(io::ErrorKind::NotFound, "the fuzz input holds no second file")),
    };
    let mut builder = SceneBuilder::new();
    let result = import_bytes(&mut builder, Path::new(name), bytes, &read_file).and_then(|()| builder.finish());
    match result {
        Ok(scene) => check_scene(&scene),
        Err(e) => {
            let _ = e.to_string();
        }
    }
}

/// The invariants of an imported scene that the bake and the field's sections depend on.
fn check_scene(scene: &Scene) {
    assert!(!scene.triangles.is_empty(), "an imported scene holds triangles");
    assert_eq!(scene.triangles.len(), scene.provenance.len());
    for t in &scene.triangles {
        let v = [t.vertex(0), t.vertex(1), t.vertex(2)];
        assert!(
            v.iter().flatten().all(|c| c.is_finite() && c.abs() as f64 <= 2.0 * vlf_bake::scene::MAX_COORDINATE),
            "{v:?}"
        );
        assert!(!vlf_geom::is_degenerate(v[0], v[1], v[2]), "a degenerate triangle was kept: {v:?}");
    }
    let string = |offset: u32, length: u32| {
        let end = offset as usize + length as usize;
        scene.strings.get(offset as usize..end).map(std::str::from_utf8)
    };
    for p in &scene.provenance {
        assert!((p.source as usize) < scene.sources.len(), "provenance names source {}", p.source);
    }
    for s in &scene.sources {
        assert!((s.input as usize) < scene.inputs.len());
        assert!(matches!(string(s.name_offset, s.name_length), Some(Ok(_))), "source name out of STRINGS");
    }
    let total: u64 = scene.inputs.iter().map(|i| i.triangle_count).sum();
    assert_eq!(total, scene.triangles.len() as u64, "input triangle counts do not add up");
    for i in &scene.inputs {
        assert!(matches!(string(i.name_offset, i.name_length), Some(Ok(_))), "input name out of STRINGS");
    }
}
