//! Bake parameters: what the user asked for ([`BakeConfig`]), what the bake uses ([`Params`]),
//! and the automatic choice of the direction count and tile resolution under a size budget.
//!
//! The policy: walk up a ladder of (directions, tiles) rungs that keeps the tiles a ray crosses
//! small (finer tiles need more directions, `docs/architecture.md`), and take the finest rung
//! whose estimated size fits the budget, the smaller of `--max-bytes` and
//! `--max-bytes-per-triangle` × the triangle count, stopping early once tiles are already nearly
//! singular (more resolution then buys little speed for much memory). The estimate bakes a few
//! sample directions for real, so it accounts for the scene's actual shape; this module asks for
//! those samples through [`Measure`], which the prepared scene implements
//! (`crate::estimate`), so that the policy here depends on nothing else in the crate.

pub use vlf_format::MAX_DEPTH;
use vlf_format::{Request, StatisticsRecord, size};
use vlf_geom::Lattice;

/// The conservative margin as a fraction of the bounding radius (`formats/vlf.md` §6.2).
pub const MARGIN_FRACTION: f64 = 1.0 / (1u64 << 20) as f64;

/// The default size budget for automatic parameters: 4 GiB.
pub const DEFAULT_MAX_BYTES: u64 = 4 << 30;
/// The default per-triangle allowance of automatic parameters: 1 KiB per triangle, so a field
/// stays proportionate to its scene. In the format 2.0 sweep (`docs/benchmarks/parameters.md`)
/// larger fields were faster at 1M triangles on primary rays only (up to 2× at 4 KiB per
/// triangle), never on incoherent ones; 1 KiB is also the size the project aims at for
/// 1M-triangle scenes. Smaller scenes get more ([`automatic_floor`]: at 100K, timed side by side
/// with Embree, twice the bytes bought primary rays 5–18%). `--max-bytes-per-triangle` buys the
/// rest.
pub const DEFAULT_MAX_BYTES_PER_TRIANGLE: u64 = 1 << 10;
/// The smallest budget automatic parameters get, whatever the triangle count: 16 MiB. A mesh of a
/// few triangles still bakes (its fixed sections alone exceed a per-triangle allowance), and a
/// small scene gets the directions that shorten its walks: measured in the peers benchmark
/// (`docs/benchmarks/parameters.md`, 2026-12-06), 10,000 random triangles at 51 × 64² (15.3 MiB)
/// traced primary rays 30–39% faster than at the 19 × 64² that 4 MiB, the floor until baker
/// revision 9, and 1 KiB per triangle allowed, for incoherent rays 4–8% slower. Scenes of more
/// triangles get more ([`automatic_floor`]).
pub const MIN_AUTOMATIC_BUDGET: u64 = 16 << 20;
/// Automatic parameters get at least this many bytes for each of a mesh's first
/// [`SMALL_SCENE_TRIANGLES`] triangles (baker revision 11): 2.5 KiB, the size the project aims at
/// for scenes of 100,000 triangles, against 1 KiB at a million. Measured
/// (`docs/benchmarks/parameters.md`, "2.5 KiB per triangle up to 100,000 triangles"): the field
/// and Embree in one process, the fields taking turns, on the peers' whole 512² views and 262,144
/// incoherent rays, the 100K random scenes traced primary rays 5–11% faster (fixed size, 73 × 64²
/// against 33 × 64²) and 14–18% (shrinking triangles, 129 × 64² against 51 × 64²), incoherent rays
/// 3–8% slower. Past 100,000 triangles the floor grows as the square root of the triangle count
/// ([`automatic_floor`]).
pub const SMALL_SCENE_BYTES_PER_TRIANGLE: u64 = 2560;
/// See [`SMALL_SCENE_BYTES_PER_TRIANGLE`].
pub const SMALL_SCENE_TRIANGLES: u64 = 100_000;

