//! One field, many users at once:
//!
//! - many threads querying one `Field` give, ray for ray and bit for bit, the answers of one
//!   thread;
//! - the mapping contract (`Field::open`), tested in a child process because its failure mode is a
//!   signal: a field modified in place while mapped shows the new bytes to the mapping at once,
//!   and queries then give different answers without crashing; a field truncated while mapped
//!   kills the process that touches it with `SIGBUS`.
//!
//! Replacing a mapped field the way `vlf-bake` does (a rename) is tested through the real command
//! line in `crates/vlf-bake/tests/reliability.rs`.

#![forbid(unsafe_code)]

use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};
use vlf_bake::generate::Rng;
use vlf_bake::{DepthPolicy, Scene, generate};
use vlf_geom::{Camera, Hit, Ray};
use vlf_runtime::Field;

fn scene() -> Scene {
    Scene::from_triangles("random", &generate::random_cube(3000, 0.1, 11)).unwrap()
}

/// A frame from outside and inside plus random rays.
fn rays(field: &Field, random: usize) -> Vec<Ray> {
    let (c, r) = field.bounding_sphere();
    let mut rays = Camera::outside(c, r, 1.0).primary_rays(64, 64);
    rays.extend(Camera::inside(c, r, 1.0).primary_rays(64, 64));
    let mut rng = Rng::new(5);
    rays.extend((0..random).map(|_| {
        let o = [rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)].map(|v| v as f32);
        let d = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)].map(|v| v as f32);
        Ray::new(o, d)
    }));
    rays
}

/// A hit as comparable bits.
fn bits(h: Option<Hit>) -> Option<[u32; 4]> {
    h.map(|h| [h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()])
}

#[test]
fn many_threads_on_one_field_answer_as_one_thread() {
    let (_dir, field) = vlf_tests::bake(&scene(), 129, 32, DepthPolicy::default());
    let rays = rays(&field, 8000);
    let closest: Vec<_> = rays.iter().map(|r| bits(field.closest_hit(r))).collect();
    let any: Vec<bool> = rays.iter().map(|r| field.any_hit(r)).collect();
    assert!(closest.iter().filter(|h| h.is_some()).count() > rays.len() / 4, "too few hits to compare");

    // Eight threads at once, each walking the rays in its own order, so that different threads
    // query different parts of the field at the same moment.
    const THREADS: usize = 8;
    std::thread::scope(|scope| {
        for t in 0..THREADS {
            let (field, rays, closest, any) = (&field, &rays, &closest, &any);
            scope.spawn(move || {
                let n = rays.len();
                for k in 0..n {
                    let i = if t % 2 == 0 { (k * (2 * t + 1) + t * 997) % n } else { n - 1 - (k + t * 131) % n };
                    assert_eq!(bits(field.closest_hit(&rays[i])), closest[i], "thread {t}, ray {i}: closest hit");
                    assert_eq!(field.any_hit(&rays[i]), any[i], "thread {t}, ray {i}: any hit");
                }
            });
        }
    });

    // The batch entry points on rayon's pool agree too.
    let mut hits = vec![Hit::MISS; rays.len()];
    field.par_closest_hits(&rays, &mut hits);
    let mut shadows = vec![false; rays.len()];
    field.par_any_hits(&rays, &mut shadows);
    for i in 0..rays.len() {
        assert_eq!(bits(Some(hits[i])).filter(|b| b[1] != u32::MAX), closest[i], "par_closest_hits, ray {i}");
        assert_eq!(shadows[i], any[i], "par_any_hits, ray {i}");
    }
}

