//! Command-line interface (clap). Progress and errors go to stderr; results to files/stdout.
//!
//! Exit status: 0 on success; 2 for bad input (a malformed command line, a flag out of range or
//! beyond the device's limits, a scene file missing or malformed: `bad_input`); 1 for any other
//! failure. An error is always one line on stderr (`error: …`), never a panic or a backtrace.
use crate::args::{debug_view_parser, precision_parser, FrameArgs};
use crate::bad_input::{bad_input, flatten_lines, EXIT_BAD_INPUT};
use crate::debug_frame::{self, FrameSpec};
use crate::gpu::Gpu;
use crate::vk::{self, ContextOptions};
use anyhow::{bail, Context as _, Result};
use clap::{Args, Parser, Subcommand};
use shaders::layout::View;
use shaders::octahedral::Precision;

#[derive(Parser, Debug)]
#[command(name = "manylights", version, about = "Many-light clustered shading research renderer (rust-gpu + Vulkan)")]
pub struct Cli {
    #[command(flatten)]
    pub device: DeviceArgs,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Args, Debug, Clone)]
pub struct DeviceArgs {
    /// Use the first Vulkan device whose name contains this (case-insensitive).
    #[arg(long, global = true, env = "MANYLIGHTS_DEVICE")]
    pub device: Option<String>,
    /// Enable the Khronos validation layer (+ synchronization validation); any message fails the run.
    /// The variable takes 1/0, true/false, yes/no, on/off.
    #[arg(long, global = true, env = "MANYLIGHTS_VALIDATION", value_parser = clap::builder::BoolishValueParser::new())]
    pub validation: bool,
    /// Print what the driver compiled each compute kernel to (registers, binary size; where the
    /// device offers VK_KHR_pipeline_executable_properties).
    #[arg(long, global = true)]
    pub kernel_stats: bool,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene with a lighting technique; write the frame as PNG (and statistics as JSON).
    Render(crate::render_cmd::RenderArgs),
    /// Render a debug frame of the analytic test scene (normal encoding, cluster keys, slices).
    DebugFrame(DebugFrameArgs),
    /// Sweep techniques × light counts × scenes; write results.csv, SVG plots and results.md.
    Bench(crate::bench::BenchArgs),
    /// Run every kernel on the GPU and compare with the CPU reference (exit 1 on a mismatch).
    Check,
    /// List Vulkan devices and whether manylights can use them.
    Devices,
    /// Open a window and fly through a scene: every frame rendered with the passes of `render`;
    /// keys switch technique, view and light count (README, "Viewer").
    View(crate::viewer::ViewArgs),
}

#[derive(Args, Debug)]
pub struct DebugFrameArgs {
    /// What to show.
    #[arg(long, value_parser = debug_view_parser(), default_value = "clusters")]
    pub view: View,
    /// Normal-encoding precision used by the normals / octa-error views.
    #[arg(long, value_parser = precision_parser(), default_value = "oct8")]
    pub precision: Precision,
    #[command(flatten)]
    pub frame: FrameArgs,
}

fn open(dev: &DeviceArgs) -> Result<Gpu> {
    open_with(dev, None)
}

/// Opens the device for presenting to windows of `display` (the viewer).
pub(crate) fn open_for_display(dev: &DeviceArgs, display: raw_window_handle::RawDisplayHandle) -> Result<Gpu> {
    open_with(dev, Some(display))
}

fn open_with(dev: &DeviceArgs, display: Option<raw_window_handle::RawDisplayHandle>) -> Result<Gpu> {
    let opts = ContextOptions { validation: dev.validation, device: dev.device.clone(), kernel_statistics: dev.kernel_stats };
    let gpu = match display {
        Some(d) => Gpu::for_display(&opts, d),
        None => Gpu::new(&opts),
    }
    .map_err(|e| {
        // A `--device` that names no device is the user's input; no usable device at all is not.
        let named = dev.device.is_some() && matches!(e, vk::VkError::NoMatchingDevice { .. });
        let e = anyhow::Error::new(e).context("opening the Vulkan device");
        if named {
            bad_input(e)
        } else {
            e
        }
    })?;
    eprintln!("device: {}", gpu.ctx.info.line());
    if dev.kernel_stats && gpu.ctx.kernel_statistics.is_none() {
        eprintln!("kernel statistics: {} does not offer VK_KHR_pipeline_executable_properties", gpu.ctx.info.name);
    }
    Ok(gpu)
}

