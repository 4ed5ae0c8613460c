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

#[test]
fn render_writes_png_and_stats() {
    let (png, json) = (tmp("city.png"), tmp("city.json"));
    let (ok, _, err) = manylights(&[
        "render", "--scene", "city", "--lights", "500", "--width", "96", "--height", "54", "--frames", "2",
        "--technique", "clustered-naive", "--stats", json.to_str().unwrap(), "--out", png.to_str().unwrap(),
    ]);
    assert!(ok, "render failed:\n{err}");
    let img = image::open(&png).expect("a readable PNG").to_rgba8();
    assert_eq!(img.dimensions(), (96, 54));
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    for pass in ["gbuffer", "keys", "page table", "assignment", "shading"] {
        let ms = stats["gpu_ms"]["passes"][pass].as_f64().unwrap_or(-1.0);
        assert!(ms.is_finite() && ms >= 0.0, "pass {pass}: {ms}");
    }
    assert_eq!(stats["lights"], 500);
    assert!(stats["clusters"]["unique"].as_u64().unwrap() > 0);
    assert!(stats["bytes"]["buffers"]["light lists"].as_u64().unwrap() > 0);
    assert!(stats["lights_per_pixel"]["mean"].as_f64().unwrap() > 0.0);
    assert!(stats["device"]["name"].as_str().unwrap().len() > 2);
}

#[test]
fn render_bad_input_is_a_one_line_error() {
    let dir = tmp("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let bad_obj = dir.join("bad.obj");
    std::fs::write(&bad_obj, "v 0 0 0\nv 1 0 0\nf 1 2 999\n").unwrap();
    let nan = dir.join("nan.toml");
    std::fs::write(&nan, "geometry = \"city\"\n[[light]]\nposition = [nan, 0, 0]\nradius = 5\n").unwrap();
    let unknown = dir.join("unknown.toml");
    std::fs::write(&unknown, "geometry = \"city\"\nbrightness = 3\n").unwrap();
    let out = dir.join("o.png");
    let o = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--scene", "/nonexistent/x.obj"], "scene file /nonexistent/x.obj not found"),
        (vec!["--scene", bad_obj.to_str().unwrap()], "not a valid OBJ"),
        (vec!["--scene", nan.to_str().unwrap()], "light 0 has a non-finite value"),
        (vec!["--scene", unknown.to_str().unwrap()], "brightness"),
        (vec!["--lights", "0"], "--lights 0"),
        (vec!["--width", "0"], "--width 0"),
        (vec!["--lights", "4000000000"], "MiB per buffer"),
        (vec!["--scene", "nosuch"], "unknown scene \"nosuch\""),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["render", "--frames", "0", "--height", "36", "--out", o];
        if !extra.contains(&"--width") {
            args.extend(["--width", "64"]);
        }
        args.extend(extra.iter().copied());
        let (ok, _, err) = manylights(&args);
        assert!(!ok, "{extra:?} must fail");
        assert!(!err.contains("panicked"), "{extra:?} panicked:\n{err}");
        let error_lines: Vec<_> = err.lines().filter(|l| l.starts_with("error: ")).collect();
        assert_eq!(error_lines.len(), 1, "{extra:?}: one error line expected:\n{err}");
        assert!(err.contains(needle), "{extra:?}: error should mention {needle:?}:\n{err}");
    }
}