/// The least budget automatic parameters get for a mesh of `n` triangles, whatever
/// `--max-bytes-per-triangle` says (`--max-bytes` still caps it): [`MIN_AUTOMATIC_BUDGET`], and
/// [`SMALL_SCENE_BYTES_PER_TRIANGLE`] for each triangle up to [`SMALL_SCENE_TRIANGLES`]; past
/// that, `2.5 KiB × √(100,000 · n)` (baker revision 12) up to [`FLOOR_TRIANGLES`], where it meets the
/// default 1 KiB per triangle: 1,619 B per triangle at 250,000, 1,145 at 500,000. So the
/// allowance per triangle falls smoothly from the size the project aims at for 100K triangles
/// towards the one for 1M, where revision 11 held it at a flat 256 MB, which left a scene of
/// 250,000 triangles 1 KiB each. Measured (`docs/benchmarks/parameters.md`, "Between 100K and 1M
/// triangles"): 250,000 random triangles of shrinking size at 99 × 64² (1,432 B per triangle)
/// against 51 × 64² (759 B), the field and Embree taking turns: primary rays 8–12% faster, the
/// inside view from 0.99 to 1.07 of Embree. The square root is an integer one: the choice, and so
/// the field, is the same on every platform.
pub fn automatic_floor(n: u64) -> u64 {
    let scaled = if n <= SMALL_SCENE_TRIANGLES { n } else { (SMALL_SCENE_TRIANGLES * n.min(FLOOR_TRIANGLES)).isqrt() };
    MIN_AUTOMATIC_BUDGET.max(SMALL_SCENE_BYTES_PER_TRIANGLE * scaled)
}

/// Where [`automatic_floor`] stops growing: 625,000 triangles, at which it reaches the default
/// 1 KiB per triangle (640 MB). Past it the floor stays there, so that it never overrides a
/// `--max-bytes-per-triangle` by more than a fixed amount on large scenes.
pub const FLOOR_TRIANGLES: u64 = 625_000;
/// Automatic refinement stops once the mean number of triangles in a non-empty tile falls to this.
pub const SPARSE_TILE_LOAD: f64 = 3.0;
/// Directions baked to estimate a rung's size.
const SAMPLE_DIRECTIONS: usize = 8;

/// The ladder of automatic (lattice N, tiles n) rungs, coarse to fine, from the format 2.0 sweep
/// (`docs/benchmarks/parameters.md`): 32² tiles are slow everywhere and hardly smaller than 64²;
/// at 64² tiles more directions shorten the walk. So the ladder refines tiles to 64² on 9
/// directions first, then adds directions. It went up to 33 while fields were larger; today's
/// fields of the 100K random scene of shrinking triangles fit 51 × 64² (905 B per triangle) and
/// trace primary rays 7–16% faster there than at 33 × 64², incoherent ones as fast
/// (`docs/benchmarks/parameters.md`, 2026-12-02), so the ladder goes on to 51 and 73 directions
/// and, since baker revision 11 gave scenes of up to 100,000 triangles 2.5 KiB each
/// ([`SMALL_SCENE_BYTES_PER_TRIANGLE`]), to 99 and 129, which the 100K scene of shrinking
/// triangles fits (129 × 64², 2,150 B per triangle); the budget stops it. (The sweep's "32² tiles
/// are slow" held on the few directions it had; on sparse scenes, with many directions, they are
/// the faster: [`COARSE_TILE_LOAD`].)
pub const LADDER: [(u32, u32); 9] = [(2, 16), (2, 32), (2, 64), (3, 64), (4, 64), (5, 64), (6, 64), (7, 64), (8, 64)];

/// Triangles per non-empty tile above which the automatic choice refines the ladder's tiles to
/// [`DENSE_TILES`], if that fits the budget. Measured (`docs/benchmarks/parameters.md`): on the
/// Stanford dragon (825 triangles per non-empty 64² tile) 19 × 128² tiles traced inside and
/// incoherent rays 1.6–1.8× faster than 19 × 64² at the same size; the 100K random scenes (96
/// and 154) did not gain. Baker revision 7 raised it from 400 to 750 when the query tested four
/// triangles at a time (`docs/benchmarks/where-the-time-goes.md`, 2026-12-04): the 1M random scene
/// of shrinking triangles (695) then traced faster at 73 × 64² than at 51 × 128² (outside +5%,
/// inside +8%, incoherent +12%), while the dragon (822) and the 1M scene of fixed size (1,648)
/// stayed faster at 128² (dragon inside +25% at 51 directions, 1M fixed inside +26% at 9).
pub const DENSE_TILE_LOAD: f64 = 750.0;

