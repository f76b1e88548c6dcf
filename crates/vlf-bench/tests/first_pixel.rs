//! `vlf-bench first-pixel` end to end: new processes open a field and trace its first ray, warm
//! and cold, with both ways of opening, and the table reports every series.

#![forbid(unsafe_code)]

use std::path::Path;
use std::process::Command;

#[test]
fn first_pixel_reports_every_series() {
    let dir = tempfile::tempdir().unwrap();
    let field = dir.path().join("tiny.vlf");
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/fields/tiny.vlf"), &field).unwrap();
    let json = dir.path().join("runs.json");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_vlf-bench"));
    cmd.args(["first-pixel", "--quiet", "--runs", "2", "--access", "open,random"]);
    if cfg!(target_os = "linux") {
        cmd.arg("--cold");
    }
    let out = cmd.arg("--json").arg(&json).arg(&field).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    let rows: Vec<&str> = stdout.lines().filter(|l| l.starts_with("| tiny.vlf")).collect();
    let expected = if cfg!(target_os = "linux") { 4 } else { 2 };
    assert_eq!(rows.len(), expected, "{stdout}");
    // The centre ray of the box's outside view hits it; a miss would be flagged in the row.
    assert!(rows.iter().all(|r| !r.contains("missed")), "{stdout}");
    let series: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let series = series.as_array().unwrap();
    assert_eq!(series.len(), expected);
    for s in series {
        assert_eq!(s["runs"].as_array().unwrap().len(), 2);
        assert!(s["runs"].as_array().unwrap().iter().all(|r| r["open_ns"].as_u64().unwrap() > 0));
        if s["cache"] == "cold" {
            // Evicted before each run: nothing of the file was cached when the process started,
            // and what it read is at most the whole (10 KB) file.
            assert_eq!(s["max_resident_before"].as_f64(), Some(0.0), "{s}");
            assert!(s["resident_after"].as_array().unwrap().iter().all(|b| b.as_u64().unwrap() <= 10_404 + 4096));
        }
    }
}
