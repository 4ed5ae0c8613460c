//! The light BVH of `clustered-bvh` (`shaders::light_bvh`): Morton keys of the view-space lights
//! → GPU sort, radix or bitonic (key = 30-bit Morton code, value = light index) → the lights'
//! spheres gathered into sorted order → node boxes built level by level, bottom-up, with
//! `branching` (32 or 64) children per node. Memory: 4 B keys + 4 B order + 16 B sphere per
//! light, sort scratch, ≈ 32/B B per light of nodes (32 B per B lights, plus the levels above).
use super::sort::{LightSorter, SortKind};
use crate::gpu::Gpu;
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
    /// `branching` (32 or 64) children per node, lights ordered by the `sort` kind of sort.
    pub fn new(gpu: &Gpu, lights: &[PointLight], branching: u32, sort: SortKind) -> VkResult<Self> {
        assert!(valid_branching(branching), "BVH branching {branching}: 32 or 64 (checked by the caller)");
        let n = lights.len() as u32;
        let (lo, hi) = position_bounds(lights);
        let nodes = total_nodes(n.max(1), branching);
        let ctx = &gpu.ctx;
        Ok(Self {
            n,
            branching,
            keys: Buffer::storage(ctx, "light Morton keys", 4 * n as u64)?,
            order: Buffer::storage(ctx, "light order", 4 * n as u64)?,
            spheres: Buffer::storage(ctx, "sorted light spheres", 16 * n.max(1) as u64)?,
            nodes: Buffer::storage(ctx, "light BVH nodes", 32 * nodes as u64)?,
            sort: LightSorter::new(gpu, sort, n.max(1))?,
            quantizers: quantizers(lo, hi, n),
        })
    }

    /// The same lights moved (a new camera, the animation): the Morton quantiser spans their
    /// new view-space positions.
    pub fn requantize(&mut self, lights: &[PointLight]) {
        let (lo, hi) = position_bounds(lights);
        self.quantizers = quantizers(lo, hi, self.n);
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
        rec.pass("light sort", |rec| self.sort.record(gpu, rec, &self.keys, &self.order, n, 3 * MORTON30_BITS))?;
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

/// Bounds of the lights' positions, which the Morton quantiser spans (the unit box for none).
fn quantizers(lo: [f32; 3], hi: [f32; 3], count: u32) -> MortonParams {
    MortonParams { q30: MortonQuantizer::new(lo, hi, MORTON30_BITS), q63: MortonQuantizer::new(lo, hi, MORTON63_BITS), count, _pad: [0; 3] }
}

fn position_bounds(lights: &[PointLight]) -> ([f32; 3], [f32; 3]) {
    if lights.is_empty() {
        return ([0.0; 3], [1.0; 3]);
    }
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for l in lights {
        for a in 0..3 {
            lo[a] = lo[a].min(l.position[a]);
            hi[a] = hi[a].max(l.position[a]);
        }
    }
    (lo, hi)
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
