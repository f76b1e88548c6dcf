//! Time to first pixel: how long a fresh process takes to open a field and trace its first ray.
//!
//! Opening maps the file and checks the header and the section table (`Field::open`); the first
//! query then reads only the pages its walk touches. Neither depends on the file's size, so a
//! 1 MiB field and a field of several GiB should give the first pixel equally fast. This module
//! measures that, in a new process for every run (nothing cached in the process, the mapping
//! new), with the file's pages either already in the page cache (*warm*) or evicted from it
//! (*cold*, the first launch after a download or a reboot).
//!
//! [`child`] runs in the measured process: it times `Field::open` and the first
//! `closest_hit` (the primary ray through the centre of the paper's outside view) with a monotonic
//! clock and prints one JSON line.
//!
//! [`Access::Random`] measures an alternative to `Field::open`: the same mapping and checks
//! (`FieldView::from_bytes` on a `memmap2` map), with `madvise(MADV_RANDOM)` given before the
//! first byte is read. By default the kernel reads ahead around every page fault on a mapping
//! (up to the device's `read_ahead_kb`, 8 MiB on this project's machine), which for a cold field
//! means megabytes read for the few kilobytes a ray needs; the advice turns that off. [`measure`] runs it `runs` times per field and mode and
//! summarises. On Linux a cold run first evicts the file's pages with
//! `posix_fadvise(POSIX_FADV_DONTNEED)`, which needs no privileges and touches no other file, and
//! then checks with `mincore` how much of the file is still resident; the report shows that
//! fraction, so a run that could not be made cold is visible as such.

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;
use vlf_geom::Camera;
use vlf_runtime::Field;

/// What the measured process reports: one JSON line on standard output.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct ChildReport {
    /// `Field::open`: map, header, section table, content hash, in nanoseconds.
    pub open_ns: u64,
    /// The first `closest_hit`, in nanoseconds.
    pub first_ray_ns: u64,
    /// Whether the first ray hit a triangle (it should: it aims at the scene's centre).
    pub hit: bool,
}

/// How the measured process opens the field.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Access {
    /// `Field::open`, as a renderer would.
    Open,
    /// Map the file, `madvise(MADV_RANDOM)`, then `FieldView::from_bytes`: `Field::open` without
    /// the kernel's read-ahead.
    Random,
}

/// The body of the measured process: open `field`, trace the centre pixel's primary ray, print
/// a [`ChildReport`].
pub fn child(field: &Path, access: Access) -> Result<()> {
    let context = || format!("opening {}", field.display());
    // Each arm times the open, then the first `closest_hit` alone.
    let (open, first_ray, hit) = match access {
        Access::Open => {
            let start = Instant::now();
            let f = Field::open(field).with_context(context)?;
            let open = start.elapsed();
            let ray = centre_ray(f.bounding_sphere());
            let start = Instant::now();
            let hit = f.closest_hit(&ray);
            (open, start.elapsed(), hit)
        }
        Access::Random => {
            let start = Instant::now();
            let file = std::fs::File::open(field).with_context(context)?;
            // SAFETY: the mapping contract of `Field::open`: the benchmark's own file, not
            // modified while mapped; every read through the mapping is bounds-checked.
            let map = unsafe { memmap2::Mmap::map(&file) }.with_context(context)?;
            #[cfg(unix)]
            map.advise(memmap2::Advice::Random).with_context(context)?;
            let view = vlf_runtime::FieldView::from_bytes(&map).with_context(context)?;
            let open = start.elapsed();
            // The view keeps the sphere to itself; read it again (untimed, pages already read).
            let scene = vlf_runtime::FieldReader::new(&map).with_context(context)?.scene;
            let ray = centre_ray((scene.center, scene.radius));
            let start = Instant::now();
            let hit = view.closest_hit(&ray);
            (open, start.elapsed(), hit)
        }
    };
    let report =
        ChildReport { open_ns: open.as_nanos() as u64, first_ray_ns: first_ray.as_nanos() as u64, hit: hit.is_some() };
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}

/// The primary ray through the centre of the paper's outside view of the bounding sphere.
fn centre_ray((center, radius): ([f64; 3], f64)) -> vlf_geom::Ray {
    Camera::outside(center, radius, 1.0).ray(0.5, 0.5)
}

/// Page-cache state of the file before the measured process starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Cache {
    /// Every page already read once (by a warm-up run).
    Warm,
    /// Pages evicted before each run.
    Cold,
}

