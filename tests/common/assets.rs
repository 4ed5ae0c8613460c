//! Where the large shared assets (Sponza, the Stanford bunny) are, and what a test does without
//! them. Also compiled into the library's scene tests (`host/src/scene/tests.rs`), so it names no
//! host type.
//!
//! The assets are not in the repository. A test that needs one runs when it is present. When it
//! is absent the test is skipped with a printed note, unless `MANYLIGHTS_REQUIRE_ASSETS` is set
//! (`./dev.sh test` sets it when it finds the assets): then the test fails, so a broken path
//! cannot turn into a silent pass.
#![allow(dead_code)]
use std::path::PathBuf;

/// The environment variable that makes absent assets a failure.
pub const REQUIRE_VAR: &str = "MANYLIGHTS_REQUIRE_ASSETS";

/// `MANYLIGHTS_ASSETS`, else `../shared/assets` beside the repository.
pub fn dir() -> PathBuf {
    std::env::var_os("MANYLIGHTS_ASSETS")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/assets")))
}

/// Whether absent assets fail a test: `MANYLIGHTS_REQUIRE_ASSETS` set to anything but empty, `0`
/// or `false`.
pub fn required() -> bool {
    std::env::var(REQUIRE_VAR).is_ok_and(|v| !matches!(v.trim(), "" | "0" | "false"))
}

/// The directory of asset `name` (`sponza`, `bunny`) when it exists. When it does not: `None`
/// after a note on stderr, or a panic naming the path when the assets are [`required`].
pub fn asset(name: &str) -> Option<PathBuf> {
    let path = dir().join(name);
    if path.is_dir() {
        return Some(path);
    }
    assert!(!required(), "{name} is required ({REQUIRE_VAR} is set) but absent at {}", path.display());
    eprintln!("note: {name} absent at {}: skipped (set MANYLIGHTS_ASSETS, or {REQUIRE_VAR}=1 to make this a failure)", path.display());
    None
}
