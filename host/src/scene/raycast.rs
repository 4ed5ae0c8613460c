//! Exact visibility between two points on the CPU: the ray-cast reference that shadows are held
//! to. Independent of every GPU path: 64-bit floats, a plain bounding volume hierarchy over the
//! scene's triangles, and a segment–triangle test that reports a hit only strictly between the
//! two end points.
//!
//! # Steps
//! 1. [`Occluders::new`] takes the triangles (degenerate ones, of zero area, are dropped: they
//!    hide nothing) and builds the hierarchy top-down: each node's triangles are split at the
//!    median centroid along the longest axis of their centroids' box, down to leaves of at most
//!    [`LEAF_TRIANGLES`]. `n` triangles take `n` + `2n / LEAF_TRIANGLES` nodes at most.
//! 2. [`Occluders::blocked`] walks the hierarchy with a stack: a node is entered when the segment
//!    meets its box (slab test over the segment's parameter interval), a leaf's triangles are
//!    tested by Möller & Trumbore (1997, "Fast, minimum storage ray/triangle intersection"),
//!    edges included (a segment through a shared edge is blocked, as it is by a closed surface).
//!
//! # What counts as blocked
//! A segment `a → b` is blocked when some triangle crosses it at a parameter `t` with
//! `t_min < t < 1 − t_min`, `t_min = EPSILON_T`: a receiver lying on a triangle (`t = 0`) is not
//! blocked by that triangle, nor is a light on a surface. Callers that want a receiver's own
//! surface ignored at grazing angles offset the start point along its normal (a documented bias,
//! like any shadow map's): this module adds none.
//!
//! Memory: 72 B per triangle (three 64-bit vertices) and 56 B per node (two 64-bit corners, two
//! indices).
use glam::DVec3;

/// Most triangles in a leaf.
pub const LEAF_TRIANGLES: usize = 4;
/// Segment parameters within this of either end are not hits (`t` is relative to the length).
pub const EPSILON_T: f64 = 1e-9;

/// Deepest walk: a median split halves the triangles at each level, so a tree of fewer than
/// 2^62 triangles is shallower; the walk's stack holds at most one node per level plus one.
const MAX_DEPTH: usize = 64;

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf (`count` > 0): the triangles `first..first + count`. Inner (`count` = 0): the right
    /// child's index; the left child is the next node (built right after its parent).
    first: u32,
    count: u32,
}

/// Triangles that block segments, in a hierarchy.
#[derive(Clone, Debug)]
pub struct Occluders {
    triangles: Vec<[DVec3; 3]>,
    nodes: Vec<Node>,
}

impl Occluders {
    /// The hierarchy of `triangles` (any order; degenerate triangles dropped).
    pub fn new(triangles: impl IntoIterator<Item = [glam::Vec3; 3]>) -> Self {
        let mut triangles: Vec<[DVec3; 3]> = triangles
            .into_iter()
            .map(|t| t.map(|v| v.as_dvec3()))
            .filter(|[a, b, c]| (*b - *a).cross(*c - *a).length_squared() > 0.0)
            .collect();
        let mut nodes = Vec::with_capacity(1 + 2 * triangles.len() / LEAF_TRIANGLES);
        if !triangles.is_empty() {
            let n = triangles.len();
            build(&mut triangles, &mut nodes, 0, n);
        }
        Self { triangles, nodes }
    }

    /// The triangles of every mesh of `scene` (world space). NURBS patches are not included:
    /// they are tessellated on the GPU.
    pub fn of_scene(scene: &super::Scene) -> Self {
        Self::new(scene.meshes.iter().flat_map(|m| {
            m.indices.chunks_exact(3).map(move |t| [t[0], t[1], t[2]].map(|i| glam::Vec3::from_array(m.positions[i as usize])))
        }))
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Whether a triangle crosses the segment `a → b` strictly between its ends (module docs).
    pub fn blocked(&self, a: DVec3, b: DVec3) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let d = b - a;
        let inv = DVec3::ONE / d;
        let (mut stack, mut top) = ([0u32; MAX_DEPTH], 1);
        while top > 0 {
            top -= 1;
            let i = stack[top];
            let node = &self.nodes[i as usize];
            if !segment_meets_box(a, inv, node.lo, node.hi) {
                continue;
            }
            if node.count > 0 {
                let tris = &self.triangles[node.first as usize..(node.first + node.count) as usize];
                if tris.iter().any(|t| crosses(a, d, t)) {
                    return true;
                }
            } else {
                stack[top] = node.first;
                stack[top + 1] = i + 1;
                top += 2;
            }
        }
        false
    }

    /// [`Self::blocked`] without the hierarchy: every triangle tested (what the tests compare the
    /// walk against).
    pub fn blocked_brute_force(&self, a: DVec3, b: DVec3) -> bool {
        self.triangles.iter().any(|t| crosses(a, b - a, t))
    }
}

/// The box of `points` (min, max).
fn box_of(points: impl Iterator<Item = DVec3>) -> (DVec3, DVec3) {
    points.fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
}

/// Builds the subtree of `tris[first..first + count]`, returns its node index.
fn build(tris: &mut [[DVec3; 3]], nodes: &mut Vec<Node>, first: usize, count: usize) -> u32 {
    let (lo, hi) = box_of(tris[first..first + count].iter().flatten().copied());
    let index = nodes.len() as u32;
    nodes.push(Node { lo, hi, first: first as u32, count: count as u32 });
    if count <= LEAF_TRIANGLES {
        return index;
    }
    let centroid = |t: &[DVec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
    let (clo, chi) = box_of(tris[first..first + count].iter().map(centroid));
    let extent = chi - clo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z { 0 } else if extent.y >= extent.z { 1 } else { 2 };
    let half = count / 2;
    tris[first..first + count].select_nth_unstable_by(half, |p, q| centroid(p)[axis].total_cmp(&centroid(q)[axis]));
    let left = build(tris, nodes, first, half);
    debug_assert_eq!(left, index + 1, "the left child follows its parent");
    let right = build(tris, nodes, first + half, count - half);
    nodes[index as usize] = Node { lo, hi, first: right, count: 0 };
    index
}

/// Slab test of the segment `a + t·d`, `t ∈ [0, 1]` (`inv = 1/d`, infinite on axis-parallel
/// segments), against the closed box `[lo, hi]`.
fn segment_meets_box(a: DVec3, inv: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if inv[k].is_infinite() {
            // Parallel to the slab: inside it or not at all.
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (mut n, mut f) = ((lo[k] - a[k]) * inv[k], (hi[k] - a[k]) * inv[k]);
        if n > f {
            std::mem::swap(&mut n, &mut f);
        }
        t0 = t0.max(n);
        t1 = t1.min(f);
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Möller–Trumbore: whether `a + t·d` crosses the triangle at `EPSILON_T < t < 1 − EPSILON_T`,
/// edges and corners included. A segment in the triangle's plane crosses nothing.
fn crosses(a: DVec3, d: DVec3, [v0, v1, v2]: &[DVec3; 3]) -> bool {
    let (e1, e2) = (*v1 - *v0, *v2 - *v0);
    let p = d.cross(e2);
    let det = e1.dot(p);
    // Parallel (or degenerate): relative to the sizes involved.
    if det.abs() <= 1e-15 * e1.length() * e2.length() * d.length() {
        return false;
    }
    let inv = 1.0 / det;
    let s = a - *v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = e2.dot(q) * inv;
    t > EPSILON_T && t < 1.0 - EPSILON_T
}

#[cfg(test)]
#[path = "raycast_tests.rs"]
mod tests;
