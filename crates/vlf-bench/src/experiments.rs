//! Figures 3 and 4 and the parameter study.

use crate::plot::{Series, line_chart};
use crate::{Settings, Skipped, Timing, bake, disagreements, mean_cv, measure, write_output};
use serde::Serialize;
use std::fmt::Write as _;
use std::time::Instant;
use vlf_bake::generate::{DEFAULT_TRIANGLE_SIZE, random_cube};
use vlf_bake::{BakeConfig, DepthPolicy, Scene};
use vlf_geom::TraceStats;
use vlf_geom::{Camera, Ray};
use vlf_kdtree::{KdParams, KdTree};

/// The paper's scene: `n` random triangles in `[-1, 1]³` (seed 1).
pub fn paper_scene(n: usize) -> Scene {
    Scene::from_triangles(&format!("random-{n}"), &random_cube(n, DEFAULT_TRIANGLE_SIZE, 1)).expect("random triangles")
}

/// The two viewpoints of Figure 3.
pub fn views(scene_center: [f64; 3], radius: f64, resolution: u32) -> [(&'static str, Vec<Ray>); 2] {
    [
        ("outside", Camera::outside(scene_center, radius, 1.0).primary_rays(resolution, resolution)),
        ("inside", Camera::inside(scene_center, radius, 1.0).primary_rays(resolution, resolution)),
    ]
}

fn bounding_sphere(tris: &[[[f32; 3]; 3]]) -> ([f64; 3], f64) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in tris.iter().flatten() {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k] as f64);
            hi[k] = hi[k].max(v[k] as f64);
        }
    }
    let c = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    let r = tris
        .iter()
        .flatten()
        .map(|v| (0..3).map(|k| (v[k] as f64 - c[k]).powi(2)).sum::<f64>())
        .fold(0.0, f64::max)
        .sqrt();
    (c, r)
}

/// A tuned kd-tree: the best (depth, leaf size) of a sweep, timed on a small frame from both views.
pub struct TunedKd {
    pub tree: KdTree,
    pub params: KdParams,
    pub build_s: f64,
    pub sweep: Vec<(KdParams, f64)>,
}

/// The sweep stops deepening a tree once it holds more references than this per triangle:
/// spatial-median splits duplicate references with depth (for 1M random triangles about 14 per
/// triangle at depth 20 and 52 at depth 24), so the usual `8 + 1.3 log2 N` rule (34 at 1M) and
/// beyond would need tens of GB, and trees that large are slower anyway.
pub const MAX_REFERENCES_PER_TRIANGLE: u64 = 64;

/// The CRT sweep (paper §6.1): for leaf sizes 1, 2, 4 and 8, depths from 6 below the usual
/// `8 + 1.3 log2 N` rule (at most 18) upwards in steps of 3, deepening while the frame time improves and the
/// tree stays within [`MAX_REFERENCES_PER_TRIANGLE`]; scored by the time of a 128×128 frame
/// from each viewpoint.
pub fn tune_kd(tris: &[[[f32; 3]; 3]], probe: &[Ray], repeats: usize) -> TunedKd {
    let rule = (8.0 + 1.3 * (tris.len().max(2) as f64).log2()).round() as i64;
    let mut sweep = Vec::new();
    let mut best: Option<(f64, KdParams)> = None;
    for leaf_size in [1, 2, 4, 8] {
        let mut previous = f64::INFINITY;
        let mut depth = (rule - 6).clamp(1, 18);
        while depth <= 60 {
            let params = KdParams { max_depth: depth as u32, leaf_size };
            let tree = KdTree::build(tris, params);
            if tree.stats().references > MAX_REFERENCES_PER_TRIANGLE * tris.len().max(1) as u64 {
                break;
            }
            let t = measure(probe, repeats, |r| tree.closest_hit(r)).median_s;
            sweep.push((params, t));
            if best.is_none_or(|(b, _)| t < b) {
                best = Some((t, params));
            }
            if t > previous * 1.02 {
                break;
            }
            previous = t;
            depth += 3;
        }
    }
    let params = best.map_or(KdParams::default(), |b| b.1);
    let start = Instant::now();
    let tree = KdTree::build(tris, params);
    let build_s = start.elapsed().as_secs_f64();
    TunedKd { tree, params, build_s, sweep }
}

