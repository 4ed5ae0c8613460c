//! `manylights bench` end to end on the local device (validation on): a tiny sweep writes a CSV
//! with the documented columns, one configuration per technique and light count, whose numbers
//! are all finite and positive and whose "frame" and "compute" rows are the sums of their passes;
//! SVG plots; and a markdown summary that names the device and the command. A technique that
//! cannot run at a size is reported as skipped, not dropped.
mod common;
use clap::ValueEnum;
use common::cli::{assert_one_line_error, manylights};
use common::csv::Csv;
use common::temp::TempDir;
use host::bench::{technique_name, CSV_COLUMNS, KIND_COMPUTE, KIND_RASTER, KIND_SPAN, QUEUE_ALL, QUEUE_ASYNC, QUEUE_MAIN};
use host::render::Technique;
use std::collections::{BTreeMap, BTreeSet};

/// Rounding of `{:.6}` cells.
const SPAN_TOLERANCE_MS: f64 = 1e-5;

#[test]
fn tiny_bench_writes_csv_plots_and_markdown() {
    let dir = TempDir::new("bench");
    let out = dir.path().to_str().unwrap();
    let run = manylights(["bench", "--lights", "100,1000", "--scenes", "city", "--width", "96", "--height", "54", "--frames", "2", "--out", out]);
    assert!(run.ok, "bench failed:\n{}", run.stderr);
    let csv = Csv::read(&dir.join("results.csv"));
    assert_eq!(csv.header, CSV_COLUMNS, "results.csv header");
    // Without --spot-fraction the share of spots is 0 and the culling the default.
    let numeric = |c: &str| !matches!(c, "scene" | "technique" | "stage" | "queue" | "kind" | "spot_fraction" | "spot_culling");
    // (technique, lights) → stage → row.
    let mut configs: BTreeMap<(String, u64), BTreeMap<String, common::csv::Row>> = BTreeMap::new();
    for row in csv.rows() {
        for col in CSV_COLUMNS.iter().filter(|c| numeric(c)) {
            let v = row.num(col);
            assert!(v.is_finite() && v > 0.0, "{col} = {v} is not finite and positive (row {:?})", row.cells);
        }
        assert_eq!((row.get("scene"), row.get("width"), row.get("height"), row.get("frames")), ("city", "96", "54", "2"), "row {:?}", row.cells);
        assert_eq!((row.get("spot_fraction"), row.get("spot_culling")), ("0", "cone"), "row {:?}", row.cells);
        assert!(row.num("min_ms") <= row.num("median_ms") && row.num("median_ms") <= row.num("max_ms"), "min ≤ median ≤ max: {:?}", row.cells);
        let key = (row.get("technique").to_string(), row.num("lights") as u64);
        let stage = row.get("stage").to_string();
        let cells = row.cells.to_vec();
        let previous = configs.entry(key).or_default().insert(stage.clone(), row);
        assert!(previous.is_none(), "stage {stage} twice: {cells:?}");
    }
    // Every technique at both light counts: nothing is skipped at this size.
    let expected: BTreeSet<(String, u64)> =
        Technique::value_variants().iter().flat_map(|&t| [(technique_name(t), 100), (technique_name(t), 1000)]).collect();
    assert_eq!(configs.keys().cloned().collect::<BTreeSet<_>>(), expected, "configurations in the CSV");
    // Each pass row names its queue and kind: the raster passes are the G-buffer where the
    // technique draws one and the passes its description names (Forward+: its depth pre-pass and
    // forward pass; raster-tiled: its light quads), and with an async-compute queue the light sort and BVH
    // build of clustered-bvh run there. "frame" spans both queues, first to last timestamp, so
    // in every timed frame each pass lies within it (and the medians keep that order); "compute"
    // is the frame without the raster passes.
    let async_queue = common::gpu().ctx.async_compute_queue.is_some();
    for ((name, lights), stages) in &configs {
        let passes: Vec<(&String, &common::csv::Row)> = stages.iter().filter(|(_, r)| r.get("kind") != KIND_SPAN).collect();
        assert!(!passes.is_empty(), "{name} {lights}: no pass rows");
        let raster: BTreeSet<&str> = passes.iter().filter(|(_, r)| r.get("kind") == KIND_RASTER).map(|(s, _)| s.as_str()).collect();
        let d = Technique::from_str(name, false).unwrap().description();
        let expected_raster: BTreeSet<&str> = d.raster_passes.iter().copied().chain(d.gbuffer.then_some("gbuffer")).collect();
        assert_eq!(raster, expected_raster, "{name} {lights}: raster passes");
        let on_async: BTreeSet<&str> = passes.iter().filter(|(_, r)| r.get("queue") == QUEUE_ASYNC).map(|(s, _)| s.as_str()).collect();
        let expected_async: BTreeSet<&str> =
            if async_queue && name == "clustered-bvh" { ["morton keys", "light sort", "bvh build"].into() } else { BTreeSet::new() };
        assert_eq!(on_async, expected_async, "{name} {lights}: async-compute passes");
        for (stage, r) in &passes {
            assert!([QUEUE_MAIN, QUEUE_ASYNC].contains(&r.get("queue")) && [KIND_RASTER, KIND_COMPUTE].contains(&r.get("kind")), "{stage}: {:?}", r.cells);
        }
        let span = |stage: &str| {
            let row = stages.get(stage).unwrap_or_else(|| panic!("{name} {lights}: no {stage} row"));
            assert_eq!((row.get("queue"), row.get("kind")), (QUEUE_ALL, KIND_SPAN), "{name} {lights}: the {stage} row");
            row.num("median_ms")
        };
        let (frame, compute) = (span("frame"), span("compute"));
        assert!(compute <= frame, "{name} {lights}: compute {compute} ms exceeds the frame {frame} ms");
        for (stage, r) in &passes {
            assert!(r.num("median_ms") <= frame + SPAN_TOLERANCE_MS, "{name} {lights}: pass {stage} ({} ms) outside the frame ({frame} ms)", r.num("median_ms"));
        }
    }
    let md = std::fs::read_to_string(dir.join("results.md")).expect("results.md");
    assert!(md.contains("**Device:**") && md.contains("\nmanylights bench --lights 100,1000 "), "results.md names the device and the command as typed:\n{md}");
    assert!(md.contains("Speed-up at 1k lights"), "results.md has the speed-up table:\n{md}");
    for svg in ["frame-vs-lights-city.svg", "compute-vs-lights-city.svg", "stages-city.svg"] {
        let s = std::fs::read_to_string(dir.join(svg)).unwrap_or_else(|e| panic!("{svg}: {e}"));
        assert!(s.starts_with("<svg") && s.contains("<text"), "{svg} is an SVG with labels");
    }
}

