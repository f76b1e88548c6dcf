//! `vlf-bake dump`: describe a field (as text or JSON) and, with `--verify`, check every byte.

use super::stdout_line;
use crate::args::DumpArgs;
use crate::progress::Bar;
use anyhow::{Context, Result, bail};
use std::time::Instant;
use vlf_bake::inspect;
use vlf_bake::params::human_bytes;
use vlf_bake::{Progress, pack::check_packed_file};

/// `vlf-bake dump`: describes a field, and with `--verify` checks every byte.
pub fn run(a: &DumpArgs) -> Result<()> {
    let field = super::open_field(&a.field)?;
    let info = match field.packed_layout() {
        Some(layout) => inspect::describe_packed(field.reader(), layout),
        None => inspect::describe(field.reader()),
    };
    let verified = if a.verify {
        if let Some(layout) = field.packed_layout() {
            // Opening decoded and hashed every section; the file's padding is all that is left.
            check_packed_file(&a.field, layout)
                .with_context(|| format!("{} failed verification", a.field.display()))?;
        }
        let bar = Bar::new(a.quiet || a.json);
        bar.begin("verifying", field.len_bytes());
        let mut last = 0;
        let t = Instant::now();
        let result = inspect::verify(field.reader(), &mut |done, _| {
            bar.advance(done - last);
            last = done;
        });
        bar.end();
        match result {
            Ok(r) => Some((r, t.elapsed().as_secs_f64())),
            Err(e) => bail!("{} failed verification: {e}", a.field.display()),
        }
    } else {
        None
    };
    if a.json {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            #[serde(flatten)]
            info: &'a inspect::Description,
            #[serde(skip_serializing_if = "Option::is_none")]
            verify: Option<serde_json::Value>,
        }
        let verify = verified.as_ref().map(|(r, secs)| {
            serde_json::json!({"ok": true, "bytes_hashed": r.bytes_hashed, "tiles": r.tiles, "triangle_ids": r.ids, "seconds": secs})
        });
        return stdout_line(&serde_json::to_string_pretty(&Out { info: &info, verify })?);
    }
    stdout_line(&inspect::text::describe_text(&info))?;
    if let Some((r, secs)) = verified {
        stdout_line(&format!(
            "verify: OK: {} hashed, {} tiles and {} triangle ids checked in {secs:.2} s",
            human_bytes(r.bytes_hashed),
            r.tiles,
            r.ids
        ))?;
    }
    Ok(())
}
