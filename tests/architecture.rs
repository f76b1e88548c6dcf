//! The shape of the code, checked (`docs/architecture.md`, "Code map"):
//!
//! - **No module imports a module that imports it back**, in any crate of the workspace: for every
//!   crate root (`src/lib.rs`, `src/main.rs`), the modules reached through `mod` declarations and
//!   the references between them (`use crate::…`, `super::…`, `self::…`, a child module's name,
//!   and the same paths written inline) form a graph without cycles. Code under `#[cfg(test)]` is
//!   left out: a `mod tests` that uses `super::*` is part of its module, not a dependency.
//! - **No source file in `crates/*/src` is over 700 lines**, and the command line's `main.rs` is
//!   under 300.
//!
//! The scanner reads Rust as text (comments and literals removed), which is enough for the
//! `use` trees and paths this workspace writes; its own tests below show it finding a cycle.

#![forbid(unsafe_code)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// No source file under `crates/*/src` may be longer than this.
const MAX_LINES: usize = 700;
/// The command line's `main.rs` (parse, dispatch, print) must be shorter than this.
const MAX_MAIN_LINES: usize = 300;
const CLI_MAIN: &str = "crates/vlf-cli/src/main.rs";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("the repository").to_path_buf()
}

// ---------------------------------------------------------------------------------------------
// Reading Rust as tokens

#[derive(Clone, Debug, PartialEq, Eq)]
enum Tok {
    Ident(String),
    /// `::`
    Path,
    Punct(char),
}

/// The tokens of `source` that matter for paths: identifiers, `::` and single punctuation, with
/// comments, string, byte-string, raw-string and character literals removed (lifetimes kept as
/// identifiers).
fn tokens(source: &str) -> Vec<Tok> {
    let c: Vec<char> = source.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        let next = c.get(i + 1).copied();
        if ch == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if ch == '"' {
            i = skip_string(&c, i);
        } else if (ch == 'r' || ch == 'b') && is_raw_string_start(&c, i) {
            i = skip_raw_string(&c, i);
        } else if ch == 'b' && next == Some('"') {
            i = skip_string(&c, i + 1);
        } else if ch == 'b' && next == Some('\'') {
            i = skip_char(&c, i + 1);
        } else if ch == '\'' {
            i = skip_char(&c, i);
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(Tok::Ident(c[start..i].iter().collect()));
        } else if ch == ':' && next == Some(':') {
            out.push(Tok::Path);
            i += 2;
        } else {
            if !ch.is_whitespace() {
                out.push(Tok::Punct(ch));
            }
            i += 1;
        }
    }
    out
}

/// Skips a `"…"` literal starting at `c[i] == '"'`; returns the index after it.
fn skip_string(c: &[char], mut i: usize) -> usize {
    i += 1;
    while i < c.len() && c[i] != '"' {
        i += if c[i] == '\\' { 2 } else { 1 };
    }
    i + 1
}

/// Whether `r"`, `r#…"`, `br"` or `br#…"` starts at `i` (and is not the end of an identifier).
fn is_raw_string_start(c: &[char], i: usize) -> bool {
    if i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_') {
        return false;
    }
    let mut j = i + if c[i] == 'b' { 1 } else { 0 };
    if c.get(j) != Some(&'r') {
        return false;
    }
    j += 1;
    while c.get(j) == Some(&'#') {
        j += 1;
    }
    c.get(j) == Some(&'"')
}

fn skip_raw_string(c: &[char], mut i: usize) -> usize {
    while c[i] != '#' && c[i] != '"' {
        i += 1;
    }
    let mut hashes = 0;
    while c[i] == '#' {
        hashes += 1;
        i += 1;
    }
    i += 1;
    loop {
        if i >= c.len() {
            return i;
        }
        if c[i] == '"' && (1..=hashes).all(|k| c.get(i + k) == Some(&'#')) {
            return i + 1 + hashes;
        }
        i += 1;
    }
}

