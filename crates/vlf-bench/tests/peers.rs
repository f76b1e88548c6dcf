//! `vlf-bench peers` on a tiny scene, so the harness cannot rot: every contestant compiled in
//! answers every ray set, the field and the kd-tree agree with the brute force bit for bit, the
//! peers with their own triangle tests agree up to rounding, and the report is written and can be
//! rewritten from its JSON.

use vlf_bench::peers::KdChoice;
use vlf_bench::peers::report::Report;
use vlf_bench::peers::scenes::{SceneSpec, SizeRule};
use vlf_bench::peers::{PeersConfig, run};

fn config(dir: &std::path::Path) -> PeersConfig {
    PeersConfig {
        // 400 triangles of half-extent 0.14 (the density rule): most primary rays hit something.
        scenes: vec![SceneSpec::Random { triangles: 400, rule: SizeRule::Density }],
        work: dir.join("work"),
        out: dir.join("out"),
        resolution: 24,
        incoherent: 600,
        repeats: 3,
        threads: vec![1, 2],
        check_rays: 100,
        check_all_below: 1_000,
        t_tolerance: 1e-4,
        kd: KdChoice::Default,
        sweep: vec![(9, 8)],
        keep_fields: false,
        command: "vlf-bench peers (test)".into(),
        verbose: false,
        quick: true,
    }
}

fn run_tiny() -> Report {
    let dir = tempfile::tempdir().unwrap();
    let cfg = config(dir.path());
    let report = run(&cfg).expect("the field agrees with the brute force");
    // The report is on disk, and rewriting it from its JSON gives the same page.
    let md = std::fs::read_to_string(cfg.out.join("peers.md")).unwrap();
    for section in
        ["## Speed (Mrays/s)", "## Builds and sizes", "## Hits against the brute force", "## Speed against field size"]
    {
        assert!(md.contains(section), "{section} missing:\n{md}");
    }
    assert!(cfg.out.join("peers-size-random-400-density.svg").exists());
    assert!(cfg.out.join("peers-ratio-2t.svg").exists());
    let again: Report = serde_json::from_str(&std::fs::read_to_string(cfg.out.join("peers.json")).unwrap()).unwrap();
    let out2 = dir.path().join("again");
    again.write(&out2).unwrap();
    assert_eq!(std::fs::read_to_string(out2.join("peers.md")).unwrap(), md);
    // Baked fields are deleted after use.
    assert_eq!(std::fs::read_dir(&cfg.work).unwrap().count(), 0);
    report
}

#[test]
fn every_contestant_answers_and_the_exact_ones_match_the_brute_force() {
    let report = run_tiny();
    let scene = &report.scenes[0];
    let names: Vec<&str> = scene.built.iter().map(|b| b.contestant.as_str()).collect();
    assert_eq!(names, report.contestants.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(names.contains(&"field") && names.contains(&"field batch") && names.contains(&"kd-tree"));
    let sets: Vec<&str> = scene.sets.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(sets, ["outside", "inside", "incoherent", "shadow-outside", "shadow-inside"]);
    for set in &scene.sets {
        assert!(set.rays > 0 && set.hits > 0, "{}: {} rays, {} hits", set.name, set.rays, set.hits);
        // Every contestant at both thread counts, with a rate.
        assert_eq!(set.speeds.len(), 2 * names.len());
        assert!(set.speeds.iter().all(|s| s.mrays_per_s > 0.0 && s.mrays_per_s.is_finite()));
        // Three rounds: every contestant ran once in each, so the field pairs with each peer.
        assert!(set.speeds.iter().all(|s| s.runs_s.len() == 3), "{:?}", set.speeds);
        for c in &names[1..] {
            for t in [1, 2] {
                let r = vlf_bench::peers::rounds::paired_ratios(set, "field", c, t).unwrap();
                assert_eq!(r.len(), 3);
                assert!(r.iter().all(|x| x.is_finite() && *x > 0.0), "{c}: {r:?}");
            }
        }
        for c in &set.checks {
            // Below check_all_below: every ray is checked.
            assert_eq!(c.rays, set.rays);
            if c.contestant.starts_with("field") || c.contestant == "kd-tree" {
                assert_eq!(c.inexact(), 0, "{} / {}: {c:?}", set.name, c.contestant);
            } else {
                // Embree and obvhs test triangles their own way (f32 Möller–Trumbore): `t`
                // within rounding on nearly every ray, hit-or-miss differences only on the odd
                // ray that grazes an edge.
                assert!(c.wrong() * 100 <= c.rays, "{} / {}: {c:?}", set.name, c.contestant);
            }
        }
    }
    assert_eq!(scene.sweep.len(), 1);
    assert_eq!((scene.sweep[0].field.directions, scene.sweep[0].field.tiles), (9, 8));
}

/// Embree through the shim: built, measured, and answering like the brute force up to rounding.
#[cfg(feature = "embree")]
#[test]
fn embree_is_built_measured_and_checked() {
    let report = run_tiny();
    let scene = &report.scenes[0];
    let built = scene.built.iter().find(|b| b.contestant == "embree").expect("embree is a contestant");
    // The memory monitor saw at least the vertex buffer (3 float3 per triangle).
    assert!(built.bytes >= 400 * 36, "{built:?}");
    assert!(built.build_s > 0.0);
    for set in &scene.sets {
        let c = set.checks.iter().find(|c| c.contestant == "embree").unwrap();
        assert_eq!(c.rays, set.rays);
        assert!(c.same + c.ties + c.t_close > 0, "{} / embree: {c:?}", set.name);
        assert!(c.wrong() * 100 <= c.rays, "{} / embree: {c:?}", set.name);
        assert!(set.mrays("embree", 1).is_some() && set.mrays("embree", 2).is_some());
    }
}
