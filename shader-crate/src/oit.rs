//! Order-independent transparency: per-pixel linked lists of transparent fragments (Yang,
//! Hensley, Grün, Thibieroz 2010, "Real-Time Concurrent Linked List Construction on the GPU",
//! Computer Graphics Forum 29(4), EGSR) resolved exactly, or keeping the `k` nearest sorted, and
//! weighted blended OIT (McGuire & Bavoil 2013, "Weighted Blended Order-Independent
//! Transparency", JCGT 2(2)). Pure functions: the passes' entry points and the CPU tests share them.
//!
//! # Steps
//!
//! 1. **Clear**: every head ← [`OIT_END`] (one per pixel), the node counter ← 0.
//! 2. **Opaque passes** as usual: the opaque colour and the depth buffer.
//! 3. **Transparent pass** (raster; depth test against the opaque depth, no depth writes): each
//!    fragment is shaded over the light lists and tonemapped, then builds a node (Yang et al.:
//!    a global counter allocates it, an exchange links it):
//!    ```text
//!    index = atomicAdd(counter, 1)                          every fragment, once
//!    old   = node_fits(index, capacity) ? atomicExchange(heads[pixel], index) : OIT_END
//!    n     = insert_node(old, index, capacity, rgb, α, z_buf, primitive)
//!    if !n.overflow { nodes[index] = n.node }
//!    ```
//!    A fragment that does not fit leaves the head alone, so every list holds only stored nodes.
//! 4. **Host**: the counter is the exact number of fragments the frame wanted; past the capacity
//!    ([`overflowed`]) the host grows the node buffer to at least the counter and re-runs the frame —
//!    never a silent drop.
//! 5. **Resolve** (one invocation per pixel): [`resolve`] walks the pixel's list through a
//!    node-reading closure and returns the composite (linear, display-referred) to encode.
//!
//! `OIT_WEIGHTED` needs no lists: its transparent pass blends [`weighted_fragment`] into two
//! targets and [`weighted_resolve`] composites them; [`resolve`] also computes it from a list.
//!
//! # Blend algebra (premultiplied colour `C = c·α`; "over" of Porter & Duff 1984, "Compositing
//! Digital Images", SIGGRAPH)
//!
//! ```text
//!   over:       D' = C + (1 − α)·D
//!   exact:      layers sorted far → near, L_1 … L_n, over the opaque colour B:
//!               D_0 = B,  D_i = C_i + (1 − α_i)·D_(i−1)
//!               D_n = Σ_i C_i·Π_(j>i)(1 − α_j) + B·Π_j(1 − α_j)
//!   k nearest:  tail T = the layers that are not among the k nearest, blended behind them
//!               order-independently by McGuire & Bavoil's §3.3, eq. (5) (weights 1): a sorted
//!               core over an approximated tail, as in Maule et al. 2013, "Hybrid Transparency",
//!               I3D:
//!               S = Σ_T C_i,  A = Σ_T α_i,  R = Π_T (1 − α_i)
//!               D_tail = (S/A)·(1 − R) + R·B      (D_tail = B for an empty tail)
//!               then the k nearest over D_tail, far → near, as exact.
//!   weighted:   accumulation (RGBA, blend ONE, ONE):   (Σ C_i·w_i, Σ α_i·w_i)
//!               revealage (R, cleared to 1, blend ZERO, ONE_MINUS_SRC_COLOR, output α_i):
//!                                                      R = Π (1 − α_i)
//!               D = (Σ C_i·w_i / max(Σ α_i·w_i, 10⁻⁵))·(1 − R) + R·B      (§3.3's eq. (5)
//!               with the depth weights of §3.4); weight eq. (7), z the view depth:
//!               w(z, α) = α · clamp(10 / (10⁻⁵ + (|z|/5)² + (|z|/200)⁶), 10⁻², 3·10³)
//! ```
//! The tail is exact in its transmittance `R` (a product commutes) and in its colour for one
//! fragment or fragments of one colour; only the mix of different colours behind the k nearest is
//! approximated, and it never depends on the list order (up to f32 rounding: the sums are taken
//! in list order). As `C_i ≤ α_i` per channel (below), `S/A ≤ 1` and every `D` stays in [0, 1].
//!
//! # Why premultiplied
//!
//! Over, the tail sums and the weighted sums all take `C = c·α`, so a node stores what they read.
//! Quantised to `q` steps, a layer's contribution `C` is off by at most ½/q and `α` by ½/q
//! whatever `α`; straight colour quantises `c` and `α` separately and their product by up to
//! `(c + α)·½/q`. `round` is monotone, so `c ≤ 1` gives stored `C ≤ α` in every channel. The
//! colour is the tonemapped linear colour (before the sRGB encoding): a fixed-point channel cannot
//! hold radiance, so the layers are blended after tonemapping, as the opaque colour `B` is.
//!
//! # Why 16 bits
//!
//! The composite is encoded to sRGB after blending, and sRGB's slope near black is 12.92: a
//! linear error `e` becomes up to `12.92·e` of the output. With 8 bits (`q = 255`) one pane of
//! α = ½ over a dark wall was 3/255 off the closed-form composite, and fifty coincident panes of
//! α = 0.1 38/255: every layer's `C` and `α` round the same way, so the bias adds up layer after
//! layer (α = 0.1 is stored as 26/255 = 0.102 in each). With 16 bits (`q = 65 535`) a layer's
//! error is at most ½/65 535 = 7.6·10⁻⁶ per channel and in α, 256 times smaller; the
//! composite's error is `Σ_i (|ΔC_i| + |Δα_i|·|D_(i−1)|)·Π_(j>i)(1 − α_j)`, each layer's share
//! shrinking with the transmittance in front of it. `oit_tests` checks the closed forms (one
//! pane of α = ½, 50 and 256 coincident panes of α = 0.1, coplanar panes of different colours,
//! over backgrounds from black to white) within 1/255 after the sRGB encoding. Cost: 20 B per
//! fragment instead of 16.
//!
//! # Order: a strict total order on layers ([`nearer`])
//!
//! By depth (`z_buf` bits: larger = nearer), then the primitive id (larger = nearer: among
//! coplanar fragments the later primitive is on top, as blending in primitive order would give;
//! the id is frame-unique: the draw's first primitive in the frame plus `PrimitiveId`, so two
//! fragments of one pixel share it only if they are one fragment drawn twice),
//! then the colour word, then the node index. Fragments equal in depth, id and colour are
//! identical in everything the composite reads; the node index — the only thing that depends on
//! the insertion order — only permutes those. The exact resolve is therefore bit-identical for
//! every insertion order.
//!
//! # Exact resolve, cost and bound
//!
//! Selection passes, [`MAX_K`] layers each: a pass walks the whole list and keeps, by insertion
//! sort into a register array, the `MAX_K` farthest layers nearer than the last one composited
//! (strictly, in the total order), then composites them. One walk counts the `L` layers first;
//! `⌈L/MAX_K⌉` passes follow: `L + L·⌈L/8⌉` node loads, O(L²). [`MAX_EXACT_LAYERS`] `= 256`
//! bounds that at 8 448 loads and 8 736 loop iterations (llvmpipe ends an invocation's loops
//! after 65 535). A deeper pixel falls back to the k-nearest resolve with `k = MAX_K` and says
//! so ([`Resolved::fallback`]): the resolve pass counts such pixels and the host reports the
//! count (a warning, and in the frame's statistics); the tests require none.
//!
//! # Memory
//!
//! Lists: 4 B per pixel (heads), 20 B per transparent fragment ([`OitNode`]), one 4 B counter;
//! the resolve holds `MAX_K` layers of 20 B and the tail's 24 B in registers. Weighted: 8 B
//! (RGBA16F, the paper's format) + 1 B (R8) per pixel, nothing per fragment; with RGBA16F more
//! than 21 layers at the largest weight overflow (the resolve then takes the average as 0).
//!
//! # Bad input
//!
//! Colour channels and α: NaN → 0, below 0 (−∞ too) → 0, above 1 (+∞ too) → 1, tested on the
//! bits as `lighting::encode_srgb8` does. Depth: NaN and ≤ 0 → 0 (farthest), ≥ 1 and +∞ → 1.
//! View depth of a weight: NaN, ∞ and past [`WEIGHT_MAX_DEPTH`] → that depth (the smallest
//! weight). Opaque colour: as a colour. Nodes are read as bits: any 20 bytes give a finite
//! colour, a walk ends after `capacity` nodes (cycles), every result is in [0, 1].
pub use crate::layout::OIT_END;
use crate::layout::{OitNode, OitParams, OIT_EXACT, OIT_WEIGHTED};
use glam::{Vec3, Vec4};