/// The tiles per side that dense tiles are refined to.
pub const DENSE_TILES: u32 = 128;

/// The fewest directions (lattice N = 4: 33) that dense tiles are refined on when the ladder
/// climbed past them and its own rung does not fit with finer tiles. Measured on the dragon
/// (`docs/benchmarks/parameters.md`, 2026-12-02): 51 × 128² traced primary and shadow rays 2–9%
/// faster than 33 × 128², and 33 × 128² was the best of the earlier ladder's; fewer directions
/// at finer tiles were not compared with the ladder's rung above them.
pub const DENSE_MIN_LATTICE: u32 = 4;

/// Triangles per non-empty tile below which the automatic choice coarsens the ladder's 64² tiles
/// to [`COARSE_TILES`] and climbs the directions again (baker revision 13): where tiles hold few
/// triangles, a ray crosses many of them for little work in each, and coarser tiles shorten the
/// walk more than their longer leaves cost. Measured (`docs/benchmarks/parameters.md`, "Coarser
/// tiles for sparse scenes"), the field and Embree taking turns on the peers' views: random
/// scenes of 3,000 (5 triangles per non-empty 64² tile), 10,000 (16) and 30,000 (45) triangles
/// and the bunny (13) traced every ray set faster at 32² (10K: inside 0.68 → 0.94 of Embree);
/// the 100K scene of shrinking triangles (94) traced as fast, the fixed-size one (150) slower.
pub const COARSE_TILE_LOAD: f64 = 64.0;

/// The tiles per side that sparse tiles are coarsened to.
pub const COARSE_TILES: u32 = 32;

pub use vlf_raster::{DEFAULT_LEAF_SIZE, DEFAULT_MAX_DEPTH, DepthPolicy};

/// What the user asks for. `None` means "choose for me".
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BakeConfig {
    /// Requested number of directions; rounded up to the next lattice size `2N² + 1`.
    pub directions: Option<u32>,
    /// Requested tiles per side.
    pub tiles: Option<u32>,
    pub depth: DepthPolicy,
    /// Size budget for automatic parameters, and a ceiling for explicit ones.
    pub max_bytes: u64,
    /// Automatic parameters aim at no more than this many bytes per triangle.
    pub max_bytes_per_triangle: u64,
}

impl Default for BakeConfig {
    fn default() -> Self {
        BakeConfig {
            directions: None,
            tiles: None,
            depth: DepthPolicy::default(),
            max_bytes: DEFAULT_MAX_BYTES,
            max_bytes_per_triangle: DEFAULT_MAX_BYTES_PER_TRIANGLE,
        }
    }
}

impl BakeConfig {
    /// Checks ranges; the CLI calls it so bad flags fail before any work.
    pub fn validate(&self) -> Result<(), ParamsError> {
        if let Some(l) = self.directions
            && !(3..=33_554_433).contains(&l)
        {
            return Err(ParamsError::Directions(l));
        }
        if let Some(n) = self.tiles
            && !(1..=65536).contains(&n)
        {
            return Err(ParamsError::Tiles(n));
        }
        if self.depth.leaf_size == 0 {
            return Err(ParamsError::LeafSize);
        }
        if self.depth.max_depth > MAX_DEPTH {
            return Err(ParamsError::MaxDepth(self.depth.max_depth));
        }
        if self.max_bytes == 0 || self.max_bytes_per_triangle == 0 {
            return Err(ParamsError::Budget);
        }
        Ok(())
    }

