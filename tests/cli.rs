//! The `manylights` binary: a real render, and bad input answered by a one-line error and exit
//! status 2 (never a panic); other failures exit with 1.
mod common;
use common::cli::{assert_refused, manylights_env, BAD_INPUT};
use common::temp::TempDir;

/// Runs a command that must fail with `status`; see [`assert_refused`].
fn refused(args: &[&str], env: &[(&str, &str)], status: i32, needles: &[&str]) {
    assert_refused(&manylights_env(args, env), &format!("{args:?}"), status, needles);
}

/// `(succeeded, stdout, stderr)` of `manylights <args>`.
fn manylights(args: &[&str]) -> (bool, String, String) {
    let r = manylights_env(args, &[]);
    (r.ok, r.stdout, r.stderr)
}

#[test]
fn render_writes_a_png() {
    let dir = TempDir::new("cli-png");
    let out = dir.join("clusters.png");
    let (ok, _, err) = manylights(&["debug-frame", "--view", "clusters", "--width", "160", "--height", "90", "--out", out.to_str().unwrap()]);
    assert!(ok, "render failed:\n{err}");
    assert!(err.contains("device: "), "stderr names the device:\n{err}");
    let img = image::open(&out).expect("a readable PNG").to_rgba8();
    assert_eq!(img.dimensions(), (160, 90));
    let distinct: std::collections::HashSet<_> = img.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 20, "a real picture has many colours, got {}", distinct.len());
}

#[test]
fn debug_frame_bad_input_is_a_one_line_error_with_status_2() {
    let dir = TempDir::new("cli-bad-frame");
    let out = dir.join("x.png");
    let o = out.to_str().unwrap();
    let cases: &[(&[&str], &[&str])] = &[
        (&["debug-frame", "--width", "0", "--out", o], &["--width 0 is out of range"]),
        (&["debug-frame", "--height", "0", "--out", o], &["--height 0 is out of range"]),
        (&["debug-frame", "--width", "100000", "--out", o], &["--width 100000", "maxImageDimension2D"]),
        (&["debug-frame", "--tile-size", "0", "--out", o], &["--tile-size 0 is out of range", "1..=1024"]),
        (&["debug-frame", "--tile-size", "4000000000", "--out", o], &["--tile-size 4000000000"]),
        (&["debug-frame", "--out", "/nonexistent-dir/x.png"], &["--out /nonexistent-dir/x.png", "does not exist"]),
        (&["--device", "no-such-gpu-xyz", "debug-frame", "--out", o], &["no Vulkan device matches"]),
        (&["debug-frame", "--view", "shaded", "--out", o], &["'shaded'", "octa-error"]),
        (&["debug-frame", "--precision", "oct9", "--out", o], &["'oct9'", "oct16"]),
        (&["debug-frame", "--width", "-5", "--out", o], &["--width"]),
        (&["debug-frame", "--no-such-flag"], &["--no-such-flag"]),
    ];
    for (args, needles) in cases {
        refused(args, &[], BAD_INPUT, needles);
    }
}