/// Layers the register array holds: the largest `k` of `OIT_K_NEAREST`, and the layers an exact
/// selection pass composites.
pub const MAX_K: u32 = 8;
/// Most layers the exact resolve sorts (module docs, "Exact resolve, cost and bound").
pub const MAX_EXACT_LAYERS: u32 = 256;
/// Smallest accumulated `Σ α·w` the weighted resolve divides by (McGuire & Bavoil's listing).
pub const WEIGHTED_MIN_ALPHA: f32 = 1e-5;
/// View depths [`weight_eq7`] evaluates are clamped to this (the weight is at its floor there).
pub const WEIGHT_MAX_DEPTH: f32 = 1e4;

/// `x` clamped to [0, 1], NaN → 0 (on the bits: a compiler assuming no NaN cannot drop the test).
#[inline]
pub fn saturate(x: f32) -> f32 {
    if (x.to_bits() & 0x7fff_ffff) > 0x7f80_0000 {
        return 0.0;
    }
    if x > 0.0 {
        if x < 1.0 {
            x
        } else {
            1.0
        }
    } else {
        0.0
    }
}

/// [`saturate`] per channel.
#[inline]
pub fn saturate3(v: Vec3) -> Vec3 {
    Vec3::new(saturate(v.x), saturate(v.y), saturate(v.z))
}

