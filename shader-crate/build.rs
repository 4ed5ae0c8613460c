//! Declares every file of `src/techniques/` as a module of the crate root (`techniques.rs` in
//! `OUT_DIR`, included by `lib.rs`): a technique's kernels are its own files, with no line to add
//! here. Files are taken in name order; a name that is not a Rust identifier is an error.
use std::fmt::Write as _;
use std::path::Path;

fn main() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/techniques");
    println!("cargo::rerun-if-changed={}", dir.display());
    let mut files: Vec<_> = match std::fs::read_dir(&dir) {
        Ok(entries) => entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|x| x == "rs")).collect(),
        Err(_) => Vec::new(),
    };
    files.sort();
    let mut out = String::new();
    for path in files {
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        // `*_tests.rs` files are the test modules of their technique (it declares them).
        if stem.ends_with("_tests") {
            continue;
        }
        let ident = !stem.is_empty() && !stem.starts_with(|c: char| c.is_ascii_digit()) && stem.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        assert!(ident, "src/techniques/{stem}.rs: a module name must be a Rust identifier");
        println!("cargo::rerun-if-changed={}", path.display());
        writeln!(out, "#[path = {:?}]\npub mod {stem};", path.display().to_string()).unwrap();
    }
    std::fs::write(Path::new(&std::env::var("OUT_DIR").unwrap()).join("techniques.rs"), out).unwrap();
}