/// Every run of one field in one cache state.
#[derive(Clone, Debug, Serialize)]
pub struct Series {
    /// The field file.
    pub field: PathBuf,
    /// Its size in bytes.
    pub bytes: u64,
    /// Cache state.
    pub cache: Cache,
    /// How the field was opened.
    pub access: Access,
    /// The measured processes' reports, in run order.
    pub runs: Vec<ChildReport>,
    /// Wall time of each whole measured process (start, load, open, trace, exit), in nanoseconds.
    pub process_ns: Vec<u64>,
    /// The largest fraction of the file resident in the page cache just before a run (cold runs;
    /// `None` where it cannot be measured).
    pub max_resident_before: Option<f64>,
    /// Cold runs: bytes of the file in the page cache just after each run, which is what the
    /// measured process made the kernel read (with the kernel's read-ahead around each fault).
    pub resident_after: Vec<u64>,
}

/// Runs the measured process `runs` times for every field, warm and (if `cold`) cold.
pub fn measure(fields: &[PathBuf], accesses: &[Access], runs: usize, cold: bool, verbose: bool) -> Result<Vec<Series>> {
    if runs == 0 {
        bail!("--runs must be at least 1");
    }
    let exe = std::env::current_exe().context("finding this program's path")?;
    let mut all = Vec::new();
    for field in fields {
        let bytes = std::fs::metadata(field).with_context(|| format!("reading {}", field.display()))?.len();
        let modes: &[Cache] = if cold { &[Cache::Warm, Cache::Cold] } else { &[Cache::Warm] };
        for (&cache, &access) in modes.iter().flat_map(|c| accesses.iter().map(move |a| (c, a))) {
            let mut series = Series {
                field: field.clone(),
                bytes,
                cache,
                access,
                runs: Vec::new(),
                process_ns: Vec::new(),
                max_resident_before: None,
                resident_after: Vec::new(),
            };
            if cache == Cache::Warm {
                run_child(&exe, field, access)?; // warm-up: the pages the first ray needs are now cached
            }
            for _ in 0..runs {
                if cache == Cache::Cold {
                    evict(field)?;
                    let resident = resident_fraction(field)?;
                    series.max_resident_before = Some(series.max_resident_before.unwrap_or(0.0).max(resident));
                }
                let start = Instant::now();
                let report = run_child(&exe, field, access)?;
                series.process_ns.push(start.elapsed().as_nanos() as u64);
                series.runs.push(report);
                if cache == Cache::Cold {
                    series.resident_after.push((resident_fraction(field)? * bytes as f64).round() as u64);
                }
            }
            if verbose {
                let mut total: Vec<f64> = series.runs.iter().map(|r| (r.open_ns + r.first_ray_ns) as f64).collect();
                eprintln!(
                    "{} ({} bytes), {cache:?}, {access:?}: open + first ray median {:.1} µs over {runs} runs",
                    field.display(),
                    bytes,
                    crate::median(&mut total) / 1e3
                );
            }
            all.push(series);
        }
    }
    Ok(all)
}

fn run_child(exe: &Path, field: &Path, access: Access) -> Result<ChildReport> {
    let out = Command::new(exe)
        .arg("first-pixel-child")
        .arg(field)
        .arg("--access")
        .arg(format!("{access:?}").to_lowercase())
        .output()
        .with_context(|| format!("starting {}", exe.display()))?;
    if !out.status.success() {
        bail!("the measured process failed ({}): {}", out.status, String::from_utf8_lossy(&out.stderr).trim());
    }
    let line = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(line.trim()).with_context(|| format!("reading the measured process's report {line:?}"))
}

/// Asks the kernel to drop the file's pages from the page cache (after writing back any dirty
/// ones, which it would otherwise keep).
#[cfg(target_os = "linux")]
pub fn evict(path: &Path) -> Result<()> {
    use std::os::fd::AsRawFd;
    let file = std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
    // Dirty pages cannot be dropped: write them back first (a no-op for a file already synced).
    file.sync_data().with_context(|| format!("syncing {}", path.display()))?;
    // SAFETY: a plain system call on a file descriptor we own; it reads no memory of ours.
    let rc = unsafe { libc::posix_fadvise(file.as_raw_fd(), 0, 0, libc::POSIX_FADV_DONTNEED) };
    if rc != 0 {
        bail!("posix_fadvise(DONTNEED) on {}: {}", path.display(), std::io::Error::from_raw_os_error(rc));
    }
    Ok(())
}

/// Cold runs need Linux's `posix_fadvise` and `mincore`.
#[cfg(not(target_os = "linux"))]
pub fn evict(_path: &Path) -> Result<()> {
    bail!("cold runs are implemented for Linux only")
}

