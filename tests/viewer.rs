//! `manylights view` in a real window under Xvfb (`xvfb-run`), validation on, driven by a
//! `--script`: it flies, turns, switches through every technique, toggles the heatmap, doubles
//! the lights, resizes the window to 1×1 and back, saves screenshots and exits with Escape.
//! Every screenshot (the frame the viewer copies to the window, without the overlay) must equal
//! `manylights render` at the same camera, animation time and settings within 1/255; a
//! technique switch changes the overlay's text, not the image.
mod common;
use common::cli::manylights;
use common::temp::TempDir;
use std::path::Path;

/// Window size and lights: small, so that the whole run takes well under a minute on lavapipe.
const SIZE: (u32, u32) = (160, 90);
const LIGHTS: u32 = 64;

fn rgba(path: &Path) -> ((u32, u32), Vec<u8>) {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8();
    (img.dimensions(), img.into_raw())
}

/// The largest channel difference of two PNGs of the same size.
fn worst(a: &Path, b: &Path) -> u8 {
    let ((sa, pa), (sb, pb)) = (rgba(a), rgba(b));
    assert_eq!(sa, sb, "{} and {} differ in size", a.display(), b.display());
    pa.iter().zip(&pb).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0)
}

fn stats(png: &Path) -> serde_json::Value {
    let json = png.with_extension("json");
    serde_json::from_slice(&std::fs::read(&json).unwrap_or_else(|e| panic!("{}: {e}", json.display()))).unwrap()
}

/// Renders what screenshot `png` shows with `manylights render` (its camera, time, technique,
/// view, light count and size from the screenshot's JSON) and asserts the two within 1/255.
fn assert_matches_render(png: &Path, dir: &TempDir) {
    assert_matches_render_of(png, dir, "city", &[]);
}

/// [`assert_matches_render`] of `scene` with `render`'s `extra` flags.
fn assert_matches_render_of(png: &Path, dir: &TempDir, scene: &str, extra: &[&str]) {
    let name = format!("render-{}", png.file_name().unwrap().to_string_lossy());
    let out = render_like(png, dir, scene, extra, &name);
    let d = worst(png, &out);
    assert!(d <= 1, "{} differs from `manylights render --scene {scene} {extra:?}` by {d}/255", png.display());
}

/// Renders `scene` as screenshot `png` shows it (camera, time, technique, view, light count and
/// size from its JSON) with `render`'s `extra` flags, into `name` in `dir`.
fn render_like(png: &Path, dir: &TempDir, scene: &str, extra: &[&str], name: &str) -> std::path::PathBuf {
    let s = stats(png);
    let v = &s["viewer"];
    let (w, h) = (s["resolution"][0].as_u64().unwrap().to_string(), s["resolution"][1].as_u64().unwrap().to_string());
    let out = dir.join(name);
    let lights = s["lights"].as_u64().unwrap().to_string();
    let time = v["time"].as_f64().unwrap().to_string();
    let args = [
        "render", "--scene", scene, "--lights", &lights, "--width", &w, "--height", &h, "--frames", "0",
        "--technique", v["technique"].as_str().unwrap(), "--view", v["view"].as_str().unwrap(),
        "--camera", v["camera"].as_str().unwrap(), "--time", &time, "--out", out.to_str().unwrap(),
    ];
    let r = manylights(args.iter().chain(extra));
    assert!(r.ok, "{args:?} {extra:?}:\n{}", r.stderr);
    out
}

/// Runs the viewer under Xvfb with `args` and `script` (shots named in it); asserts success.
fn view(dir: &TempDir, name: &str, args: &[&str], script: &str) -> String {
    let script_path = dir.write(&format!("{name}.script"), script);
    let (w, h) = (SIZE.0.to_string(), SIZE.1.to_string());
    let out = std::process::Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24", env!("CARGO_BIN_EXE_manylights"), "view", "--width", &w, "--height", &h])
        .args(args)
        .args(["--script", script_path.to_str().unwrap()])
        .env("MANYLIGHTS_VALIDATION", "true")
        .output()
        .expect("running xvfb-run");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "the viewer failed ({:?}):\n{err}\nscript:\n{script}", out.status.code());
    assert!(!err.contains("validation") && !err.contains("panicked"), "{err}");
    err
}