    /// The request recorded in the file and hashed into the input hash: `None` ("choose for me")
    /// is encoded as 0 (`formats/vlf.md` §3.3; [`Request::requested_directions`] decodes it).
    pub fn request(&self) -> Request {
        Request {
            requested_directions: self.directions.unwrap_or(0),
            requested_tiles: self.tiles.unwrap_or(0),
            leaf_size: self.depth.leaf_size,
            max_depth: self.depth.max_depth,
            max_bytes: self.max_bytes,
            max_bytes_per_triangle: self.max_bytes_per_triangle,
        }
    }
}

/// The parameters a bake runs with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    pub lattice_n: u32,
    pub tiles: u32,
    pub depth: DepthPolicy,
    /// The conservative margin μ in world units.
    pub margin: f64,
}

impl Params {
    /// The tile grid of a field of these parameters around a sphere of `radius`.
    pub fn grid(&self, radius: f64) -> vlf_raster::Grid {
        vlf_raster::Grid {
            tiles: self.tiles,
            lattice_n: self.lattice_n,
            radius,
            margin: self.margin,
            depth: self.depth,
        }
    }
}

/// The chosen parameters and why.
#[derive(Clone, Debug)]
pub struct Choice {
    pub params: Params,
    pub automatic: bool,
    pub estimated_bytes: Option<u64>,
    pub reason: String,
    /// What [`Measure::coverage`] said of `params` on the scene they were chosen for: measured
    /// once, while choosing, and handed on to the checks of the bake that follows.
    pub coverage: Coverage,
}

/// Why parameters cannot be chosen: a flag out of range, or a budget nothing fits. The messages
/// name the flags, for the command line to print as they are.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ParamsError {
    #[error("--directions {0} is outside 3..=33554433 (a lattice of N = 1..=4096)")]
    Directions(u32),
    #[error("--tiles {0} is outside 1..=65536")]
    Tiles(u32),
    #[error("--leaf-size must be at least 1")]
    LeafSize,
    #[error("--max-depth {0} exceeds the format's limit of {max}", max = MAX_DEPTH)]
    MaxDepth(u32),
    #[error("--max-bytes and --max-bytes-per-triangle must be positive")]
    Budget,
    /// Explicit parameters whose field cannot fit `--max-bytes`, whatever the scene's shape.
    #[error(
        "{directions} directions × {tiles}² tiles need at least {} for {}, over the --max-bytes budget of {}",
        human_bytes(*.at_least),
        count(*.triangles, "triangle", "triangles"),
        human_bytes(*.budget)
    )]
    ExplicitOverBudget { directions: u64, tiles: u32, triangles: u64, at_least: u64, budget: u64 },
    /// Not even the coarsest rung of the automatic search fits the budget.
    #[error(
        "even the coarsest field ({directions} directions × {tiles}² tiles) does not fit the budget of {} for {} \
         (--max-bytes {}, --max-bytes-per-triangle {}); raise them or give --directions and --tiles",
        human_bytes(*.budget),
        count(*.triangles, "triangle", "triangles"),
        human_bytes(*.max_bytes),
        human_bytes(*.max_bytes_per_triangle)
    )]
    NothingFits {
        directions: u64,
        tiles: u32,
        triangles: u64,
        budget: u64,
        max_bytes: u64,
        max_bytes_per_triangle: u64,
    },
}

/// What baking a few sample directions of a candidate measured.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// The mean bytes a direction adds to the file.
    pub bytes_per_direction: u64,
    /// The sample directions' statistics, summed.
    pub statistics: StatisticsRecord,
}