/// A field configuration of Figure 3.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FieldKind {
    pub tiles: u32,
    pub bsp: bool,
}

impl FieldKind {
    pub fn label(&self) -> String {
        format!("field {} {}²", if self.bsp { "BSP" } else { "linear" }, self.tiles)
    }

    fn depth(&self) -> DepthPolicy {
        if self.bsp { DepthPolicy::default() } else { DepthPolicy { leaf_size: 1, max_depth: 0 } }
    }
}

/// The six field configurations of Figure 3.
pub const FIGURE3_FIELDS: [FieldKind; 6] = [
    FieldKind { tiles: 32, bsp: false },
    FieldKind { tiles: 64, bsp: false },
    FieldKind { tiles: 128, bsp: false },
    FieldKind { tiles: 32, bsp: true },
    FieldKind { tiles: 64, bsp: true },
    FieldKind { tiles: 128, bsp: true },
];

#[derive(Clone, Debug, Serialize)]
pub struct Fig3Row {
    pub triangles: usize,
    pub view: &'static str,
    pub method: String,
    pub params: String,
    pub frame_ms: f64,
    pub runs_ms: Vec<f64>,
    pub mrays_per_s: f64,
    /// CRT frame time over this method's (above 1: faster than CRT).
    pub speedup_vs_crt: f64,
    pub build_or_bake_s: f64,
    pub memory_bytes: u64,
    pub disagreements: usize,
    /// Ray/triangle tests per ray (the work the structure leaves to the kernel).
    pub tests_per_ray: f64,
    /// Field only: tiles visited per ray.
    pub tiles_per_ray: f64,
}

fn ms(t: &Timing) -> (f64, Vec<f64>) {
    (t.median_s * 1e3, t.runs_s.iter().map(|s| s * 1e3).collect())
}

/// Figure 3. Returns the markdown written.
pub fn figure3(s: &Settings, sizes: &[usize]) -> anyhow::Result<String> {
    let mut rows: Vec<Fig3Row> = Vec::new();
    let mut skipped: Vec<String> = Vec::new();
    for &n in sizes {
        let scene = paper_scene(n);
        let tris = scene.vertices();
        let (c, r) = bounding_sphere(&tris);
        let views = views(c, r, s.resolution);
        let probe: Vec<Ray> = views
            .iter()
            .flat_map(|(name, _)| {
                let cam = if *name == "outside" { Camera::outside(c, r, 1.0) } else { Camera::inside(c, r, 1.0) };
                cam.primary_rays(128, 128)
            })
            .collect();
        if s.verbose {
            eprintln!("figure 3: {n} triangles: tuning CRT");
        }
        let kd = tune_kd(&tris, &probe, s.repeats);
        let kd_stats = kd.tree.stats();
        let mut crt_ms = Vec::new();
        let mut crt_answers = Vec::new();
        for (view, rays) in &views {
            let t = measure(rays, s.repeats, |ray| kd.tree.closest_hit(ray));
            let (frame_ms, runs_ms) = ms(&t);
            crt_ms.push(frame_ms);
            let mut counted = TraceStats::default();
            crt_answers.push(rays.iter().map(|ray| kd.tree.closest_hit_counted(ray, &mut counted)).collect::<Vec<_>>());
            rows.push(Fig3Row {
                triangles: n,
                view,
                method: "CRT kd-tree".into(),
                params: format!("depth {}, leaf {}", kd.params.max_depth, kd.params.leaf_size),
                frame_ms,
                runs_ms,
                mrays_per_s: rays.len() as f64 / t.median_s / 1e6,
                speedup_vs_crt: 1.0,
                build_or_bake_s: kd.build_s,
                memory_bytes: kd_stats.bytes,
                disagreements: 0,
                tests_per_ray: counted.triangle_tests as f64 / rays.len() as f64,
                tiles_per_ray: 0.0,
            });
        }
        for kind in FIGURE3_FIELDS {
            let config = BakeConfig {
                tiles: Some(kind.tiles),
                depth: kind.depth(),
                max_bytes: s.max_field_bytes,
                max_bytes_per_triangle: u64::MAX,
                ..BakeConfig::default()
            };
            if s.verbose {
                eprintln!("figure 3: {n} triangles: baking {}", kind.label());
            }
            let baked = match bake(&scene, &config, &s.work, "figure3")? {
                Ok(b) => b,
                Err(Skipped::OverBudget(why)) => {
                    skipped.push(format!("{n} triangles, {}: {why}", kind.label()));
                    continue;
                }
            };
            for (i, (view, rays)) in views.iter().enumerate() {
                let t = measure(rays, s.repeats, |ray| baked.field.closest_hit(ray));
                let mut counted = TraceStats::default();
                let answers: Vec<_> =
                    rays.iter().map(|ray| baked.field.view().closest_hit_counted(ray, &mut counted)).collect();
                let (frame_ms, runs_ms) = ms(&t);
                rows.push(Fig3Row {
                    triangles: n,
                    view,
                    method: kind.label(),
                    params: format!("{} directions × {}² tiles", baked.directions, baked.tiles),
                    frame_ms,
                    runs_ms,
                    mrays_per_s: rays.len() as f64 / t.median_s / 1e6,
                    speedup_vs_crt: crt_ms[i] / frame_ms,
                    build_or_bake_s: baked.seconds,
                    memory_bytes: baked.bytes,
                    disagreements: disagreements(&answers, &crt_answers[i]),
                    tests_per_ray: counted.triangle_tests as f64 / rays.len() as f64,
                    tiles_per_ray: counted.cells as f64 / rays.len() as f64,
                });
            }
        }
        // After every scene, so a long run that is stopped keeps what it measured.
        render_figure3(s, &rows, &skipped)?;
    }
    render_figure3(s, &rows, &skipped)
}

