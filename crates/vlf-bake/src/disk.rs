//! The room a file system has for a bake's output, checked before the directions are baked: a
//! field that cannot fit is refused in one line naming both sizes, instead of filling the disk
//! and failing after minutes of work (`docs/reliability.md`, the limits table).

use crate::error::BakeError;
use crate::floor::EntryFloor;
use crate::params::{Choice, human_bytes};
use std::path::Path;
use vlf_geom::Lattice;

/// What a bake will write, by what it knows before it starts: the estimate of automatic
/// parameters (sampled on real directions), or, for explicit parameters and for a shard, the size
/// no field (or shard) of the parameters can be smaller than, with the tiles its triangles cover
/// (`crate::floor`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Need {
    /// About this many bytes.
    Estimated(u64),
    /// At least this many bytes.
    AtLeast(u64),
}

impl Need {
    /// What a bake of `triangles` triangles with `choice`'s parameters will write, the
    /// directions `floor` covers (all of them, or a shard's).
    pub fn of(choice: &Choice, triangles: u64, floor: &EntryFloor) -> Need {
        let all = Lattice::new(choice.params.lattice_n).direction_count();
        match choice.estimated_bytes {
            Some(bytes) if floor.directions.len() as u64 == all => Need::Estimated(bytes),
            _ => Need::AtLeast(floor.bytes_at_least(choice.params.tiles, triangles)),
        }
    }

    fn bytes(self) -> u64 {
        match self {
            Need::Estimated(b) | Need::AtLeast(b) => b,
        }
    }
}

/// `Err` if the file system that will hold `output` (a field, or a shard: `what`, for the
/// message) has less free space than `need` (as an unprivileged writer sees it). Where the free
/// space cannot be read, nothing is checked.
pub fn check(output: &Path, what: &'static str, need: Need) -> Result<(), BakeError> {
    let dir = crate::atomic::parent_dir(output);
    match free_space(&dir) {
        Some(free) => check_against(&dir, free, what, need),
        None => Ok(()),
    }
}

fn check_against(dir: &Path, free: u64, what: &'static str, need: Need) -> Result<(), BakeError> {
    if need.bytes() <= free {
        return Ok(());
    }
    let needs = match need {
        Need::Estimated(b) => format!("is estimated at {}", human_bytes(b)),
        Need::AtLeast(b) => format!("needs {} or more", human_bytes(b)),
    };
    Err(BakeError::NotEnoughDisk { what, needs, dir: dir.to_path_buf(), free: human_bytes(free) })
}

/// The free space of the file system holding `dir`, for an unprivileged writer; `None` where it
/// cannot be read.
pub fn free_space(dir: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let s = rustix::fs::statvfs(dir).ok()?;
        Some(s.f_bavail.saturating_mul(s.f_frsize))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_larger_than_the_free_space_is_refused_naming_both() {
        let dir = Path::new("/data");
        let gib = 1u64 << 30;
        assert!(check_against(dir, 10 * gib, "field", Need::Estimated(10 * gib)).is_ok());
        let e = check_against(dir, 10 * gib, "field", Need::Estimated(10 * gib + 1)).unwrap_err().to_string();
        assert!(
            e.starts_with("the field is estimated at 10.0 GiB but the file system of /data has 10.0 GiB free"),
            "{e}"
        );
        let e = check_against(dir, gib, "shard", Need::AtLeast(128 * gib)).unwrap_err().to_string();
        assert!(
            e.starts_with("the shard needs 128.0 GiB or more but the file system of /data has 1.0 GiB free"),
            "{e}"
        );
        // This machine's temporary directory has some room, and none for 2⁶³ bytes.
        let tmp = std::env::temp_dir();
        assert!(free_space(&tmp).is_some_and(|f| f > 0));
        assert!(check(&tmp.join("f.vlf"), "field", Need::AtLeast(1)).is_ok());
        assert!(matches!(
            check(&tmp.join("f.vlf"), "field", Need::AtLeast(1 << 63)),
            Err(BakeError::NotEnoughDisk { .. })
        ));
    }
}
