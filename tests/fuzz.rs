//! Fuzzing the scene loaders — OBJ, MTL, TOML descriptions and lights (point, spot and directional
//! lights with their `type`, `direction`, `inner_angle`, `outer_angle` and `spot_fraction` keys),
//! glTF documents (JSON with data-URI or external buffers) and `.glb` containers — through their real entry
//! point, `Scene::load` (the bytes are written to files, so `mtllib`, `map_Kd` and `geometry`
//! references are followed as in use), and the light generators directly.
//!
//! Inputs: the seed corpus `tests/fuzz-corpus/{obj,mtl,toml,lights,gltf,glb}/` (small valid files, and
//! known-bad ones named `bad-*`), mutated with structure-aware mutations (numbers swapped for
//! NaN, ∞, 1e39, 2^31, 4e9, …; format keywords and paths such as `/dev/zero` inserted; lines
//! deleted, duplicated, swapped and spliced from other seeds; bit flips; truncation; CRLF; very
//! long words; non-UTF-8 bytes), plus arbitrary bytes. Proptest drives the cases and shrinks a
//! failing one to its fewest mutations.
//!
//! Properties of every input:
//! - no panic (each case runs in its own thread under `catch_unwind`), no hang (a case longer
//!   than [`HANG_SECONDS`] fails the run);
//! - an error is `BadInput`, one line, names a file of the case and a line, key or item;
//! - a scene that loads has only finite, in-range values (positions, unit normals, uvs, lights,
//!   materials, camera), valid indices, and adapts to the renderer (`flatten`, cluster grid)
//!   without a panic.
//!
//! Budget: by default each target runs one round of [`CASES`] cases (or [`BOUNDED_SECONDS`],
//! whichever ends first): about 30 s for the file on 2 cores. `MANYLIGHTS_FUZZ_SECONDS=N` makes
//! it a long run of N seconds in all, split evenly between the targets, in rounds of [`CASES`]
//! cases, each round with a new seed, e.g. one hour on one core:
//! `MANYLIGHTS_FUZZ_SECONDS=3600 cargo test -p host --test fuzz -- --test-threads 1 --nocapture`.
//! A failing input is saved under `target/tmp/fuzz-failures/`; fix the loader and add the input
//! to the corpus.
mod fuzz_input;

use fuzz_input::{bytes_of, input, mutate, Mutation, Pick};
use host::bad_input::is_bad_input;
use host::scene::{flatten::flatten, lights, Scene};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestError, TestRng, TestRunner};
use shaders::cluster_key::ClusterGrid;
use shaders::layout::PointLight;
use shaders::octahedral::Precision;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Cases per round (the bounded run is one round per target).
const CASES: u32 = 15_000;
/// Time cap per target in the bounded run (the case count normally ends it first).
const BOUNDED_SECONDS: f64 = 20.0;
/// A case that takes longer than this is a hang.
const HANG_SECONDS: u64 = 60;
/// Fuzz targets whose long-run time `MANYLIGHTS_FUZZ_SECONDS` is split between.
const TARGETS: u32 = 7;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Obj,
    Mtl,
    Toml,
    Lights,
    Gltf,
    Glb,
}

impl Kind {
    fn dir(self) -> &'static str {
        match self {
            Kind::Obj => "obj",
            Kind::Mtl => "mtl",
            Kind::Toml => "toml",
            Kind::Lights => "lights",
            Kind::Gltf => "gltf",
            Kind::Glb => "glb",
        }
    }

    fn ext(self) -> &'static str {
        match self {
            Kind::Obj => "obj",
            Kind::Mtl => "mtl",
            Kind::Toml | Kind::Lights => "toml",
            Kind::Gltf => "gltf",
            Kind::Glb => "glb",
        }
    }

    const ALL: [Kind; 6] = [Kind::Obj, Kind::Mtl, Kind::Toml, Kind::Lights, Kind::Gltf, Kind::Glb];
}

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fuzz-corpus")
}

/// The seeds of a kind: (file name, bytes), sorted by name.
fn seeds(kind: Kind) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(corpus_dir().join(kind.dir()))
        .expect("the fuzz corpus")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == kind.ext()))
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()))
        .collect();
    v.sort();
    assert!(v.len() >= 5, "{kind:?}: the corpus holds {} seeds", v.len());
    v
}

