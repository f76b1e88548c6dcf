//! The sections of format 1.1 that carry what a renderer needs (MATERIALS, CAMERAS, LIGHTS,
//! `formats/vlf.md` §5.10–5.12): a 1.0 field still reads, full verification rejects every record
//! that breaks a rule (each case rewritten with valid hashes, so only the rule can catch it), a
//! flipped byte is caught, and lying records never make the runtime or the renderer panic.

#![forbid(unsafe_code)]

use vlf_bake::{DepthPolicy, MaterialDesc, SceneBuilder, SourceDesc, generate};
use vlf_format::{CameraRecord, LightRecord, SectionKind, camera_kind, light_kind};
use vlf_runtime::{CameraProjection, Field, LightKind};

/// The optional sections a renderer reads.
const RENDERING: [SectionKind; 3] = [SectionKind::Materials, SectionKind::Cameras, SectionKind::Lights];

/// A box with one material, plus a camera and a spot light: a few KiB.
fn field_bytes() -> Vec<u8> {
    let mut b = SceneBuilder::new();
    let input = b.begin_input("box.gltf", [7; 32]);
    let source = b.add_source(input, SourceDesc { material: 1, ..SourceDesc::program("box") });
    for (i, t) in generate::closed_box([0.0; 3], [1.0, 2.0, 3.0]).into_iter().enumerate() {
        b.push_triangle(source, i as u64, t.map(|v| v.map(f64::from))).unwrap();
    }
    let plain = MaterialDesc {
        name: "plain".into(),
        diffuse: [0.5; 3],
        shininess: 1.0,
        specular: [0.0; 3],
        ior: 1.0,
        reflection: [0.0; 3],
        transmission: [0.0; 3],
        emission: [0.0; 3],
    };
    b.add_material(input, 0, &plain);
    b.add_material(input, 1, &MaterialDesc { name: "glass".into(), transmission: [0.9; 3], ior: 1.5, ..plain.clone() });
    b.add_camera(
        "cam",
        CameraRecord {
            kind: camera_kind::PERSPECTIVE,
            input,
            camera: 0,
            node: 1,
            name_offset: 0,
            name_length: 0,
            position: [0.5, 1.0, 10.0],
            forward: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            yfov: 0.5,
            aspect_ratio: 1.5,
            znear: 0.1,
            zfar: 0.0,
            xmag: 0.0,
            ymag: 0.0,
            reserved: 0,
        },
    );
    b.add_light(
        "spot",
        LightRecord {
            kind: light_kind::SPOT,
            input,
            light: 0,
            node: 2,
            name_offset: 0,
            name_length: 0,
            position: [0.5, 5.0, 1.5],
            direction: [0.0, -1.0, 0.0],
            color: [1.0, 0.9, 0.8],
            intensity: 20.0,
            range: 0.0,
            inner_cone: 0.3,
            outer_cone: 0.6,
            reserved: 0,
        },
    );
    let scene = b.finish().unwrap();
    let (dir, _) = vlf_tests::bake(&scene, 3, 2, DepthPolicy { leaf_size: 2, max_depth: 3 });
    std::fs::read(dir.path().join("scene.vlf")).unwrap()
}

fn open(bytes: &[u8]) -> Field {
    Field::from_bytes(bytes).unwrap()
}

fn verify(bytes: &[u8]) -> Result<(), String> {
    let field = Field::from_bytes(bytes).map_err(|e| e.to_string())?;
    vlf_bake::inspect::verify(field.reader(), &mut |_, _| {}).map(|_| ()).map_err(|e| e.to_string())
}

/// The table index, offset and length of section `kind`.
fn section(bytes: &[u8], kind: SectionKind) -> (usize, usize, usize) {
    let field = open(bytes);
    let (i, e) = field.reader().table.iter().enumerate().find(|(_, e)| e.kind == kind as u32).unwrap();
    (i, e.offset as usize, e.stored_length as usize)
}