#[test]
fn bench_bad_input_is_a_one_line_error() {
    let dir = TempDir::new("bench-bad");
    for (args, needle) in [
        (vec!["--techniques", "warp-drive"], "unknown technique"),
        (vec!["--lights", "0"], "positive light counts"),
        (vec!["--scenes", "no-such-scene.obj"], "no-such-scene"),
        (vec!["--spot-fraction", "1.5"], "--spot-fraction"),
        (vec!["--spot-fraction", "-0.1"], "--spot-fraction"),
        (vec!["--spot-fraction", "nan"], "--spot-fraction"),
        (vec!["--spot-fraction", "half"], "--spot-fraction"),
        (vec!["--spot-culling", "sphere"], "no spot lights to cull"),
        (vec!["--spot-culling", "both"], "no spot lights to cull"),
        (vec!["--spot-fraction", "0", "--spot-culling", "both"], "no spot lights to cull"),
        (vec!["--spot-fraction", "0.5", "--spot-culling", "cones"], "--spot-culling"),
        (vec!["--spot-fraction", "0.5", "--study", "accuracy"], "accuracy study"),
    ] {
        let out = dir.path().to_str().unwrap();
        let run = manylights(["bench"].into_iter().chain(args.iter().copied()).chain(["--width", "32", "--height", "18", "--frames", "1", "--out", out]));
        assert_one_line_error(&run, &format!("{args:?}"), needle);
    }
}