/// Writes Figure 3's JSON, plots and table for the rows so far.
fn render_figure3(s: &Settings, rows: &[Fig3Row], skipped: &[String]) -> anyhow::Result<String> {
    write_output(&s.out, "figure3.json", &serde_json::to_string_pretty(rows)?)?;

    // Plots: one per view, one line per method.
    for view in ["outside", "inside"] {
        let mut series: Vec<Series> = Vec::new();
        let mut methods: Vec<String> = vec!["CRT kd-tree".into()];
        methods.extend(FIGURE3_FIELDS.iter().map(|k| k.label()));
        for m in methods {
            let points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.view == view && r.method == m)
                .map(|r| (r.triangles as f64, r.frame_ms))
                .collect();
            if !points.is_empty() {
                series.push(Series { label: m, points });
            }
        }
        let svg = line_chart(
            &format!("Figure 3, {view} view: {0}×{0} primary rays, one thread", s.resolution),
            "triangles",
            "frame time (ms)",
            &series,
            true,
            true,
        )?;
        write_output(&s.out, &format!("figure3-{view}.svg"), &svg)?;
    }

    let mut md = String::new();
    writeln!(md, "# Figure 3: frame time against the number of triangles\n")?;
    writeln!(
        md,
        "The paper's scene (uniformly distributed random triangles, half-extent {DEFAULT_TRIANGLE_SIZE} in a cube of \
         side 2, seed 1), a {0}×{0} frame of unshaded primary rays traced on one thread, median of {1} runs after a \
         warm-up. CRT is the kd-tree at the best depth and leaf size of a sweep per scene (`tune_kd`: leaf sizes 1–8, depths deepened in steps of 3 while it helps). Field \
         directions are chosen by the baker for each tile resolution under a {2} budget. `speedup` is CRT's frame \
         time over the method's. `disagree` counts rays whose closest-hit `t` differs from CRT's bit for bit \
         (both use the same kernel; it must be 0).\n",
        s.resolution,
        s.repeats,
        vlf_bake::params::human_bytes(s.max_field_bytes)
    )?;
    writeln!(md, "![outside](figure3-outside.svg)\n![inside](figure3-inside.svg)\n")?;
    writeln!(
        md,
        "| triangles | view | method | parameters | frame ms | Mrays/s | speedup vs CRT | tests/ray | tiles/ray | build/bake s | memory MiB | disagree |"
    )?;
    writeln!(md, "| ---: | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")?;
    for r in rows {
        writeln!(
            md,
            "| {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.1} | {:.2} | {:.2} | {:.1} | {} |",
            r.triangles,
            r.view,
            r.method,
            r.params,
            r.frame_ms,
            r.mrays_per_s,
            r.speedup_vs_crt,
            r.tests_per_ray,
            r.tiles_per_ray,
            r.build_or_bake_s,
            r.memory_bytes as f64 / (1 << 20) as f64,
            r.disagreements
        )?;
    }
    if !skipped.is_empty() {
        writeln!(md, "\nNot baked (over the budget):\n")?;
        for s in skipped {
            writeln!(md, "- {s}")?;
        }
    }
    write_output(&s.out, "figure3.md", &md)?;
    Ok(md)
}