/// Skips a character literal at `c[i] == '\''`, or a lifetime's quote (`'a` without a closing
/// quote right after one character).
fn skip_char(c: &[char], i: usize) -> usize {
    match (c.get(i + 1), c.get(i + 2)) {
        (Some('\\'), _) => {
            let mut j = i + 2;
            while j < c.len() && c[j] != '\'' {
                j += 1;
            }
            j + 1
        }
        (Some(_), Some('\'')) => i + 3,
        _ => i + 1,
    }
}

// ---------------------------------------------------------------------------------------------
// Modules and the references between them

/// What one module file says: its file-backed child modules, and the module paths it refers to
/// (absolute within the crate, `[]` being the crate root).
#[derive(Debug, Default)]
struct ModuleFile {
    children: Vec<String>,
    references: BTreeSet<Vec<String>>,
}

/// Reads a module file whose module path is `module`.
fn read_module(module: &[String], source: &str) -> ModuleFile {
    let toks = tokens(source);
    let mut file = ModuleFile::default();
    // Inline modules (`mod x { … }`) are part of the file's module; `super` inside them first
    // climbs out of them. The stack holds the brace depth at which each one closes.
    let mut inline: Vec<usize> = Vec::new();
    let mut depth = 0usize;
    let mut paths: Vec<(usize, Vec<String>)> = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        match &toks[i] {
            Tok::Punct('#') if is_cfg_test(&toks, i) => {
                i = skip_item(&toks, attribute_end(&toks, i));
                continue;
            }
            Tok::Punct('{') => depth += 1,
            Tok::Punct('}') => {
                depth = depth.saturating_sub(1);
                if inline.last() == Some(&depth) {
                    inline.pop();
                }
            }
            Tok::Ident(kw) if kw == "mod" => {
                if let (Some(Tok::Ident(name)), Some(next)) = (toks.get(i + 1), toks.get(i + 2)) {
                    match next {
                        Tok::Punct(';') => file.children.push(name.clone()),
                        Tok::Punct('{') => {
                            inline.push(depth);
                            depth += 1;
                            i += 3;
                            continue;
                        }
                        _ => {}
                    }
                }
            }
            Tok::Ident(kw) if kw == "use" => {
                let (end, trees) = use_paths(&toks, i + 1);
                paths.extend(trees.into_iter().map(|p| (inline.len(), p)));
                i = end;
                continue;
            }
            Tok::Ident(first)
                if toks.get(i + 1) == Some(&Tok::Path) && toks.get(i.wrapping_sub(1)) != Some(&Tok::Path) =>
            {
                let mut path = vec![first.clone()];
                let mut j = i + 1;
                while toks.get(j) == Some(&Tok::Path) {
                    match toks.get(j + 1) {
                        Some(Tok::Ident(seg)) => path.push(seg.clone()),
                        _ => break,
                    }
                    j += 2;
                }
                paths.push((inline.len(), path));
                i = j;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    for (inline_depth, path) in paths {
        if let Some(absolute) = resolve(module, inline_depth, &file.children, &path) {
            file.references.insert(absolute);
        }
    }
    file
}

/// Whether `#[cfg(test)]` starts at `i`.
fn is_cfg_test(toks: &[Tok], i: usize) -> bool {
    let want = [Tok::Punct('#'), Tok::Punct('['), Tok::Ident("cfg".into()), Tok::Punct('('), Tok::Ident("test".into())];
    toks.len() > i + want.len() && toks[i..i + want.len()] == want && toks[i + 5] == Tok::Punct(')')
}

/// The index after the attribute starting at `i` (`#[ … ]`).
fn attribute_end(toks: &[Tok], i: usize) -> usize {
    let mut depth = 0;
    for (k, t) in toks.iter().enumerate().skip(i + 1) {
        match t {
            Tok::Punct('[') => depth += 1,
            Tok::Punct(']') => {
                depth -= 1;
                if depth == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
    }
    toks.len()
}

/// The index after the item starting at `i`: through its first `;` outside braces, or through
/// the brace block that is its body.
fn skip_item(toks: &[Tok], i: usize) -> usize {
    let mut depth = 0;
    for (k, t) in toks.iter().enumerate().skip(i) {
        match t {
            Tok::Punct('{') => depth += 1,
            Tok::Punct('}') => {
                depth -= 1;
                if depth == 0 {
                    return if toks.get(k + 1) == Some(&Tok::Punct(';')) { k + 2 } else { k + 1 };
                }
            }
            Tok::Punct(';') if depth == 0 => return k + 1,
            _ => {}
        }
    }
    toks.len()
}

/// The paths of the `use` tree starting at `i` (after `use`), and the index after its `;`.
fn use_paths(toks: &[Tok], i: usize) -> (usize, Vec<Vec<String>>) {
    let mut out = Vec::new();
    let end = use_tree(toks, i, &mut Vec::new(), &mut out);
    let end = toks[end..].iter().position(|t| *t == Tok::Punct(';')).map_or(toks.len(), |k| end + k + 1);
    (end, out)
}

/// Parses one use tree at `i` under `prefix`, adding its paths to `out`; returns the index after it.
fn use_tree(toks: &[Tok], mut i: usize, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) -> usize {
    let base = prefix.len();
    if toks.get(i) == Some(&Tok::Path) {
        // `::name`: an external crate.
        prefix.push("::".into());
        i += 1;
    }
    loop {
        match toks.get(i) {
            // `{self, …}`: the prefix itself.
            Some(Tok::Ident(seg)) if seg == "self" && base > 0 && prefix.len() == base => i += 1,
            Some(Tok::Ident(seg)) => {
                prefix.push(seg.clone());
                i += 1;
            }
            Some(Tok::Punct('*')) => i += 1,
            Some(Tok::Punct('{')) => {
                i += 1;
                while toks.get(i).is_some_and(|t| *t != Tok::Punct('}')) {
                    i = use_tree(toks, i, prefix, out);
                    if toks.get(i) == Some(&Tok::Punct(',')) {
                        i += 1;
                    }
                }
                prefix.truncate(base);
                return i + 1;
            }
            _ => break,
        }
        if toks.get(i) == Some(&Tok::Path) {
            i += 1;
        } else {
            break;
        }
    }
    if toks.get(i) == Some(&Tok::Ident("as".into())) {
        i += 2;
    }
    if prefix.len() > base || base > 0 {
        out.push(prefix.clone());
    }
    prefix.truncate(base);
    i
}

/// The crate-absolute module path a path written in `module` (inside `inline_depth` inline
/// modules) starts from, if it refers into the crate: `crate::…`, `super::…`, `self::…`, or a
/// child module's name. `None` for external crates, types and locals.
fn resolve(module: &[String], inline_depth: usize, children: &[String], path: &[String]) -> Option<Vec<String>> {
    let mut base = module.to_vec();
    let mut rest = path;
    match path.first().map(String::as_str) {
        Some("crate") => {
            base.clear();
            rest = &path[1..];
        }
        Some("super") => {
            let mut inline = inline_depth;
            while rest.first().map(String::as_str) == Some("super") {
                if inline > 0 {
                    inline -= 1;
                } else {
                    base.pop()?;
                }
                rest = &rest[1..];
            }
        }
        Some("self") => rest = &path[1..],
        Some(first) if children.iter().any(|c| c == first) => {}
        _ => return None,
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

/// A crate root's modules (by path) and the module each reference lands in.
struct Graph {
    root_file: PathBuf,
    edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
}

/// Walks the modules of the crate rooted at `root_file` (relative to `src`) through their `mod`
/// declarations, reading files with `read`; each reference goes to the longest known module that
/// prefixes it.
fn graph(src: &Path, root_file: &str, read: &dyn Fn(&Path) -> Option<String>) -> Graph {
    let mut files: BTreeMap<Vec<String>, ModuleFile> = BTreeMap::new();
    let mut todo = vec![(Vec::<String>::new(), src.join(root_file), src.to_path_buf())];
    while let Some((module, path, dir)) = todo.pop() {
        let source = read(&path).unwrap_or_else(|| panic!("cannot read {}", path.display()));
        let file = read_module(&module, &source);
        for child in &file.children {
            let (flat, nested) = (dir.join(format!("{child}.rs")), dir.join(child).join("mod.rs"));
            let (child_file, child_dir) =
                if read(&flat).is_some() { (flat, dir.join(child)) } else { (nested, dir.join(child)) };
            let mut child_module = module.clone();
            child_module.push(child.clone());
            todo.push((child_module, child_file, child_dir));
        }
        files.insert(module, file);
    }
    let mut edges = BTreeMap::new();
    for (module, file) in &files {
        let targets: BTreeSet<Vec<String>> = file
            .references
            .iter()
            .map(|r| (0..=r.len()).rev().map(|k| r[..k].to_vec()).find(|p| files.contains_key(p)).unwrap_or_default())
            .filter(|target| target != module)
            .collect();
        edges.insert(module.clone(), targets);
    }
    Graph { root_file: src.join(root_file), edges }
}

fn name(module: &[String]) -> String {
    if module.is_empty() { "crate".into() } else { module.join("::") }
}

/// Every cycle of the graph, one per strongly connected component, as `a -> b -> a`.
fn cycles(g: &Graph) -> Vec<String> {
    let nodes: Vec<&Vec<String>> = g.edges.keys().collect();
    let reach = |from: &Vec<String>| -> BTreeMap<Vec<String>, Vec<String>> {
        // Breadth-first, remembering each module's predecessor.
        let mut seen = BTreeMap::new();
        let mut queue = std::collections::VecDeque::from([from.clone()]);
        while let Some(m) = queue.pop_front() {
            for next in &g.edges[&m] {
                if !seen.contains_key(next) {
                    seen.insert(next.clone(), m.clone());
                    queue.push_back(next.clone());
                }
            }
        }
        seen
    };
    let mut reported: BTreeSet<Vec<String>> = BTreeSet::new();
    let mut out = Vec::new();
    for m in nodes {
        if reported.contains(m) {
            continue;
        }
        let seen = reach(m);
        if let Some(mut at) = seen.get(m).cloned() {
            // A path back to `m`: follow predecessors from m's predecessor.
            let mut cycle = vec![m.clone()];
            while at != *m {
                cycle.push(at.clone());
                at = seen[&at].clone();
            }
            cycle.push(m.clone());
            cycle.reverse();
            reported.extend(cycle.iter().cloned());
            out.push(cycle.iter().map(|c| name(c)).collect::<Vec<_>>().join(" -> "));
        }
    }
    out
}

/// The crate roots of the workspace: `src/lib.rs` and `src/main.rs` of every package under
/// `crates/`, and the `tests` package's library.
fn crate_roots() -> Vec<(PathBuf, &'static str)> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root().join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path().join("src"))
        .filter(|p| p.is_dir())
        .collect();
    dirs.push(root().join("tests/src"));
    dirs.sort();
    dirs.into_iter()
        .flat_map(|src| ["lib.rs", "main.rs"].into_iter().map(move |f| (src.clone(), f)))
        .filter(|(src, f)| src.join(f).is_file())
        .collect()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The rules

#[test]
fn no_module_imports_a_module_that_imports_it_back() {
    let read = |p: &Path| std::fs::read_to_string(p).ok();
    let mut found = Vec::new();
    let mut modules = 0;
    for (src, root_file) in crate_roots() {
        let g = graph(&src, root_file, &read);
        modules += g.edges.len();
        for cycle in cycles(&g) {
            found.push((g.root_file.strip_prefix(root()).unwrap().to_str().unwrap().to_string(), cycle));
        }
    }
    assert!(modules > 50, "only {modules} modules found: is the scanner reading the crates?");
    let cycles: Vec<String> = found.iter().map(|(file, cycle)| format!("{file}: {cycle}")).collect();
    assert!(
        cycles.is_empty(),
        "modules that import each other (a module graph must have no cycle):\n{}",
        cycles.join("\n")
    );
}

#[test]
fn no_source_file_is_over_700_lines_and_the_command_lines_main_is_under_300() {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(root().join("crates")).unwrap() {
        let src = entry.unwrap().path().join("src");
        if src.is_dir() {
            rust_files(&src, &mut files);
        }
    }
    assert!(files.len() > 50, "only {} files under crates/*/src", files.len());
    let lines = |p: &Path| std::fs::read_to_string(p).unwrap().lines().count();
    let mut long = Vec::new();
    for file in &files {
        let relative = file.strip_prefix(root()).unwrap().to_str().unwrap().to_string();
        let n = lines(file);
        if n > MAX_LINES {
            long.push(format!("{relative}: {n} lines"));
        }
    }
    assert!(long.is_empty(), "source files over {MAX_LINES} lines (split them by job):\n{}", long.join("\n"));
    let main = lines(&root().join(CLI_MAIN));
    assert!(main < MAX_MAIN_LINES, "{CLI_MAIN} is {main} lines; it only parses, dispatches and prints");
}

// ---------------------------------------------------------------------------------------------
// The scanner, on made-up crates

/// A crate of in-memory files (paths relative to `src/`).
fn made_up(files: &[(&str, &str)]) -> Graph {
    let files: BTreeMap<PathBuf, String> =
        files.iter().map(|(p, s)| (Path::new("src").join(p), s.to_string())).collect();
    graph(Path::new("src"), "lib.rs", &|p: &Path| files.get(p).cloned())
}

/// Every edge as `from -> to`, sorted.
fn edges(g: &Graph) -> Vec<String> {
    let mut all: Vec<String> = g
        .edges
        .iter()
        .flat_map(|(from, to)| to.iter().map(move |t| format!("{} -> {}", name(from), name(t))))
        .collect();
    all.sort();
    all
}

#[test]
fn the_scanner_finds_and_names_a_cycle() {
    let g = made_up(&[
        ("lib.rs", "pub mod bake;\npub mod params;\npub mod shard;\npub use bake::run;"),
        ("bake.rs", "use crate::params::{Params, choose};\npub fn run() { crate::shard::ShardSpec::new(); }"),
        ("params.rs", "use super::bake::{sample, Prepared as P};"),
        ("shard.rs", "// use crate::bake;\nconst S: &str = \"crate::bake::x\";\npub struct ShardSpec;"),
    ]);
    assert_eq!(edges(&g), ["bake -> params", "bake -> shard", "crate -> bake", "params -> bake"]);
    assert_eq!(cycles(&g), ["bake -> params -> bake"]);
}

#[test]
fn the_scanner_follows_use_trees_inline_paths_and_nested_modules() {
    let g = made_up(&[
        ("lib.rs", "mod a;\nmod b;\nmod c;\npub use self::a::{self as alias, x::{Y, z::*}};"),
        ("a/mod.rs", "pub mod x;\nfn f() { x::g(); }"),
        ("a/x.rs", "pub mod z;\nuse super::super::b;\nuse ::std::fmt;\nuse std::io;"),
        ("a/x/z.rs", "fn h<'a>(s: &'a str) -> char { let _ = '\\''; let _ = r#\"crate::c\"#; 'x' }"),
        ("b.rs", "use crate::{a::x::z as zz, c};\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use crate::a;\n}"),
        ("c.rs", "mod inner {\n    use super::super::b;\n    pub fn f() { super::g(); }\n}\nfn g() {}"),
    ]);
    assert_eq!(
        edges(&g),
        [
            "a -> a::x",
            "a::x -> b",
            "b -> a::x::z",
            "b -> c",
            "c -> b",
            "crate -> a",
            "crate -> a::x",
            "crate -> a::x::z"
        ]
    );
    assert_eq!(cycles(&g), ["b -> c -> b"]);
}
