//! The automatic choice against a cost model: which rung, which tiles refined, and why.

use super::*;
use std::cell::RefCell;

/// A scene whose directions cost what a model says: `a n² + b T + 200` bytes per direction
/// (above the lower bound, as real directions are; `a` = 16 and `b` = 8 unless said), and
/// `c T / n²` triangles per non-empty tile (at least one; `c` = 1 unless said). Records every
/// rung it is asked about.
struct Model {
    triangles: u64,
    per_triangle: u64,
    per_tile: u64,
    clustering: f64,
    sampled: RefCell<Vec<(u32, u32)>>,
}

impl Model {
    fn new(triangles: u64) -> Self {
        Model::with_bytes_per_triangle(triangles, 8)
    }

    fn with_bytes_per_triangle(triangles: u64, per_triangle: u64) -> Self {
        Model::with_costs(triangles, per_triangle, 16)
    }

    fn with_costs(triangles: u64, per_triangle: u64, per_tile: u64) -> Self {
        Model { triangles, per_triangle, per_tile, clustering: 1.0, sampled: RefCell::new(Vec::new()) }
    }

    /// The same scene with its triangles `c` times as crowded in the tiles that hold any.
    fn clustered(self, c: f64) -> Self {
        Model { clustering: c, ..self }
    }

    fn bytes_per_direction(&self, tiles: u32) -> u64 {
        self.per_tile * tiles as u64 * tiles as u64 + self.per_triangle * self.triangles + 200
    }

    fn load(&self, tiles: u32) -> f64 {
        (self.clustering * self.triangles as f64 / (tiles as f64 * tiles as f64)).max(1.0)
    }

    /// The estimate `choose` makes of a rung.
    fn estimate(&self, lattice_n: u32, tiles: u32) -> u64 {
        let l = Lattice::new(lattice_n).direction_count();
        size::estimate(l, self.bytes_per_direction(tiles), self.triangles)
    }

    fn sampled(&self) -> Vec<(u32, u32)> {
        self.sampled.borrow().clone()
    }
}

impl Measure for Model {
    type Error = ParamsError;

    fn triangle_count(&self) -> u64 {
        self.triangles
    }

    fn radius(&self) -> f64 {
        2.0
    }

    fn sample(&self, p: &Params, directions: usize, _max_bytes: u64) -> Result<Sample, ParamsError> {
        assert_eq!(directions, SAMPLE_DIRECTIONS);
        self.sampled.borrow_mut().push((p.lattice_n, p.tiles));
        let n2 = p.tiles as u64 * p.tiles as u64;
        let mut statistics = StatisticsRecord::zeroed_record();
        statistics.tile_count = n2;
        statistics.tile_triangle_sum = (self.load(p.tiles) * n2 as f64) as u64;
        Ok(Sample { bytes_per_direction: self.bytes_per_direction(p.tiles), statistics })
    }

    fn coverage(&self, p: &Params) -> Coverage {
        Coverage::one_each(self.triangles, Lattice::new(p.lattice_n).direction_count())
    }
}

/// A scene that must never be measured by sample directions; its triangles each cover `covered`
/// tiles in every direction.
struct Unmeasured {
    covered: u64,
}

const UNMEASURED: Unmeasured = Unmeasured { covered: 1 };

impl Measure for Unmeasured {
    type Error = ParamsError;
    fn triangle_count(&self) -> u64 {
        1000
    }
    fn radius(&self) -> f64 {
        4.0
    }
    fn sample(&self, _: &Params, _: usize, _: u64) -> Result<Sample, ParamsError> {
        panic!("explicit parameters need no estimate")
    }
    fn coverage(&self, p: &Params) -> Coverage {
        // Each triangle in `covered` tiles of every direction.
        Coverage::one_each(self.triangle_count() * self.covered, Lattice::new(p.lattice_n).direction_count())
    }
}

fn automatic(max_bytes: u64) -> BakeConfig {
    BakeConfig { max_bytes, max_bytes_per_triangle: u64::MAX / 2, ..BakeConfig::default() }
}