/// The old name of the depth view still works, and a machine without Vulkan is not bad input.
#[test]
fn other_failures_exit_with_1() {
    let dir = TempDir::new("cli-slices");
    let out = dir.join("slices.png");
    let (ok, _, err) = manylights(&["debug-frame", "--view", "slices", "--width", "32", "--height", "18", "--out", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    let no_vulkan = [("VK_ICD_FILENAMES", "/nonexistent/icd.json"), ("VK_DRIVER_FILES", "/nonexistent/icd.json")];
    refused(&["debug-frame", "--out", out.to_str().unwrap()], &no_vulkan, 1, &["Vulkan"]);
}

#[test]
fn devices_lists_at_least_one_usable_device() {
    let (ok, out, err) = manylights(&["devices"]);
    assert!(ok, "{err}");
    assert!(out.lines().any(|l| l.contains("subgroup") && !l.contains("unusable")), "{out}");
}

/// `MANYLIGHTS_VALIDATION` takes the usual spellings of a switch (the README writes `=1`); a
/// value that is none is a bad-input error naming it.
#[test]
fn the_validation_variable_takes_1_and_0() {
    for v in ["1", "0", "yes", "off"] {
        let run = manylights_env(["devices"], &[("MANYLIGHTS_VALIDATION", v)]);
        assert!(run.ok, "MANYLIGHTS_VALIDATION={v}: {}", run.stderr);
    }
    refused(&["devices"], &[("MANYLIGHTS_VALIDATION", "maybe")], BAD_INPUT, &["maybe"]);
}

#[test]
fn render_writes_png_and_stats() {
    let dir = TempDir::new("cli-stats");
    let (png, json) = (dir.join("city.png"), dir.join("city.json"));
    let (ok, _, err) = manylights(&[
        "render", "--scene", "city", "--lights", "500", "--width", "96", "--height", "54", "--frames", "2",
        "--technique", "clustered-naive", "--stats", json.to_str().unwrap(), "--out", png.to_str().unwrap(),
    ]);
    assert!(ok, "render failed:\n{err}");
    let img = image::open(&png).expect("a readable PNG").to_rgba8();
    assert_eq!(img.dimensions(), (96, 54));
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    for pass in ["gbuffer", "unique clusters", "assignment", "shading"] {
        let ms = stats["gpu_ms"]["passes"][pass].as_f64().unwrap_or(-1.0);
        assert!(ms.is_finite() && ms >= 0.0, "pass {pass}: {ms}");
    }
    assert_eq!(stats["lights"], 500);
    assert!(stats["clusters"]["unique"].as_u64().unwrap() > 0);
    assert!(stats["bytes"]["buffers"]["light lists"].as_u64().unwrap() > 0);
    assert!(stats["lights_per_pixel"]["mean"].as_f64().unwrap() > 0.0);
    assert!(stats["device"]["name"].as_str().unwrap().len() > 2);
}

/// `--dispatch-times` times each command inside the passes as `pass · kernel` (in the stats
/// and on stderr); without it only the passes are listed. `--unique-clusters` picks the kernels
/// that find the unique clusters: the tile kernel (the default) or the page table's.
#[test]
fn render_times_each_dispatch_on_request() {
    let dir = TempDir::new("cli-dispatch-times");
    let (png, json) = (dir.join("city.png"), dir.join("city.json"));
    let run = |extra: &[&str]| {
        let mut args = vec![
            "render", "--scene", "city", "--lights", "300", "--width", "64", "--height", "36", "--frames", "1",
            "--technique", "clustered-bvh", "--stats", json.to_str().unwrap(), "--out", png.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let (ok, _, err) = manylights(&args);
        assert!(ok, "render failed:\n{err}");
        let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        (stats["gpu_ms"]["passes"].as_object().unwrap().clone(), err)
    };
    let (passes, _) = run(&[]);
    assert!(passes.keys().all(|k| !k.contains(" · ")), "no parts without the flag: {passes:?}");
    let tiles = ["unique clusters · clustered::tile_clusters", "shading · clustered::shade_clustered_tiles"];
    let pages = ["keys · clustered::pixel_keys", "page table · clustered::allocate_pages", "page table · clustered::store_slots"];
    for (flags, parts, absent, timed) in [
        (&["--dispatch-times"][..], &tiles[..], &pages[..], &["unique clusters", "assignment", "shading"][..]),
        (&["--dispatch-times", "--unique-clusters", "page-table"], &pages, &tiles, &["keys", "page table", "assignment", "shading"]),
    ] {
        let (passes, err) = run(flags);
        for part in parts {
            let ms = passes.iter().find(|(k, _)| k.starts_with(part)).and_then(|(_, v)| v.as_f64());
            assert!(ms.is_some_and(|ms| ms.is_finite() && ms >= 0.0), "{flags:?}: part {part:?}: {passes:?}");
            assert!(err.contains(part), "{flags:?}: stderr lists {part:?}:\n{err}");
        }
        for part in absent {
            assert!(!passes.keys().any(|k| k.starts_with(part)), "{flags:?}: {part:?} does not run: {passes:?}");
        }
        for pass in timed {
            assert!(passes[*pass].is_number(), "{flags:?}: the pass {pass} is still timed: {passes:?}");
        }
    }
}

/// `--sort` reaches the light sort's kernels (`--dispatch-times` names them): `auto`, the
/// default, runs the bitonic sort up to 32 768 lights (one block sort up to 1 024, then merge
/// levels) and the radix sort above; `radix` and `bitonic` run theirs at any count.
#[test]
fn sort_flag_picks_the_light_sort_kernels() {
    let dir = TempDir::new("cli-sort");
    let (png, json) = (dir.join("city.png"), dir.join("city.json"));
    let kernels = |lights: &str, extra: &[&str]| -> Vec<String> {
        let mut args = vec![
            "render", "--scene", "city", "--lights", lights, "--width", "64", "--height", "36", "--frames", "1",
            "--technique", "clustered-bvh", "--dispatch-times", "--stats", json.to_str().unwrap(), "--out", png.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let (ok, _, err) = manylights(&args);
        assert!(ok, "render failed:\n{err}");
        let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        stats["gpu_ms"]["passes"].as_object().unwrap().keys().filter_map(|k| k.strip_prefix("light sort · ").map(str::to_owned)).collect()
    };
    for (lights, flags, runs, absent) in [
        ("1000", &[][..], "entries::bitonic_block_sort", "entries::radix_"),
        ("3000", &[], "entries::bitonic_merge", "entries::radix_"),
        ("40000", &[], "entries::radix_histogram", "entries::bitonic_"),
        ("1000", &["--sort", "radix"], "entries::radix_sort_tile", "entries::bitonic_"),
        ("3000", &["--sort", "bitonic"], "entries::bitonic_merge", "entries::radix_"),
    ] {
        let got = kernels(lights, flags);
        assert!(got.iter().any(|k| k.starts_with(runs)), "{lights} lights {flags:?}: {runs} runs: {got:?}");
        assert!(!got.iter().any(|k| k.starts_with(absent)), "{lights} lights {flags:?}: no {absent}: {got:?}");
    }
}

/// `--kernel-stats` lists what the driver compiled each kernel that ran to, one line per kernel
/// executable, or says in one line that the device cannot tell; either way the render succeeds
/// without a validation message.
#[test]
fn render_reports_kernel_statistics_or_why_not() {
    let dir = TempDir::new("cli-kernel-stats");
    let png = dir.join("city.png");
    let (ok, _, err) = manylights(&[
        "render", "--scene", "city", "--lights", "300", "--width", "64", "--height", "36", "--frames", "1",
        "--technique", "clustered-bvh", "--kernel-stats", "--out", png.to_str().unwrap(),
    ]);
    assert!(ok, "render failed:\n{err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("kernel ") && l.contains("): ")).collect();
    if err.contains("kernel statistics: ") {
        assert!(err.contains("does not offer VK_KHR_pipeline_executable_properties"), "names the missing extension:\n{err}");
        assert!(lines.is_empty(), "no statistics from a device that cannot give them:\n{err}");
    } else {
        for kernel in ["clustered::tile_clusters", "clustered::shade_clustered"] {
            assert!(lines.iter().any(|l| l.starts_with(&format!("kernel {kernel}"))), "{kernel} listed:\n{err}");
        }
    }
}

/// `--fp-lists array` reaches Forward+ and its stats: the layout is named and the array's
/// buffers are listed.
#[test]
fn render_forward_plus_with_array_lists() {
    let dir = TempDir::new("cli-fp-lists");
    let (png, json) = (dir.join("fp.png"), dir.join("fp.json"));
    let (ok, _, err) = manylights(&[
        "render", "--scene", "city", "--lights", "300", "--width", "64", "--height", "36", "--frames", "1",
        "--technique", "forward-plus", "--fp-lists", "array", "--stats", json.to_str().unwrap(), "--out", png.to_str().unwrap(),
    ]);
    assert!(ok, "render failed:\n{err}");
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(stats["fp_lists"], "array");
    for buffer in ["tile light ranges", "tile light indices"] {
        assert!(stats["bytes"]["buffers"][buffer].as_u64().unwrap_or(0) > 0, "buffer {buffer:?}: {}", stats["bytes"]["buffers"]);
    }
    assert!(stats["bytes"]["buffers"].get("light list nodes").is_none(), "no linked-list nodes: {}", stats["bytes"]["buffers"]);
    assert!(stats["clusters"]["light_references"].as_u64().unwrap() > 0);
}

/// `--oit exact` reaches the transparent pass and its stats on a scene with transparent
/// materials: the resolve is named, the fragments, the layers and the node buffer recorded.
#[test]
fn render_glass_with_exact_oit() {
    let dir = TempDir::new("cli-oit");
    let (png, json) = (dir.join("glass.png"), dir.join("glass.json"));
    let (ok, _, err) = manylights(&[
        "render", "--scene", "glass@stack", "--lights", "200", "--width", "64", "--height", "36", "--frames", "1",
        "--technique", "clustered-bvh", "--oit", "exact", "--stats", json.to_str().unwrap(), "--out", png.to_str().unwrap(),
    ]);
    assert!(ok, "render failed:\n{err}");
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(stats["oit"], "exact");
    let t = &stats["transparency"];
    assert!(t["fragments"].as_u64().unwrap() > 0 && t["max_layers"].as_u64().unwrap() > 8, "{t}");
    assert_eq!(t["unlisted_fragments"], 0, "{t}");
    assert_eq!(stats["bytes"]["buffers"]["oit nodes"], t["node_bytes"], "{}", stats["bytes"]);
}

#[test]
fn render_bad_input_is_a_one_line_error_with_status_2() {
    let dir = TempDir::new("cli-bad-render");
    let write = |name: &str, text: &str| dir.write(name, text).to_str().unwrap().to_owned();
    let bad_obj = write("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 999\n");
    let nan_obj = write("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
    let nan = write("nan.toml", "geometry = \"city\"\n[[light]]\nposition = [nan, 0, 0]\nradius = 5\n");
    let unknown = write("unknown.toml", "geometry = \"city\"\nbrightness = 3\n");
    let syntax = write("syntax.toml", "geometry = \"city\"\n[camera\n");
    let many = write("many.toml", "geometry = \"city\"\n[lights]\ncount = 60000000\ndistribution = \"uniform\"\n");
    let out = dir.join("o.png");
    let o = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (vec!["--scene", "/nonexistent/x.obj"], vec!["scene file /nonexistent/x.obj not found"]),
        (vec!["--scene", "/nonexistent/x.toml"], vec!["scene file /nonexistent/x.toml not found"]),
        (vec!["--scene", &bad_obj], vec!["bad.obj line 3", "face position index 999"]),
        (vec!["--scene", &nan_obj], vec!["nan.obj line 2", "not a finite"]),
        (vec!["--scene", &nan], vec!["nan.toml", "light[0].position must be finite"]),
        (vec!["--scene", &unknown], vec!["unknown.toml line 2, column 1", "brightness"]),
        (vec!["--scene", &syntax], vec!["syntax.toml line 2"]),
        (vec!["--scene", "nosuch"], vec!["unknown scene \"nosuch\""]),
        (vec!["--lights", "0"], vec!["--lights 0"]),
        (vec!["--width", "0"], vec!["--width 0 is out of range"]),
        (vec!["--width", "40000"], vec!["--width 40000", "1..="]),
        (vec!["--width", "16384", "--height", "16384"], vec!["--width 16384 --height 16384", "MiB", "maxStorageBufferRange"]),
        (vec!["--height", "4294967295"], vec!["--height 4294967295"]),
        (vec!["--width", "1e30"], vec!["--width", "1e30"]),
        (vec!["--lights", "4000000000"], vec!["--lights 4000000000", "at most"]),
        (vec!["--lights", "4294967296"], vec!["--lights", "4294967296"]),
        (vec!["--scene", &many], vec!["many.toml", "60000000 lights", "at most"]),
        (vec!["--technique", "tiled", "--lights", "300000"], vec!["--lights 300000", "tiled"]),
        (vec!["--tile-size", "0"], vec!["--tile-size 0 is out of range"]),
        (vec!["--tile-size", "100000"], vec!["--tile-size 100000 is out of range"]),
        (vec!["--technique", "tiled", "--tile-size", "64"], vec!["--tile-size 64", "tiled"]),
        (vec!["--frames", "1000000000"], vec!["--frames", "1000000000"]),
        (vec!["--time", "nan"], vec!["--time NaN"]),
        (vec!["--normal-precision", "f64"], vec!["'f64'", "oct8"]),
        (vec!["--technique", "forward-plus", "--fp-lists", "ring"], vec!["'ring'", "linked", "array"]),
        (vec!["--view", "octa-error"], vec!["'octa-error'", "heatmap"]),
        (vec!["--oit", "k3"], vec!["'k3'", "exact", "weighted"]),
        (vec!["--stats", "/nonexistent-dir/s.json"], vec!["--stats", "does not exist"]),
        (vec!["--spot-fraction", "-0.1"], vec!["--spot-fraction", "-0.1 is not in [0, 1]"]),
        (vec!["--spot-fraction", "1.5"], vec!["--spot-fraction", "1.5 is not in [0, 1]"]),
    ];
    for (extra, needles) in cases {
        let mut args = vec!["render", "--out", o];
        for (flag, default) in [("--frames", "0"), ("--width", "64"), ("--height", "36")] {
            if !extra.contains(&flag) {
                args.extend([flag, default]);
            }
        }
        args.extend(extra.iter().copied());
        refused(&args, &[], BAD_INPUT, &needles);
    }
}

/// Compact light records report how far they moved the lights (`--stats`
/// `light_record.max_position_error`), and warn in one line where that is more than 1 % of the
/// smallest radius: here one light far outside the city stretches the position grid.
#[test]
fn compact_records_report_and_warn_how_far_lights_moved() {
    let dir = TempDir::new("cli-compact");
    let scene = dir.write("far.toml", "geometry = \"city\"\n[lights]\ncount = 100\ndistribution = \"uniform\"\n[[light]]\nposition = [1e7, 1e7, 1e7]\nradius = 1\n");
    let json = dir.join("s.json");
    let error_of = |record: &str| {
        let (ok, _, err) = manylights(&[
            "render", "--scene", scene.to_str().unwrap(), "--light-record", record, "--width", "64", "--height", "36", "--frames", "1",
            "--stats", json.to_str().unwrap(), "--out", dir.join("o.png").to_str().unwrap(),
        ]);
        assert!(ok, "{record}: render failed:\n{err}");
        let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        (stats["light_record"]["max_position_error"].as_f64().unwrap(), err)
    };
    let (full, err) = error_of("full");
    assert!(full == 0.0 && !err.contains("warning: compact"), "full records: {full}\n{err}");
    let (compact, err) = error_of("compact");
    let warning: Vec<&str> = err.lines().filter(|l| l.starts_with("warning: compact light records move lights by up to")).collect();
    assert!(compact > 0.5 && warning.len() == 1, "compact records moved lights by {compact}:\n{err}");
}

/// `--light-order`: `spatial` (the default) and `given` render the city within 1/255 of each
/// other, and the stats record which order stored the lights (`tests/render.rs` shows that the
/// two orders list the lights under other indices).
#[test]
fn light_order_stores_the_lights_otherwise_with_the_same_image() {
    let dir = TempDir::new("cli-light-order");
    let frame = |order: Option<&str>| {
        let (png, json) = (dir.join("city.png"), dir.join("city.json"));
        let mut args = vec!["render", "--scene", "city", "--lights", "400", "--width", "96", "--height", "54", "--frames", "1", "--technique", "clustered-bvh"];
        args.extend(["--stats", json.to_str().unwrap(), "--out", png.to_str().unwrap()]);
        if let Some(o) = order {
            args.extend(["--light-order", o]);
        }
        let (ok, _, err) = manylights(&args);
        assert!(ok, "render {order:?} failed:\n{err}");
        let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        (stats["light_order"].as_str().unwrap().to_owned(), image::open(&png).unwrap().to_rgba8())
    };
    let (default, a) = frame(None);
    let (given, b) = frame(Some("given"));
    assert_eq!((default.as_str(), given.as_str()), ("spatial", "given"));
    let worst = a.pixels().zip(b.pixels()).flat_map(|(p, q)| (0..4).map(move |c| p[c].abs_diff(q[c]))).max().unwrap();
    assert!(worst <= 1, "the two orders differ by {worst}/255");
    let lit = a.pixels().filter(|p| p[0] > 0 || p[1] > 0 || p[2] > 0).count();
    assert!(lit * 4 > (a.width() * a.height()) as usize, "the city should be mostly lit: {lit} pixels");
}
