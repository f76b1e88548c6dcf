//! A field that passes the open checks but lies inside a section (the open checks cover the header
//! and table only; payload hashes are checked by `dump --verify`). Queries on it must never panic
//! or read out of bounds; they may return wrong answers, of a kind `docs/reliability.md` states:
//!
//! - [`queries_on_a_lying_field_never_panic`]: every payload section overwritten with zeros, ones,
//!   sparse and dense random bytes in turn, and a frame of rays traced;
//! - [`targeted_lies_deep_inside_sections`]: one value at a time made out of range (or wrong but in
//!   range) deep inside a section: a triangle id, a ref's box, a leaf's end or boundary, a block's
//!   leaf count, a TILES entry, a direction's BEAMS record, its rotation, its LOOKUP entry, the
//!   scene's radius, a triangle's vertices. Each answer
//!   must be *sound* (a hit is a real hit on a stored triangle, never closer than the true closest;
//!   an any-hit is a real hit) and each lie confined to the rays that use the lied-about direction;
//! - [`a_lying_direction_vector_changes_only_lattices_past_the_fine_table`]: DIRECTIONS, which
//!   only fields of more than 129 directions read.

#![forbid(unsafe_code)]

use vlf_bake::generate::Rng;
use vlf_bake::{DepthPolicy, Scene, generate};
use vlf_format::block::{Block, MAX_LEAVES, header_bytes};
use vlf_format::{BeamRecord, EMPTY_TILE, FieldReader, LOOKUP_FLIP, LOOKUP_NONE, SectionKind};
use vlf_geom::{BruteForce, Camera, Hit, Intersector, Ray, TriRay};
use vlf_runtime::Field;

#[test]
fn queries_on_a_lying_field_never_panic() {
    let scene = Scene::from_triangles("random", &generate::random_cube(400, 0.1, 4)).unwrap();
    let (dir, field) = vlf_tests::bake(&scene, 33, 16, DepthPolicy { leaf_size: 2, max_depth: 6 });
    let bytes = std::fs::read(dir.path().join("scene.vlf")).unwrap();
    let (c, r) = field.bounding_sphere();
    let mut rays = Camera::outside(c, r, 1.0).primary_rays(48, 48);
    rays.extend(Camera::inside(c, r, 1.0).primary_rays(48, 48));
    let mut rng = Rng::new(1);
    rays.extend((0..2000).map(|_| {
        let o = [rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)].map(|v| v as f32);
        let d = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)].map(|v| v as f32);
        Ray::new(o, d)
    }));

    let entries: Vec<_> = {
        let words = aligned(&bytes);
        let reader = FieldReader::new(bytemuck::cast_slice::<u64, u8>(&words).split_at(bytes.len()).0).unwrap();
        reader.table.to_vec()
    };
    let payload_kinds = [
        SectionKind::Directions,
        SectionKind::Rotations,
        SectionKind::Lookup,
        SectionKind::Beams,
        SectionKind::Tiles,
        SectionKind::Leaves,
        SectionKind::Triangles,
    ];
    let mut opened = 0;
    for kind in payload_kinds {
        let e = entries.iter().find(|e| e.kind == kind as u32).unwrap();
        for fill in 0..6u64 {
            let mut lying = bytes.clone();
            let section = &mut lying[e.offset as usize..(e.offset + e.stored_length) as usize];
            let mut rng = Rng::new(fill);
            for b in section.iter_mut() {
                *b = match fill {
                    0 => 0x00,
                    1 => 0xff,
                    // Sparse damage keeps most of the structure, so traversal goes deep.
                    2 | 3 => {
                        if rng.unit() < 0.05 {
                            rng.next_u64() as u8
                        } else {
                            *b
                        }
                    }
                    _ => rng.next_u64() as u8,
                };
            }
            let Ok(field) = Field::from_bytes(&lying) else { continue };
            opened += 1;
            for ray in &rays {
                let _ = field.closest_hit(ray);
                let _ = field.any_hit(ray);
            }
        }
    }
    assert_eq!(opened, payload_kinds.len() * 6, "payload damage is not an open-time error");
}

fn aligned(bytes: &[u8]) -> Vec<u64> {
    let mut words = vec![0u64; bytes.len().div_ceil(8)];
    bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
    words
}

