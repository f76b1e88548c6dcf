//! A field that passes the open checks but lies inside a section (the open checks cover the header
//! and table only; payload hashes are checked by `dump --verify`). Queries on it must never panic
//! or read out of bounds; they may return wrong answers. Every payload section is overwritten with
//! random bytes, all-zero and all-one bytes in turn, and a frame of rays is traced.

use vlf_bake::generate::Rng;
use vlf_bake::{DepthPolicy, Scene, generate};
use vlf_format::{FieldReader, SectionKind};
use vlf_geom::{Camera, Ray};
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
        SectionKind::LeafBounds,
        SectionKind::TriangleIds,
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