#[test]
fn the_viewer_flies_switches_resizes_and_matches_render() {
    let xvfb = std::process::Command::new("xvfb-run").arg("--help").output();
    assert!(xvfb.is_ok(), "xvfb-run is missing: install xvfb and xauth (./dev.sh test installs them)");
    let dir = TempDir::new("viewer");
    let shot = |name: &str| dir.join(&format!("{name}.png"));
    let p = |name: &str| shot(name).to_str().unwrap().to_owned();
    // Tab from clustered-naive (the default) visits every other registered technique in the
    // registry's order; its number key selects it again.
    let all = host::render::Technique::ALL;
    let start = all.iter().position(|&t| t == host::render::Technique::ClusteredNaive).unwrap();
    let names: Vec<&str> = (1..all.len()).map(|k| all[(start + k) % all.len()].name()).collect();
    let mut script = String::from("# fly a little, turn, stop the animation\n0 key Space\n1 down W\n1 mouse-down right\n2 mouse-move 60 -8\n3 mouse-up right\n6 up W\n");
    script += &format!("8 shot {}\n8 key Tab\n", p("clustered-naive"));
    let mut frame = 10;
    for (i, name) in names.iter().enumerate() {
        script += &format!("{frame} shot {}\n", p(name));
        if i + 1 < names.len() {
            script += &format!("{frame} key Tab\n");
        }
        frame += 2;
    }
    script += &format!("{frame} key {}\n{} key H\n{} shot {}\n", start + 1, frame + 2, frame + 4, p("heatmap"));
    script += &format!("{} key H\n{} key Plus\n{} shot {}\n", frame + 6, frame + 8, frame + 10, p("more-lights"));
    script += &format!("{} resize 1 1\n{} shot {}\n", frame + 12, frame + 14, p("tiny"));
    script += &format!("{} resize {} {}\n{} shot {}\n{} key Escape\n", frame + 16, SIZE.0, SIZE.1, frame + 18, p("back"), frame + 20);
    let script_path = dir.write("fly.script", &script);
    let bin = env!("CARGO_BIN_EXE_manylights");
    let (w, h) = (SIZE.0.to_string(), SIZE.1.to_string());
    let out = std::process::Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24", bin, "view", "--scene", "city", "--lights", &LIGHTS.to_string(), "--width", &w, "--height", &h])
        .args(["--present-mode", "mailbox", "--script", script_path.to_str().unwrap()])
        .env("MANYLIGHTS_VALIDATION", "true")
        .output()
        .expect("running xvfb-run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "the viewer failed ({:?}):\n{err}\nscript:\n{script}", out.status.code());
    assert!(!err.contains("validation") && !err.contains("panicked"), "{err}");

    // Every technique's frame equals `render` at the same camera, and the others' frames.
    let first = shot("clustered-naive");
    assert_matches_render(&first, &dir);
    for &name in &names {
        let png = shot(name);
        let s = stats(&png);
        assert_eq!(s["viewer"]["technique"], name, "Tab reached {name}");
        assert_matches_render(&png, &dir);
        assert!(worst(&first, &png) <= 1, "{name}: a technique switch changed the image");
    }
    // The switch changed the overlay's text (the technique line), and nothing else moved.
    let (a, b) = (stats(&first), stats(&shot("clustered-bvh")));
    assert_ne!(a["viewer"]["overlay"][1], b["viewer"]["overlay"][1], "the overlay names the technique");
    assert!(a["viewer"]["overlay"][1].as_str().unwrap().contains("clustered-naive"), "{}", a["viewer"]["overlay"]);
    assert_eq!(a["viewer"]["camera"], b["viewer"]["camera"]);
    assert_eq!(a["viewer"]["time"], 0.0, "the animation was paused at once");
    assert_ne!(a["viewer"]["camera"], "", "the camera moved");

    let heat = stats(&shot("heatmap"));
    assert_eq!((heat["viewer"]["technique"].as_str(), heat["viewer"]["view"].as_str()), (Some("clustered-naive"), Some("heatmap")));
    assert_matches_render(&shot("heatmap"), &dir);
    assert!(worst(&first, &shot("heatmap")) > 1, "the heatmap is another image");
    let more = stats(&shot("more-lights"));
    assert_eq!(more["lights"], 2 * LIGHTS, "Plus doubles the lights");
    assert_matches_render(&shot("more-lights"), &dir);
    assert_eq!(stats(&shot("tiny"))["resolution"], serde_json::json!([1, 1]));
    assert_eq!(stats(&shot("back"))["resolution"], serde_json::json!([SIZE.0, SIZE.1]));
    assert!(worst(&shot("more-lights"), &shot("back")) <= 1, "the frame after 1×1 and back is the frame before");
}

/// Generated spot lights follow the light count: `+` and `−` regenerate the cones with the
/// same share and seed, so every screenshot equals `render` with that many lights and the same
/// `--spot-fraction` (or description); spots listed one by one keep their count, with a note.
#[test]
fn the_viewer_regenerates_spot_lights() {
    let dir = TempDir::new("viewer-spots");
    let shot = |name: &str| dir.join(&format!("{name}.png"));
    let p = |name: &str| shot(name).to_str().unwrap().to_owned();
    // `--spot-fraction`: 64 lights, then 128, then 32.
    let script = format!("0 key Space\n2 shot {}\n2 key Plus\n4 shot {}\n4 key Minus\n6 key Minus\n8 shot {}\n9 key Escape\n", p("cli-64"), p("cli-128"), p("cli-32"));
    let err = view(&dir, "cli", &["--scene", "city", "--lights", &LIGHTS.to_string(), "--spot-fraction", "0.5"], &script);
    assert!(!err.contains("warning"), "no count change was refused:\n{err}");
    for (name, n) in [("cli-64", LIGHTS), ("cli-128", 2 * LIGHTS), ("cli-32", LIGHTS / 2)] {
        assert_eq!(stats(&shot(name))["lights"], n, "{name}");
        assert_matches_render_of(&shot(name), &dir, "city", &["--spot-fraction", "0.5"]);
    }
    // The spots are there after the change: the same lights without cones give another image.
    let points = render_like(&shot("cli-128"), &dir, "city", &[], "points-128.png");
    assert!(worst(&shot("cli-128"), &points) > 1, "128 lights with spots look like 128 point lights");

    // `[lights] spot_fraction` in a description: `+` regenerates like a description of 128.
    let description = |n: u32| format!("geometry = \"city\"\n[lights]\ncount = {n}\ndistribution = \"uniform\"\nspot_fraction = 0.5\n");
    let d64 = dir.write("spots-64.toml", &description(LIGHTS));
    let d128 = dir.write("spots-128.toml", &description(2 * LIGHTS));
    let script = format!("0 key Space\n2 key Plus\n4 shot {}\n5 key Escape\n", p("toml-128"));
    let err = view(&dir, "toml", &["--scene", d64.to_str().unwrap()], &script);
    assert!(!err.contains("warning"), "no count change was refused:\n{err}");
    assert_eq!(stats(&shot("toml-128"))["lights"], 2 * LIGHTS);
    assert_matches_render_of(&shot("toml-128"), &dir, d128.to_str().unwrap(), &[]);

    // A spot light listed in a description keeps its count; the overlay says why.
    let listed = dir.write(
        "listed.toml",
        "geometry = \"city\"\n[[light]]\ntype = \"spot\"\nposition = [0, 12, 0]\nradius = 40\ndirection = [0, -1, 0]\nouter_angle = 40\n",
    );
    let script = format!("0 key Space\n2 key Plus\n4 shot {}\n5 key Escape\n", p("listed"));
    let err = view(&dir, "listed", &["--scene", listed.to_str().unwrap()], &script);
    let s = stats(&shot("listed"));
    assert_eq!(s["lights"], 1, "the listed spot light stays alone");
    let note = "listed one by one";
    assert!(err.lines().any(|l| l.starts_with("warning: ") && l.contains(note)), "{err}");
    assert!(s["viewer"]["overlay"].as_array().unwrap().iter().any(|l| l.as_str().unwrap_or("").contains(note)), "{}", s["viewer"]["overlay"]);
    assert_matches_render_of(&shot("listed"), &dir, listed.to_str().unwrap(), &[]);
}

/// A malformed script or camera is a one-line error (exit status 2) before any window opens.
#[test]
fn bad_viewer_input_is_a_one_line_error() {
    let dir = TempDir::new("viewer-bad");
    let bad = dir.write("bad.script", "0 key W\n1 jump\n");
    let out = dir.join("x.png");
    let cases: [(Vec<&str>, &str); 4] = [
        (vec!["view", "--script", bad.to_str().unwrap()], "line 2: unknown command \"jump\""),
        (vec!["view", "--script", "/nonexistent/x.script"], "cannot read it"),
        (vec!["view", "--camera", "1,2,3"], "3 values"),
        (vec!["render", "--camera", "1,2,3,0,95", "--out", out.to_str().unwrap()], "pitch 95"),
    ];
    for (args, needle) in cases {
        common::cli::assert_refused(&manylights(&args), &format!("{args:?}"), common::cli::BAD_INPUT, &[needle]);
    }
}

/// `view` honours the flags it shares with `render`: `--stats FILE` is written when the viewer
/// exits (`--exit-after`: it exits after that many presented frames), its timings the medians of
/// the last `--frames` frames; `--tess-level` tessellates the NURBS patches as `render` does
/// (same levels in both statistics) and `--tess-error` gives the adaptive levels `render` gives.
#[test]
fn the_viewer_honours_stats_frames_exit_after_and_tessellation_flags() {
    let dir = TempDir::new("viewer-flags");
    let json = |name: &str| -> serde_json::Value { serde_json::from_str(&std::fs::read_to_string(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))).unwrap() };
    for (name, extra) in [("level", ["--tess-level", "3"]), ("adaptive", ["--tess-error", "0.5"])] {
        let viewed = dir.join(&format!("view-{name}.json"));
        let viewed = viewed.to_str().unwrap();
        view(&dir, name, &["--scene", "nurbs", "--lights", "200", "--exit-after", "4", "--frames", "3", "--stats", viewed, extra[0], extra[1]], "");
        let v = json(&format!("view-{name}.json"));
        assert_eq!(v["viewer"]["frame"], 4, "{name}: --exit-after 4 renders 4 frames: {}", v["viewer"]);
        assert_eq!(v["timed_frames"], 3, "{name}: --frames 3 sets the frames the timings are medians of");
        let rendered = dir.join(&format!("render-{name}.json"));
        let out = dir.join(&format!("render-{name}.png"));
        let (w, h) = (SIZE.0.to_string(), SIZE.1.to_string());
        let r = manylights(["render", "--scene", "nurbs", "--lights", "200", "--width", &w, "--height", &h, "--out", out.to_str().unwrap(), "--stats", rendered.to_str().unwrap(), extra[0], extra[1]]);
        assert!(r.ok, "{}", r.stderr);
        let levels = json(&format!("render-{name}.json"))["tess_levels"].clone();
        assert!(levels.as_array().is_some_and(|l| !l.is_empty()), "{name}: render reports the patches' levels: {levels}");
        assert_eq!(v["tess_levels"], levels, "{name}: the viewer tessellates as render does");
    }
    // Without the flag the levels differ from `--tess-level 3`'s (the flag reached the viewer).
    let plain = dir.join("view-plain.json");
    view(&dir, "plain", &["--scene", "nurbs", "--lights", "200", "--exit-after", "2", "--stats", plain.to_str().unwrap()], "");
    assert_ne!(json("view-plain.json")["tess_levels"], json("view-level.json")["tess_levels"], "--tess-level changed nothing");
}