/// The accuracy study on a tiny frame with 10k lights (enough for llvmpipe's loop limiter to
/// bite if a test looped per light): the reference setting reproduces the reference, tile
/// sizes only move time (lists are conservative), a smaller ε is never less accurate, 4× MSAA
/// comes closer to 16× supersampling than one sample, compact light records differ from full
/// ones by at most 1/255 but differ, and the Pareto plots and markdown are written.
#[test]
fn tiny_accuracy_study() {
    let dir = TempDir::new("accuracy");
    let out = dir.path().to_str().unwrap();
    let run = manylights(["bench", "--study", "accuracy", "--lights", "10000", "--scenes", "city", "--width", "96", "--height", "54", "--frames", "1", "--out", out]);
    assert!(run.ok, "study failed:\n{}", run.stderr);
    let csv = Csv::read(&dir.join("accuracy.csv"));
    let msaa: Vec<_> = csv.rows().filter(|r| r.get("knob") == "MSAA").collect();
    let shadows = csv.rows().filter(|r| r.get("knob") == "shadows").count();
    assert_eq!(shadows, 8, "one shadows row per map resolution and filter");
    assert_eq!(csv.rows.len(), 18 + shadows + msaa.len(), "{:?}", csv.rows);
    // MSAA: one sample and four at least (every device has 4); more samples come closer to the
    // 16× supersampled reference, so the knob reaches the frame.
    let msaa_psnr = |prefix: &str| msaa.iter().find(|r| r.get("setting").starts_with(prefix)).unwrap_or_else(|| panic!("no MSAA row {prefix:?}")).num("psnr_db");
    assert!(msaa_psnr("4 ×") > msaa_psnr("1 ×") + 1.0, "4 samples closer to supersampling than 1: {} vs {} dB", msaa_psnr("4 ×"), msaa_psnr("1 ×"));
    let setting = |prefix: &str| {
        let mut rows = csv.rows().filter(|r| r.get("setting").starts_with(prefix));
        let row = rows.next().unwrap_or_else(|| panic!("no setting {prefix:?}"));
        assert!(rows.next().is_none(), "several settings start with {prefix:?}");
        row
    };
    let psnr = |s: &str| setting(s).num("psnr_db");
    let max_abs = |s: &str| setting(s).num("max_abs_255");
    let normal_max_deg = |s: &str| setting(s).num("normal_max_deg");
    let per_cluster = |s: &str| setting(s).num("lights_per_cluster");
    assert!(max_abs("float32") <= 1.0, "the reference setting reproduces brute force");
    assert_eq!(normal_max_deg("float32"), 0.0, "float32 normals are the reference's");
    use shaders::octahedral::Precision;
    for (s, p) in [("oct 2×8", Precision::Oct8), ("oct 2×12", Precision::Oct12), ("oct 2×16", Precision::Oct16)] {
        let bound = (p.max_angular_error_bound() as f64).to_degrees();
        assert!(normal_max_deg(s) <= bound + 1e-4, "{s}: {}° over the proven bound {bound}°", normal_max_deg(s));
    }
    // Per scene the error need not fall with every added bit (a normal on the 2×12 grid is not on
    // the 2×16 one), but 2×8 bits are far coarser.
    assert!(normal_max_deg("oct 2×8") > 10.0 * normal_max_deg("oct 2×16"), "2×8 bits: larger normal error than 2×16");
    for tile in ["16 px", "32 px", "64 px"] {
        assert!(max_abs(tile) <= 1.0, "tile {tile}: conservative lists give the reference image");
    }
    for test in ["sphere–AABB", "sphere–frustum planes", "exact sphere–frustum"] {
        assert!(max_abs(test) <= 1.0, "culling test {test} is conservative: the reference image");
    }
    assert!(per_cluster("exact sphere–frustum") <= per_cluster("sphere–AABB"), "the exact test keeps no more lights than the box");
    // Spot lights: the cone test changes the lists, not the image.
    for test in ["spots: cone", "spots: sphere"] {
        assert!(max_abs(test) <= 1.0, "culling test {test} is conservative: the reference image");
    }
    assert!(per_cluster("spots: cone") < per_cluster("spots: sphere"), "the cone test keeps fewer lights than the range sphere");
    assert!(per_cluster("exact sphere–frustum") <= per_cluster("sphere–frustum planes"), "the exact test keeps no more lights than the planes");
    let (e2, e3, e4) = (psnr("inverse square cut at ε = 1e-2"), psnr("inverse square cut at ε = 1e-3"), psnr("inverse square cut at ε = 1e-4"));
    assert!(e2 <= e3 && e3 <= e4, "a smaller cut threshold is never less accurate: {e2} {e3} {e4}");
    // Light records: full records are the reference's; compact ones move the image (the knob
    // reaches the kernels) by no more than their quantisation, 1/255 here.
    assert_eq!(max_abs("full (32 B"), 0.0, "full records reproduce the reference");
    assert!(max_abs("compact (16 B") > 0.0 && max_abs("compact (16 B") <= 1.0, "compact records: {}/255", max_abs("compact (16 B"));
    let md = std::fs::read_to_string(dir.join("results.md")).expect("results.md");
    assert!(md.contains("| normal encoding | oct 2×8 |") && md.contains("pareto-city.svg"), "{md}");
    assert!(std::fs::read_to_string(dir.join("pareto-city.svg")).expect("pareto plot").starts_with("<svg"));
    assert!(std::fs::read_to_string(dir.join("pareto-msaa-city.svg")).expect("MSAA pareto plot").starts_with("<svg"));
}

