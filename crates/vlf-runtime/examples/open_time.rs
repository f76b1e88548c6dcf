//! Times `Field::open` on a field file: the median over RUNS opens (default 5), as one JSON line.
//! A raw field is mapped (time independent of its size); a packed one is decoded into memory.
//!
//! ```sh
//! cargo run --release -p vlf-runtime --example open_time -- scene.vlf 5
//! ```

use std::time::Instant;
use vlf_runtime::Field;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: open_time FIELD [RUNS]")?;
    let runs: usize = args.next().map_or(Ok(5), |r| r.parse())?;
    let mut seconds = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs.max(1) {
        drop(last.take());
        let t = Instant::now();
        let field = Field::open(&path)?;
        seconds.push(t.elapsed().as_secs_f64());
        last = Some(field);
    }
    let field = last.expect("at least one run");
    seconds.sort_by(f64::total_cmp);
    println!(
        "{{\"seconds\": {}, \"packed\": {}, \"field_bytes\": {}, \"file_bytes\": {}}}",
        seconds[seconds.len() / 2],
        field.is_packed(),
        field.len_bytes(),
        std::fs::metadata(&path)?.len()
    );
    Ok(())
}
