//! Progress reporting: the [`Progress`] callbacks a long operation (a bake, a merge, packing)
//! calls, which the command line draws as a bar, and [`NoProgress`].

/// Progress callbacks; the CLI draws a bar, tests pass [`NoProgress`].
pub trait Progress: Sync {
    /// A phase with `total` units of work begins.
    fn begin(&self, _phase: &str, _total: u64) {}
    /// `done` more units of the current phase are complete.
    fn advance(&self, _done: u64) {}
    /// The current phase ended.
    fn end(&self) {}
}

/// Reports nothing.
pub struct NoProgress;
impl Progress for NoProgress {}