/// A private copy of the corpus tree (seeds refer to each other by relative paths), plus an OBJ
/// that uses the MTL under test. Removed on drop.
struct Workspace(PathBuf);

impl Workspace {
    fn new(tag: &str) -> Self {
        static N: AtomicU64 = AtomicU64::new(0);
        let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("fuzz-{tag}-{}-{}", std::process::id(), N.fetch_add(1, Ordering::Relaxed)));
        let _ = std::fs::remove_dir_all(&root);
        for sub in Kind::ALL.map(Kind::dir).into_iter().chain(["textures"]) {
            std::fs::create_dir_all(root.join(sub)).unwrap();
            for e in std::fs::read_dir(corpus_dir().join(sub)).unwrap() {
                let p = e.unwrap().path();
                std::fs::copy(&p, root.join(sub).join(p.file_name().unwrap())).unwrap();
            }
        }
        let host = "mtllib fuzz-input.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 1\n\
                    usemtl brick\nf 1/1 2/2 3/1\nusemtl leaf\nf 2/2 4/1 3/2\n";
        std::fs::write(root.join("mtl/fuzz-host.obj"), host).unwrap();
        Self(root)
    }

}

/// Writes a case into the workspace at `root`; returns the file `Scene::load` opens.
fn write_case(root: &Path, kind: Kind, bytes: &[u8]) -> PathBuf {
    let input = root.join(kind.dir()).join(format!("fuzz-input.{}", kind.ext()));
    std::fs::write(&input, bytes).unwrap();
    match kind {
        Kind::Mtl => root.join("mtl/fuzz-host.obj"),
        _ => input,
    }
}

impl Drop for Workspace {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Whether an error message says where: a line, a key, or the item of the scene at fault.
fn names_a_place(msg: &str) -> bool {
    let line = msg.match_indices(" line ").any(|(i, _)| msg[i + 6..].starts_with(|c: char| c.is_ascii_digit()));
    let keys = ["geometry", "name", "camera", "lights", "light[", "[[light]]", "material[", "mtl_d_zero_is_opaque", "effects", "distribution", "count", "nurbs["];
    let items = ["not found", "cannot read", "mesh ", "light ", "material ", "texture ", "spans ", "triangle", "materials"];
    // glTF: the document's own places (a buffer, view or accessor by index, a JSON path such as
    // `accessors[0].bufferView` — the validation's `invalid glTF: <path>: <problem>` always has
    // one —, the `.glb` container as a whole or its chunk, a JSON column).
    let gltf = [
        "buffer ", "view ", "accessor ", "primitive", "meshes[", "nodes[", "accessors[", "bufferViews[", "buffers[", "materials[", "textures[",
        "images[", "samplers[", "cameras[", "scenes[", "skins[", "animations[", "extensions", ".glb container", "chunk", "column ",
        "invalid glTF: ", "scenes: ",
    ];
    let items: Vec<&str> = items.iter().chain(&gltf).copied().collect();
    line || keys.iter().chain(&items).any(|k| msg.contains(k))
}

/// The properties of a loaded scene (see the module docs).
fn check_scene(s: &Scene) -> Result<(), String> {
    s.validate().map_err(|e| format!("a loaded scene fails validation: {e:#}"))?;
    s.camera.validate().map_err(|e| format!("camera: {e:#}"))?;
    for (m, mesh) in s.meshes.iter().enumerate() {
        let n = mesh.positions.len();
        if mesh.normals.len() != n || mesh.uvs.len() != n || mesh.indices.iter().any(|&i| i as usize >= n) || mesh.indices.len() % 3 != 0 {
            return Err(format!("mesh {m}: inconsistent arrays or indices"));
        }
        if !mesh.positions.iter().flatten().chain(mesh.normals.iter().flatten()).chain(mesh.uvs.iter().flatten()).all(|v| v.is_finite()) {
            return Err(format!("mesh {m}: a non-finite vertex value"));
        }
        if let Some(nv) = mesh.normals.iter().find(|nv| (glam::Vec3::from_array(**nv).length() - 1.0).abs() > 1e-3) {
            return Err(format!("mesh {m}: normal {nv:?} is not unit length"));
        }
    }
    for m in &s.materials {
        let unit = |v: f32| (0.0..=1.0).contains(&v);
        if !(m.albedo.iter().all(|&v| unit(v)) && unit(m.specular) && unit(m.opacity) && m.roughness > 0.0 && m.roughness <= 1.0) {
            return Err(format!("material out of range: {m:?}"));
        }
    }
    check_lights(&s.lights)?;
    let flat = flatten(s, Precision::Oct16).map_err(|e| format!("flatten: {e:#}"));
    if let Err(e) = &flat {
        if e.contains('\n') {
            return Err(format!("flatten error on several lines: {e}"));
        }
    }
    // The renderer's grid for this camera: an error is fine, a panic is not.
    let c = s.camera;
    let _ = ClusterGrid::new(64, 36, 16, c.near, c.far, c.fov_y_degrees.to_radians());
    Ok(())
}

fn check_lights(l: &[PointLight]) -> Result<(), String> {
    for (i, l) in l.iter().enumerate() {
        let finite = l.position.iter().chain(&l.colour).chain([&l.radius, &l.intensity]).all(|v| v.is_finite());
        if !finite || l.radius < 0.0 || l.intensity < 0.0 || l.colour.iter().any(|&c| c < 0.0) {
            return Err(format!("light {i} out of range: {l:?}"));
        }
    }
    Ok(())
}

/// The properties of an error: `BadInput`, one line, a file of the case and a place named.
fn check_error(e: &anyhow::Error, ws: &Path) -> Result<(), String> {
    let msg = format!("{e:#}");
    if !is_bad_input(e) {
        return Err(format!("error not marked as bad input: {msg}"));
    }
    if msg.chars().any(char::is_control) {
        return Err(format!("error is not one line: {msg:?}"));
    }
    if !msg.contains(&ws.display().to_string()) {
        return Err(format!("error names no file of the case: {msg}"));
    }
    if !names_a_place(&msg) {
        return Err(format!("error names no line, key or item: {msg}"));
    }
    Ok(())
}

/// What one case did.
#[derive(Debug)]
enum Outcome {
    Loaded,
    Refused,
    /// A property failed (or a panic): the message.
    Broken(String),
}

/// Runs `f` in its own thread, catching panics; a case that outlives `limit` is a hang and ends
/// the whole process after saving the input (a stuck thread cannot be stopped).
fn guarded(limit: Duration, on_hang: impl FnOnce(), f: impl FnOnce() -> Outcome + Send + 'static) -> Outcome {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
        let _ = tx.send(r.unwrap_or_else(|p| {
            let what = p.downcast_ref::<String>().cloned().or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string())).unwrap_or_default();
            Outcome::Broken(format!("panicked: {what}"))
        }));
    });
    match rx.recv_timeout(limit) {
        Ok(o) => o,
        Err(_) => {
            on_hang();
            eprintln!("fuzz: a case ran longer than {} s: a hang", limit.as_secs());
            std::process::exit(1);
        }
    }
}