#[test]
fn explicit_parameters_are_taken_as_requested_without_an_estimate() {
    let config = BakeConfig { directions: Some(33), tiles: Some(16), ..BakeConfig::default() };
    let choice = choose(&UNMEASURED, &config).unwrap();
    let expected = Params { lattice_n: 4, tiles: 16, depth: DepthPolicy::default(), margin: 4.0 * MARGIN_FRACTION };
    assert_eq!(choice.params, expected);
    assert!(!choice.automatic);
    assert_eq!((choice.estimated_bytes, choice.reason.as_str()), (None, "as requested"));
    // Directions round up to the next lattice size 2N² + 1.
    let config = BakeConfig { directions: Some(34), tiles: Some(8), ..BakeConfig::default() };
    assert_eq!(choose(&UNMEASURED, &config).unwrap().params.lattice_n, 5);
}

#[test]
fn the_choice_carries_the_coverage_it_measured_once() {
    /// Counts the coverages asked of [`UNMEASURED`].
    struct Counted(RefCell<u32>);
    impl Measure for Counted {
        type Error = ParamsError;
        fn triangle_count(&self) -> u64 {
            UNMEASURED.triangle_count()
        }
        fn radius(&self) -> f64 {
            UNMEASURED.radius()
        }
        fn sample(&self, p: &Params, directions: usize, max_bytes: u64) -> Result<Sample, ParamsError> {
            UNMEASURED.sample(p, directions, max_bytes)
        }
        fn coverage(&self, p: &Params) -> Coverage {
            *self.0.borrow_mut() += 1;
            Unmeasured { covered: 3 }.coverage(p)
        }
    }
    let scene = Counted(RefCell::new(0));
    let config = BakeConfig { directions: Some(33), tiles: Some(16), ..BakeConfig::default() };
    let choice = choose(&scene, &config).unwrap();
    assert_eq!(*scene.0.borrow(), 1, "explicit parameters are measured once");
    assert_eq!(choice.coverage, Coverage { at_least: 33 * 3000, per_direction: 3000.0, largest: 3000 });
    // Automatic parameters carry the coverage of the rung they chose.
    let model = Model::new(10_000);
    let choice = choose(&model, &automatic(1 << 30)).unwrap();
    assert_eq!(choice.coverage, model.coverage(&choice.params));
}

#[test]
fn explicit_parameters_whose_lower_bound_exceeds_max_bytes_are_refused() {
    let lb = lower_bound_bytes(1000, 4, 16);
    assert_eq!(lb, 33 * (32 + 4 * 256 + 8 * 1000 + 16 + 72) + 44 * 1000);
    let fits = BakeConfig { directions: Some(33), tiles: Some(16), max_bytes: lb, ..BakeConfig::default() };
    assert!(choose(&UNMEASURED, &fits).is_ok(), "the bound itself fits");
    let config = BakeConfig { max_bytes: lb - 1, ..fits };
    let e = choose(&UNMEASURED, &config).unwrap_err();
    assert_eq!(
        e,
        ParamsError::ExplicitOverBudget { directions: 33, tiles: 16, triangles: 1000, at_least: lb, budget: lb - 1 }
    );
    assert_eq!(
        e.to_string(),
        "33 directions × 16² tiles need at least 337.6 KiB for 1000 triangles, over the --max-bytes budget of 337.6 KiB"
    );
    // Triangles that each cover 50 tiles add 49 refs each in every direction, which the bound from
    // the tile and triangle counts alone does not see.
    let covering = Unmeasured { covered: 50 };
    let at_least = lb + 33 * 1000 * 49 * 8;
    let e = choose(&covering, &fits).unwrap_err();
    assert_eq!(e, ParamsError::ExplicitOverBudget { directions: 33, tiles: 16, triangles: 1000, at_least, budget: lb });
    let config = BakeConfig { max_bytes: at_least, ..fits };
    assert!(choose(&covering, &config).is_ok(), "the bound with the tiles covered fits");
}

