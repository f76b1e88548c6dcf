//! `vlf-bake pack` and `vlf-bake unpack`: transport compression of a field and its inverse.

use super::stdout_line;
use crate::args::{PackArgs, UnpackArgs};
use crate::distinct::{Writes, check_outputs};
use crate::progress::Bar;
use anyhow::Result;
use vlf_bake::pack::{pack_path, unpack_path};
use vlf_bake::params::human_bytes;

/// `vlf-bake pack`: compresses a field for transport and prints the summary.
pub fn pack(a: &PackArgs) -> Result<()> {
    check_outputs(&[("FIELD", &a.field)], &[("-o/--output", &a.output)], Writes::Files)?;
    let bar = Bar::new(a.quiet || a.json);
    let s = pack_path(&a.field, &a.output, a.level, &bar)?;
    if a.json {
        stdout_line(&serde_json::to_string(&s)?)?;
    } else if !a.quiet {
        stdout_line(&format!(
            "packed {} into {}: {} to {} ({:.2}×) at zstd level {} in {:.2} s ({:.0} MB/s)\n  content hash {}\n  unpacks to   {}",
            s.input.display(),
            s.output.display(),
            human_bytes(s.raw_bytes),
            human_bytes(s.packed_bytes),
            s.ratio,
            s.level,
            s.seconds,
            s.mb_per_s,
            s.content_hash,
            s.raw_content_hash
        ))?;
    }
    Ok(())
}

/// `vlf-bake unpack`: restores the raw field and prints the summary.
pub fn unpack(a: &UnpackArgs) -> Result<()> {
    check_outputs(&[("PACKED", &a.packed)], &[("-o/--output", &a.output)], Writes::Files)?;
    let bar = Bar::new(a.quiet || a.json);
    let s = unpack_path(&a.packed, &a.output, &bar)?;
    if a.json {
        stdout_line(&serde_json::to_string(&s)?)?;
    } else if !a.quiet {
        stdout_line(&format!(
            "unpacked {} into {}: {} to {} in {:.2} s ({:.0} MB/s)\n  content hash {}",
            s.input.display(),
            s.output.display(),
            human_bytes(s.packed_bytes),
            human_bytes(s.raw_bytes),
            s.seconds,
            s.mb_per_s,
            s.content_hash
        ))?;
    }
    Ok(())
}
