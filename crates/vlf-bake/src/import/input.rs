//! Reading input files (meshes, OBJ material libraries, external glTF buffers): only regular
//! files, and never more bytes than asked for, by the rule of [`vlf_runtime::regular`], which
//! every crate of the pipeline reads its inputs by (re-exported here for the importers' callers).

use std::io;
use std::path::Path;

pub use vlf_runtime::regular::{NotARegularFile, check_regular_file, read_regular_file};

/// How the importers fetch a file a mesh refers to: its path, and the most bytes wanted of it.
pub(super) type ReadFile<'a> = dyn Fn(&Path, u64) -> io::Result<Vec<u8>> + 'a;