/// What choosing parameters needs of a scene: its size, and what a candidate's directions cost,
/// measured on a few of them. The prepared scene answers by baking them (`crate::estimate`); tests
/// answer with a model.
pub trait Measure {
    /// What measuring can fail with; parameter errors convert into it.
    type Error: From<ParamsError>;
    /// The triangles of the scene.
    fn triangle_count(&self) -> u64;
    /// The radius of the scene's bounding sphere, in world units.
    fn radius(&self) -> f64;
    /// Measures `directions` sample directions of a field with `params`. A direction that passes
    /// `max_bytes` (the budget: such a field cannot fit it) need not be baked to its end; its
    /// bytes are then given as at least what was made, more than `max_bytes`.
    fn sample(&self, params: &Params, directions: usize, max_bytes: u64) -> Result<Sample, Self::Error>;
    /// How many entries (triangle-tile pairs) the directions of a field with `params` make, from
    /// the triangles' projected areas and lengths alone, without baking (`crate::floor`).
    fn coverage(&self, params: &Params) -> Coverage;
}

/// What some directions' entries (triangle-tile pairs) come to, at least: what
/// [`crate::floor::EntryFloor::measure`] finds, and what the parameter choice is told of a
/// candidate ([`Measure::coverage`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coverage {
    /// At least this many in all the directions: explicit parameters are held to `--max-bytes`
    /// by it.
    pub at_least: u64,
    /// About this many in a direction: the mean of the bounds of the directions measured (one per
    /// triangle if none was). Candidates of automatic parameters whose pairs alone would pass the
    /// budget are not baked to be measured (long thin triangles on fine tiles make millions).
    pub per_direction: f64,
    /// At least this many in the direction that makes the most (the largest bound measured): what
    /// the bake's memory check counts.
    pub largest: u64,
}

impl Coverage {
    /// One pair per triangle in each of `directions` directions: what the format's lower bound
    /// counts, and the floor where no direction is measured.
    pub fn one_each(triangles: u64, directions: u64) -> Coverage {
        Coverage { at_least: triangles.saturating_mul(directions), per_direction: triangles as f64, largest: triangles }
    }

    /// The bytes of a field of `directions` directions on `tiles`² tiles over `triangles`
    /// triangles whose directions each make `per_direction` pairs: the tiles' records and a ref
    /// for each pair (the blocks' headers and leaf words not counted).
    fn bytes_about(&self, directions: u64, tiles: u32, triangles: u64) -> u64 {
        let refs = (self.per_direction * directions as f64) as u64;
        size::lower_bound_with_refs(directions, tiles as u64 * tiles as u64, triangles, refs)
    }
}

/// A lower bound on a field's size (`vlf_format::size::lower_bound`): every tile costs a record
/// and a bound, every triangle lands in at least one tile per direction, plus the fixed sections.
pub fn lower_bound_bytes(triangles: u64, lattice_n: u32, tiles: u32) -> u64 {
    let l = Lattice::new(lattice_n).direction_count();
    size::lower_bound(l, tiles as u64 * tiles as u64, triangles)
}

fn params_for(radius: f64, lattice_n: u32, tiles: u32, depth: DepthPolicy) -> Params {
    Params { lattice_n, tiles, depth, margin: radius * MARGIN_FRACTION }
}

/// A candidate that fits the budget: its parameters, estimated size and load (the mean triangles
/// per non-empty tile), and its coverage.
#[derive(Clone, Copy)]
struct Fit {
    params: Params,
    bytes: u64,
    load: f64,
    coverage: Coverage,
}

/// Whether a candidate may fit `budget`, before it is baked to be measured: its lower bound, then
/// its tiles' records with a ref for each of its triangle-tile pairs (measured on the triangles'
/// projections, [`Measure::coverage`]), are within it. `Some` with the coverage if it may.
fn may_fit<M: Measure>(scene: &M, p: &Params, budget: u64) -> Option<Coverage> {
    let (tris, l) = (scene.triangle_count(), Lattice::new(p.lattice_n).direction_count());
    if lower_bound_bytes(tris, p.lattice_n, p.tiles) > budget {
        return None;
    }
    Some(scene.coverage(p)).filter(|c| c.bytes_about(l, p.tiles, tris) <= budget)
}

