//! What every contestant of the peers benchmark answers, and the two that ship with the project:
//! the visibility field (baked at its default automatic parameters, then mapped) and the paper's
//! CRT kd-tree.

use super::model::{KdChoice, Tri};
use crate::experiments::tune_kd;
use std::path::{Path, PathBuf};
use std::time::Instant;
use vlf_bake::{BakeConfig, NoProgress, Prepared, Scene};
use vlf_geom::Ray;
use vlf_kdtree::{KdParams, KdTree};
use vlf_runtime::Field;

/// A closest hit as every contestant reports it: the ray parameter and the input triangle's index.
/// (Barycentrics are not compared: obvhs's traversal does not compute them.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeerHit {
    pub t: f32,
    pub prim: u32,
}

/// One structure under test. Every method answers one ray per call on the calling thread; the
/// batch methods are the loops the timings run (monomorphised per contestant, so the only dynamic
/// dispatch is one call per chunk of rays).
pub trait Contestant: Sync {
    /// Short name for tables: `field`, `embree`, `obvhs`, `kd-tree`.
    fn name(&self) -> &'static str;
    /// Parameters it was built with, for the table.
    fn describe(&self) -> String;
    /// Seconds to build (bake, for the field) from the triangles.
    fn build_seconds(&self) -> f64;
    /// Bytes the structure holds to answer queries (triangles included).
    fn bytes(&self) -> u64;
    /// The closest hit on `[tmin, tmax]`.
    fn closest_hit(&self, ray: &Ray) -> Option<PeerHit>;
    /// Whether anything is hit on `[tmin, tmax]`.
    fn any_hit(&self, ray: &Ray) -> bool;

    fn closest_hits(&self, rays: &[Ray], out: &mut [Option<PeerHit>]) {
        for (r, o) in rays.iter().zip(out) {
            *o = self.closest_hit(r);
        }
    }

    fn any_hits(&self, rays: &[Ray], out: &mut [bool]) {
        for (r, o) in rays.iter().zip(out) {
            *o = self.any_hit(r);
        }
    }
}

/// The field, baked at `BakeConfig::default()` (automatic directions and tiles) into
/// `work/name.vlf` and opened with `Field::open`. The file is deleted on drop unless kept.
pub struct FieldContestant {
    pub field: Field,
    pub path: PathBuf,
    pub bake_seconds: f64,
    pub open_seconds: f64,
    pub file_bytes: u64,
    pub directions: u32,
    pub tiles: u32,
    pub choice: String,
    pub keep: bool,
}

impl FieldContestant {
    /// Bakes `scene` with `config` (all cores) and opens the result.
    pub fn bake(scene: &Scene, config: &BakeConfig, work: &Path, name: &str) -> anyhow::Result<FieldContestant> {
        std::fs::create_dir_all(work)?;
        let path = work.join(format!("{name}.vlf"));
        let start = Instant::now();
        let prep = Prepared::new(scene);
        let choice = vlf_bake::choose(&prep, config)?;
        let summary = vlf_bake::writer::write_field(&prep, &choice, &config.request(), &path, &NoProgress)?;
        let bake_seconds = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let field = Field::open(&path)?;
        let open_seconds = start.elapsed().as_secs_f64();
        anyhow::ensure!(
            field.triangle_count() as usize == scene.len(),
            "the field of {name} holds {} triangles, the scene {}",
            field.triangle_count(),
            scene.len()
        );
        Ok(FieldContestant {
            field,
            path,
            bake_seconds,
            open_seconds,
            file_bytes: summary.bytes,
            directions: summary.directions,
            tiles: summary.tile_resolution,
            choice: summary.choice,
            keep: false,
        })
    }
}

