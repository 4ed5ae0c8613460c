//! The `manylights` binary: a real render, and bad input answered by a one-line error and a
//! non-zero exit (never a panic).
use std::process::Command;

fn manylights(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(args)
        .env("MANYLIGHTS_VALIDATION", "true")
        .output()
        .expect("running manylights");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("manylights-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn render_writes_a_png() {
    let out = tmp("clusters.png");
    let (ok, _, err) = manylights(&["debug-frame", "--view", "clusters", "--width", "160", "--height", "90", "--out", out.to_str().unwrap()]);
    assert!(ok, "render failed:\n{err}");
    assert!(err.contains("device: "), "stderr names the device:\n{err}");
    let img = image::open(&out).expect("a readable PNG").to_rgba8();
    assert_eq!(img.dimensions(), (160, 90));
    let distinct: std::collections::HashSet<_> = img.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 20, "a real picture has many colours, got {}", distinct.len());
}

#[test]
fn bad_input_is_a_one_line_error() {
    let out = tmp("x.png");
    let o = out.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["debug-frame", "--width", "0", "--out", o], "resolution 0x"),
        (&["debug-frame", "--height", "0", "--out", o], "resolution"),
        (&["debug-frame", "--width", "100000", "--out", o], "resolution"),
        (&["debug-frame", "--tile-size", "0", "--out", o], "tile size 0"),
        (&["debug-frame", "--out", "/nonexistent-dir/x.png"], "/nonexistent-dir/x.png"),
        (&["--device", "no-such-gpu-xyz", "debug-frame", "--out", o], "no Vulkan device matches"),
    ];
    for (args, needle) in cases {
        let (ok, _, err) = manylights(args);
        assert!(!ok, "{args:?} must fail");
        assert!(!err.contains("panicked"), "{args:?} panicked:\n{err}");
        let error_lines: Vec<_> = err.lines().filter(|l| l.starts_with("error: ")).collect();
        assert_eq!(error_lines.len(), 1, "{args:?}: one error line expected:\n{err}");
        assert!(err.contains(needle), "{args:?}: error should mention {needle:?}:\n{err}");
    }
}

#[test]
fn devices_lists_at_least_one_usable_device() {
    let (ok, out, err) = manylights(&["devices"]);
    assert!(ok, "{err}");
    assert!(out.lines().any(|l| l.contains("subgroup") && !l.contains("unusable")), "{out}");
}
