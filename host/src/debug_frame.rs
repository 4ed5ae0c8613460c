//! Debug frames of the analytic scene (`shaders::debug_view`): GPU render and CPU reference.
use crate::gpu::Gpu;
use crate::vk::{Buffer, PassTiming, Profiler};
use crate::args::view_name;
use anyhow::{bail, Context as _, Result};
use shaders::cluster_key::{slice_bounds, ClusterGrid};
use shaders::debug_view::shade_pixel;
use shaders::layout::{DebugViewParams, View};
use shaders::octahedral::Precision;

/// Camera and grid of a debug frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameSpec {
    pub width: u32,
    pub height: u32,
    pub tile_size: u32,
    pub near: f32,
    pub far: f32,
    pub fov_y_degrees: f32,
    /// One of [`View::DEBUG`].
    pub view: View,
    pub precision: Precision,
}

impl FrameSpec {
    pub fn params(&self) -> Result<(DebugViewParams, Vec<f32>)> {
        if !View::DEBUG.contains(&self.view) {
            bail!("view {} is not a view of the debug frame ({})", view_name(self.view), View::DEBUG.map(view_name).join(", "));
        }
        let grid = ClusterGrid::new(self.width, self.height, self.tile_size, self.near, self.far, self.fov_y_degrees.to_radians())
            .context("cluster grid")?;
        let bounds = slice_bounds(&grid);
        let params = DebugViewParams { grid, view: self.view.code(), precision: self.precision.code(), _pad: [0; 2] };
        Ok((params, bounds))
    }
}

/// Renders the frame on the GPU; returns RGBA8 pixels (row-major, top row first) and timings.
pub fn render_gpu(gpu: &Gpu, spec: &FrameSpec) -> Result<(Vec<u32>, Vec<PassTiming>)> {
    let (params, bounds) = spec.params()?;
    let n = spec.width as u64 * spec.height as u64;
    let ctx = &gpu.ctx;
    let bounds_buf = Buffer::from_slice(ctx, "slice bounds", &bounds)?;
    let mut pixels = Buffer::storage(ctx, "debug frame", n * 4).context("allocating the frame")?;
    let mut profiler = Profiler::new(ctx, 4)?;
    gpu.run(Some(&mut profiler), |rec| {
        rec.pass("debug view", |rec| {
            rec.dispatch_threads(&gpu.kernels.debug_view, &[&bounds_buf, &pixels], &params, [spec.width, spec.height, 1])
        })
    })?;
    let timings = profiler.results()?;
    Ok((pixels.read(n as usize)?, timings))
}

/// The same frame computed on the CPU with the same functions (reference for tests).
pub fn render_cpu(spec: &FrameSpec) -> Result<Vec<u32>> {
    let (params, bounds) = spec.params()?;
    Ok((0..spec.height)
        .flat_map(|y| (0..spec.width).map(move |x| (x, y)))
        .map(|(x, y)| shade_pixel(&params, &bounds, x, y))
        .collect())
}

/// Writes RGBA8 pixels as a PNG.
pub fn save_png(path: &std::path::Path, width: u32, height: u32, pixels: &[u32]) -> Result<()> {
    let bytes: Vec<u8> = bytemuck::cast_slice(pixels).to_vec();
    let img = image::RgbaImage::from_raw(width, height, bytes).context("frame size mismatch")?;
    img.save(path).with_context(|| format!("writing {}", path.display()))
}
