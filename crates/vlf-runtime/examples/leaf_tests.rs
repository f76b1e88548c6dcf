//! Where a ray file's triangle tests go, by the rank of the leaf along the ray: how many rays
//! reach their first, second, ... leaf with refs, and how many triangle tests each of those
//! leaves takes. It showed that a shadow ray's first leaf (the one it starts in) takes most of
//! its tests (`docs/benchmarks/where-the-time-goes.md`).
//!
//! ```text
//! cargo run --release -p vlf-runtime --example leaf_tests -- FIELD RAYS [--any]
//! ```
//!
//! `RAYS` is a file of 32-byte ray records (`formats/rays.md`), traced by
//! `FieldView::closest_hit_counted` (or `any_hit_counted` with `--any`) with a counter that
//! splits the tests by leaf. Leaves past the sixteenth are counted with it. An any-hit search
//! walks a segment that leaves the scene from its far end (ranks then count from there), and
//! otherwise tests the leaf it starts in last, without reaching it again: those tests are
//! counted with the last leaf the ray reached (the first leaf then shows none).

use vlf_geom::Counter;
use vlf_runtime::{Field, Ray};

/// Tests per leaf rank, over all rays.
#[derive(Default)]
struct ByLeaf {
    /// Leaves visited by the current ray so far, and tests since its last leaf began.
    leaf: usize,
    tests: u64,
    tiles: u64,
    /// Per rank: rays that reached it, and their tests there.
    ranks: Vec<[u64; 2]>,
}

impl ByLeaf {
    /// Books the tests of the current ray's latest leaf.
    fn close_leaf(&mut self) {
        if self.leaf > 0 {
            let rank = (self.leaf - 1).min(15);
            if self.ranks.len() <= rank {
                self.ranks.resize(rank + 1, [0; 2]);
            }
            self.ranks[rank][0] += 1;
            self.ranks[rank][1] += self.tests;
        }
        self.tests = 0;
    }
}

impl Counter for ByLeaf {
    fn cell(&mut self) {
        self.tiles += 1;
    }
    fn leaf(&mut self) {
        self.close_leaf();
        self.leaf += 1;
    }
    fn test(&mut self) {
        self.tests += 1;
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let usage = "usage: leaf_tests FIELD RAYS [--any]";
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(field), Some(rays)) = (args.first(), args.get(1)) else { return Err(usage.into()) };
    let any = match args.get(2).map(String::as_str) {
        None => false,
        Some("--any") => true,
        Some(other) => return Err(format!("unknown argument {other}; {usage}").into()),
    };
    let field = Field::open(field)?;
    let bytes = std::fs::read(rays)?;
    let rays = match Ray::from_records(&bytes) {
        Some(rays) if !rays.is_empty() => rays,
        _ => return Err(format!("{rays}: {} bytes, not a whole number of 32-byte rays", bytes.len()).into()),
    };
    let view = field.view();
    let mut count = ByLeaf::default();
    let mut hits = 0;
    for ray in &rays {
        count.leaf = 0;
        let hit = if any { view.any_hit_counted(ray, &mut count) } else { view.closest_hit_counted(ray, &mut count) };
        hits += hit.is_some() as usize;
        count.close_leaf();
    }
    let n = rays.len() as f64;
    let tests: u64 = count.ranks.iter().map(|r| r[1]).sum();
    println!(
        "{} rays, {hits} hits; per ray: {:.2} tiles, {:.2} triangle tests",
        rays.len(),
        count.tiles as f64 / n,
        tests as f64 / n
    );
    for (rank, [visits, tests]) in count.ranks.iter().enumerate() {
        let more = if rank == 15 { " and later" } else { "" };
        println!(
            "leaf {}{more}: reached by {:.1}% of rays, {:.2} tests per visit",
            rank + 1,
            100.0 * *visits as f64 / n,
            *tests as f64 / *visits as f64
        );
    }
    Ok(())
}