/// Rewrites the bytes of section `kind` with `edit`, then its table hash and the content hash, so
/// the file is consistent except for what `edit` did.
fn edited(bytes: &[u8], kind: SectionKind, edit: impl FnOnce(&mut [u8])) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let (i, offset, len) = section(bytes, kind);
    edit(&mut out[offset..offset + len]);
    let hash = *blake3::hash(&out[offset..offset + len]).as_bytes();
    let entry = 128 + 72 * i;
    out[entry + 40..entry + 72].copy_from_slice(&hash);
    rehash_header(&mut out);
    out
}

fn rehash_header(bytes: &mut [u8]) {
    let count = u32::from_le_bytes(bytes[32..36].try_into().unwrap()) as usize;
    let hash = vlf_format::content_hash(&bytes[..128 + 72 * count]);
    bytes[48..80].copy_from_slice(&hash);
}

#[test]
fn the_runtime_reads_materials_cameras_and_lights() {
    let bytes = field_bytes();
    verify(&bytes).unwrap();
    let field = open(&bytes);
    assert_eq!(field.materials().map(|m| m.name).collect::<Vec<_>>(), ["plain", "glass"]);
    let glass = field.material(0).unwrap();
    assert_eq!((glass.name, glass.ior, glass.transmission), ("glass", 1.5, [0.9; 3]));
    assert_eq!(field.material_index(11), Some(1));
    assert_eq!(field.material_index(12), None, "out of range");
    let cameras: Vec<_> = field.cameras().collect();
    assert_eq!(cameras.len(), 1);
    assert_eq!(cameras[0].projection, CameraProjection::Perspective { yfov: 0.5, aspect_ratio: Some(1.5) });
    assert_eq!((cameras[0].name, cameras[0].zfar, cameras[0].node), ("cam", None, 1));
    let lights: Vec<_> = field.lights().collect();
    assert_eq!(lights[0].kind, LightKind::Spot { inner_cone: 0.3, outer_cone: 0.6 });
    assert_eq!((lights[0].name, lights[0].range), ("spot", None));
}

/// The rendering sections are optional: a field baked from inputs that define no material,
/// camera or light holds none of them, opens, verifies, and has no materials, cameras or lights.
#[test]
fn a_field_without_the_optional_sections_reads_as_one_without_materials() {
    let scene = vlf_bake::import::import_paths(&[vlf_tests::fixtures().join("meshes/small/groups.obj")]).unwrap();
    assert_eq!(scene.materials.len(), 2, "groups.obj has two materials");
    let without = vlf_bake::Scene { materials: Vec::new(), ..scene };
    let (dir, _) = vlf_tests::bake(&without, 3, 2, DepthPolicy { leaf_size: 2, max_depth: 3 });
    let bytes = std::fs::read(dir.path().join("scene.vlf")).unwrap();
    verify(&bytes).unwrap();
    let field = open(&bytes);
    for kind in RENDERING {
        assert!(field.reader().entry(kind).is_none(), "{} written although empty", kind.name());
    }
    assert!(field.reader().entry(SectionKind::Materials).is_none());
    // The sources still name material indices; without records, every triangle gets the default.
    assert_eq!(field.provenance(0).unwrap().material, Some(0));
    assert_eq!(
        (field.materials().len(), field.material(0), field.cameras().count(), field.lights().count()),
        (0, None, 0, 0)
    );
}