/// A node colour: premultiplied RGBA, 16-bit UNORM each, `[r | g << 16, b | a << 16]`.
pub type NodeColour = [u32; 2];

/// Two `packUnorm2x16`: each channel `round(clamp(v, 0, 1)·65535)` (halves up; NaN → 0).
#[inline]
pub fn pack_unorm4x16(v: Vec4) -> NodeColour {
    [unorm16(v.x) | (unorm16(v.y) << 16), unorm16(v.z) | (unorm16(v.w) << 16)]
}

/// `round(saturate(x)·65535)` without `round`: `t − trunc(t)` is exact for `t` in [0, 65535].
#[inline]
fn unorm16(x: f32) -> u32 {
    let t = saturate(x) * 65535.0;
    let q = t as u32;
    q + (t - q as f32 >= 0.5) as u32
}

/// The inverse of [`pack_unorm4x16`]: `u / 65535` per channel.
#[inline]
pub fn unpack_unorm4x16(w: NodeColour) -> Vec4 {
    let c = |word: u32, s: u32| ((word >> s) & 0xffff) as f32 / 65535.0;
    Vec4::new(c(w[0], 0), c(w[0], 16), c(w[1], 0), c(w[1], 16))
}

/// The node colour of straight colour `rgb` with coverage `alpha`: `(rgb·α, α)` packed, both
/// saturated first (so every stored channel is at most the stored α).
#[inline]
pub fn premultiplied_rgba16(rgb: Vec3, alpha: f32) -> NodeColour {
    let a = saturate(alpha);
    pack_unorm4x16((saturate3(rgb) * a).extend(a))
}

/// The reversed-Z depth a node stores: `z_buf` clamped to [0, 1], NaN → 0 (farthest).
#[inline]
pub fn node_depth(z_buf: f32) -> u32 {
    saturate(z_buf).to_bits()
}

/// Whether the node the counter gave (`node_index`) has a slot: only then does the fragment
/// exchange the head.
#[inline]
pub fn node_fits(node_index: u32, capacity: u32) -> bool {
    node_index < capacity
}

/// Whether a frame's fragments overflowed the node buffer: the counter ends at the number of
/// fragments the frame wanted, the size to grow to.
#[inline]
pub fn overflowed(counter: u32, capacity: u32) -> bool {
    counter > capacity
}

/// What [`insert_node`] gives a fragment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inserted {
    /// The node to store at `node_index`.
    pub node: OitNode,
    /// `node_index` is past the capacity: store nothing (the head was not exchanged).
    pub overflow: bool,
}

/// The node a fragment stores (module docs, step 3): `node_index` from the counter,
/// `head_word_old` from the exchange of its pixel's head (`OIT_END` when the node does not fit),
/// straight colour `rgb` with coverage `alpha`, reversed-Z depth `z_buf` and the primitive's
/// frame-unique id. Inputs are sanitised (module docs, "Bad input").
#[inline]
pub fn insert_node(head_word_old: u32, node_index: u32, capacity: u32, rgb: Vec3, alpha: f32, z_buf: f32, primitive: u32) -> Inserted {
    let fits = node_fits(node_index, capacity);
    let next = if fits { head_word_old } else { OIT_END };
    Inserted { node: OitNode { colour: premultiplied_rgba16(rgb, alpha), depth: node_depth(z_buf), next, tie: primitive }, overflow: !fits }
}