/// The first of `lattices` on which `tiles`² tiles fit `budget`; rungs that cannot fit it
/// ([`may_fit`]) are not estimated.
fn first_that_fits<M: Measure>(
    scene: &M,
    lattices: impl Iterator<Item = u32>,
    tiles: u32,
    budget: u64,
    depth: DepthPolicy,
) -> Result<Option<Fit>, M::Error> {
    for lattice_n in lattices {
        let params = params_for(scene.radius(), lattice_n, tiles, depth);
        let Some(coverage) = may_fit(scene, &params, budget) else {
            continue;
        };
        let (bytes, load) = estimate(scene, &params, budget)?;
        if bytes <= budget {
            return Ok(Some(Fit { params, bytes, load, coverage }));
        }
    }
    Ok(None)
}

/// Estimated size of a field: sample directions measured, scaled to all directions; and the mean
/// triangles per non-empty tile of the sample.
fn estimate<M: Measure>(scene: &M, p: &Params, budget: u64) -> Result<(u64, f64), M::Error> {
    let sample = scene.sample(p, SAMPLE_DIRECTIONS, budget)?;
    let stats = &sample.statistics;
    let l = Lattice::new(p.lattice_n).direction_count();
    let nonempty = (stats.tile_count - stats.empty_tiles).max(1);
    Ok((
        size::estimate(l, sample.bytes_per_direction, scene.triangle_count()),
        stats.tile_triangle_sum as f64 / nonempty as f64,
    ))
}