/// The walkthrough camera: `frames` frames from outside the scene to its centre, then a turn.
pub fn walkthrough(c: [f64; 3], r: f64, frames: usize) -> Vec<Camera> {
    let approach = frames * 2 / 3;
    (0..frames)
        .map(|i| {
            if i < approach {
                let t = i as f64 / approach as f64;
                let dist = 2.5 * r * (1.0 - t) + 0.05 * r * t;
                let eye = [c[0] + 0.3 * dist, c[1] + 0.2 * dist, c[2] + dist];
                Camera::look_at(eye, c, [0.0, 1.0, 0.0], 50.0, 1.0)
            } else {
                let t = (i - approach) as f64 / (frames - approach) as f64;
                let eye = [c[0] + 0.015 * r, c[1] + 0.01 * r, c[2] + 0.05 * r];
                let a = std::f64::consts::PI * t;
                let target = [eye[0] - a.sin() * r, eye[1], eye[2] - a.cos() * r];
                Camera::look_at(eye, target, [0.0, 1.0, 0.0], 60.0, 1.0)
            }
        })
        .collect()
}

#[derive(Clone, Debug, Serialize)]
pub struct Fig4Frame {
    pub frame: usize,
    pub crt_ms: f64,
    pub field_ms: f64,
    pub crt_tests_per_ray: f64,
    pub field_tests_per_ray: f64,
    pub field_tiles_per_ray: f64,
    pub disagreements: usize,
}