/// A node as the resolve orders and composites it: its contents and its index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Layer {
    pub depth: u32,
    pub tie: u32,
    pub colour: NodeColour,
    pub index: u32,
}

impl Layer {
    #[inline]
    pub fn of(index: u32, n: OitNode) -> Self {
        Self { depth: n.depth, tie: n.tie, colour: n.colour, index }
    }
}

/// The strict total order of the resolve (module docs, "Order"): `x` is composited on top of `y`.
#[inline]
pub fn nearer(x: Layer, y: Layer) -> bool {
    if x.depth != y.depth {
        return x.depth > y.depth;
    }
    if x.tie != y.tie {
        return x.tie > y.tie;
    }
    if x.colour[1] != y.colour[1] {
        return x.colour[1] > y.colour[1];
    }
    if x.colour[0] != y.colour[0] {
        return x.colour[0] > y.colour[0];
    }
    x.index > y.index
}

/// Porter & Duff's over: `C + (1 − α)·D` of a premultiplied node colour over `d`.
#[inline]
pub fn over(colour: NodeColour, d: Vec3) -> Vec3 {
    let c = unpack_unorm4x16(colour);
    c.truncate() + d * (1.0 - c.w)
}

/// What a list walk does with each node ([`walk`]).
pub trait Visit {
    fn visit(&mut self, index: u32, node: OitNode);
}

/// Visits the list from `head` (node `i` read as `node_at(i)`) in list order; ends at an index
/// `≥ capacity` ([`OIT_END`] among them) or after `capacity` nodes (a cycle). Returns the count.
#[inline]
pub fn walk<F: Fn(u32) -> OitNode, V: Visit>(head: u32, capacity: u32, node_at: &F, v: &mut V) -> u32 {
    let mut i = head;
    let mut count = 0;
    while i < capacity && count < capacity {
        let node = node_at(i);
        v.visit(i, node);
        i = node.next;
        count += 1;
    }
    count
}

/// A visitor that only lets [`walk`] count.
pub struct Count;

impl Visit for Count {
    #[inline]
    fn visit(&mut self, _: u32, _: OitNode) {}
}

/// Layers kept sorted in registers: `a[0..n]`, first the layer kept longest (the nearest with
/// `NEAR_FIRST`, else the farthest), at most `k ≤ MAX_K`.
#[derive(Clone, Copy)]
pub struct Kept<const NEAR_FIRST: bool> {
    pub a: [Layer; MAX_K as usize],
    pub n: u32,
    pub k: u32,
}

impl<const NEAR_FIRST: bool> Kept<NEAR_FIRST> {
    /// An empty array that keeps `k` layers (clamped to 1..=MAX_K).
    #[inline]
    pub fn new(k: u32) -> Self {
        let k = if k < 1 {
            1
        } else if k > MAX_K {
            MAX_K
        } else {
            k
        };
        Self { a: [Layer::default(); MAX_K as usize], n: 0, k }
    }

    /// `x` before `y` in the array's order.
    #[inline]
    fn before(x: Layer, y: Layer) -> bool {
        if NEAR_FIRST {
            nearer(x, y)
        } else {
            nearer(y, x)
        }
    }

    /// Insertion sort of `x` (straight-line: no loop iterations per layer); when the array was
    /// full, returns `(true, the layer that no longer fits)`: its last one, or `x` itself.
    #[inline]
    pub fn keep(&mut self, x: Layer) -> (bool, Layer) {
        let k = self.k;
        let full = self.n >= k;
        if full && !Self::before(x, self.a[(k - 1) as usize]) {
            return (true, x);
        }
        let evicted = (full, self.a[(k - 1) as usize]);
        let len = if full { k } else { self.n + 1 };
        let mut placed = false;
        unroll8!(u => {
            let j = MAX_K - 1 - u;
            if j > 0 && j < len && !placed {
                let prev = self.a[(j - 1) as usize];
                if Self::before(x, prev) {
                    self.a[j as usize] = prev;
                } else {
                    self.a[j as usize] = x;
                    placed = true;
                }
            }
        });
        if !placed {
            self.a[0] = x;
        }
        self.n = len;
        evicted
    }
}

/// The tail of the k-nearest resolve: `S = Σ C`, `A = Σ α`, `R = Π (1 − α)` (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tail {
    pub sum: Vec3,
    pub alpha: f32,
    pub transmit: f32,
    pub count: u32,
}

