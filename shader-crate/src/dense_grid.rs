//! The full cluster grid's dense index (`clustered-aabb`'s clusters, and the clusters its
//! transparent fragments mark): screen tiles × exponential depth slices of
//! [`crate::cluster_key`], numbered slice by slice, row by row.
//!
//! ```text
//! dense index = (k · tiles_y + j) · tiles_x + i      i: tile column, j: tile row, k: slice
//! ```
use crate::cluster_key::ClusterGrid;
use crate::reconstruct;

/// Dense cluster of a background pixel.
pub const NO_CLUSTER: u32 = u32::MAX;

/// Clusters of the full grid.
#[inline]
pub fn cluster_count(g: &ClusterGrid) -> u32 {
    g.tiles_x * g.tiles_y * g.num_slices
}

/// Dense index of cluster `(i, j, k)`: `(k·tiles_y + j)·tiles_x + i`.
#[inline]
pub fn dense_index(g: &ClusterGrid, i: u32, j: u32, k: u32) -> u32 {
    (k * g.tiles_y + j) * g.tiles_x + i
}

/// Inverse of [`dense_index`].
#[inline]
pub fn dense_coords(g: &ClusterGrid, c: u32) -> (u32, u32, u32) {
    (c % g.tiles_x, (c / g.tiles_x) % g.tiles_y, c / (g.tiles_x * g.tiles_y))
}

/// Dense cluster of pixel `(px, py)` with depth-buffer value `z_buf`, or [`NO_CLUSTER`] for
/// background: its tile and the exact slice of its distance.
#[inline]
pub fn pixel_cluster(g: &ClusterGrid, bounds: &[f32], px: u32, py: u32, z_buf: f32) -> u32 {
    if reconstruct::is_background(z_buf) {
        return NO_CLUSTER;
    }
    let (i, j) = g.tile_of_pixel(px, py);
    dense_index(g, i, j, g.slice_of_depth(bounds, reconstruct::distance_from_depth(g.near, z_buf)))
}