/// The OIT knob of the accuracy study, on the glass stack (up to 50 transparent surfaces per
/// pixel): exact OIT is the reference (error 0), k = 1 and weighted blending differ from it
/// (the knob reaches the resolve), more sorted layers are never less accurate here, and the OIT
/// Pareto plot is written. Scenes without transparency get no OIT rows (the city study above
/// has 14 rows). `--knobs` picks the knobs measured: here the OIT knob and the tile size only.
#[test]
fn accuracy_study_oit_knob() {
    let dir = TempDir::new("accuracy-oit");
    let out = dir.path().to_str().unwrap();
    let run = manylights([
        "bench", "--study", "accuracy", "--knobs", "oit,tile-size", "--lights", "300", "--scenes", "glass@stack", "--width", "96", "--height", "54", "--frames", "1", "--out", out,
    ]);
    assert!(run.ok, "study failed:\n{}", run.stderr);
    let csv = Csv::read(&dir.join("accuracy.csv"));
    let mut knobs: Vec<String> = csv.rows().map(|r| r.get("knob").to_string()).collect();
    knobs.dedup();
    assert_eq!(knobs, ["tile size", "transparency (OIT)"], "the knobs asked for, and only those");
    let oit: Vec<_> = csv.rows().filter(|r| r.get("knob") == "transparency (OIT)").collect();
    let settings: Vec<&str> = oit.iter().map(|r| r.get("setting")).collect();
    assert_eq!(settings, ["exact", "k = 8", "k = 4", "k = 2", "k = 1", "weighted blended"]);
    let max_abs = |s: &str| oit.iter().find(|r| r.get("setting") == s).unwrap().num("max_abs_255");
    let psnr = |s: &str| oit.iter().find(|r| r.get("setting") == s).unwrap().num("psnr_db");
    assert_eq!(max_abs("exact"), 0.0, "exact OIT is the reference");
    assert!(max_abs("k = 1") > 1.0 && max_abs("weighted blended") > 1.0, "approximate resolves differ from exact");
    assert!(psnr("k = 8") >= psnr("k = 1"), "8 sorted layers are not less accurate than 1 here");
    assert!(oit.iter().all(|r| r.num("transparent_ms") > 0.0), "the transparent passes are timed");
    assert!(std::fs::read_to_string(dir.join("pareto-oit-glass-stack.svg")).expect("OIT pareto plot").starts_with("<svg"));
}

/// The shadows knob of the accuracy study on a wall over a floor (10 % of 40 generated lights
/// casting): every resolution and filter is a row measured against the ray-cast reference, the
/// knob reaches the maps (the coarsest and the finest settings give different errors), the finest
/// maps are closer to the reference than the coarsest, the frames are timed, and the Pareto plot
/// is written.
#[test]
fn accuracy_study_shadows_knob() {
    let dir = TempDir::new("accuracy-shadows");
    let out = dir.path().to_str().unwrap();
    dir.write("floor.obj", "v -6 0 -6\nv 6 0 -6\nv 6 0 6\nv -6 0 6\nv 0 0 -6\nv 0 0 6\nv 0 2 6\nv 0 2 -6\nf 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 5 8 7\nf 5 7 6\n");
    let scene = dir.write("wall.toml", "geometry = \"floor.obj\"\n[camera]\nposition = [0, 14, 0.01]\ntarget = [0, 0, 0]\nfov_y = 60\nnear = 0.5\nfar = 40\n");
    let run = manylights([
        "bench", "--study", "accuracy", "--knobs", "shadows", "--lights", "40", "--scenes", scene.to_str().unwrap(), "--width", "160", "--height", "90", "--frames", "1", "--out", out,
    ]);
    assert!(run.ok, "study failed:\n{}", run.stderr);
    let csv = Csv::read(&dir.join("accuracy.csv"));
    let rows: Vec<_> = csv.rows().filter(|r| r.get("knob") == "shadows").collect();
    assert_eq!(rows.len(), 8, "one row per resolution and filter");
    let error = |i: usize| (rows[i].num("psnr_db"), rows[i].num("max_abs_255"), rows[i].num("pixels_differing_pct"));
    eprintln!("32² nearest {:?}, 2048² bilinear {:?}", error(0), error(7));
    assert_ne!(error(0), error(7), "32² nearest and 2048² bilinear give the same image");
    assert!(rows[7].num("psnr_db") > rows[0].num("psnr_db"), "2048² is no closer to the ray cast than 32²: {:?} against {:?}", error(7), error(0));
    assert!(rows.iter().all(|r| r.num("frame_ms") > 0.0), "the frames are timed");
    let plot = std::fs::read_dir(dir.path()).unwrap().filter_map(|e| e.ok()).find(|e| e.file_name().to_string_lossy().starts_with("pareto-shadows-"));
    assert!(std::fs::read_to_string(plot.expect("shadows pareto plot").path()).unwrap().starts_with("<svg"));
}