/// Chooses the parameters for `config` on a scene (for a bake, the prepared scene).
pub fn choose<M: Measure>(scene: &M, config: &BakeConfig) -> Result<Choice, M::Error> {
    config.validate()?;
    let tris = scene.triangle_count();
    // Explicit parameters are held to the absolute budget only; automatic ones also to the
    // per-triangle allowance.
    let budget = config.max_bytes;
    let auto_budget = budget.min(config.max_bytes_per_triangle.saturating_mul(tris).max(automatic_floor(tris)));
    let explicit_n = config.directions.map(|l| Lattice::with_at_least(l as u64).n);
    if let (Some(lattice_n), Some(tiles)) = (explicit_n, config.tiles) {
        // The bound from the tiles and triangle count first; then, where that fits, the one that
        // also counts the tiles each triangle covers (cheap, but not free on large meshes).
        let params = params_for(scene.radius(), lattice_n, tiles, config.depth);
        let mut lb = lower_bound_bytes(tris, lattice_n, tiles);
        let mut coverage = None;
        if lb <= budget {
            let l = Lattice::new(lattice_n).direction_count();
            let measured = scene.coverage(&params);
            lb = size::lower_bound_with_refs(l, tiles as u64 * tiles as u64, tris, measured.at_least);
            coverage = Some(measured);
        }
        let Some(coverage) = coverage.filter(|_| lb <= budget) else {
            return Err(ParamsError::ExplicitOverBudget {
                directions: Lattice::new(lattice_n).direction_count(),
                tiles,
                triangles: tris,
                at_least: lb,
                budget,
            }
            .into());
        };
        return Ok(Choice { params, automatic: false, estimated_bytes: None, reason: "as requested".into(), coverage });
    }

    // Rungs consistent with whatever the user fixed, coarse to fine. A ray crosses about
    // 1 + 2n/N tiles (n tiles per side, lattice N; docs/architecture.md), so with the tiles fixed
    // the lattice climbs towards N = n/2, and with the lattice fixed the tiles climb towards 4N.
    let rungs: Vec<(u32, u32)> = match (explicit_n, config.tiles) {
        (None, None) => LADDER.to_vec(),
        (None, Some(t)) => {
            let top = (t / 2).clamp(2, 64);
            [2, 4, 8, 16, 32, 64].into_iter().filter(|&ln| ln <= top).map(|ln| (ln, t)).collect()
        }
        (Some(ln), None) => {
            let top = (4 * ln).clamp(8, 256);
            [8, 16, 32, 64, 128, 256].into_iter().filter(|&t| t <= top).map(|t| (ln, t)).collect()
        }
        (Some(_), Some(_)) => unreachable!("handled above"),
    };
    // Finer tiles stop paying once tiles are nearly singular; more directions always shorten the
    // walk, so with the tiles fixed only the budget stops the climb.
    let sparse_stop = config.tiles.is_none();
    let mut chosen: Option<Fit> = None;
    for &(lattice_n, tiles) in &rungs {
        let params = params_for(scene.radius(), lattice_n, tiles, config.depth);
        let Some(coverage) = may_fit(scene, &params, auto_budget) else {
            break;
        };
        let (bytes, load) = estimate(scene, &params, auto_budget)?;
        if bytes > auto_budget {
            break;
        }
        chosen = Some(Fit { params, bytes, load, coverage });
        if sparse_stop && load <= SPARSE_TILE_LOAD {
            break;
        }
    }
    // Dense tiles: the leaves of a tile that holds hundreds of triangles are long lists, and a
    // ray that reaches a surface tests them all. Automatic parameters refine such tiles to
    // DENSE_TILES when that fits the budget too (docs/benchmarks/parameters.md): on the
    // directions the ladder reached or, if that is too large, on fewer, down to
    // DENSE_MIN_LATTICE: finer tiles matter more to dense scenes than the last rungs of directions.
    if let (None, None, Some(Fit { params: p, load, .. })) = (explicit_n, config.tiles, chosen)
        && load > DENSE_TILE_LOAD
        && p.tiles < DENSE_TILES
    {
        let reached = rungs
            .iter()
            .rev()
            .filter(|&&(ln, t)| t == p.tiles && (ln == p.lattice_n || (DENSE_MIN_LATTICE..p.lattice_n).contains(&ln)));
        if let Some(finer) = first_that_fits(scene, reached.map(|&(ln, _)| ln), DENSE_TILES, auto_budget, config.depth)?
        {
            chosen = Some(finer);
        }
    }
    // Sparse tiles: where the ladder's 64² tiles hold few triangles, a ray crosses many of them
    // for little work in each. Automatic parameters coarsen such tiles to COARSE_TILES and take
    // the most directions of the ladder that then fit (at least the ones reached: coarser tiles
    // make a smaller field on the same directions).
    if let (None, None, Some(Fit { params: p, load, .. })) = (explicit_n, config.tiles, chosen)
        && load < COARSE_TILE_LOAD
        && p.tiles > COARSE_TILES
    {
        let top = rungs.iter().map(|&(ln, _)| ln).max().unwrap_or(p.lattice_n);
        if let Some(coarser) =
            first_that_fits(scene, (p.lattice_n..=top).rev(), COARSE_TILES, auto_budget, config.depth)?
        {
            chosen = Some(coarser);
        }
    }
    let Some(Fit { params, bytes, load, coverage }) = chosen else {
        let (ln, t) = rungs[0];
        return Err(ParamsError::NothingFits {
            directions: Lattice::new(ln).direction_count(),
            tiles: t,
            triangles: tris,
            budget: auto_budget,
            max_bytes: budget,
            max_bytes_per_triangle: config.max_bytes_per_triangle,
        }
        .into());
    };
    Ok(Choice {
        params,
        automatic: true,
        estimated_bytes: Some(bytes),
        reason: format!(
            "chose {} directions × {}² tiles: estimated {} (budget {}: the smaller of --max-bytes and \
             --max-bytes-per-triangle × {tris}, at least {}), {load:.1} triangles per non-empty tile",
            Lattice::new(params.lattice_n).direction_count(),
            params.tiles,
            human_bytes(bytes),
            human_bytes(auto_budget),
            human_bytes(automatic_floor(tris))
        ),
        coverage,
    })
}

/// `1 triangle`, `2 triangles`: a count and its noun, `many` unless the count is one.
pub fn count(n: u64, one: &str, many: &str) -> String {
    if n == 1 { format!("1 {one}") } else { format!("{n} {many}") }
}

/// `1.5 GiB`-style sizes.
pub fn human_bytes(b: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 { format!("{b} B") } else { format!("{v:.1} {}", UNITS[u]) }
}

#[cfg(test)]
mod tests;