fn save_failure(kind: &str, bytes: &[u8]) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-failures");
    std::fs::create_dir_all(&dir).unwrap();
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    let p = dir.join(format!("{kind}-{hash:016x}.bin"));
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Loads one input of `kind` in `ws` and checks every property.
fn run_case(kind: Kind, ws: &Path, bytes: Vec<u8>) -> Outcome {
    let root = ws.to_owned();
    let saved = bytes.clone();
    guarded(
        Duration::from_secs(HANG_SECONDS),
        || eprintln!("fuzz: hanging input saved as {}", save_failure(kind.dir(), &saved).display()),
        move || {
            let path = write_case(&root, kind, &bytes);
            let r = Scene::load(path.to_str().unwrap(), &root.join("no-assets"));
            let o = match &r {
                Ok(s) => check_scene(s).map(|_| Outcome::Loaded),
                Err(e) => check_error(e, &root).map(|_| Outcome::Refused),
            };
            o.unwrap_or_else(Outcome::Broken)
        },
    )
}

// ---------------------------------------------------------------------------------------------
// Budget and runner

/// Seconds this target may run in a long run (`MANYLIGHTS_FUZZ_SECONDS` / [`TARGETS`]).
fn long_run_seconds() -> Option<f64> {
    let total: f64 = std::env::var("MANYLIGHTS_FUZZ_SECONDS").ok()?.parse().expect("MANYLIGHTS_FUZZ_SECONDS must be a number of seconds");
    Some(total / TARGETS as f64)
}

