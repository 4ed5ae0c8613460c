//! Command-line interface (clap). Progress and errors go to stderr; results to files/stdout.
use crate::debug_frame::{self, DebugView, FrameSpec, Precision};
use crate::gpu::Gpu;
use crate::vk::{self, ContextOptions};
use anyhow::{bail, Context as _, Result};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

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
    #[arg(long, global = true, env = "MANYLIGHTS_VALIDATION")]
    pub validation: bool,
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
}

/// Size, cluster tile and output file of a frame (shared by `render` and `debug-frame`).
#[derive(Args, Debug, Clone)]
pub struct FrameArgs {
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Cluster tile edge in pixels.
    #[arg(long, default_value_t = 32)]
    pub tile_size: u32,
    /// Output PNG.
    #[arg(long, default_value = "frame.png")]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct DebugFrameArgs {
    /// What to show.
    #[arg(long, value_enum, default_value_t = DebugView::Clusters)]
    pub view: DebugView,
    /// Normal-encoding precision used by the normals / octa-error views.
    #[arg(long, value_enum, default_value_t = Precision::Oct8)]
    pub precision: Precision,
    #[command(flatten)]
    pub frame: FrameArgs,
}

fn open(dev: &DeviceArgs) -> Result<Gpu> {
    let gpu = Gpu::new(&ContextOptions { validation: dev.validation, device: dev.device.clone() })
        .context("opening the Vulkan device")?;
    eprintln!("device: {}", gpu.ctx.info.line());
    Ok(gpu)
}

/// Fails when validation reported anything.
fn finish(gpu: &Gpu) -> Result<()> {
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