#[test]
fn the_ladder_climbs_to_the_finest_rung_whose_estimate_fits() {
    // Dense enough that tiles never become sparse: only the budget stops the climb.
    let model = Model::new(10_000_000);
    let budget = model.estimate(LADDER[3].0, LADDER[3].1);
    let choice = choose(&model, &automatic(budget)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), LADDER[3]);
    assert!(choice.automatic);
    assert_eq!(choice.estimated_bytes, Some(budget));
    assert_eq!(choice.params.margin, 2.0 * MARGIN_FRACTION);
    // The next rung was ruled out, by its lower bound before any estimate; none beyond it.
    // Its tiles are dense, so the finer tiles were estimated too, and did not fit.
    assert!(model.load(64) > DENSE_TILE_LOAD);
    assert_eq!(model.sampled(), [&LADDER[..4], &[(LADDER[3].0, DENSE_TILES)]].concat());
    assert!(choice.reason.starts_with("chose 19 directions × 64² tiles: estimated "), "{}", choice.reason);
    // A budget one byte smaller stops a rung earlier (whose dense tiles are then refined,
    // which fits).
    let choice = choose(&Model::new(10_000_000), &automatic(budget - 1)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (LADDER[2].0, DENSE_TILES));
}

#[test]
fn dense_tiles_are_refined_when_the_budget_allows() {
    // 64² tiles of 2,000 triangles: dense. A budget that fits 33 × 128² gets it...
    let model = Model::new(2_000 * 64 * 64);
    assert!(model.load(64) > DENSE_TILE_LOAD);
    let budget = model.estimate(LADDER[4].0, DENSE_TILES);
    let choice = choose(&model, &automatic(budget)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (LADDER[4].0, DENSE_TILES));
    assert!(choice.reason.starts_with("chose 33 directions × 128² tiles"), "{}", choice.reason);
    // ... one a byte smaller stays at the ladder's choice.
    let choice = choose(&Model::new(2_000 * 64 * 64), &automatic(budget - 1)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), LADDER[4]);
    // Tiles at the load threshold are not refined, whatever the budget.
    let model = Model::new(DENSE_TILE_LOAD as u64 * 64 * 64);
    let choice = choose(&model, &automatic(u64::MAX / 2)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), LADDER[LADDER.len() - 1]);
    assert!(!model.sampled().iter().any(|&(_, t)| t == DENSE_TILES));
    // Explicit directions or tiles are never refined.
    let config = BakeConfig { directions: Some(33), ..automatic(u64::MAX / 2) };
    assert!(choose(&Model::new(2_000 * 64 * 64), &config).unwrap().params.tiles <= 4 * LADDER[4].0);
}

#[test]
fn dense_tiles_are_refined_on_fewer_directions_down_to_33() {
    // Tile records dominate: the ladder reaches 73 × 64², whose finer tiles do not fit, nor
    // do 51 × 128²; 33 × 128² does, and is taken.
    let model = || Model::with_costs(2_000 * 64 * 64, 8, 16_384);
    let m = model();
    let budget = m.estimate(4, DENSE_TILES);
    assert!(m.estimate(6, 64) <= budget && m.estimate(5, DENSE_TILES) > budget);
    let m = model();
    let choice = choose(&m, &automatic(budget)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (4, DENSE_TILES));
    // (99 × 64², the rung after 73 × 64², is estimated and does not fit.)
    let refined: Vec<(u32, u32)> = m.sampled().into_iter().filter(|&(_, t)| t == DENSE_TILES).collect();
    assert_eq!(refined, [(6, DENSE_TILES), (5, DENSE_TILES), (4, DENSE_TILES)]);
    assert!(m.estimate(7, 64) > budget);
    // Below 33 directions the ladder's own rung stands: a byte less keeps 73 × 64², and 19 ×
    // 128² is not tried.
    let m = model();
    let choice = choose(&m, &automatic(budget - 1)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (6, 64));
    assert!(!m.sampled().contains(&(3, DENSE_TILES)));
}

