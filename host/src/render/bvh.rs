//! The light BVH of `clustered-bvh` (`shaders::light_bvh`): Morton keys of the view-space lights
//! → GPU sort, radix or bitonic (key = Morton code of `3·b` bits, `b` ≤ 10 bits per axis
//! ([`LightBvh::morton_bits`]); value = light index) → the lights' spheres gathered into sorted
//! order → node boxes built level by level, bottom-up, with
//! `branching` (32 or 64) children per node. Memory: 4 B keys + 4 B order + 16 B sphere per
//! light, sort scratch, ≈ 32/B B per light of nodes (32 B per B lights, plus the levels above).
use super::sort::{LightSorter, SortKind};
use crate::gpu::Gpu;
use crate::scene::lights::position_bounds;
use crate::vk::{Buffer, Recorder, VkResult};
use shaders::layout::{BvhParams, LightSphere, MortonParams, PointLight};
use shaders::light_bvh::{level_count, level_nodes, level_offset, total_nodes, valid_branching};
use shaders::morton::{MortonQuantizer, MORTON30_BITS, MORTON63_BITS};

pub struct LightBvh {
    pub n: u32,
    /// Children per node (32 or 64).
    pub branching: u32,
    keys: Buffer,
    pub order: Buffer,
    /// The lights' spheres in sorted order (what the leaves and the walks test).
    pub spheres: Buffer,
    pub nodes: Buffer,
    sort: LightSorter,
    quantizers: MortonParams,
    /// Bits per axis of the Morton keys (`--morton-bits`): the radix sort orders `3·b` bits, a
    /// pass per 8 of them (24 bits: three passes, 30: four).
    pub morton_bits: u32,
}

/// Bits per axis of the lights' Morton keys unless `--morton-bits` says otherwise.
pub const DEFAULT_MORTON_BITS: u32 = MORTON30_BITS;

/// The bits per axis a `--morton-bits` setting asks (0: [`DEFAULT_MORTON_BITS`]).
pub fn morton_bits(setting: u32) -> u32 {
    if setting == 0 {
        DEFAULT_MORTON_BITS
    } else {
        setting
    }
}

/// Checks `--morton-bits`.
pub fn check_morton_bits(bits: u32) -> anyhow::Result<()> {
    if !(1..=MORTON30_BITS).contains(&bits) {
        anyhow::bail!("--morton-bits {bits}: bits per axis of the lights' Morton keys must be in 1..={MORTON30_BITS}");
    }
    Ok(())
}

impl LightBvh {
    /// The default branching for a device: 64 where subgroups are 32 or more lanes wide (the
    /// H200, subgroup 32, Sponza 1080p: assignment 0.260 against 0.282 ms at 10k lights, 0.567
    /// against 0.630 ms at 1M; shading unchanged), 32 on narrower ones (lavapipe's 8 lanes: the
    /// shallower tree costs 8 ballots per node instead of 4).
    pub fn default_branching(subgroup_size: u32) -> u32 {
        if subgroup_size >= 32 { 64 } else { 32 }
    }

    /// Buffers for `lights` (view space: the quantiser spans their positions) and a tree of
    /// `branching` (32 or 64) children per node, lights ordered by the `sort` kind of sort on
    /// Morton keys of `morton_bits` bits per axis (1..=10).
    pub fn new(gpu: &Gpu, lights: &[PointLight], branching: u32, sort: SortKind, morton_bits: u32) -> VkResult<Self> {
        assert!(valid_branching(branching), "BVH branching {branching}: 32 or 64 (checked by the caller)");
        assert!((1..=MORTON30_BITS).contains(&morton_bits), "Morton bits {morton_bits} (checked by the caller)");
        let n = lights.len() as u32;
        let (lo, hi) = position_bounds(lights);
        let nodes = total_nodes(n.max(1), branching);
        let ctx = &gpu.ctx;
        Ok(Self {
            n,
            branching,
            keys: Buffer::storage(ctx, "light Morton keys", 4 * n as u64)?,
            order: Buffer::storage(ctx, "light order", 4 * n as u64)?,
            spheres: Buffer::length_free(ctx, "sorted light spheres", 16 * n.max(1) as u64)?,
            nodes: Buffer::storage(ctx, "light BVH nodes", 32 * nodes as u64)?,
            sort: LightSorter::new(gpu, sort, n.max(1))?,
            quantizers: quantizers(lo, hi, n, morton_bits),
            morton_bits,
        })
    }

    /// The same lights moved (a new camera, the animation): the Morton quantiser spans their
    /// new view-space positions.
    pub fn requantize(&mut self, lights: &[PointLight]) {
        let (lo, hi) = position_bounds(lights);
        self.quantizers = quantizers(lo, hi, self.n, self.morton_bits);
    }

    pub fn bytes(&self) -> u64 {
        self.keys.size + self.order.size + self.spheres.size + self.nodes.size + self.sort.bytes()
    }

