//! The `manylights` binary: a real render, and bad input answered by a one-line error and a
//! non-zero exit (never a panic).
mod common;
use common::cli::{assert_one_line_error, manylights};
use common::temp::TempDir;

#[test]
fn render_writes_a_png() {
    let dir = TempDir::new("cli-png");
    let out = dir.join("clusters.png");
    let run = manylights(["debug-frame", "--view", "clusters", "--width", "160", "--height", "90", "--out", out.to_str().unwrap()]);
    assert!(run.ok, "render failed:\n{}", run.stderr);
    assert!(run.stderr.contains("device: "), "stderr names the device:\n{}", run.stderr);
    let img = image::open(&out).expect("a readable PNG").to_rgba8();
    assert_eq!(img.dimensions(), (160, 90));
    let distinct: std::collections::HashSet<_> = img.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 20, "a real picture has many colours, got {}", distinct.len());
}

#[test]
fn bad_input_is_a_one_line_error() {
    let dir = TempDir::new("cli-bad-frame");
    let out = dir.join("x.png");
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
        assert_one_line_error(&manylights(*args), &format!("{args:?}"), needle);
    }
}

#[test]
fn devices_lists_at_least_one_usable_device() {
    let run = manylights(["devices"]);
    assert!(run.ok, "{}", run.stderr);
    assert!(run.stdout.lines().any(|l| l.contains("subgroup") && !l.contains("unusable")), "{}", run.stdout);
}

#[test]
fn render_writes_png_and_stats() {
    let dir = TempDir::new("cli-stats");
    let (png, json) = (dir.join("city.png"), dir.join("city.json"));
    let run = manylights([
        "render", "--scene", "city", "--lights", "500", "--width", "96", "--height", "54", "--frames", "2",
        "--technique", "clustered-naive", "--stats", json.to_str().unwrap(), "--out", png.to_str().unwrap(),
    ]);
    assert!(run.ok, "render failed:\n{}", run.stderr);
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
    let dir = TempDir::new("cli-bad-render");
    let bad_obj = dir.write("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 999\n");
    let nan = dir.write("nan.toml", "geometry = \"city\"\n[[light]]\nposition = [nan, 0, 0]\nradius = 5\n");
    let unknown = dir.write("unknown.toml", "geometry = \"city\"\nbrightness = 3\n");
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
        assert_one_line_error(&manylights(&args), &format!("{extra:?}"), needle);
    }
}