/// Runs `case` on inputs from `strategy` for the budget; panics with the shrunk failing input
/// (saved under `target/tmp/fuzz-failures/`) on the first property violation.
fn fuzz<T: std::fmt::Debug + Clone>(name: &str, strategy: impl Strategy<Value = T>, to_bytes: impl Fn(&T) -> Vec<u8>, case: impl Fn(&T) -> Outcome) {
    let seconds = long_run_seconds().unwrap_or(BOUNDED_SECONDS);
    let t0 = Instant::now();
    let (ran, loaded, refused) = (AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0));
    let mut round = 0u64;
    while t0.elapsed().as_secs_f64() < seconds && (round == 0 || long_run_seconds().is_some()) {
        let config = Config { cases: CASES, failure_persistence: None, max_shrink_iters: 2000, ..Config::default() };
        let seed: Vec<u8> = (0..32).map(|i| (round.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> (i % 8 * 8)) as u8 ^ i as u8).collect();
        let mut runner = TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
        let result = runner.run(&strategy, |v| {
            if t0.elapsed().as_secs_f64() >= seconds {
                return Ok(()); // budget spent: the remaining cases pass untried
            }
            ran.fetch_add(1, Ordering::Relaxed);
            match case(&v) {
                Outcome::Loaded => loaded.fetch_add(1, Ordering::Relaxed),
                Outcome::Refused => refused.fetch_add(1, Ordering::Relaxed),
                Outcome::Broken(why) => return Err(TestCaseError::fail(why)),
            };
            Ok(())
        });
        if let Err(e) = result {
            let (why, value) = match e {
                TestError::Fail(why, v) => (why.to_string(), v),
                TestError::Abort(why) => panic!("fuzz {name}: aborted: {why}"),
            };
            let saved = save_failure(name, &to_bytes(&value));
            panic!("fuzz {name}: {why}\nminimal input saved as {} ({value:?})", saved.display());
        }
        round += 1;
    }
    let (n, s) = (ran.load(Ordering::Relaxed), t0.elapsed().as_secs_f64());
    println!(
        "fuzz {name}: {n} inputs in {s:.1} s ({:.0}/s), {} rounds: {} loaded, {} refused with a clean error, 0 failures",
        n as f64 / s,
        round,
        loaded.load(Ordering::Relaxed),
        refused.load(Ordering::Relaxed)
    );
    assert!(n > 0, "fuzz {name}: no input ran");
}

fn fuzz_kind(kind: Kind) {
    let seeds = seeds(kind);
    let ws = Workspace::new(kind.dir());
    fuzz(kind.dir(), input(), |i| bytes_of(i, &seeds), |i| run_case(kind, &ws.0, bytes_of(i, &seeds)));
}

#[test]
fn fuzz_obj() {
    fuzz_kind(Kind::Obj);
}

#[test]
fn fuzz_mtl() {
    fuzz_kind(Kind::Mtl);
}

#[test]
fn fuzz_toml() {
    fuzz_kind(Kind::Toml);
}

#[test]
fn fuzz_lights() {
    fuzz_kind(Kind::Lights);
}

#[test]
fn fuzz_gltf() {
    fuzz_kind(Kind::Gltf);
}

#[test]
fn fuzz_glb() {
    fuzz_kind(Kind::Glb);
}

/// Floats that break generators, and ordinary ones.
fn any_float() -> impl Strategy<Value = f32> {
    prop_oneof![
        2 => proptest::sample::select(vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN, 1e30, -1e30, 0.0, -0.0, 1e-45]),
        3 => -1000.0f32..1000.0,
        1 => any::<f32>(),
    ]
}

