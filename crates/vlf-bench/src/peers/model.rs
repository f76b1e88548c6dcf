//! What the peers benchmark measures and reports: the types every other module of it shares
//! (a leaf module, so that none of them imports the module that imports it).

use super::scenes::SceneSpec;
pub use super::scenes::Tri;
use std::path::PathBuf;

/// What a ray set asks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Query {
    /// Closest hit (`rtcIntersect1`).
    Closest,
    /// Any hit (`rtcOccluded1`).
    Any,
}

/// Everything a run needs.
#[derive(Clone, Debug)]
pub struct PeersConfig {
    pub scenes: Vec<SceneSpec>,
    /// Where fields are baked (deleted after use unless `keep_fields`).
    pub work: PathBuf,
    /// Where `peers.md`, `peers.json` and the plots go.
    pub out: PathBuf,
    /// Primary images are `resolution²` rays.
    pub resolution: u32,
    /// Incoherent rays per scene.
    pub incoherent: usize,
    /// Timed runs per measurement, after a warm-up run.
    pub repeats: usize,
    /// Thread counts to time at (a rayon pool of each size).
    pub threads: Vec<usize>,
    /// Rays sampled per set for the brute-force check of scenes with more than `check_all_below`
    /// triangles; smaller scenes are checked on every ray.
    pub check_rays: usize,
    pub check_all_below: usize,
    /// Relative `t` difference counted as rounding for contestants with another triangle test.
    pub t_tolerance: f64,
    pub kd: KdChoice,
    /// Explicit (directions, tiles) settings for the size sweep; empty: no sweep.
    pub sweep: Vec<(u32, u32)>,
    pub keep_fields: bool,
    /// The command line, as the report shows it.
    pub command: String,
    /// Print progress lines.
    pub verbose: bool,
    /// A quick run: said in the report's title.
    pub quick: bool,
}

/// One timed measurement.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Speed {
    pub contestant: String,
    pub threads: usize,
    pub median_s: f64,
    pub runs_s: Vec<f64>,
    pub mrays_per_s: f64,
    /// The 1-minute load average when the measurement started.
    pub load: f64,
    /// Before each timed round, the slowest of the pool's threads on `latency::core_probe_ns`
    /// (nanoseconds per step; the same for every contestant of the round). Empty in reports
    /// written before it was recorded.
    #[serde(default)]
    pub core_probe_ns: Vec<f64>,
}

/// One ray set of one scene.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SetResult {
    pub name: String,
    pub query: Query,
    pub rays: usize,
    /// The rays hit (closest) or blocked (any), by the field.
    pub hits: usize,
    /// Nanoseconds per dependent load of a pointer chase through
    /// `crate::latency::PEERS_WORKING_SET_MIB` MiB, measured just before the set was timed: what a
    /// miss cost the machine then. `None` in reports written before it was recorded.
    #[serde(default)]
    pub memory_latency_ns: Option<f64>,
    pub speeds: Vec<Speed>,
    pub checks: Vec<Counts>,
}

impl SetResult {
    /// Mrays/s of `contestant` at `threads`.
    pub fn mrays(&self, contestant: &str, threads: usize) -> Option<f64> {
        self.speeds.iter().find(|s| s.contestant == contestant && s.threads == threads).map(|s| s.mrays_per_s)
    }
}

/// A contestant's build.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Built {
    pub contestant: String,
    pub params: String,
    pub build_s: f64,
    pub bytes: u64,
    pub bytes_per_triangle: f64,
}

/// The field's own figures.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct FieldInfo {
    pub directions: u32,
    pub tiles: u32,
    pub bake_s: f64,
    pub open_ms: f64,
    pub bytes: u64,
    pub bytes_per_triangle: f64,
    pub choice: String,
}

/// The field at one explicit setting of the sweep.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SweepPoint {
    pub field: FieldInfo,
    /// (set, threads, Mrays/s).
    pub speeds: Vec<(String, usize, f64)>,
}

/// Everything measured on one scene.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SceneResult {
    pub name: String,
    pub description: String,
    pub triangles: usize,
    pub field: FieldInfo,
    pub built: Vec<Built>,
    pub sets: Vec<SetResult>,
    pub sweep: Vec<SweepPoint>,
    /// Settings the sweep could not bake, and why.
    pub sweep_skipped: Vec<String>,
    pub light: [f64; 3],
    pub seconds: f64,
}

/// The load average over the last minute.
pub fn load_average() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse().ok()))
        .unwrap_or(f64::NAN)
}

/// How the kd-tree's depth and leaf size are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
pub enum KdChoice {
    /// The paper's tuning (`tune_kd`, as Figure 3): a sweep of depths and leaf sizes, scored on
    /// 128×128 frames from both views; only the final build is timed.
    Tuned,
    /// `KdParams::default()`: depth 20, leaf size 2.
    Default,
}

/// One contestant's agreement with the brute force on one set's sample.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Counts {
    pub contestant: String,
    /// Rays compared.
    pub rays: usize,
    /// The same answer: both miss, or the same `t` bit for bit and the same triangle (any-hit:
    /// the same yes or no).
    pub same: usize,
    /// The same `t` bit for bit on another triangle: a float tie (triangles meeting at the hit
    /// point), which only the order of the tests decides.
    pub ties: usize,
    /// Both hit, `t` differs but by at most the relative tolerance.
    pub t_close: usize,
    /// Of `t_close`, those on another triangle.
    pub other_prim_close: usize,
    /// Both hit, `t` differs by more than the tolerance.
    pub t_far: usize,
    /// The contestant hits, the brute force misses.
    pub extra_hits: usize,
    /// The brute force hits, the contestant misses.
    pub missed: usize,
}

impl Counts {
    /// Answers that are not bit-identical to the brute force's, float ties aside.
    pub fn inexact(&self) -> usize {
        self.t_close + self.t_far + self.extra_hits + self.missed
    }

    /// Disagreements beyond rounding: a hit against a miss, or a `t` beyond the tolerance.
    pub fn wrong(&self) -> usize {
        self.t_far + self.extra_hits + self.missed
    }
}
