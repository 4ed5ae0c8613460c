//! The rust-gpu backend (`rustc_codegen_spirv`) built against the system's SPIRV-Tools.
//!
//! `cargo-gpu-install`'s `Install::run` builds the backend once into its cache
//! (`$XDG_CACHE_HOME/rust-gpu`, else `~/.cache/rust-gpu`) from a generated crate that depends on
//! `rustc_codegen_spirv` with its default features. The default, `use-compiled-tools`, compiles
//! SPIRV-Tools' C++ sources into the backend: most of a cold build's CPU time. The other feature,
//! `use-installed-tools`, runs the `spirv-opt` and `spirv-val` executables found on `PATH`
//! instead (`./dev.sh` installs Debian's `spirv-tools`).
//!
//! [`prepare`] runs before `Install::run`. When the backend is not built yet and both tools run,
//! it writes that crate itself with `default-features = false, features = ["use-installed-tools"]`,
//! builds it with the pinned toolchain and puts the library where `Install::run` looks for it,
//! which then finds it and builds nothing. Without the tools, when that build fails, or for a
//! local rust-gpu checkout, it says why and leaves the build to `Install::run`, with the compiled
//! tools. `MANYLIGHTS_COMPILED_SPIRV_TOOLS=1` asks for the compiled tools even where the system's
//! run (and replaces a cached backend built against the installed ones).
//!
//! Same rust-gpu, other SPIRV-Tools: the modules are validated and optimised by the system's
//! version instead of the bundled one, so their bytes can differ where the two versions'
//! `spirv-opt -O` recipes differ (README, "Toolchain").
use cargo_gpu_install::install::FileLock;
use cargo_gpu_install::spirv_builder::cargo_cmd::CargoCmd;
use cargo_gpu_install::spirv_source::{get_channel_from_rustc_codegen_spirv_build_script, CrateMetadata, SpirvSource};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The SPIRV-Tools executables the backend runs with `use-installed-tools`.
const TOOLS: [&str; 2] = ["spirv-opt", "spirv-val"];
/// Asks for the compiled tools even where the installed ones run.
const FORCE_COMPILED: &str = "MANYLIGHTS_COMPILED_SPIRV_TOOLS";
/// Components the backend is built with (as `cargo-gpu-install` installs them).
const COMPONENTS: [&str; 3] = ["rust-src", "rustc-dev", "llvm-tools"];

/// Which SPIRV-Tools the backend uses.
pub enum Tools {
    /// Built by an earlier build (against either).
    Cached,
    /// Just built against the installed tools (their versions).
    Installed(String),
    /// `Install::run` compiles SPIRV-Tools into the backend, for this reason.
    Compiled(String),
}

