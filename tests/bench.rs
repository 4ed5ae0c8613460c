//! `manylights bench` end to end on the local device (validation on): a tiny sweep writes a CSV
//! with the documented columns whose numbers are all finite and positive, SVG plots, and a
//! markdown summary that names the device and the command; a technique that cannot run at a size
//! is reported as skipped, not dropped.
use host::bench::CSV_COLUMNS;
use std::process::Command;

#[test]
fn tiny_bench_writes_csv_plots_and_markdown() {
    let dir = std::env::temp_dir().join(format!("manylights-bench-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(["bench", "--lights", "100,1000", "--scenes", "city", "--width", "96", "--height", "54", "--frames", "2", "--out"])
        .arg(&dir)
        .env("MANYLIGHTS_VALIDATION", "true")
        .output()
        .expect("running manylights bench");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "bench failed:\n{err}");
    let csv = std::fs::read_to_string(dir.join("results.csv")).expect("results.csv");
    let mut lines = csv.lines();
    assert_eq!(lines.next().unwrap(), CSV_COLUMNS.join(","));
    let numeric = |c: &str| !matches!(c, "scene" | "technique" | "stage");
    let mut rows = 0;
    let mut techniques = std::collections::BTreeSet::new();
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), CSV_COLUMNS.len(), "row {line:?}");
        techniques.insert(cells[1].to_string());
        for (col, cell) in CSV_COLUMNS.iter().zip(&cells) {
            if numeric(col) {
                let v: f64 = cell.parse().unwrap_or_else(|_| panic!("{col} = {cell:?} is not a number (row {line:?})"));
                assert!(v.is_finite() && v > 0.0, "{col} = {v} is not finite and positive (row {line:?})");
            }
        }
        rows += 1;
    }
    // Every technique at both light counts, each with its passes + frame + compute.
    assert!(techniques.len() >= 3, "techniques in the CSV: {techniques:?}");
    assert!(rows >= techniques.len() * 2 * 3, "{rows} rows");
    let md = std::fs::read_to_string(dir.join("results.md")).expect("results.md");
    assert!(md.contains("**Device:**") && md.contains("bench --lights 100,1000"), "results.md names the device and the command:\n{md}");
    assert!(md.contains("Speed-up at 1k lights"), "results.md has the speed-up table:\n{md}");
    for svg in ["frame-vs-lights-city.svg", "compute-vs-lights-city.svg", "stages-city.svg"] {
        let s = std::fs::read_to_string(dir.join(svg)).unwrap_or_else(|e| panic!("{svg}: {e}"));
        assert!(s.starts_with("<svg") && s.contains("<text"), "{svg} is an SVG with labels");
    }
}

#[test]
fn bench_bad_input_is_a_one_line_error() {
    let dir = std::env::temp_dir().join(format!("manylights-bench-bad-{}", std::process::id()));
    for (args, needle) in [
        (vec!["--techniques", "warp-drive"], "unknown technique"),
        (vec!["--lights", "0"], "positive light counts"),
        (vec!["--scenes", "no-such-scene.obj"], "no-such-scene"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_manylights"))
            .arg("bench")
            .args(&args)
            .args(["--width", "32", "--height", "18", "--frames", "1", "--out"])
            .arg(&dir)
            .output()
            .expect("running manylights bench");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?} is bad input: {err}");
        assert!(err.contains(needle) && !err.contains("panicked"), "{args:?}: {err}");
    }
}

/// The accuracy study on a tiny frame with 10k lights (enough for llvmpipe's loop limiter to
/// bite if a test looped per light): the reference setting reproduces the reference, tile
/// sizes only move time (lists are conservative), a smaller ε is never less accurate, and the
/// Pareto plot and markdown are written.
#[test]
fn tiny_accuracy_study() {
    let dir = std::env::temp_dir().join(format!("manylights-accuracy-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(["bench", "--study", "accuracy", "--lights", "10000", "--scenes", "city", "--width", "96", "--height", "54", "--frames", "1", "--out"])
        .arg(&dir)
        .env("MANYLIGHTS_VALIDATION", "true")
        .output()
        .expect("running manylights bench --study accuracy");
    assert!(out.status.success(), "study failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let csv = std::fs::read_to_string(dir.join("accuracy.csv")).expect("accuracy.csv");
    let rows: Vec<Vec<String>> = csv.lines().skip(1).map(|l| l.split(',').map(|c| c.trim_matches('"').to_string()).collect()).collect();
    assert_eq!(rows.len(), 14, "{csv}");
    let psnr = |setting: &str| -> f64 { rows.iter().find(|r| r[2].starts_with(setting)).unwrap_or_else(|| panic!("{setting}")).get(3).unwrap().parse().unwrap() };
    let max_abs = |setting: &str| -> u32 { rows.iter().find(|r| r[2].starts_with(setting)).unwrap()[4].parse().unwrap() };
    assert!(max_abs("float32") <= 1, "the reference setting reproduces brute force");
    let normal_max_deg = |setting: &str| -> f64 { rows.iter().find(|r| r[2].starts_with(setting)).unwrap()[6].parse().unwrap() };
    assert_eq!(normal_max_deg("float32"), 0.0, "float32 normals are the reference's");
    use shaders::octahedral::Precision;
    for (setting, p) in [("oct 2×8", Precision::Oct8), ("oct 2×12", Precision::Oct12), ("oct 2×16", Precision::Oct16)] {
        let bound = (p.max_angular_error_bound() as f64).to_degrees();
        assert!(normal_max_deg(setting) <= bound + 1e-4, "{setting}: {}° over the proven bound {bound}°", normal_max_deg(setting));
    }
    // Per scene the error need not fall with every added bit (a normal on the 2×12 grid is not on
    // the 2×16 one), but 2×8 bits are far coarser.
    assert!(normal_max_deg("oct 2×8") > 10.0 * normal_max_deg("oct 2×16"), "2×8 bits: larger normal error than 2×16");
    for tile in ["16 px", "32 px", "64 px"] {
        assert!(max_abs(tile) <= 1, "tile {tile}: conservative lists give the reference image");
    }
    let per_cluster = |setting: &str| -> f64 { rows.iter().find(|r| r[2].starts_with(setting)).unwrap()[12].parse().unwrap() };
    for test in ["sphere–AABB", "sphere–frustum planes", "exact sphere–frustum"] {
        assert!(max_abs(test) <= 1, "culling test {test} is conservative: the reference image");
    }
    assert!(per_cluster("exact sphere–frustum") <= per_cluster("sphere–AABB"), "the exact test keeps no more lights than the box");
    assert!(per_cluster("exact sphere–frustum") <= per_cluster("sphere–frustum planes"), "the exact test keeps no more lights than the planes");
    let (e2, e3, e4) = (psnr("inverse square cut at ε = 1e-2"), psnr("inverse square cut at ε = 1e-3"), psnr("inverse square cut at ε = 1e-4"));
    assert!(e2 <= e3 && e3 <= e4, "a smaller cut threshold is never less accurate: {e2} {e3} {e4}");
    let md = std::fs::read_to_string(dir.join("results.md")).expect("results.md");
    assert!(md.contains("| normal encoding | oct 2×8 |") && md.contains("pareto-city.svg"), "{md}");
    assert!(std::fs::read_to_string(dir.join("pareto-city.svg")).expect("pareto plot").starts_with("<svg"));
}