/// What the window shows is the frame `render` writes: with the overlay hidden, the swapchain
/// image read back after it is drawn (`presented` in a script) equals the viewer's frame (`shot`)
/// within 1/255, and that frame equals `render` at the same camera.
#[test]
fn the_presented_image_is_the_rendered_frame() {
    let dir = TempDir::new("viewer-presented");
    let (shot, presented) = (dir.join("shot.png"), dir.join("presented.png"));
    let script = format!("0 key Space\n4 shot {}\n4 presented {}\n8 key Escape\n", shot.display(), presented.display());
    view(&dir, "presented", &["--scene", "city", "--lights", &LIGHTS.to_string(), "--no-overlay"], &script);
    assert_eq!(rgba(&presented).0, SIZE, "the presented image has the window's size");
    let d = worst(&shot, &presented);
    assert!(d <= 1, "the presented image differs from the frame by {d}/255");
    assert_matches_render(&shot, &dir);
}

/// G turns the shadows of the casting lights off and on: a screenshot with shadows equals
/// `render` with the same `--shadow-fraction`, one after G equals `render` without, and `+`
/// gives the doubled lights their casters with the same share; the shadow pass shows in the
/// statistics only while shadows are on. A scene without casters says so on G.
#[test]
fn the_viewer_toggles_shadows() {
    let dir = TempDir::new("viewer-shadows");
    let shot = |name: &str| dir.join(&format!("{name}.png"));
    let p = |name: &str| shot(name).to_str().unwrap().to_owned();
    let script = format!("0 key Space\n2 shot {}\n2 key G\n4 shot {}\n4 key G\n5 key Plus\n7 shot {}\n8 key Escape\n", p("on"), p("off"), p("more"));
    let args = ["--scene", "city", "--lights", &LIGHTS.to_string(), "--technique", "clustered-bvh", "--shadow-fraction", "0.25"];
    let err = view(&dir, "shadows", &args, &script);
    assert!(!err.contains("warning"), "no toggle was refused:\n{err}");
    let (on, off, more) = (stats(&shot("on")), stats(&shot("off")), stats(&shot("more")));
    assert_eq!(on["shadows"]["casters"], LIGHTS / 4, "{}", on["shadows"]);
    assert!(off["shadows"].is_null(), "{}", off["shadows"]);
    assert_eq!(more["shadows"]["casters"], LIGHTS / 2, "{}", more["shadows"]);
    assert!(on["gpu_ms"]["passes"]["shadow maps"].is_number() && off["gpu_ms"]["passes"]["shadow maps"].is_null());
    let share = ["--shadow-fraction", "0.25"];
    assert_matches_render_of(&shot("on"), &dir, "city", &share);
    assert_matches_render_of(&shot("off"), &dir, "city", &[]);
    assert_matches_render_of(&shot("more"), &dir, "city", &share);
    assert!(worst(&shot("on"), &shot("off")) > 1, "the shadows change nothing in the city");

    let script = format!("0 key G\n2 shot {}\n3 key Escape\n", p("none"));
    let err = view(&dir, "no-casters", &["--scene", "city", "--lights", "8"], &script);
    assert!(err.lines().any(|l| l.starts_with("warning: ") && l.contains("no light casts shadows")), "{err}");
}
