//! The pool of worker threads a command runs on. `--threads` (or `RAYON_NUM_THREADS`) above the
//! cores available is reduced to them with one warning: the work is CPU-bound, so more threads
//! cannot make it faster, and thousands of them made a bake forty times slower (and, past the
//! system's limits, hang). `--threads` itself accepts 1 to [`MAX_THREADS`], and so does
//! `RAYON_NUM_THREADS` when `--threads` is not given: any other value of it (`abc`, `0`, `-1`,
//! `5000`) is a bad command line (exit 2) with the message of `--threads`, not silently ignored as
//! rayon would; set but empty, it counts as unset. Failing to start the workers is an error, not a
//! panic; a worker that panics ends the process (`crate::stop`).

use crate::values::{BadUsage, MAX_THREADS, between};
use anyhow::{Result, anyhow};

/// The environment variable rayon reads, honoured here with the range and clamp of `--threads`.
const THREADS_ENV: &str = "RAYON_NUM_THREADS";

/// How many workers to start for `requested` (`--threads`), else for `RAYON_NUM_THREADS`, else
/// one per core; with the warning to print if a request was reduced. A `RAYON_NUM_THREADS` out of
/// the range of `--threads` is a [`BadUsage`].
fn thread_count(
    requested: Option<usize>,
    env: Option<&str>,
    cores: usize,
) -> Result<(usize, Option<String>), BadUsage> {
    let env = env.filter(|v| !v.is_empty());
    let (asked, what) = match (requested, env) {
        (Some(t), _) => (t, format!("--threads {t}")),
        (None, Some(v)) => {
            let t = between(1, MAX_THREADS).check(THREADS_ENV, v, "")?;
            (t, format!("{THREADS_ENV}={t}"))
        }
        (None, None) => return Ok((cores, None)),
    };
    let most = cores.clamp(1, MAX_THREADS);
    if asked <= most {
        return Ok((asked, None));
    }
    let warning = format!(
        "warning: {what} is more than the {most} cores available; using {most} (more threads than cores cannot speed up this work)"
    );
    Ok((most, Some(warning)))
}

/// Runs `f` on a new pool of worker threads (see the module documentation): everything the
/// libraries do in parallel inside `f` runs there.
pub fn with_threads<T: Send>(requested: Option<usize>, f: impl FnOnce() -> Result<T> + Send) -> Result<T> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let env = std::env::var(THREADS_ENV).ok();
    let (threads, warning) = thread_count(requested, env.as_deref(), cores)?;
    if let Some(w) = warning {
        eprintln!("{w}");
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("vlf-worker-{i}"))
        .build()
        .map_err(|e| anyhow!("cannot start {threads} worker threads: {e}"))?;
    pool.install(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_above_the_cores_are_reduced_with_a_warning() {
        let count = |requested, env, cores| thread_count(requested, env, cores).unwrap();
        assert_eq!(count(None, None, 8), (8, None));
        assert_eq!(count(Some(3), None, 8), (3, None));
        assert_eq!(count(Some(8), Some("2"), 8), (8, None));
        let (n, w) = count(Some(1024), None, 2);
        assert_eq!(n, 2);
        assert_eq!(
            w.unwrap(),
            "warning: --threads 1024 is more than the 2 cores available; using 2 (more threads than cores cannot speed up this work)"
        );
        let (n, w) = count(None, Some("1000"), 4);
        assert_eq!(n, 4);
        assert!(w.unwrap().starts_with("warning: RAYON_NUM_THREADS=1000 is more than the 4 cores"));
        // Empty is unset.
        assert_eq!(count(None, Some(""), 4), (4, None));
        // A machine with more cores than the cap still gets at most the cap.
        assert_eq!(count(Some(1024), None, 4096), (1024, None));
        assert_eq!(count(None, None, 4096).0, 4096);
    }

    /// What rayon would silently ignore is refused, as `--threads` would refuse it.
    #[test]
    fn an_environment_out_of_range_is_refused_like_threads() {
        for bad in ["0", "-1", "abc", "1025", "100000"] {
            let e = thread_count(None, Some(bad), 4).unwrap_err();
            assert_eq!(e.0, format!("RAYON_NUM_THREADS must be between 1 and 1024, got {bad}"));
        }
        // --threads wins: the environment is not read.
        assert_eq!(thread_count(Some(2), Some("abc"), 4).unwrap(), (2, None));
    }
}
