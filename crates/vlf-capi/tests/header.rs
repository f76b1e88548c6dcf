//! `include/vlf.h` is what cbindgen generates from `src/lib.rs`, so the header cannot drift from
//! the library. `UPDATE_EXPECT=1 cargo test -p vlf-capi --test header` rewrites it.

use std::path::Path;

#[test]
fn header_is_current() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).expect("read cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_crate(crate_dir)
        .with_config(config)
        .generate()
        .expect("cbindgen cannot generate the header");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let generated = String::from_utf8(generated).expect("UTF-8 header");
    let path = crate_dir.join("include/vlf.h");
    if std::env::var_os("UPDATE_EXPECT").is_some() {
        std::fs::write(&path, &generated).expect("write include/vlf.h");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != generated {
        let line = committed.lines().zip(generated.lines()).position(|(a, b)| a != b);
        let at = line.map_or_else(|| "the end".to_owned(), |l| format!("line {}", l + 1));
        let show = |text: &str| line.and_then(|l| text.lines().nth(l)).unwrap_or("").to_owned();
        panic!(
            "include/vlf.h is stale (first difference at {at}: committed {:?}, generated {:?}); regenerate it \
             with `UPDATE_EXPECT=1 cargo test -p vlf-capi --test header` and commit it",
            show(&committed),
            show(&generated)
        );
    }
}