/// `--kernel-stats`: one line per compiled kernel executable, in the order they were made.
fn print_kernel_statistics(gpu: &Gpu) {
    if let Some(capture) = &gpu.ctx.kernel_statistics {
        for k in capture.statistics() {
            eprintln!("kernel {}", k.line());
        }
    }
}

/// Prints the kernel statistics (`--kernel-stats`); fails when validation reported anything.
pub(crate) fn finish(gpu: &Gpu) -> Result<()> {
    print_kernel_statistics(gpu);
    let msgs = gpu.ctx.take_validation_messages();
    if !msgs.is_empty() {
        for m in &msgs {
            eprintln!("validation: {m}");
        }
        bail!("the validation layer reported {} message(s)", msgs.len());
    }
    Ok(())
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(a) => {
            let gpu = open(&cli.device)?;
            crate::render_cmd::run(&gpu, &a)?;
            finish(&gpu)
        }
        Command::Bench(a) => {
            let gpu = open(&cli.device)?;
            crate::bench::run(&gpu, &a)?;
            finish(&gpu)
        }
        Command::DebugFrame(a) => {
            let gpu = open(&cli.device)?;
            let f = &a.frame;
            crate::preflight::check_frame(&gpu.ctx.info, f.width, f.height, f.tile_size, Precision::Oct8)?;
            crate::args::check_output_dir("--out", &f.out)?;
            let spec = FrameSpec {
                width: f.width,
                height: f.height,
                tile_size: f.tile_size,
                near: 0.1,
                far: 500.0,
                fov_y_degrees: 60.0,
                view: a.view,
                precision: a.precision,
            };
            let (pixels, timings) = debug_frame::render_gpu(&gpu, &spec)?;
            debug_frame::save_png(&f.out, f.width, f.height, &pixels)?;
            for t in &timings {
                eprintln!("{:<12} {:8.3} ms (GPU)", t.name, t.ms);
            }
            eprintln!("wrote {}", f.out.display());
            finish(&gpu)
        }
        Command::View(a) => crate::viewer::run(&cli.device, &a),
        Command::Check => {
            let gpu = open(&cli.device)?;
            let reports = crate::parity::run_all(&gpu)?;
            for r in &reports {
                println!("{r}");
            }
            finish(&gpu)?;
            println!("all {} parity checks passed on {}", reports.len(), gpu.ctx.info.name);
            Ok(())
        }
        Command::Devices => {
            let instance = vk::instance::Instance::new(false).context("creating a Vulkan instance")?;
            let list = vk::device::list(&instance.raw)?;
            if list.is_empty() {
                bail!(vk::VkError::NoDevices);
            }
            for (_, info, _, why) in list {
                match why {
                    None => println!("{}", info.line()),
                    Some(w) => println!("{} — unusable: lacks {w}", info.line()),
                }
            }
            Ok(())
        }
    }
}

/// Parses the command line. `--help` and `--version` print and exit 0; a malformed command line
/// is one `error:` line on stderr and exit status 2.
pub fn parse_or_exit() -> Cli {
    match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            let text = e.render().to_string();
            let kept: Vec<&str> = text.lines().filter(|l| !l.starts_with("Usage:") && !l.starts_with("For more information")).collect();
            let line = flatten_lines(&kept.join("\n"));
            eprintln!("error: {}", line.strip_prefix("error: ").unwrap_or(&line));
            std::process::exit(EXIT_BAD_INPUT.into());
        }
    }
}