/// `bench` on a scene with transparent materials: every technique with a transparent pass is
/// timed with it (its `transparent` and `oit resolve` rows), and the tiled techniques, which
/// refuse such scenes, are reported as skipped with their refusal, not dropped.
#[test]
fn bench_times_the_transparent_pass() {
    let dir = TempDir::new("bench-glass");
    let out = dir.path().to_str().unwrap();
    let run = manylights(["bench", "--lights", "200", "--scenes", "glass@stack", "--width", "64", "--height", "36", "--frames", "1", "--out", out]);
    assert!(run.ok, "bench failed:\n{}", run.stderr);
    let csv = Csv::read(&dir.join("results.csv"));
    for &t in Technique::value_variants() {
        let stages: BTreeSet<String> = csv.rows().filter(|r| r.get("technique") == technique_name(t)).map(|r| r.get("stage").to_string()).collect();
        if t.draws_transparency() {
            assert!(stages.contains("transparent") && stages.contains("oit resolve"), "{t:?}: stages {stages:?}");
        } else {
            assert!(stages.is_empty(), "{t:?} refuses the scene: {stages:?}");
            let line = format!("skipped glass@stack {} 200 lights: ", technique_name(t));
            assert!(run.stderr.lines().any(|l| l.starts_with(&line) && l.contains("no transparent pass")), "{t:?}: no skip line in\n{}", run.stderr);
        }
    }
}

/// The tessellation knob of the accuracy study on the NURBS scene: the finest level is the
/// reference (error 0), the knob reaches the pass (level 4 gives another image), the geometric
/// error falls with the level and with the adaptive tolerance, the tessellation pass + G-buffer
/// is timed, and its Pareto plot is written.
#[test]
fn accuracy_study_tessellation_knob() {
    let dir = TempDir::new("accuracy-tess");
    let out = dir.path().to_str().unwrap();
    let run = manylights([
        "bench", "--study", "accuracy", "--knobs", "tessellation", "--lights", "300", "--scenes", "nurbs", "--width", "96", "--height", "54", "--frames", "1", "--out", out,
    ]);
    assert!(run.ok, "study failed:\n{}", run.stderr);
    let csv = Csv::read(&dir.join("accuracy.csv"));
    let rows: Vec<_> = csv.rows().filter(|r| r.get("knob") == "tessellation").collect();
    let settings: Vec<&str> = rows.iter().map(|r| r.get("setting")).collect();
    assert_eq!(settings, ["level 4", "level 8", "level 16", "level 32", "level 64", "adaptive, 2 px", "adaptive, 1 px", "adaptive, 0.5 px", "adaptive, 0.25 px"]);
    let geo: Vec<f64> = rows.iter().map(|r| r.num("geometric_error")).collect();
    assert!(geo[..5].windows(2).all(|w| w[1] < w[0]), "the geometric error falls with the level: {geo:?}");
    assert!(geo[5..].windows(2).all(|w| w[1] <= w[0]), "and with the adaptive tolerance: {geo:?}");
    assert_eq!(rows[4].num("max_abs_255"), 0.0, "the finest level is the reference");
    assert!(rows[0].num("max_abs_255") > 1.0, "level 4 gives another image: the knob reaches the pass");
    assert!(rows.iter().all(|r| r.num("tessellation_gbuffer_ms") > 0.0), "the tessellation pass and the G-buffer are timed");
    assert!(std::fs::read_to_string(dir.join("pareto-tessellation-nurbs.svg")).expect("tessellation pareto plot").starts_with("<svg"));
}