#[test]
fn the_ladder_stops_once_tiles_are_nearly_singular() {
    // 3 × 64² triangles: three per tile at 64² tiles. The ladder stops there; then the sparse
    // tiles are coarsened to 32², on the most directions (the budget does not stop them).
    let model = Model::new(3 * 64 * 64);
    let choice = choose(&model, &automatic(u64::MAX / 2)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (8, COARSE_TILES));
    assert_eq!(model.sampled()[..3], LADDER[..3], "nothing finer is estimated");
    assert_eq!(model.sampled()[3..], [(8, COARSE_TILES)]);
    assert!(choice.reason.ends_with(", 12.0 triangles per non-empty tile"), "{}", choice.reason);
}

#[test]
fn sparse_tiles_are_coarsened_and_the_directions_climb_as_far_as_the_budget_allows() {
    // 20 triangles per 64² tile: below COARSE_TILE_LOAD.
    let model = || Model::new(20 * 64 * 64);
    let m = model();
    let choice = choose(&m, &automatic(u64::MAX / 2)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (8, COARSE_TILES));
    assert_eq!(m.sampled()[..LADDER.len()], LADDER, "the ladder first, to its top");
    assert!(choice.reason.ends_with(", 80.0 triangles per non-empty tile"), "{}", choice.reason);
    // A budget that fits 73 × 32² but not 99 × 32²: 73 × 32², though the ladder stopped at 64²
    // on fewer directions (coarser tiles on the same directions make a smaller field).
    let budget = m.estimate(6, COARSE_TILES);
    assert!(m.estimate(7, COARSE_TILES) > budget && m.estimate(6, 64) > budget);
    let m = model();
    let choice = choose(&m, &automatic(budget)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (6, COARSE_TILES));
    // Tiles that hold COARSE_TILE_LOAD triangles or more stay at 64².
    let m = model().clustered(COARSE_TILE_LOAD / 20.0);
    let choice = choose(&m, &automatic(u64::MAX / 2)).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (8, 64));
    assert_eq!(m.sampled(), LADDER, "nothing coarser is estimated");
    // Explicit tiles or directions are never coarsened.
    let fixed = BakeConfig { tiles: Some(64), ..automatic(u64::MAX / 2) };
    assert_eq!(choose(&model(), &fixed).unwrap().params.tiles, 64);
    // (With 513 directions fixed the tiles climb to 64², and stay there.)
    let fixed = BakeConfig { directions: Some(513), ..automatic(u64::MAX / 2) };
    assert_eq!(choose(&model(), &fixed).unwrap().params.tiles, 64);
}

#[test]
fn the_per_triangle_allowance_caps_automatic_parameters() {
    // The allowance times the triangles lies between the estimates of rungs 1 and 2, both above
    // the floor.
    let model = Model::with_costs(4_000_000, 24, 4096);
    let allowance = model.estimate(LADDER[1].0, LADDER[1].1).div_ceil(4_000_000);
    assert!(allowance * 4_000_000 < model.estimate(LADDER[2].0, LADDER[2].1));
    assert!(model.estimate(LADDER[1].0, LADDER[1].1) > automatic_floor(4_000_000));
    let config = BakeConfig { max_bytes: u64::MAX / 2, max_bytes_per_triangle: allowance, ..BakeConfig::default() };
    let choice = choose(&model, &config).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), LADDER[1]);
    // Explicit parameters are held to --max-bytes only.
    let explicit = BakeConfig { directions: Some(33), tiles: Some(256), ..config };
    assert_eq!(choose(&model, &explicit).unwrap().params.tiles, 256);
}

#[test]
fn a_mesh_of_a_few_triangles_bakes_at_the_default_budget() {
    // One triangle's allowance (1 KiB) is below any field's fixed sections; the floor of the
    // automatic budget lets it bake, and its single triangle stops the ladder at once.
    for triangles in [1, 2, 12] {
        let model = Model::new(triangles);
        let choice = choose(&model, &BakeConfig::default()).unwrap();
        assert_eq!((choice.params.lattice_n, choice.params.tiles), LADDER[0], "{triangles} triangles");
        assert!(choice.estimated_bytes.unwrap() <= MIN_AUTOMATIC_BUDGET);
    }
    // The floor never lifts the automatic budget over --max-bytes.
    let config = BakeConfig { max_bytes: 1000, ..BakeConfig::default() };
    let e = choose(&Model::new(1), &config).unwrap_err();
    assert!(matches!(e, ParamsError::NothingFits { budget: 1000, .. }), "{e:?}");
    assert!(e.to_string().contains("for 1 triangle ("), "{e}");
}