/// The generators with arbitrary bounds, counts (over the limit too), seeds, clusters and
/// offsets: an error is one line; lights are finite, in range and inside the bounds.
#[test]
fn fuzz_light_generators() {
    let scene = Scene::load(corpus_dir().join("obj/cube.obj").to_str().unwrap(), Path::new("no-assets")).unwrap();
    let counts = prop_oneof![8 => 0usize..3000, 1 => proptest::sample::select(vec![lights::MAX_LIGHTS + 1, u32::MAX as usize, usize::MAX])];
    let clusters = prop_oneof![8 => 0usize..50, 1 => proptest::sample::select(vec![lights::MAX_HOTSPOT_CLUSTERS + 1, usize::MAX])];
    let strategy = (proptest::array::uniform6(any_float()), counts, any::<u64>(), clusters, any_float(), 0u8..3);
    fuzz(
        "light-generators",
        strategy,
        |v| format!("{v:?}").into_bytes(),
        |&(b, n, seed, clusters, offset, which)| {
            let scene = scene.clone();
            guarded(Duration::from_secs(HANG_SECONDS), || eprintln!("fuzz: generators hung on {b:?} {n} {seed} {clusters} {offset}"), move || {
                let bounds = (glam::Vec3::new(b[0], b[1], b[2]), glam::Vec3::new(b[3], b[4], b[5]));
                let r = match which {
                    0 => lights::uniform_in(bounds, n, seed, (offset.abs().min(1.0), 1.0), 1.0),
                    1 => lights::hotspots(bounds, n, seed, clusters),
                    _ => lights::on_surfaces(&scene, n, seed, offset),
                };
                match r {
                    Err(e) if format!("{e:#}").chars().any(char::is_control) => Outcome::Broken(format!("error on several lines: {e:#}")),
                    Err(_) => Outcome::Refused,
                    Ok(l) if l.len() != n => Outcome::Broken(format!("{} lights for {n}", l.len())),
                    Ok(l) => {
                        let inside = |p: [f32; 3]| (0..3).all(|k| p[k] >= bounds.0[k] && p[k] <= bounds.1[k]);
                        match check_lights(&l) {
                            Err(e) => Outcome::Broken(e),
                            Ok(()) if which < 2 && !l.iter().all(|l| inside(l.position)) => Outcome::Broken("a light outside the bounds".into()),
                            Ok(()) => Outcome::Loaded,
                        }
                    }
                }
            })
        },
    );
}

/// Every corpus file unmutated: valid files load, `bad-*` files are refused, all with the
/// properties above.
#[test]
fn corpus_files_load_or_are_refused_as_named() {
    let ws = Workspace::new("corpus");
    let mut counts = (0, 0);
    for kind in Kind::ALL {
        for (name, bytes) in seeds(kind) {
            let o = run_case(kind, &ws.0, bytes);
            match (&o, name.starts_with("bad-")) {
                (Outcome::Loaded, false) => counts.0 += 1,
                (Outcome::Refused, true) => counts.1 += 1,
                _ => panic!("{}/{name}: {o:?}", kind.dir()),
            }
        }
    }
    println!("corpus: {} files load, {} bad files are refused", counts.0, counts.1);
}

/// The harness itself fails where it must: a panic, an error on two lines, an error naming no
/// file, and a non-finite light are all reported.
#[test]
fn the_harness_catches_what_it_looks_for() {
    let broken = |o: Outcome| matches!(o, Outcome::Broken(_));
    assert!(broken(guarded(Duration::from_secs(10), || (), || panic!("a deliberate panic: the harness must report it"))));
    let ws = Path::new("/some/dir");
    let bad = |msg: &str| host::bad_input::bad_input(anyhow::anyhow!("{msg}"));
    assert!(check_error(&bad("/some/dir/x.obj line 3: bad"), ws).is_ok());
    assert!(check_error(&anyhow::Error::new(host::bad_input::BadInput("/some/dir/x.obj line 3:\nbad".into())), ws).is_err());
    assert!(check_error(&bad("line 3: bad"), ws).is_err(), "no file");
    assert!(check_error(&bad("/some/dir/x.obj: bad"), ws).is_err(), "no place");
    assert!(check_error(&anyhow::anyhow!("/some/dir/x.obj line 3: bad"), ws).is_err(), "not bad input");
    let light = PointLight { position: [0.0, f32::NAN, 0.0], radius: 1.0, colour: [1.0; 3], intensity: 1.0 };
    assert!(check_lights(&[light]).is_err());
    // Mutations do what they say.
    let seeds = vec![("a".to_string(), b"v 1 2 3\nf 1 2 3\n".to_vec())];
    let m = |m: Mutation| String::from_utf8_lossy(&mutate(seeds[0].1.clone(), &m, &seeds)).into_owned();
    let zero = Pick(0);
    assert_eq!(m(Mutation::ReplaceNumber(zero, zero)), "v nan 2 3\nf 1 2 3\n");
    assert_eq!(m(Mutation::DeleteLine(zero)), "f 1 2 3\n");
    assert_eq!(m(Mutation::Crlf), "v 1 2 3\r\nf 1 2 3\r\n");
    assert_eq!(m(Mutation::SwapLines(zero, Pick(u64::MAX))), "f 1 2 3\nv 1 2 3\n");
}