/// `--camera-path`: every configuration also flies the path, one frame per camera, and reports
/// median ≤ 99th percentile ≤ max frame time over it (`flythrough.csv`, `results.md`); a path
/// with a malformed line is a one-line error naming its file and line.
#[test]
fn bench_flies_a_camera_path() {
    let dir = TempDir::new("bench-path");
    let path = dir.join("path.txt");
    std::fs::write(&path, "# down the avenue\n0,20,60,0,-10\n0,20,40,10,-10\n0,20,20,20,-15\n").unwrap();
    let out = dir.path().to_str().unwrap();
    let run = manylights([
        "bench", "--lights", "200", "--scenes", "city", "--techniques", "clustered-bvh,tiled", "--width", "64", "--height", "36", "--frames", "1", "--camera-path", path.to_str().unwrap(),
        "--out", out,
    ]);
    assert!(run.ok, "bench failed:\n{}", run.stderr);
    let csv = Csv::read(&dir.join("flythrough.csv"));
    let rows: Vec<_> = csv.rows().collect();
    assert_eq!(rows.len(), 2, "one fly-through per configuration");
    for r in &rows {
        assert_eq!(r.get("frames"), "3", "{:?}", r.cells);
        assert!(r.num("median_ms") > 0.0 && r.num("median_ms") <= r.num("p99_ms") && r.num("p99_ms") <= r.num("max_ms"), "{:?}", r.cells);
    }
    let md = std::fs::read_to_string(dir.join("results.md")).unwrap();
    assert!(md.contains("## Fly-through"), "{md}");
    std::fs::write(&path, "0,20,60,0,-10\n0,20\n").unwrap();
    let bad = manylights(["bench", "--lights", "200", "--scenes", "city", "--width", "64", "--height", "36", "--camera-path", path.to_str().unwrap(), "--out", out]);
    assert_one_line_error(&bad, "a malformed path", "path.txt:2");
}