impl Drop for FieldContestant {
    fn drop(&mut self) {
        if !self.keep {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

impl Contestant for FieldContestant {
    fn name(&self) -> &'static str {
        "field"
    }
    fn describe(&self) -> String {
        format!("{} directions × {}² tiles", self.directions, self.tiles)
    }
    fn build_seconds(&self) -> f64 {
        self.bake_seconds
    }
    fn bytes(&self) -> u64 {
        self.file_bytes
    }
    #[inline]
    fn closest_hit(&self, ray: &Ray) -> Option<PeerHit> {
        self.field.view().closest_hit(ray).map(|h| PeerHit { t: h.t, prim: h.prim })
    }
    #[inline]
    fn any_hit(&self, ray: &Ray) -> bool {
        self.field.view().any_hit(ray)
    }
    fn closest_hits(&self, rays: &[Ray], out: &mut [Option<PeerHit>]) {
        let view = self.field.view();
        for (r, o) in rays.iter().zip(out) {
            *o = view.closest_hit(r).map(|h| PeerHit { t: h.t, prim: h.prim });
        }
    }
    fn any_hits(&self, rays: &[Ray], out: &mut [bool]) {
        let view = self.field.view();
        for (r, o) in rays.iter().zip(out) {
            *o = view.any_hit(r);
        }
    }
}

/// The same field through its batch queries (`FieldView::closest_hits` and `any_hits`), which
/// interleave incoherent rays to overlap their cache misses: what `trace`, the C arrays and the
/// Python package call. Named `field batch` in the tables.
pub struct FieldBatch<'a>(pub &'a FieldContestant);

impl Contestant for FieldBatch<'_> {
    fn name(&self) -> &'static str {
        "field batch"
    }
    fn describe(&self) -> String {
        format!("{}, batch queries", self.0.describe())
    }
    fn build_seconds(&self) -> f64 {
        self.0.build_seconds()
    }
    fn bytes(&self) -> u64 {
        self.0.bytes()
    }
    fn closest_hit(&self, ray: &Ray) -> Option<PeerHit> {
        self.0.closest_hit(ray)
    }
    fn any_hit(&self, ray: &Ray) -> bool {
        self.0.any_hit(ray)
    }
    fn closest_hits(&self, rays: &[Ray], out: &mut [Option<PeerHit>]) {
        let mut hits = [None; BATCH];
        for (rays, out) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
            let hits = &mut hits[..rays.len()];
            self.0.field.view().closest_hits(rays, hits);
            for (o, h) in out.iter_mut().zip(hits.iter()) {
                *o = h.map(|h| PeerHit { t: h.t, prim: h.prim });
            }
        }
    }
    fn any_hits(&self, rays: &[Ray], out: &mut [bool]) {
        self.0.field.view().any_hits(rays, out);
    }
}

/// Rays per call of the batch query in [`FieldBatch`] (its output is converted on the stack).
const BATCH: usize = 1024;

/// The CRT kd-tree of `vlf-kdtree`.
pub struct KdContestant {
    pub tree: KdTree,
    pub build_seconds: f64,
    pub tuning_seconds: f64,
}

impl KdContestant {
    /// Builds the tree; `probe` are the rays `KdChoice::Tuned` scores candidates on.
    pub fn build(tris: &[Tri], choice: KdChoice, probe: &[Ray]) -> KdContestant {
        match choice {
            KdChoice::Tuned => {
                let start = Instant::now();
                let tuned = tune_kd(tris, probe, 2);
                let tuning_seconds = start.elapsed().as_secs_f64() - tuned.build_s;
                KdContestant { tree: tuned.tree, build_seconds: tuned.build_s, tuning_seconds }
            }
            KdChoice::Default => {
                let start = Instant::now();
                let tree = KdTree::build(tris, KdParams::default());
                KdContestant { tree, build_seconds: start.elapsed().as_secs_f64(), tuning_seconds: 0.0 }
            }
        }
    }
}

impl Contestant for KdContestant {
    fn name(&self) -> &'static str {
        "kd-tree"
    }
    fn describe(&self) -> String {
        let p = self.tree.params();
        let tuned =
            if self.tuning_seconds > 0.0 { format!(", tuned in {:.1} s", self.tuning_seconds) } else { String::new() };
        format!("depth {}, leaf {}{tuned}", p.max_depth, p.leaf_size)
    }
    fn build_seconds(&self) -> f64 {
        self.build_seconds
    }
    fn bytes(&self) -> u64 {
        self.tree.stats().bytes
    }
    #[inline]
    fn closest_hit(&self, ray: &Ray) -> Option<PeerHit> {
        self.tree.closest_hit(ray).map(|h| PeerHit { t: h.t, prim: h.prim })
    }
    #[inline]
    fn any_hit(&self, ray: &Ray) -> bool {
        self.tree.any_hit(ray)
    }
}