impl Tail {
    pub const EMPTY: Tail = Tail { sum: Vec3::ZERO, alpha: 0.0, transmit: 1.0, count: 0 };

    #[inline]
    pub fn add(&mut self, colour: NodeColour) {
        let c = unpack_unorm4x16(colour);
        self.sum += c.truncate();
        self.alpha += c.w;
        self.transmit *= 1.0 - c.w;
        self.count += 1;
    }

    /// `D_tail = (S/A)·(1 − R) + R·B`; `B` itself for an empty tail (or one of zero coverage).
    #[inline]
    pub fn over(&self, b: Vec3) -> Vec3 {
        if self.count == 0 || !(self.alpha > 0.0) {
            return b;
        }
        self.sum * ((1.0 - self.transmit) / self.alpha) + b * self.transmit
    }
}

/// Walk of the k-nearest resolve: the `k` nearest in registers, every other layer in the tail.
pub struct Nearest {
    pub kept: Kept<true>,
    pub tail: Tail,
}

impl Visit for Nearest {
    #[inline]
    fn visit(&mut self, index: u32, node: OitNode) {
        let (evicted, e) = self.kept.keep(Layer::of(index, node));
        if evicted {
            self.tail.add(e.colour);
        }
    }
}

/// Walk of an exact selection pass: the `MAX_K` farthest layers nearer than `after` (all layers
/// in the first pass, `bounded = false`).
pub struct Farthest {
    pub kept: Kept<false>,
    pub after: Layer,
    pub bounded: bool,
}

impl Visit for Farthest {
    #[inline]
    fn visit(&mut self, index: u32, node: OitNode) {
        let x = Layer::of(index, node);
        if !self.bounded || nearer(x, self.after) {
            self.kept.keep(x);
        }
    }
}

/// Walk of the weighted variant over a list: the two targets' sums ([`weighted_fragment`]).
pub struct Weighted {
    pub near: f32,
    pub accum: Vec4,
    pub revealage: f32,
}

impl Visit for Weighted {
    #[inline]
    fn visit(&mut self, _: u32, node: OitNode) {
        let c = unpack_unorm4x16(node.colour);
        let z = f32::from_bits(node.depth);
        let view_depth = if z > self.near * (1.0 / WEIGHT_MAX_DEPTH) { self.near / z } else { WEIGHT_MAX_DEPTH };
        self.accum += c * weight_eq7(view_depth, c.w);
        self.revealage *= 1.0 - c.w;
    }
}

/// The colour of a pixel and what its resolve did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    /// Linear display-referred colour in [0, 1] (the sRGB encoding follows).
    pub rgb: Vec3,
    /// Nodes in the pixel's list.
    pub layers: u32,
    /// `OIT_EXACT` with more than [`MAX_EXACT_LAYERS`] layers: resolved as k-nearest, `k = MAX_K`.
    pub fallback: bool,
}

/// The composite of the pixel whose list starts at `head` over the opaque colour `opaque`
/// (linear, tonemapped, saturated here), by `p.variant` (module docs; a value other than the
/// three `OIT_*` resolves as `OIT_K_NEAREST`); node `i` is `node_at(i)`. Walks the list once to
/// count it, then as the variant needs.
#[inline]
pub fn resolve<F: Fn(u32) -> OitNode>(p: &OitParams, head: u32, opaque: Vec3, node_at: &F) -> Resolved {
    let b = saturate3(opaque);
    let layers = walk(head, p.capacity, node_at, &mut Count);
    let (rgb, fallback) = if p.variant == OIT_WEIGHTED {
        (resolve_weighted(p, head, b, node_at), false)
    } else if p.variant == OIT_EXACT && layers <= MAX_EXACT_LAYERS {
        (resolve_exact(p.capacity, head, layers, b, node_at), false)
    } else {
        let k = if p.variant == OIT_EXACT { MAX_K } else { p.k };
        (resolve_k_nearest(p.capacity, head, k, b, node_at), p.variant == OIT_EXACT)
    };
    Resolved { rgb: saturate3(rgb), layers, fallback }
}