/// The child side of the mapping tests (run only by them, in a separate process): maps the field
/// named by `VLF_MAPPED_FIELD`, traces rays and prints a checksum of the answers, says `ready`,
/// waits for a line on standard input (the parent changes the file meanwhile), then traces the
/// same rays again, reads every byte of the mapping, and prints the new checksum.
#[test]
#[ignore = "run by the mapping tests in a child process"]
fn mapped_field_child() {
    let Some(path) = std::env::var_os("VLF_MAPPED_FIELD") else {
        eprintln!("mapped_field_child: VLF_MAPPED_FIELD is not set; this is the child of the mapping tests");
        return;
    };
    let field = Field::open(&path).unwrap();
    let rays = rays(&field, 2000);
    let checksum = |field: &Field| {
        let answers: Vec<_> = rays.iter().map(|r| bits(field.closest_hit(r))).collect();
        let mut h = std::hash::DefaultHasher::new();
        std::hash::Hash::hash(&answers, &mut h);
        format!("{:016x}", std::hash::Hasher::finish(&h))
    };
    println!("before {}", checksum(&field));
    println!("ready");
    std::io::stdout().flush().unwrap();
    let mut line = String::new();
    std::io::stdin().read_line(&mut line).unwrap();
    let after = checksum(&field);
    let sum = field.reader().bytes.iter().fold(0u64, |a, &b| a.wrapping_add(b as u64));
    println!("after {after} bytes {sum}");
}

/// Runs [`mapped_field_child`] on `path`, lets `change` alter the file once the child has mapped
/// it and answered once, and returns the child's exit status and output.
fn with_mapped_child(path: &std::path::Path, change: impl FnOnce()) -> (std::process::ExitStatus, String) {
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args(["mapped_field_child", "--exact", "--ignored", "--nocapture", "--test-threads=1"])
        .env("VLF_MAPPED_FIELD", path)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut output = String::new();
    loop {
        let mut line = String::new();
        assert!(stdout.read_line(&mut line).unwrap() > 0, "the child ended before it was ready:\n{output}");
        output.push_str(&line);
        if line.trim() == "ready" {
            break;
        }
    }
    change();
    child.stdin.take().unwrap().write_all(b"go\n").unwrap();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stdout, &mut rest).unwrap();
    output.push_str(&rest);
    (child.wait().unwrap(), output)
}

/// The word after `label` in the child's output (libtest may print its own words on the same line).
fn checksum(output: &str, label: &str) -> String {
    let mut words = output.split_whitespace().skip_while(|w| *w != label);
    words.nth(1).unwrap_or_else(|| panic!("no `{label}` in:\n{output}")).to_string()
}

#[cfg(unix)]
#[test]
fn a_field_modified_in_place_while_mapped_answers_differently_without_crashing() {
    use std::os::unix::fs::FileExt;
    let (dir, field) = vlf_tests::bake(&scene(), 33, 16, DepthPolicy::default());
    let path = dir.path().join("scene.vlf");
    let ids = *field.reader().entry(vlf_format::SectionKind::Leaves).unwrap();
    drop(field);
    let (status, output) = with_mapped_child(&path, || {
        // Another program overwrites LEAVES in place, keeping the length.
        let mut rng = Rng::new(3);
        let noise: Vec<u8> = (0..ids.stored_length).map(|_| rng.next_u64() as u8).collect();
        let file = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
        file.write_all_at(&noise, ids.offset).unwrap();
    });
    assert!(status.success(), "the child crashed ({status}):\n{output}");
    assert_ne!(checksum(&output, "before"), checksum(&output, "after"), "the mapping did not see the change");
}

#[cfg(unix)]
#[test]
fn a_field_truncated_while_mapped_kills_the_process_that_touches_it_with_sigbus() {
    use std::os::unix::process::ExitStatusExt;
    let (dir, field) = vlf_tests::bake(&scene(), 33, 16, DepthPolicy::default());
    let path = dir.path().join("scene.vlf");
    drop(field);
    let (status, output) = with_mapped_child(&path, || {
        std::fs::OpenOptions::new().write(true).open(&path).unwrap().set_len(0).unwrap();
    });
    // SIGBUS is 7 on Linux and 10 on the BSDs and macOS.
    let sigbus = if cfg!(target_os = "linux") { 7 } else { 10 };
    assert_eq!(status.signal(), Some(sigbus), "expected SIGBUS, got {status}:\n{output}");
    assert!(!output.contains("after"), "{output}");
}