/// `--spot-fraction 0.5 --spot-culling both`: every technique is measured with cone culling and
/// with range-sphere culling of the same lights (half of them spots); each row says its share
/// and culling; the sphere rows of the clustered techniques have longer lists than their cone
/// rows (the knob reaches the kernels) and no technique's lists get shorter; both are timed,
/// drawn as separate lines, and tabled in `results.md`.
#[test]
fn bench_spot_culling_both() {
    let dir = TempDir::new("bench-spots");
    let out = dir.path().to_str().unwrap();
    let techniques = ["clustered-bvh", "clustered-aabb", "clustered-naive", "forward-plus"];
    let run = manylights([
        "bench", "--lights", "400", "--scenes", "city", "--techniques", &techniques.join(","), "--width", "64", "--height", "64", "--frames", "1",
        "--spot-fraction", "0.5", "--spot-culling", "both", "--out", out,
    ]);
    assert!(run.ok, "bench failed:\n{}", run.stderr);
    let csv = Csv::read(&dir.join("results.csv"));
    assert_eq!(csv.header, CSV_COLUMNS, "results.csv header");
    // (technique, culling) → the "frame" row's light lists, mean and longest list.
    let mut lists: BTreeMap<(String, String), (f64, f64, f64)> = BTreeMap::new();
    for row in csv.rows() {
        assert_eq!(row.get("spot_fraction"), "0.5", "row {:?}", row.cells);
        assert!(row.num("median_ms").is_finite() && row.num("median_ms") > 0.0, "timed: {:?}", row.cells);
        if row.get("stage") == "frame" {
            let key = (row.get("technique").to_string(), row.get("spot_culling").to_string());
            let previous = lists.insert(key, (row.num("light_lists"), row.num("lights_per_list_mean"), row.num("lights_per_list_max")));
            assert!(previous.is_none(), "one frame row per technique and culling: {:?}", row.cells);
        }
    }
    let expected: BTreeSet<(String, String)> = techniques.iter().flat_map(|t| [(t.to_string(), "cone".to_string()), (t.to_string(), "sphere".to_string())]).collect();
    assert_eq!(lists.keys().cloned().collect::<BTreeSet<_>>(), expected, "every technique measured both ways");
    for t in techniques {
        let (cone, sphere) = (lists[&(t.to_string(), "cone".to_string())], lists[&(t.to_string(), "sphere".to_string())]);
        assert!(cone.1 > 0.0, "{t}: the cone lists hold lights: {cone:?}");
        assert!(sphere.1 >= cone.1 && sphere.2 >= cone.2, "{t}: the range sphere keeps every light the cone keeps: cone {cone:?}, sphere {sphere:?}");
        if t.starts_with("clustered") {
            assert!(sphere.1 > cone.1, "{t}: sphere-only culling keeps more lights per list than the cone: cone {cone:?}, sphere {sphere:?}");
        }
    }
    // Separate lines in the plots, separate columns and a spot table in the report.
    let svg = std::fs::read_to_string(dir.join("frame-vs-lights-city.svg")).expect("frame plot");
    let stages = std::fs::read_to_string(dir.join("stages-city.svg")).expect("stage plot");
    for t in techniques {
        for c in ["cone", "sphere"] {
            assert!(svg.contains(&format!("{t} ({c})")), "frame plot: no line {t} ({c})");
        }
    }
    assert!(stages.contains("bvh 400 cone") && stages.contains("bvh 400 sphere"), "stage plot: a bar per culling");
    let md = std::fs::read_to_string(dir.join("results.md")).expect("results.md");
    assert!(md.contains("## city (64×64, 50 % of the lights spots)") && md.contains("| clustered-bvh (cone) | clustered-bvh (sphere) |"), "{md}");
    assert!(md.contains("### Spot lights (50 % of the lights)"), "{md}");
    for t in techniques {
        for c in ["cone", "sphere"] {
            let (_, mean, max) = lists[&(t.to_string(), c.to_string())];
            let line = format!("| 400 | {t} | {c} | ");
            let row = md.lines().find(|l| l.starts_with(&line)).unwrap_or_else(|| panic!("no spot table row {line:?} in\n{md}"));
            let cells: Vec<f64> = row.split('|').skip(5).take(2).map(|c| c.trim().parse().unwrap_or(f64::NAN)).collect();
            assert!((cells[0] - mean).abs() <= 0.005 + 1e-4 && cells[1] == max, "{row}: lights per list {mean}, max {max} in results.csv");
        }
    }
}

/// `--spot-fraction 0` is the default: the same rows as without the flag (lists, bytes, stages;
/// only the measured times vary), with share 0 and cone culling; the columns before the spot
/// columns are those of earlier results.
#[test]
fn bench_spot_fraction_zero_changes_nothing() {
    assert_eq!(
        CSV_COLUMNS[..16],
        [
            "scene", "technique", "width", "height", "lights", "frames", "stage", "queue", "kind", "median_ms", "min_ms", "max_ms", "bytes",
            "light_lists", "lights_per_list_mean", "lights_per_list_max",
        ],
        "earlier readers of results.csv find their columns where they were"
    );
    let dir = TempDir::new("bench-spots-zero");
    let rows = |extra: &[&str], sub: &str| {
        let out = dir.join(sub);
        let args = ["bench", "--lights", "200", "--scenes", "city", "--techniques", "clustered-bvh,forward-plus,tiled", "--width", "64", "--height", "36", "--frames", "1"];
        let run = manylights(args.iter().copied().chain(extra.iter().copied()).chain(["--out", out.to_str().unwrap()]));
        assert!(run.ok, "bench {extra:?} failed:\n{}", run.stderr);
        let csv = Csv::read(&out.join("results.csv"));
        let untimed: Vec<Vec<String>> = csv
            .rows()
            .map(|r| CSV_COLUMNS.iter().filter(|c| !c.ends_with("_ms")).map(|c| r.get(c).to_string()).collect())
            .collect();
        untimed
    };
    let (plain, zero) = (rows(&[], "plain"), rows(&["--spot-fraction", "0"], "zero"));
    assert!(!plain.is_empty());
    assert_eq!(plain, zero, "--spot-fraction 0 changes no row");
    let spot_cells = |r: &Vec<String>| r[r.len() - 2..].to_vec();
    assert!(zero.iter().all(|r| spot_cells(r) == ["0", "cone"]), "{zero:?}");
}