#[test]
fn verification_rejects_every_broken_rule_naming_the_section() {
    use std::mem::offset_of;
    use vlf_format::MaterialRecord as M;
    let bytes = field_bytes();
    let f32_at = |at: usize, v: f32| move |s: &mut [u8]| s[at..at + 4].copy_from_slice(&v.to_le_bytes());
    let u32_at = |at: usize, v: u32| move |s: &mut [u8]| s[at..at + 4].copy_from_slice(&v.to_le_bytes());
    let m2 = size_of::<M>(); // the second material's offset
    type Edit = Box<dyn FnOnce(&mut [u8])>;
    let cases: Vec<(SectionKind, &str, Edit)> = vec![
        (SectionKind::Materials, "input 9 out of range", Box::new(u32_at(offset_of!(M, input), 9))),
        (SectionKind::Materials, "not greater than the previous", Box::new(u32_at(m2 + offset_of!(M, index), 0))),
        (SectionKind::Materials, "name is out of bounds", Box::new(u32_at(offset_of!(M, name_length), 999))),
        (SectionKind::Materials, "not finite", Box::new(f32_at(offset_of!(M, diffuse), f32::NAN))),
        (SectionKind::Materials, "negative", Box::new(f32_at(offset_of!(M, emission) + 4, -1.0))),
        (SectionKind::Materials, "negative", Box::new(f32_at(offset_of!(M, ior), 0.0))),
        (SectionKind::Materials, "reserved", Box::new(u32_at(offset_of!(M, reserved1), 1))),
        (SectionKind::Cameras, "unknown kind 7", Box::new(u32_at(offset_of!(CameraRecord, kind), 7))),
        (SectionKind::Cameras, "not a unit vector", Box::new(f32_at(offset_of!(CameraRecord, forward) + 8, -2.0))),
        (SectionKind::Cameras, "do not fit its kind", Box::new(f32_at(offset_of!(CameraRecord, yfov), 3.5))),
        (SectionKind::Cameras, "do not fit its kind", Box::new(f32_at(offset_of!(CameraRecord, xmag), 1.0))),
        (SectionKind::Cameras, "not finite", Box::new(f32_at(offset_of!(CameraRecord, position), f32::INFINITY))),
        (SectionKind::Lights, "unknown kind 0", Box::new(u32_at(offset_of!(LightRecord, kind), 0))),
        (SectionKind::Lights, "cone angles", Box::new(f32_at(offset_of!(LightRecord, inner_cone), 0.7))),
        (SectionKind::Lights, "negative", Box::new(f32_at(offset_of!(LightRecord, intensity), -3.0))),
        (SectionKind::Lights, "input 5 out of range", Box::new(u32_at(offset_of!(LightRecord, input), 5))),
        (SectionKind::Lights, "reserved", Box::new(u32_at(offset_of!(LightRecord, reserved), 2))),
    ];
    for (kind, says, edit) in cases {
        let broken = edited(&bytes, kind, edit);
        let e = verify(&broken).expect_err(says);
        assert!(e.contains(kind.name()) && e.contains(says), "{}: expected {says:?}, got {e}", kind.name());
    }
}

#[test]
fn a_flipped_byte_in_the_rendering_sections_is_caught() {
    let bytes = field_bytes();
    for kind in RENDERING {
        let (_, offset, len) = section(&bytes, kind);
        for at in offset..offset + len {
            let mut damaged = bytes.clone();
            damaged[at] ^= 0x10;
            assert!(verify(&damaged).is_err(), "{}: a flip at {at} was not caught", kind.name());
        }
    }
}

/// Records full of junk (and hashes that agree, as a careless writer would make them): the
/// accessors and the renderer answer something and never panic.
#[test]
fn lying_records_never_make_the_runtime_or_the_renderer_panic() {
    let bytes = field_bytes();
    let mut rng = vlf_bake::generate::Rng::new(3);
    for round in 0..40 {
        let mut lying = bytes.clone();
        for kind in RENDERING {
            lying = edited(&lying, kind, |s| {
                for b in s.iter_mut() {
                    *b = match round % 4 {
                        0 => 0xff,
                        1 => rng.next_u64() as u8,
                        2 if rng.unit() < 0.1 => rng.next_u64() as u8,
                        _ => *b ^ ((rng.unit() < 0.05) as u8 * 0x40),
                    };
                }
            });
        }
        let field = open(&lying);
        for prim in 0..14 {
            let _ = field.material(prim);
        }
        let cameras: Vec<_> = field.cameras().collect();
        let lights: Vec<_> = field.lights().filter_map(|l| vlf_render::Light::from_scene_light(&l)).collect();
        let scene = vlf_render::Scene::from_field(&field, &vlf_render::SceneOptions::default());
        let settings = vlf_render::Settings { width: 12, height: 9, samples: 1, ..Default::default() };
        let bounds = vlf_render::SceneBounds::of(&field);
        let view = cameras
            .first()
            .and_then(|c| vlf_render::View::from_scene_camera(c, 12.0 / 9.0))
            .unwrap_or_else(|| vlf_render::View::outside(&bounds, 12.0 / 9.0));
        let frame = vlf_render::render(&field, &scene, &view, &lights, &settings, &|_| {});
        let _ = vlf_render::to_srgb8(&frame, 1.0);
    }
}