/// Figure 4: the walkthrough of the `n`-triangle scene (the paper's 16K): the field at the best
/// resolution of Figure 3 (BSP tiles, 128², directions chosen under the budget), CRT tuned.
pub fn figure4(s: &Settings, n: usize, frames: usize) -> anyhow::Result<String> {
    let scene = paper_scene(n);
    let tris = scene.vertices();
    let (c, r) = bounding_sphere(&tris);
    let cams = walkthrough(c, r, frames);
    let probe: Vec<Ray> = [0, frames / 2, frames - 1].iter().flat_map(|&i| cams[i].primary_rays(128, 128)).collect();
    let kd = tune_kd(&tris, &probe, s.repeats);
    let config = BakeConfig {
        tiles: Some(128),
        max_bytes: s.max_field_bytes,
        max_bytes_per_triangle: u64::MAX,
        ..BakeConfig::default()
    };
    let baked = match bake(&scene, &config, &s.work, "figure4")? {
        Ok(b) => b,
        Err(Skipped::OverBudget(why)) => anyhow::bail!("figure 4 field does not fit: {why}"),
    };
    let mut out = Vec::new();
    for (i, cam) in cams.iter().enumerate() {
        let rays = cam.primary_rays(s.resolution, s.resolution);
        let crt = measure(&rays, s.repeats, |ray| kd.tree.closest_hit(ray));
        let field = measure(&rays, s.repeats, |ray| baked.field.closest_hit(ray));
        let mut kd_stats = TraceStats::default();
        let mut f_stats = TraceStats::default();
        let kd_answers: Vec<_> = rays.iter().map(|ray| kd.tree.closest_hit_counted(ray, &mut kd_stats)).collect();
        let f_answers: Vec<_> =
            rays.iter().map(|ray| baked.field.view().closest_hit_counted(ray, &mut f_stats)).collect();
        let per_ray = rays.len() as f64;
        out.push(Fig4Frame {
            frame: i,
            crt_ms: crt.median_s * 1e3,
            field_ms: field.median_s * 1e3,
            crt_tests_per_ray: kd_stats.triangle_tests as f64 / per_ray,
            field_tests_per_ray: f_stats.triangle_tests as f64 / per_ray,
            field_tiles_per_ray: f_stats.cells as f64 / per_ray,
            disagreements: disagreements(&f_answers, &kd_answers),
        });
        if s.verbose && i % 10 == 0 {
            eprintln!("figure 4: frame {i}/{frames}");
        }
    }
    write_output(&s.out, "figure4.json", &serde_json::to_string_pretty(&out)?)?;
    let series = |f: fn(&Fig4Frame) -> f64, label: &str| Series {
        label: label.into(),
        points: out.iter().map(|x| (x.frame as f64, f(x))).collect(),
    };
    let svg = line_chart(
        &format!("Figure 4: walkthrough of the {n}-triangle scene, {0}×{0} frames, one thread", s.resolution),
        "frame",
        "frame time (ms)",
        &[series(|x| x.crt_ms, "CRT kd-tree"), series(|x| x.field_ms, "field")],
        false,
        false,
    )?;
    write_output(&s.out, "figure4-frame-time.svg", &svg)?;
    let svg = line_chart(
        &format!("Figure 4: triangle tests per ray along the walkthrough ({n} triangles)"),
        "frame",
        "triangle tests per ray",
        &[series(|x| x.crt_tests_per_ray, "CRT kd-tree"), series(|x| x.field_tests_per_ray, "field")],
        false,
        false,
    )?;
    write_output(&s.out, "figure4-tests.svg", &svg)?;

    let crt: Vec<f64> = out.iter().map(|x| x.crt_ms).collect();
    let field: Vec<f64> = out.iter().map(|x| x.field_ms).collect();
    let (crt_mean, crt_cv) = mean_cv(&crt);
    let (field_mean, field_cv) = mean_cv(&field);
    let total_disagree: usize = out.iter().map(|x| x.disagreements).sum();
    let mut md = String::new();
    writeln!(md, "# Figure 4: a walkthrough of the {n}-triangle scene\n")?;
    writeln!(
        md,
        "{frames} frames of {0}×{0} primary rays along a path from outside the scene (2.5 radii from its centre) \
         to its centre, then a half turn inside. One thread; each frame's time is the median of {1} runs after a \
         warm-up. Field: BSP tiles at Figure 3's best resolution ({2} directions × {3}² tiles, {4:.0} MiB, baked in {5:.1} s). \
         CRT: kd-tree depth {6}, leaf size {7} (best of a sweep), built in {8:.2} s.\n",
        s.resolution,
        s.repeats,
        baked.directions,
        baked.tiles,
        baked.bytes as f64 / (1 << 20) as f64,
        baked.seconds,
        kd.params.max_depth,
        kd.params.leaf_size,
        kd.build_s
    )?;
    writeln!(md, "| | mean frame ms | coefficient of variation |")?;
    writeln!(md, "| --- | ---: | ---: |")?;
    writeln!(md, "| CRT kd-tree | {crt_mean:.2} | {crt_cv:.3} |")?;
    writeln!(md, "| field | {field_mean:.2} | {field_cv:.3} |")?;
    writeln!(md, "\nRays whose closest hit differs between the two (bitwise `t`): {total_disagree}.\n")?;
    writeln!(md, "![frame time](figure4-frame-time.svg)\n![tests per ray](figure4-tests.svg)\n")?;
    writeln!(md, "| frame | CRT ms | field ms | CRT tests/ray | field tests/ray | field tiles/ray |")?;
    writeln!(md, "| ---: | ---: | ---: | ---: | ---: | ---: |")?;
    for x in &out {
        writeln!(
            md,
            "| {} | {:.2} | {:.2} | {:.1} | {:.1} | {:.2} |",
            x.frame, x.crt_ms, x.field_ms, x.crt_tests_per_ray, x.field_tests_per_ray, x.field_tiles_per_ray
        )?;
    }
    write_output(&s.out, "figure4.md", &md)?;
    Ok(md)
}