/// Builds the backend against the installed SPIRV-Tools when it is missing and they run.
pub fn prepare(shader_crate: &Path) -> anyhow::Result<Tools> {
    println!("cargo::rerun-if-env-changed={FORCE_COMPILED}");
    let source = SpirvSource::new(&CrateMetadata::query(shader_crate.to_path_buf())?, None, None)?;
    let version_spec = match &source {
        SpirvSource::CratesIO(version) => format!("version = \"{version}\""),
        SpirvSource::Git { url, rev } => format!("git = \"{url}\"\nrev = \"{rev}\""),
        _ => return Ok(Tools::Compiled("rust-gpu is a local checkout: `cargo-gpu-install` builds it in place".into())),
    };
    let install_dir = source.install_dir()?;
    let dylib = install_dir.join(format!("{}rustc_codegen_spirv{}", std::env::consts::DLL_PREFIX, std::env::consts::DLL_SUFFIX));
    let manifest = install_dir.join("Cargo.toml");
    let built = || dylib.is_file() && manifest.is_file() && install_dir.join("src/lib.rs").is_file();
    let uses_installed = || std::fs::read_to_string(&manifest).is_ok_and(|m| m.contains("use-installed-tools"));
    let force_compiled = std::env::var(FORCE_COMPILED).is_ok_and(|v| v == "1");
    if built() {
        if !(force_compiled && uses_installed()) {
            return Ok(Tools::Cached);
        }
        std::fs::remove_file(&dylib)?; // `Install::run` rebuilds it with the compiled tools
    }
    if force_compiled {
        return Ok(Tools::Compiled(format!("{FORCE_COMPILED}=1")));
    }
    let versions: Result<Vec<String>, String> = TOOLS.iter().map(|t| tool_version(t)).collect();
    let mut versions = match versions {
        Ok(v) => v,
        Err(why) => return Ok(Tools::Compiled(why)),
    };
    versions.dedup(); // both come from one SPIRV-Tools package
    std::fs::create_dir_all(install_dir.join("src"))?;
    let _lock = FileLock::lock(&install_dir.join("lockfile"))?;
    if built() {
        return Ok(Tools::Cached); // another build finished it meanwhile
    }
    std::fs::write(install_dir.join("src/lib.rs"), "")?;
    std::fs::write(
        &manifest,
        format!(
            "[package]\nname = \"rustc_codegen_spirv_dummy\"\nversion = \"0.1.0\"\nedition = \"2021\"\n\n\
             [dependencies.spirv-builder]\npackage = \"rustc_codegen_spirv\"\n{version_spec}\n\
             default-features = false\nfeatures = [\"use-installed-tools\"]\n"
        ),
    )?;
    let _ = std::fs::remove_file(install_dir.join("Cargo.lock"));
    let metadata = CrateMetadata::query(install_dir.clone())?;
    let channel = get_channel_from_rustc_codegen_spirv_build_script(metadata.find_package("rustc_codegen_spirv")?)?;
    ensure_toolchain(&channel)?;
    eprintln!("building rustc_codegen_spirv with the installed SPIRV-Tools ({})", versions.join(", "));
    let mut cargo: Command = CargoCmd::new().into();
    cargo.env_remove("CLIPPY_ARGS").current_dir(&install_dir).arg(format!("+{channel}")).args(["build", "--release"]);
    // Cargo reads a build script's stdout: the inner build's output goes to stderr.
    let status = cargo.stdout(Stdio::from(std::io::stderr())).status()?;
    let target = install_dir.join("target");
    let output = target.join("release").join(dylib.file_name().unwrap());
    if !status.success() || !output.is_file() {
        // `Install::run` writes its own crate and builds it from scratch.
        let _ = std::fs::remove_dir_all(&target);
        return Ok(Tools::Compiled(format!("building it against the installed tools failed ({status})")));
    }
    std::fs::rename(&output, &dylib)?;
    std::fs::remove_dir_all(&target)?;
    Ok(Tools::Installed(versions.join(", ")))
}

/// `<tool> --version`'s first line (`spirv-opt` prints it on stderr), or why the tool does not run.
fn tool_version(tool: &str) -> Result<String, String> {
    match Command::new(tool).arg("--version").output() {
        Ok(out) if out.status.success() => {
            let text = [out.stdout, out.stderr].concat();
            Ok(String::from_utf8_lossy(&text).lines().find(|l| !l.trim().is_empty()).unwrap_or(tool).trim().to_string())
        }
        Ok(out) => Err(format!("`{tool} --version` failed ({})", out.status)),
        Err(e) => Err(format!("{tool} not found ({e}); install spirv-tools (Debian/Ubuntu: apt-get install spirv-tools)")),
    }
}

/// Installs the pinned toolchain with the backend's components through rustup unless present
/// (what `Install::run` does before its own build).
fn ensure_toolchain(channel: &str) -> anyhow::Result<()> {
    let stdout = |args: &[&str]| Command::new("rustup").args(args).stderr(Stdio::null()).output().ok().filter(|o| o.status.success()).map(|o| String::from_utf8_lossy(&o.stdout).into_owned());
    // Listing the components of an absent toolchain would install it: ask for the toolchain first.
    let toolchain = stdout(&["toolchain", "list"]).is_some_and(|l| l.lines().any(|t| t.starts_with(&format!("{channel}-"))));
    let components = toolchain.then(|| stdout(&["component", "list", "--installed", "--toolchain", channel])).flatten();
    let have = |c: &str, list: &str| list.lines().any(|l| l == c || l.starts_with(&format!("{c}-")));
    if components.is_some_and(|list| COMPONENTS.iter().all(|c| have(c, &list))) {
        return Ok(());
    }
    eprintln!("installing toolchain {channel} with {}", COMPONENTS.join(", "));
    let status = Command::new("rustup")
        .args(["toolchain", "install", channel, "--profile", "minimal", "-c"])
        .arg(COMPONENTS.join(","))
        .stdout(Stdio::from(std::io::stderr()))
        .status()?;
    anyhow::ensure!(status.success(), "rustup toolchain install {channel} failed ({status})");
    Ok(())
}

/// Where the cache lives (for messages).
pub fn cache_dir() -> PathBuf {
    cargo_gpu_install::cache_dir().unwrap_or_else(|_| PathBuf::from("~/.cache/rust-gpu"))
}
