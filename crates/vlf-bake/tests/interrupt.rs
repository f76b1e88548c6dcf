//! `atomic::remove_live_temp_files`, which the command line's SIGINT and SIGTERM handler calls
//! before it exits. A test binary of its own: after it, no atomic write of the process starts or
//! commits.

use std::io::Write;
use std::path::PathBuf;
use vlf_bake::atomic::{AtomicFile, remove_live_temp_files, write_atomically};

fn names(dir: &std::path::Path) -> Vec<String> {
    let mut n: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    n.sort();
    n
}

#[test]
fn an_interruption_removes_every_live_temporary_file_and_stops_later_writes() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    write_atomically(&path("done.bin"), |w| w.write_all(b"committed before")).unwrap();
    std::fs::write(path("kept.bin"), b"previous").unwrap();
    let replacing = AtomicFile::create(&path("kept.bin")).unwrap();
    replacing.file().write_all(b"new contents, never committed").unwrap();
    let fresh = AtomicFile::create(&path("fresh.bin")).unwrap();
    drop(AtomicFile::create(&path("dropped.bin")).unwrap());
    let mut live: Vec<PathBuf> = vec![replacing.temp_path().to_path_buf(), fresh.temp_path().to_path_buf()];
    live.sort();

    let mut removed = remove_live_temp_files();
    removed.sort();
    assert_eq!(removed, live, "exactly the live temporary files are removed");
    assert_eq!(names(dir.path()), ["done.bin", "kept.bin"]);

    // A commit after it fails and leaves the path as it was; nothing new starts.
    assert_eq!(replacing.commit().unwrap_err().kind(), std::io::ErrorKind::Interrupted);
    drop(fresh);
    assert_eq!(std::fs::read(path("kept.bin")).unwrap(), b"previous");
    assert_eq!(AtomicFile::create(&path("later.bin")).err().map(|e| e.kind()), Some(std::io::ErrorKind::Interrupted));
    assert!(write_atomically(&path("later.bin"), |w| w.write_all(b"x")).is_err());
    assert_eq!(names(dir.path()), ["done.bin", "kept.bin"]);
    assert_eq!(remove_live_temp_files(), Vec::<PathBuf>::new());
}