#[derive(Clone, Debug, Serialize)]
pub struct ParamRow {
    pub directions: u32,
    pub tiles: u32,
    pub leaf_size: u32,
    pub max_depth: u32,
    pub bake_s: f64,
    pub bytes: u64,
    pub outside_ms: f64,
    pub inside_ms: f64,
    pub tri_dirs_per_s_per_core: f64,
}

/// The parameter study on the `n`-triangle scene (the 100K): a grid of direction counts
/// and tile resolutions at the default BSP policy, then BSP policies at one point.
pub fn parameters(
    s: &Settings,
    n: usize,
    grid: &[(u32, u32)],
    policies: &[DepthPolicy],
    policy_at: (u32, u32),
) -> anyhow::Result<String> {
    let scene = paper_scene(n);
    let tris = scene.vertices();
    let (c, r) = bounding_sphere(&tris);
    let views = views(c, r, s.resolution);
    let cores = rayon::current_num_threads() as f64;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let mut points: Vec<(u32, u32, DepthPolicy)> = grid.iter().map(|&(l, t)| (l, t, DepthPolicy::default())).collect();
    points.extend(policies.iter().map(|&p| (policy_at.0, policy_at.1, p)));
    for (l, t, depth) in points {
        let config = BakeConfig {
            directions: Some(l),
            tiles: Some(t),
            depth,
            max_bytes: s.max_field_bytes,
            max_bytes_per_triangle: u64::MAX,
        };
        if s.verbose {
            eprintln!("parameters: {l} directions × {t}², {depth:?}");
        }
        let baked = match bake(&scene, &config, &s.work, "parameters")? {
            Ok(b) => b,
            Err(Skipped::OverBudget(why)) => {
                skipped.push(format!("{l} directions × {t}²: {why}"));
                continue;
            }
        };
        let outside = measure(&views[0].1, s.repeats, |ray| baked.field.closest_hit(ray));
        let inside = measure(&views[1].1, s.repeats, |ray| baked.field.closest_hit(ray));
        rows.push(ParamRow {
            directions: baked.directions,
            tiles: baked.tiles,
            leaf_size: depth.leaf_size,
            max_depth: depth.max_depth,
            bake_s: baked.seconds,
            bytes: baked.bytes,
            outside_ms: outside.median_s * 1e3,
            inside_ms: inside.median_s * 1e3,
            tri_dirs_per_s_per_core: n as f64 * baked.directions as f64 / baked.seconds / cores,
        });
    }
    write_output(&s.out, "parameters.json", &serde_json::to_string_pretty(&rows)?)?;
    let mut md = String::new();
    writeln!(md, "# Parameter study: the {n}-triangle scene\n")?;
    writeln!(
        md,
        "Frame time ({0}×{0} primary rays, one thread, median of {1} runs after a warm-up), field size and bake time \
         ({2} cores, including preparation and writing) against the number of directions, the tile resolution and \
         the BSP policy. `rate` is triangle-directions baked per second per core.\n",
        s.resolution, s.repeats, cores
    )?;
    writeln!(
        md,
        "| directions | tiles | leaf size | max depth | bake s | rate M/s/core | field MiB | outside ms | inside ms |"
    )?;
    writeln!(md, "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")?;
    for r in &rows {
        writeln!(
            md,
            "| {} | {}² | {} | {} | {:.1} | {:.2} | {:.0} | {:.2} | {:.2} |",
            r.directions,
            r.tiles,
            r.leaf_size,
            r.max_depth,
            r.bake_s,
            r.tri_dirs_per_s_per_core / 1e6,
            r.bytes as f64 / (1 << 20) as f64,
            r.outside_ms,
            r.inside_ms
        )?;
    }
    if !skipped.is_empty() {
        writeln!(md, "\nNot baked (over the {} budget):\n", vlf_bake::params::human_bytes(s.max_field_bytes))?;
        for x in skipped {
            writeln!(md, "- {x}")?;
        }
    }
    write_output(&s.out, "parameters-table.md", &md)?;
    Ok(md)
}