    /// Records the Morton keys ("morton keys"), their sort ("light sort") and the level-by-level
    /// build ("bvh build").
    /// `effects`: the frame's, whose light-type bits say how `lights` stores them (full or compact
    /// records).
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, lights: &Buffer, effects: u32) -> VkResult<()> {
        let k = &gpu.kernels;
        let n = self.n;
        if n == 0 {
            return Ok(());
        }
        rec.pass("morton keys", |rec| rec.dispatch_linear(k.light_keys.get(effects)?, &[lights, &self.keys, &self.order], &self.quantizers, n))?;
        rec.pass("light sort", |rec| self.sort.record(gpu, rec, &self.keys, &self.order, n, 3 * self.morton_bits))?;
        rec.pass("bvh build", |rec| {
            let b = self.branching;
            let leaves = level_nodes(n, 0, b);
            let p = BvhParams { count: n, level: 0, nodes: leaves, branching: b };
            rec.dispatch_linear(k.bvh_spheres.get(effects)?, &[lights, &self.order, &self.spheres], &p, n)?;
            rec.dispatch_subgroups(&k.bvh_leaves, &[&self.spheres, &self.nodes], &p, leaves)?;
            for level in 1..level_count(n, b) {
                let nodes = level_nodes(n, level, b);
                let p = BvhParams { count: n, level, nodes, branching: b };
                debug_assert!(level_offset(n, level, b) > 0);
                rec.dispatch_linear(&k.bvh_level, &[&self.nodes], &p, nodes)?;
            }
            Ok(())
        })
    }
}

/// The key kernel's quantisers for lights within `lo..=hi`, `bits` per axis of the 30-bit code:
/// the kernel quantises into 2^10 cells per axis, so for fewer bits the scale `2^bits / extent`
/// shrinks by 2^−20 (far above the rounding of `(p − min) · scale`), which keeps every cell
/// below 2^bits and the key below 2^(3·bits).
fn quantizers(lo: [f32; 3], hi: [f32; 3], count: u32, bits: u32) -> MortonParams {
    let mut q30 = MortonQuantizer::new(lo, hi, bits);
    if bits < MORTON30_BITS {
        q30.scale = q30.scale.map(|s| s * (1.0 - 1.0 / (1 << 20) as f32));
    }
    MortonParams { q30, q63: MortonQuantizer::new(lo, hi, MORTON63_BITS), count, _pad: [0; 3] }
}

/// The same BVH on the CPU, from the kernels' own functions run one after the other: Morton keys
/// of `lights` (view space) → `sort_unstable_by_key` → leaf and inner node boxes. Returns the
/// sorted order, the sorted spheres and the nodes (the CPU baseline of benches/bvh.rs, and a test
/// oracle).
pub fn build_cpu(lights: &[PointLight], branching: u32) -> (Vec<u32>, Vec<LightSphere>, Vec<shaders::layout::ClusterAabb>) {
    use shaders::light_bvh::{inner_node_box, leaf_node_box, sorted_spheres, EMPTY_BOX};
    let n = lights.len() as u32;
    let (lo, hi) = position_bounds(lights);
    let q = MortonQuantizer::new(lo, hi, MORTON30_BITS);
    let mut keyed: Vec<(u32, u32)> = lights.iter().enumerate().map(|(i, l)| (q.morton30_of(l.position), i as u32)).collect();
    keyed.sort_unstable_by_key(|e| e.0);
    let order: Vec<u32> = keyed.into_iter().map(|e| e.1).collect();
    let spheres = sorted_spheres(lights, &order);
    let mut nodes = vec![EMPTY_BOX; total_nodes(n.max(1), branching) as usize];
    if n == 0 {
        return (order, spheres, nodes);
    }
    for node in 0..level_nodes(n, 0, branching) {
        nodes[node as usize] = leaf_node_box(&spheres, n, branching, node);
    }
    for level in 1..level_count(n, branching) {
        for node in 0..level_nodes(n, level, branching) {
            let b = inner_node_box(&nodes, n, branching, level, node);
            nodes[(level_offset(n, level, branching) + node) as usize] = b;
        }
    }
    (order, spheres, nodes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With `b` bits per axis every light's key (the key kernel's own function) stays below
    /// `2^(3b)`, the corners of the box included, and the 24-bit keys keep the 30-bit keys' order
    /// but for points within a rounding of a cell's boundary (the scales differ by 2^−20).
    #[test]
    fn keys_of_fewer_bits_stay_below_their_width_and_keep_the_order() {
        let mut x = 0x2545_f491u32;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as f32 / u32::MAX as f32
        };
        let (lo, hi) = ([-3.0, 0.5, -40.0], [7.0, 0.5 + 1e-3, -0.1]);
        let mut points: Vec<[f32; 3]> = (0..20_000).map(|_| std::array::from_fn(|a| lo[a] + (hi[a] - lo[a]) * next())).collect();
        points.extend([lo, hi, [hi[0], lo[1], hi[2]]]);
        for bits in 1..=MORTON30_BITS {
            let q = quantizers(lo, hi, 1, bits).q30;
            for p in &points {
                let key = q.morton30_of(*p);
                assert!(key < 1 << (3 * bits), "{bits} bits: {p:?} has key {key:#x}");
            }
        }
        let (q8, q10) = (quantizers(lo, hi, 1, 8).q30, quantizers(lo, hi, 1, 10).q30);
        let mut by_fine: Vec<&[f32; 3]> = points.iter().collect();
        by_fine.sort_by_key(|p| q10.morton30_of(**p));
        assert!(by_fine.windows(2).filter(|w| q8.morton30_of(*w[0]) > q8.morton30_of(*w[1])).count() < points.len() / 100, "the 24-bit keys mostly follow the 30-bit order");
    }
}