/// Bytes to write at offsets.
type Edits = Vec<(usize, Vec<u8>)>;

/// One lie: byte edits, and the direction it is confined to (if it is).
struct Lie {
    what: &'static str,
    edits: Edits,
    direction: Option<usize>,
}

/// Checks that `got` (closest hit) and `any` (any-hit) of a field whose stored triangles are
/// `tris` (relative to `origin`) are sound for `ray`: a hit is the kernel's own hit on the stored
/// triangle it names, and no closer than the brute-force closest hit over all stored triangles; an
/// any-hit is a real hit.
fn assert_sound(what: &str, tris: &[[[f32; 3]; 3]], origin: [f64; 3], ray: &Ray, got: Option<Hit>, any: Option<Hit>) {
    let truth = BruteForce::relative(tris, origin).closest_hit(ray);
    for (kind, hit) in [("closest", got), ("any", any)] {
        let Some(h) = hit else { continue };
        let tri = tris
            .get(h.prim as usize)
            .unwrap_or_else(|| panic!("{what}: {kind} hit on triangle {} of {}", h.prim, tris.len()));
        let own = TriRay::relative(ray, origin).intersect(tri[0], tri[1], tri[2], ray.tmax);
        assert_eq!(
            own.map(|o| o.t.to_bits()),
            Some(h.t.to_bits()),
            "{what}: {kind} hit {h:?} is not a hit on its triangle for {ray:?}"
        );
        let best = truth.unwrap_or_else(|| panic!("{what}: {kind} hit {h:?} where brute force finds none, {ray:?}"));
        if kind == "closest" {
            assert!(h.t >= best.t, "{what}: closest hit {h:?} is closer than the true closest {best:?}, {ray:?}");
        }
    }
}

/// The ids of every leaf a ray visits, in order: the candidate set the query tests.
fn candidates(field: &Field, ray: &Ray) -> Vec<u32> {
    let mut out = Vec::new();
    field.view().for_each_leaf(ray, &mut (), |ids, _| {
        out.extend_from_slice(ids);
        false
    });
    out
}

fn put<T: bytemuck::Pod>(edits: &mut Edits, at: usize, value: T) {
    edits.push((at, bytemuck::bytes_of(&value).to_vec()));
}

/// A direction vector of NaNs in DIRECTIONS. Up to 129 directions the runtime picks a ray's
/// direction from its own table and never reads DIRECTIONS, so every answer stays the honest one;
/// past that it compares dot products with the stored vectors, and the rays along the lied-about
/// direction take another one, with sound answers.
#[test]
fn a_lying_direction_vector_changes_only_lattices_past_the_fine_table() {
    let scene = Scene::from_triangles("random", &generate::random_cube(400, 0.1, 4)).unwrap();
    for (directions, read) in [(33, false), (513, true)] {
        let (dir, honest) = vlf_tests::bake(&scene, directions, 8, DepthPolicy::default());
        let mut bytes = std::fs::read(dir.path().join("scene.vlf")).unwrap();
        let r = honest.reader();
        let j = r.directions.len() / 2 + 1;
        let w = r.directions[j];
        let at = r.entry(SectionKind::Directions).unwrap().offset as usize + 16 * j;
        bytes[at..at + 16].copy_from_slice(bytemuck::bytes_of(&[f32::NAN, f32::NAN, f32::NAN, 0.0]));
        let field = Field::from_bytes(&bytes).unwrap();
        let (c, radius) = honest.bounding_sphere();
        let tris = vlf_tests::stored_triangles(&field);
        // Rays along the direction, through the scene, and a frame from outside.
        let mut rays: Vec<Ray> = (0..64)
            .map(|i| {
                let o: [f32; 3] = std::array::from_fn(|k| {
                    (c[k] - 2.0 * radius * w[k] as f64 + 0.02 * radius * ((i * (k + 3)) % 17) as f64) as f32
                });
                Ray::new(o, [w[0], w[1], w[2]])
            })
            .collect();
        rays.extend(Camera::outside(c, radius, 1.0).primary_rays(24, 24));
        let mut changed = 0;
        for ray in &rays {
            let (got, any) = (field.closest_hit(ray), field.view().any_hit_counted(ray, &mut ()));
            assert_sound("a direction of NaNs", &tris, field.origin(), ray, got, any);
            changed += (candidates(&field, ray) != candidates(&honest, ray)) as usize;
        }
        if read {
            assert!(changed > 0, "{directions} directions: no ray reads the lying direction");
        } else {
            assert_eq!(changed, 0, "{directions} directions: a ray reads DIRECTIONS");
        }
    }
}

