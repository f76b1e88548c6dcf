//! The `threads` argument: `None` (or 0) runs on a pool of every core (`RAYON_NUM_THREADS` if
//! set), 1 on the calling thread, `k` on a pool of `k` threads.
//!
//! Pools are made here with `ThreadPoolBuilder::build`, never rayon's lazily made global pool,
//! whose failure to start (threads or memory exhausted) is a panic: here it is a `RuntimeError`.
//! The every-core pool is kept for later calls, and so is the last sized pool used: a caller that
//! asks for many sizes in turn does not pile up pools (each keeps its threads until dropped).

use pyo3::PyResult;
use pyo3::exceptions::PyRuntimeError;
use rayon::{ThreadPool, ThreadPoolBuilder};
use std::sync::{Arc, Mutex};

use crate::errors::value_error;

/// The most threads a call may ask for (the command line's limit).
pub const MAX_THREADS: usize = 1024;

/// Where a call runs.
#[derive(Clone)]
pub enum Threads {
    /// The calling thread, with no pool.
    One,
    /// A pool: of every core, or of the size asked for.
    Pool(Arc<ThreadPool>),
}

/// The pools kept for later calls: the every-core pool, and the last sized one (with its size).
#[derive(Default)]
struct Kept {
    every_core: Option<Arc<ThreadPool>>,
    sized: Option<(usize, Arc<ThreadPool>)>,
}

static KEPT: Mutex<Kept> = Mutex::new(Kept { every_core: None, sized: None });

fn build(threads: Option<usize>) -> PyResult<Arc<ThreadPool>> {
    let mut builder = ThreadPoolBuilder::new().thread_name(|i| format!("vlf-{i}"));
    if let Some(k) = threads {
        builder = builder.num_threads(k);
    }
    builder.build().map(Arc::new).map_err(|e| {
        let what = threads.map_or_else(|| "a thread for every core".to_owned(), |k| format!("{k} threads"));
        PyRuntimeError::new_err(format!("cannot start {what}: {e}"))
    })
}

impl Threads {
    /// The pool for the `threads` argument; a `ValueError` above [`MAX_THREADS`], a
    /// `RuntimeError` if its threads cannot be started.
    pub fn new(threads: Option<usize>) -> PyResult<Threads> {
        if threads == Some(1) {
            return Ok(Threads::One);
        }
        if let Some(k) = threads
            && k > MAX_THREADS
        {
            return Err(value_error(format!("threads = {k} is over the limit of {MAX_THREADS}")));
        }
        // A poisoned lock only means another call panicked while holding it: the pools are
        // still sound.
        let mut kept = KEPT.lock().unwrap_or_else(|p| p.into_inner());
        let pool = match threads {
            None | Some(0) => match &kept.every_core {
                Some(pool) => pool.clone(),
                None => kept.every_core.insert(build(None)?).clone(),
            },
            Some(k) => match &kept.sized {
                Some((size, pool)) if *size == k => pool.clone(),
                _ => {
                    // The pool kept before is dropped first (its threads end once no call
                    // uses it), so that at most one sized pool is kept at a time.
                    kept.sized = None;
                    let pool = build(Some(k))?;
                    kept.sized = Some((k, pool.clone()));
                    pool
                }
            },
        };
        Ok(Threads::Pool(pool))
    }

    /// Whether work should be split across threads.
    pub fn parallel(&self) -> bool {
        !matches!(self, Threads::One)
    }

    /// Runs `f` in this pool (on the calling thread for [`Threads::One`]). rayon's parallel
    /// iterators called in `f` run in the pool.
    pub fn run<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match self {
            Threads::Pool(pool) => pool.install(f),
            Threads::One => f(),
        }
    }
}