/// The fraction of the file's pages in the page cache, from `mincore` on a fresh mapping (which
/// reports the page cache without reading a byte).
#[cfg(target_os = "linux")]
pub fn resident_fraction(path: &Path) -> Result<f64> {
    let file = std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
    // SAFETY: a read-only mapping we never read through (mincore only inspects it); the file is
    // ours and not modified while mapped.
    let map = unsafe { memmap2::Mmap::map(&file) }.with_context(|| format!("mapping {}", path.display()))?;
    if map.is_empty() {
        return Ok(0.0);
    }
    // SAFETY: sysconf with a valid name has no preconditions.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) } as usize;
    let mut vec = vec![0u8; map.len().div_ceil(page)];
    // SAFETY: the range is the whole (page-aligned) mapping, and `vec` has one byte per page.
    let rc = unsafe { libc::mincore(map.as_ptr() as *mut libc::c_void, map.len(), vec.as_mut_ptr()) };
    if rc != 0 {
        bail!("mincore on {}: {}", path.display(), std::io::Error::last_os_error());
    }
    Ok(vec.iter().filter(|&&b| b & 1 != 0).count() as f64 / vec.len() as f64)
}

/// Residency cannot be measured off Linux.
#[cfg(not(target_os = "linux"))]
pub fn resident_fraction(_path: &Path) -> Result<f64> {
    bail!("page-cache residency is measured on Linux only")
}

/// `median (min – max)` of values in nanoseconds, shown in microseconds.
fn spread(v: &[u64]) -> String {
    let mut f: Vec<f64> = v.iter().map(|&x| x as f64 / 1e3).collect();
    let m = crate::median(&mut f);
    format!("{m:.1} ({:.1} – {:.1})", f[0], f[f.len() - 1])
}

/// The markdown table of every series: medians with the range over the runs, in microseconds.
pub fn table(series: &[Series]) -> String {
    let mut s = String::from(
        "| field | bytes | cache | open with | runs | open µs | first ray µs | open + first ray µs | whole process µs | cached before | read from disk, KiB |\n\
         | --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for x in series {
        let open: Vec<u64> = x.runs.iter().map(|r| r.open_ns).collect();
        let ray: Vec<u64> = x.runs.iter().map(|r| r.first_ray_ns).collect();
        let total: Vec<u64> = x.runs.iter().map(|r| r.open_ns + r.first_ray_ns).collect();
        let resident = x.max_resident_before.map_or_else(|| "—".to_owned(), |r| format!("≤ {:.2}%", 100.0 * r));
        let read = if x.resident_after.is_empty() {
            "—".to_owned()
        } else {
            let mut kib: Vec<f64> = x.resident_after.iter().map(|&b| b as f64 / 1024.0).collect();
            let m = crate::median(&mut kib);
            format!("{m:.0} ({:.0} – {:.0})", kib[0], kib[kib.len() - 1])
        };
        let misses = x.runs.iter().filter(|r| !r.hit).count();
        let name = x.field.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        s.push_str(&format!(
            "| {name}{} | {} | {} | {} | {} | {} | {} | {} | {} | {resident} | {read} |\n",
            if misses > 0 { format!(" ({misses} runs missed)") } else { String::new() },
            x.bytes,
            format!("{:?}", x.cache).to_lowercase(),
            match x.access {
                Access::Open => "`Field::open`",
                Access::Random => "map + `MADV_RANDOM`",
            },
            x.runs.len(),
            spread(&open),
            spread(&ray),
            spread(&total),
            spread(&x.process_ns),
        ));
    }
    s
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    #[test]
    fn eviction_empties_the_page_cache_of_a_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("data");
        std::fs::write(&path, vec![7u8; 1 << 20]).unwrap();
        // Not synced: `evict` must write the dirty pages back before it can drop them.
        assert_eq!(std::fs::read(&path).unwrap().len(), 1 << 20);
        let before = resident_fraction(&path).unwrap();
        assert!(before > 0.99, "a file just read is resident ({before})");
        evict(&path).unwrap();
        let after = resident_fraction(&path).unwrap();
        // tmpfs keeps every page in memory: nothing can be evicted there (the benchmark's
        // "resident before" column shows it). On a disk file system the file must be gone.
        if on_tmpfs(dir.path()) {
            assert!(after > 0.99, "{after}");
        } else {
            assert!(after < 0.01, "{:.1}% of the file is still cached after eviction", 100.0 * after);
        }
    }

    fn on_tmpfs(dir: &Path) -> bool {
        const TMPFS_MAGIC: i64 = 0x0102_1994;
        let c = std::ffi::CString::new(dir.as_os_str().as_encoded_bytes()).unwrap();
        // SAFETY: a NUL-terminated path and a zeroed struct for statfs to fill.
        unsafe {
            let mut st: libc::statfs = std::mem::zeroed();
            libc::statfs(c.as_ptr(), &mut st) == 0 && st.f_type as i64 == TMPFS_MAGIC
        }
    }
}