#[test]
fn targeted_lies_deep_inside_sections() {
    // Enough triangles that the fullest tile holds several leaves under the leaf heuristic (400
    // did until baker revision 6 made leaf visits dearer).
    let scene = Scene::from_triangles("random", &generate::random_cube(1500, 0.1, 4)).unwrap();
    let (dir, honest) = vlf_tests::bake(&scene, 33, 16, DepthPolicy { leaf_size: 2, max_depth: 6 });
    let bytes = std::fs::read(dir.path().join("scene.vlf")).unwrap();
    let r = honest.reader();
    let offset = |kind: SectionKind| r.entry(kind).unwrap().offset as usize;
    let (l, n) = (r.directions.len(), r.params.tile_resolution as usize);
    let t_count = r.triangles.len() as u32;

    // A direction near the end of the file's sections and its fullest tile: values deep inside
    // BEAMS, TILES and LEAVES, far from where each section starts.
    let j = l - 2;
    let beam: BeamRecord = r.beams[j];
    let tiles = &r.tiles[j * n * n..(j + 1) * n * n];
    let block_of = |entry: u32| Block::parse(&r.leaves[(beam.leaves_base + entry as u64) as usize..]).unwrap();
    let tile_index =
        (0..n * n).filter(|&i| tiles[i] != EMPTY_TILE).max_by_key(|&i| block_of(tiles[i]).ref_count()).unwrap();
    let entry = tiles[tile_index];
    let block = block_of(entry);
    assert!(block.leaf_count() > 1 && block.ref_count() > 4, "the test needs a full tile of several leaves");
    // The tile's first non-empty leaf and its first ref, and the byte offsets of everything lied
    // about.
    let k = (0..block.leaf_count()).find(|&k| !block.leaf(k).unwrap().is_empty()).unwrap();
    let leaf = block.leaf(k).unwrap();
    let kk = block.leaf_count();
    let block_at = offset(SectionKind::Leaves) + 8 * (beam.leaves_base + entry as u64) as usize;
    let bounds_at = block_at + 4;
    let ends_at = block_at + header_bytes(kk) - 4 * kk;
    let first_ref: usize = (0..k).map(|i| block.leaf(i).unwrap().len).sum();
    let leaf_at = block_at + header_bytes(kk) + 8 * first_ref;
    let id_at = leaf_at + 4 * leaf.len;
    let tile_at = offset(SectionKind::Tiles) + 4 * (j * n * n + tile_index);
    let beam_at = offset(SectionKind::Beams) + j * size_of::<BeamRecord>();
    let rotation_at = offset(SectionKind::Rotations) + j * 72;
    let lookup_index = r.lookup.iter().position(|&e| e != LOOKUP_NONE && (e & !LOOKUP_FLIP) as usize == j).unwrap();
    let lookup_at = offset(SectionKind::Lookup) + 4 * lookup_index;
    let victim = block.ids(leaf)[0];
    assert_eq!(u32::from_le_bytes(bytes[id_at..id_at + 4].try_into().unwrap()), victim, "the offsets are the layout's");
    for (what, at) in [("TILES", tile_at), ("LEAVES", id_at), ("BEAMS", beam_at)] {
        let e =
            r.table.iter().find(|e| (e.offset as usize..(e.offset + e.stored_length) as usize).contains(&at)).unwrap();
        assert!(at - e.offset as usize > e.stored_length as usize / 2, "{what}: the lie at {at} is not deep inside");
    }
    // Where each leaf's refs start, and how many it has.
    let leaf_starts: Vec<(usize, usize)> = (0..kk)
        .map(|i| {
            let before: usize = (0..i).map(|p| block.leaf(p).unwrap().len).sum();
            (block_at + header_bytes(kk) + 8 * before, block.leaf(i).unwrap().len)
        })
        .collect();
    let previous_entry = tiles[..tile_index].iter().rev().copied().find(|&e| e != EMPTY_TILE).unwrap();
    let bound = |i: usize| block.bounds()[i];

    let lies = {
        let mut lies = Vec::new();
        let mut lie = |what, direction: Option<usize>, edit: &dyn Fn(&mut Edits)| {
            let mut edits = Vec::new();
            edit(&mut edits);
            lies.push(Lie { what, edits, direction });
        };
        let d = Some(j);
        lie("a triangle id equal to triangle_count", d, &|e| put(e, id_at, t_count));
        lie("a triangle id of u32::MAX", d, &|e| put(e, id_at, u32::MAX));
        lie("a wrong triangle id in range", d, &|e| put(e, id_at, (victim + 1) % t_count));
        lie("every box of a tile turned inside out", d, &|e| {
            for (at, len) in &leaf_starts {
                e.push((*at, vec![255u8; *len]));
            }
        });
        lie("every box of a tile emptied", d, &|e| {
            for (at, len) in &leaf_starts {
                e.push((*at, vec![255u8; 2 * *len]));
            }
        });
        lie("a leaf's end of u32::MAX", d, &|e| put(e, ends_at + 4 * k, u32::MAX));
        lie("leaf ends that decrease", d, &|e| put(e, ends_at, u32::MAX - 1));
        lie("a block's leaf count above the limit", d, &|e| put(e, block_at, MAX_LEAVES + 1));
        lie("a block's leaf count at the limit", d, &|e| put(e, block_at, MAX_LEAVES));
        lie("a block of no leaf", d, &|e| put(e, block_at, 0u32));
        lie("a block's z range inverted", d, &|e| {
            put(e, bounds_at, bound(kk));
            put(e, bounds_at + 2 * kk, bound(0));
        });
        lie("leaf boundaries out of order", d, &|e| put(e, bounds_at + 2, u16::MAX));
        lie("a block's z range shrunk to one level", d, &|e| put(e, bounds_at + 2 * kk, bound(0) + 1));
        lie("a TILES entry past the end of LEAVES", d, &|e| put(e, tile_at, EMPTY_TILE - 1));
        lie("a TILES entry pointing at the previous tile's block", d, &|e| put(e, tile_at, previous_entry));
        lie("a TILES entry pointing into the middle of a block", d, &|e| put(e, tile_at, entry + 1));
        lie("BEAMS leaves_base of u64::MAX", d, &|e| put(e, beam_at, u64::MAX));
        lie("BEAMS leaves_base pointing at the previous direction", d, &|e| {
            put(e, beam_at, r.beams[j - 1].leaves_base)
        });
        lie("a rotation of NaNs", d, &|e| put(e, rotation_at, [f64::NAN; 9]));
        lie("a rotation of zeros", d, &|e| put(e, rotation_at, [0.0f64; 9]));
        lie("a rotation turned upside down", d, &|e| {
            let m = r.rotations[j];
            put(e, rotation_at, [m[0], m[1], m[2], -m[3], -m[4], -m[5], -m[6], -m[7], -m[8]]);
        });
        lie("a LOOKUP entry one past the last direction", None, &|e| put(e, lookup_at, l as u32));
        lie("a LOOKUP entry of 2^31 - 1", None, &|e| put(e, lookup_at, LOOKUP_FLIP - 1));
        lie("a LOOKUP entry erased", None, &|e| put(e, lookup_at, LOOKUP_NONE));
        lie("the scene's radius halved", None, &|e| put(e, offset(SectionKind::Scene) + 24, r.scene.radius / 2.0));
        lie("the scene's box shrunk to a point", None, &|e| put(e, offset(SectionKind::Scene) + 32, [0.0f64; 6]));
        lie("a triangle's vertices of NaNs", None, &|e| {
            put(e, offset(SectionKind::Triangles) + 36 * victim as usize, [f32::NAN; 9])
        });
        lie("a triangle moved far away", None, &|e| {
            put(e, offset(SectionKind::Triangles) + 36 * victim as usize, [1e6f32; 9])
        });
        lies
    };

    // Rays along direction j through the damaged tile (exactly parallel, and tilted within the
    // tile), both ways, then rays in every direction.
    let (c, radius) = honest.bounding_sphere();
    let m = r.rotations[j];
    let w = 2.0 * radius / n as f64;
    let (s, t) = ((tile_index % n) as f64, (tile_index / n) as f64);
    let mut rng = Rng::new(7);
    let mut rays = Vec::new();
    for i in 0..64 {
        let p = [-radius + (s + rng.range(0.05, 0.95)) * w, -radius + (t + rng.range(0.05, 0.95)) * w, -1.5 * radius];
        let world: [f64; 3] = std::array::from_fn(|a| c[a] + m[a] * p[0] + m[3 + a] * p[1] + m[6 + a] * p[2]);
        let tilt = if i % 2 == 0 { 0.0 } else { rng.range(-0.2, 0.2) * w / radius };
        let d = [m[6] + tilt * m[0], m[7] + tilt * m[1], m[8] + tilt * m[2]];
        let ray = Ray::new(world.map(|v| v as f32), d.map(|v| v as f32));
        // The same line travelled the other way, from beyond the scene.
        let far: [f64; 3] = std::array::from_fn(|a| world[a] + 3.0 * radius * d[a]);
        rays.push(ray);
        rays.push(Ray::new(far.map(|v| v as f32), d.map(|v| -v as f32)));
    }
    // Rays along direction j straight at the victim triangle (the first ref of the leaf lied
    // about), which a lie about its id or box must change for some of them.
    let victim_world = honest.triangle(victim).unwrap();
    for i in 0..16 {
        let (a, b) = (rng.range(0.1, 0.4), rng.range(0.1, 0.4));
        let p: [f64; 3] = std::array::from_fn(|k| {
            victim_world[0][k]
                + a * (victim_world[1][k] - victim_world[0][k])
                + b * (victim_world[2][k] - victim_world[0][k])
        });
        let d = if i % 2 == 0 { [m[6], m[7], m[8]] } else { [-m[6], -m[7], -m[8]] };
        let start: [f64; 3] = std::array::from_fn(|k| p[k] - 1e-3 * radius * d[k]);
        rays.push(Ray::new(start.map(|v| v as f32), d.map(|v| v as f32)));
    }
    let targeted = rays.len();
    assert!(rays.iter().all(|ray| honest.view().select_direction(ray.dir.map(f64::from)).unwrap().0 == j));
    rays.extend(Camera::outside(c, radius, 1.0).primary_rays(32, 32));
    rays.extend(Camera::inside(c, radius, 1.0).primary_rays(32, 32));

    let mut lying = bytes.clone();
    for lie in &lies {
        let started = std::time::Instant::now();
        lying.copy_from_slice(&bytes);
        for (at, value) in &lie.edits {
            lying[*at..*at + value.len()].copy_from_slice(value);
        }
        let field = Field::from_bytes(&lying).unwrap_or_else(|e| panic!("{}: the lie does not open: {e}", lie.what));
        let tris = vlf_tests::stored_triangles(&field);
        let origin = field.origin();
        let mut touched = 0;
        for (i, ray) in rays.iter().enumerate() {
            let got = field.closest_hit(ray);
            let any = field.view().any_hit_counted(ray, &mut ());
            assert_eq!(field.any_hit(ray), any.is_some(), "{}", lie.what);
            assert_sound(lie.what, &tris, origin, ray, got, any);
            let seen = candidates(&field, ray);
            let confined =
                lie.direction.is_some_and(|d| honest.view().select_direction(ray.dir.map(f64::from)).unwrap().0 != d);
            if confined {
                assert_eq!(seen, candidates(&honest, ray), "{}: a ray of another direction sees the lie", lie.what);
                assert_eq!(
                    got,
                    honest.closest_hit(ray),
                    "{}: a ray of another direction answers differently",
                    lie.what
                );
            }
            if i < targeted && (seen != candidates(&honest, ray) || got != honest.closest_hit(ray)) {
                touched += 1;
            }
        }
        assert!(touched > 0, "{}: no targeted ray reaches the lie", lie.what);
        println!(
            "{}: {touched} of {targeted} targeted rays see a different candidate set or answer ({:?})",
            lie.what,
            started.elapsed()
        );
    }
}
