//! Host side of `tiled` and `tiled-2.5d` (kernels and algorithm: `shaders::tiled`): one dispatch
//! of one workgroup per screen tile that culls the lights into a tile-local list in workgroup
//! memory and shades the tile. No light-list buffer exists, so nothing can overflow: a tile with
//! more lights than the list holds is culled and shaded in several rounds on the GPU.
//!
//! Memory: one word per tile (its light count, for statistics and `--stats`).
use super::technique::{boxed, Description, FrameInputs, LightCost, LightingTechnique, ListStats, TransparentDraws};
use crate::gpu::Gpu;
use crate::vk::{Buffer, Recorder, VkResult};
use anyhow::{bail, Result};
use shaders::layout::{FrameParams, TiledParams};
use shaders::tile_cull::{MAX_TILED_TILE, MODE_TILED, MODE_TILED_25D};
use shaders::tiled::max_lights_llvmpipe;

pub const TILED: Description = Description {
    name: "tiled",
    summary: "Tiled deferred (Olsson & Assarsson 2011; Harada et al. 2012): per screen tile, depth bounds, frustum culling into a workgroup-memory list, shading in the same dispatch.",
    create: |gpu, f| boxed(Tiled::plain(gpu, f)),
    // The lists live in workgroup memory during one dispatch: nothing is left for a later pass.
    transparent: TransparentDraws::Refused,
    gbuffer: true,
    raster_passes: &[],
    cost: LightCost::Culled,
    max_tile: Some(MAX_TILED_TILE),
    llvmpipe_lights: max_lights_llvmpipe,
    knobs: &[],
    own_kernels: &[],
    own_raster: &[],
    msaa: true,
    light_words: 0,
    shadows: true,
};

pub const TILED_25D: Description = Description {
    name: "tiled-2.5d",
    summary: "`tiled` plus Harada's 2.5D culling: a 32-cell depth mask per tile against each light's.",
    create: |gpu, f| boxed(Tiled::depth_mask(gpu, f)),
    ..TILED
};

pub struct Tiled {
    params: TiledParams,
    /// Lights in each tile's list (all rounds).
    pub tile_lights: Buffer,
}

impl Tiled {
    /// `tiled`: per-tile depth bounds and frustum.
    pub fn plain(gpu: &Gpu, f: &FrameInputs<'_>) -> Result<Self> {
        Self::new(gpu, &f.params, false)
    }

    /// `tiled-2.5d`: plus Harada's 32-cell depth mask per tile.
    pub fn depth_mask(gpu: &Gpu, f: &FrameInputs<'_>) -> Result<Self> {
        Self::new(gpu, &f.params, true)
    }

    /// Checks the tile size and, on llvmpipe, the light count (its loop limiter), and allocates.
    fn new(gpu: &Gpu, frame: &FrameParams, depth_mask: bool) -> Result<Self> {
        let g = &frame.grid;
        if g.tile_size > MAX_TILED_TILE {
            bail!("--tile-size {}: the tiled techniques handle tiles up to {MAX_TILED_TILE} px (4 pixels per invocation of a 16x16 workgroup)", g.tile_size);
        }
        let max = max_lights_llvmpipe(g.tile_size);
        if gpu.ctx.info.is_llvmpipe() && frame.num_lights > max {
            bail!(
                "{} lights: on lavapipe (loop limiter: 65 535 iterations per invocation) a tiled frame with {} px tiles handles at most {max}",
                frame.num_lights,
                g.tile_size
            );
        }
        let tiles = g.tiles_x * g.tiles_y;
        Ok(Self {
            params: TiledParams { frame: *frame, mode: if depth_mask { MODE_TILED_25D } else { MODE_TILED }, _pad: [0; 3] },
            tile_lights: Buffer::storage(&gpu.ctx, "tile light counts", 4 * tiles as u64)?,
        })
    }

}

impl LightingTechnique for Tiled {
    fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, f: &FrameInputs<'_>) -> VkResult<()> {
        let grid = &self.params.frame.grid;
        let g = f.targets;
        let [slots, maps] = f.shadow_buffers();
        rec.pass("culling + shading", |rec| {
            rec.dispatch(
                super::shading_pipeline(&gpu.kernels.shade_tiled, &self.params.frame)?,
                &[&g.depth_buf, &g.normal_buf, &g.albedo_buf, f.lights, f.materials, f.frame, f.bounds, &self.tile_lights, slots, maps],
                &self.params,
                [grid.tiles_x, grid.tiles_y, 1],
            )
        })
    }

    /// Light references of the frame (the sum of the tiles' list lengths) and the longest list.
    fn stats(&mut self) -> Result<ListStats> {
        let g = &self.params.frame.grid;
        let counts: Vec<u32> = self.tile_lights.read((g.tiles_x * g.tiles_y) as usize)?;
        Ok(ListStats {
            light_refs: counts.iter().fold(0u32, |a, &c| a.saturating_add(c)),
            max_list: counts.iter().copied().max().unwrap_or(0),
            ..ListStats::default()
        })
    }

    fn buffers(&self) -> Vec<(String, u64)> {
        vec![(self.tile_lights.name.clone(), self.tile_lights.size)]
    }
}