/// Every one of the `layers` layers far → near over `b`: `⌈layers / MAX_K⌉` selection passes.
#[inline]
pub fn resolve_exact<F: Fn(u32) -> OitNode>(capacity: u32, head: u32, layers: u32, b: Vec3, node_at: &F) -> Vec3 {
    let mut d = b;
    let mut after = Layer::default();
    let mut bounded = false;
    let passes = layers.div_ceil(MAX_K);
    let mut pass = 0;
    while pass < passes {
        let mut sel = Farthest { kept: Kept::new(MAX_K), after, bounded };
        walk(head, capacity, node_at, &mut sel);
        let n = sel.kept.n;
        if n == 0 {
            break;
        }
        let mut j = 0;
        while j < n {
            d = over(sel.kept.a[j as usize].colour, d);
            j += 1;
        }
        after = sel.kept.a[(n - 1) as usize];
        bounded = true;
        pass += 1;
    }
    d
}

/// The `k` nearest layers (`k` clamped to 1..=MAX_K) over the tail's average over `b`.
#[inline]
pub fn resolve_k_nearest<F: Fn(u32) -> OitNode>(capacity: u32, head: u32, k: u32, b: Vec3, node_at: &F) -> Vec3 {
    let mut near = Nearest { kept: Kept::new(k), tail: Tail::EMPTY };
    walk(head, capacity, node_at, &mut near);
    let mut d = near.tail.over(b);
    let mut j = near.kept.n;
    while j > 0 {
        j -= 1;
        d = over(near.kept.a[j as usize].colour, d);
    }
    d
}

/// The weighted variant computed from a list: what its blending pass accumulates, resolved.
#[inline]
pub fn resolve_weighted<F: Fn(u32) -> OitNode>(p: &OitParams, head: u32, b: Vec3, node_at: &F) -> Vec3 {
    let mut w = Weighted { near: p.near, accum: Vec4::ZERO, revealage: 1.0 };
    walk(head, p.capacity, node_at, &mut w);
    weighted_resolve(w.accum, w.revealage, b)
}

/// McGuire & Bavoil's eq. (7): `α · clamp(10 / (10⁻⁵ + (|z|/5)² + (|z|/200)⁶), 10⁻², 3·10³)` of
/// the view depth `z` (view-space units as metres) and the coverage `α` (saturated). `|z|` past
/// [`WEIGHT_MAX_DEPTH`] (NaN and ∞ too) counts as that: the weight is at its floor from
/// `|z| ≈ 632` on, and no intermediate reaches ∞ (which a GPU may assume never happens).
#[inline]
pub fn weight_eq7(z: f32, alpha: f32) -> f32 {
    // |z| on the bits, compared as an integer: NaN and ∞ (bits ≥ 0x7f80_0000) are past the limit.
    let bits = z.to_bits() & 0x7fff_ffff;
    let d = if bits < WEIGHT_MAX_DEPTH.to_bits() { f32::from_bits(bits) } else { WEIGHT_MAX_DEPTH };
    let a = d * (1.0 / 5.0);
    let b = d * (1.0 / 200.0);
    let b2 = b * b;
    let w = 10.0 / (1e-5 + a * a + b2 * b2 * b2);
    let w = if w > 1e-2 {
        if w < 3e3 {
            w
        } else {
            3e3
        }
    } else {
        1e-2
    };
    saturate(alpha) * w
}

/// One fragment's outputs in the weighted pass: `accum` = `(C·w, α·w)` for the additive target,
/// `alpha` = α for the revealage target (which its blend multiplies by `1 − α`). `rgb` straight,
/// `view_depth` the fragment's view depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightedFragment {
    pub accum: Vec4,
    pub alpha: f32,
}

/// [`WeightedFragment`] of a fragment (inputs sanitised as in the lists).
#[inline]
pub fn weighted_fragment(rgb: Vec3, alpha: f32, view_depth: f32) -> WeightedFragment {
    let a = saturate(alpha);
    let w = weight_eq7(view_depth, a);
    WeightedFragment { accum: (saturate3(rgb) * a).extend(a) * w, alpha: a }
}

/// The weighted composite over `b`: `(Σ C·w / max(Σ α·w, 10⁻⁵))·(1 − R) + R·B`. A non-finite
/// accumulation (an overflowed half-float target) gives an average of 0; `R` and `B` are
/// saturated.
#[inline]
pub fn weighted_resolve(accum: Vec4, revealage: f32, b: Vec3) -> Vec3 {
    let r = saturate(revealage);
    let s = 1.0 / if accum.w > WEIGHTED_MIN_ALPHA { accum.w } else { WEIGHTED_MIN_ALPHA };
    saturate3(accum.truncate() * s) * (1.0 - r) + saturate3(b) * r
}

#[cfg(test)]
#[path = "oit_tests.rs"]
mod tests;
