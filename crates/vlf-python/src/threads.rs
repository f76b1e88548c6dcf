//! The `threads` argument: `None` (or 0) runs on rayon's global pool (every core), 1 on the
//! calling thread, `k` on a pool of `k` threads made once and kept for later calls.

use crate::errors::value_error;
use pyo3::PyResult;
use rayon::{ThreadPool, ThreadPoolBuilder};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// The most threads a call may ask for (the command line's limit).
pub const MAX_THREADS: usize = 1024;

/// Where a call runs.
#[derive(Clone)]
pub enum Threads {
    /// rayon's global pool.
    All,
    /// The calling thread, with no pool.
    One,
    /// A pool of its own.
    Pool(Arc<ThreadPool>),
}

fn pools() -> &'static Mutex<HashMap<usize, Arc<ThreadPool>>> {
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<ThreadPool>>>> = OnceLock::new();
    POOLS.get_or_init(Default::default)
}

impl Threads {
    /// The pool for the `threads` argument; a `ValueError` above [`MAX_THREADS`].
    pub fn new(threads: Option<usize>) -> PyResult<Threads> {
        match threads {
            None | Some(0) => Ok(Threads::All),
            Some(1) => Ok(Threads::One),
            Some(k) if k > MAX_THREADS => Err(value_error(format!("threads = {k} is over the limit of {MAX_THREADS}"))),
            Some(k) => {
                // A poisoned lock only means another call panicked while holding it: the map is
                // still sound.
                let mut map = pools().lock().unwrap_or_else(|p| p.into_inner());
                if let Some(pool) = map.get(&k) {
                    return Ok(Threads::Pool(pool.clone()));
                }
                let pool = ThreadPoolBuilder::new()
                    .num_threads(k)
                    .thread_name(|i| format!("vlf-{i}"))
                    .build()
                    .map_err(|e| value_error(format!("cannot start {k} threads: {e}")))?;
                let pool = Arc::new(pool);
                map.insert(k, pool.clone());
                Ok(Threads::Pool(pool))
            }
        }
    }

    /// Whether work should be split across threads.
    pub fn parallel(&self) -> bool {
        !matches!(self, Threads::One)
    }

    /// Runs `f` in this pool (on the calling thread for [`Threads::All`] and [`Threads::One`]:
    /// rayon's parallel iterators called there use the global pool).
    pub fn run<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match self {
            Threads::Pool(pool) => pool.install(f),
            Threads::All | Threads::One => f(),
        }
    }
}