#[test]
fn the_default_allowance_is_a_kibibyte_per_triangle_above_the_floor() {
    let config = BakeConfig::default();
    assert_eq!(config.max_bytes_per_triangle, 1024);
    // Two million triangles costing 60 B each per direction, as the random scenes measure: 9 × 64²
    // fits 1 KiB per triangle, 19 × 64² does not, and the floor is below both.
    let model = Model::with_bytes_per_triangle(2_000_000, 60);
    assert!(model.estimate(2, 64) <= 1024 * 2_000_000 && model.estimate(3, 64) > 1024 * 2_000_000);
    assert!(automatic_floor(2_000_000) < model.estimate(2, 64));
    let choice = choose(&model, &config).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (2, 64));
}

#[test]
fn scenes_of_up_to_100k_triangles_get_two_and_a_half_kibibytes_each_and_larger_ones_less_and_less() {
    assert_eq!(automatic_floor(1), MIN_AUTOMATIC_BUDGET);
    assert_eq!(automatic_floor(6_000), MIN_AUTOMATIC_BUDGET);
    assert_eq!(automatic_floor(10_000), 25_600_000);
    assert_eq!(automatic_floor(100_000), 256_000_000);
    // Past 100K, 2.5 KiB × √(100,000 · n): 1,619 B per triangle at 250K, 1,145 at 500K, up to
    // 625K, where it meets the default 1 KiB per triangle and stops.
    assert_eq!(automatic_floor(100_001), 256_000_000);
    assert_eq!(automatic_floor(250_000), 2560 * 158_113);
    assert_eq!(automatic_floor(500_000), 2560 * 223_606);
    assert_eq!(automatic_floor(FLOOR_TRIANGLES), 1024 * 625_000);
    assert_eq!(automatic_floor(4_000_000), 1024 * 625_000, "a fixed 640 MB past 625,000 triangles");
    assert_eq!(automatic_floor(u64::MAX), 1024 * 625_000);
    let mut last = 0;
    for n in (0..2_000_000).step_by(997) {
        assert!(automatic_floor(n) >= last, "the floor never falls as triangles are added ({n})");
        assert!(automatic_floor(n) <= MIN_AUTOMATIC_BUDGET.max(2560 * n), "nor exceeds 2.5 KiB a triangle ({n})");
        last = automatic_floor(n);
    }
    // 100K triangles at 60 B each per direction: 33 × 64² fits 2.5 KiB per triangle, 51 × 64²
    // does not; the default 1 KiB alone would stop at 9 × 64².
    // (Clustered so that its tiles are not sparse: COARSE_TILE_LOAD does not apply.)
    let model = Model::with_bytes_per_triangle(100_000, 60).clustered(4.0);
    assert!(model.estimate(4, 64) <= 256_000_000 && model.estimate(5, 64) > 256_000_000);
    assert!(model.estimate(3, 64) > 1024 * 100_000);
    let choice = choose(&model, &BakeConfig::default()).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (4, 64));
    assert!(choice.reason.contains("at least 244.1 MiB"), "{}", choice.reason);
    // --max-bytes caps the floor.
    let config = BakeConfig { max_bytes: model.estimate(3, 64), ..BakeConfig::default() };
    let choice = choose(&Model::with_bytes_per_triangle(100_000, 60).clustered(4.0), &config).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (3, 64));
}

#[test]
fn with_the_tiles_fixed_only_the_lattice_climbs_and_sparse_tiles_do_not_stop_it() {
    let model = Model::new(10);
    let config = BakeConfig { tiles: Some(32), ..automatic(u64::MAX / 2) };
    let choice = choose(&model, &config).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (16, 32), "up to N = n/2");
    assert_eq!(model.sampled(), [(2, 32), (4, 32), (8, 32), (16, 32)]);
}

#[test]
fn with_the_directions_fixed_the_tiles_climb_towards_four_times_the_lattice() {
    let model = Model::new(10_000_000);
    let config = BakeConfig { directions: Some(33), ..automatic(u64::MAX / 2) };
    let choice = choose(&model, &config).unwrap();
    assert_eq!((choice.params.lattice_n, choice.params.tiles), (4, 16));
    assert_eq!(model.sampled(), [(4, 8), (4, 16)]);
}

#[test]
fn a_budget_that_nothing_fits_is_an_error_naming_the_coarsest_rung() {
    let model = Model::new(1000);
    let config = BakeConfig { max_bytes: 1000, max_bytes_per_triangle: 2048, ..BakeConfig::default() };
    let e = choose(&model, &config).unwrap_err();
    assert_eq!(
        e,
        ParamsError::NothingFits {
            directions: 9,
            tiles: 16,
            triangles: 1000,
            budget: 1000,
            max_bytes: 1000,
            max_bytes_per_triangle: 2048
        }
    );
    assert_eq!(
        e.to_string(),
        "even the coarsest field (9 directions × 16² tiles) does not fit the budget of 1000 B for 1000 triangles \
         (--max-bytes 1000 B, --max-bytes-per-triangle 2.0 KiB); raise them or give --directions and --tiles"
    );
    assert!(model.sampled().is_empty(), "the lower bound alone rules the rung out");
}

#[test]
fn flags_out_of_range_are_refused_before_any_estimate() {
    let d = BakeConfig::default();
    let depth = |leaf_size, max_depth| BakeConfig { depth: DepthPolicy { leaf_size, max_depth }, ..d };
    for (config, error, message) in [
        (
            BakeConfig { directions: Some(2), ..d },
            ParamsError::Directions(2),
            "--directions 2 is outside 3..=33554433 (a lattice of N = 1..=4096)",
        ),
        (
            BakeConfig { directions: Some(33_554_434), ..d },
            ParamsError::Directions(33_554_434),
            "--directions 33554434",
        ),
        (BakeConfig { tiles: Some(0), ..d }, ParamsError::Tiles(0), "--tiles 0 is outside 1..=65536"),
        (BakeConfig { tiles: Some(65537), ..d }, ParamsError::Tiles(65537), "--tiles 65537 is outside"),
        (depth(0, 8), ParamsError::LeafSize, "--leaf-size must be at least 1"),
        (depth(4, 13), ParamsError::MaxDepth(13), "--max-depth 13 exceeds the format's limit of 12"),
        (
            BakeConfig { max_bytes: 0, ..d },
            ParamsError::Budget,
            "--max-bytes and --max-bytes-per-triangle must be positive",
        ),
        (BakeConfig { max_bytes_per_triangle: 0, ..d }, ParamsError::Budget, "must be positive"),
    ] {
        assert_eq!(config.validate(), Err(error.clone()));
        assert_eq!(choose(&UNMEASURED, &config).unwrap_err(), error);
        assert!(error.to_string().contains(message), "{error}");
    }
    for ok in [BakeConfig { directions: Some(3), tiles: Some(1), ..d }, depth(1, MAX_DEPTH), d] {
        assert_eq!(ok.validate(), Ok(()));
    }
}

#[test]
fn the_request_encodes_automatic_values_as_zero() {
    let request = BakeConfig::default().request();
    assert_eq!((request.requested_directions, request.requested_tiles), (0, 0));
    assert_eq!((request.requested_directions(), request.requested_tiles()), (None, None));
    assert!(request.is_automatic());
    let request = BakeConfig { directions: Some(129), tiles: Some(64), ..BakeConfig::default() }.request();
    assert_eq!((request.requested_directions(), request.requested_tiles()), (Some(129), Some(64)));
    assert!(!request.is_automatic());
    let half = BakeConfig { tiles: Some(64), ..BakeConfig::default() }.request();
    assert!(half.is_automatic(), "the directions are still chosen");
}
