//! Cluster keys: screen tile `(i, j)` × exponential depth slice `k`, packed into 32 bits.
//!
//! ## The slice formula (Olsson, Billeter, Assarsson 2012, "Clustered Deferred and Forward
//! Shading", §3.1, eq. 1)
//! Clusters should be about as deep as they are wide. A tile subtends `2·tan(θ)/S_y` of the view
//! height per unit of depth (θ half the vertical field of view, `S_y` tiles vertically), so slice
//! `k` starts at
//! ```text
//!   near_k = near · (1 + 2·tan(θ)/S_y)^k        ⇔   k = floor( ln(d / near) / ln(1 + 2·tan(θ)/S_y) )
//! ```
//! for a point at distance `d = −z_view` in front of the camera, and
//! `S = ceil( ln(far/near) / ln(1 + 2·tan(θ)/S_y) )` slices cover `[near, far]`.
//! Example: 1920×1080, 32 px tiles (`S_y` = 34), 60° fov, near 0.1, far 1000 → growth 3.4 % per
//! slice, 276 slices.
//!
//! ## One source of truth for slice boundaries
//! [`ClusterGrid::slice_near_depth`] is the only definition of where slice `k` starts; the host
//! evaluates it once into a table of `S + 1` floats ([`slice_bounds`], 4·(S+1) bytes — 1.1 KiB in the
//! example) that both the key kernel and (later) the cluster-bounds kernel read. The key function
//! takes the logarithm only as a *guess* and then corrects it with exact comparisons against the
//! table, so
//! * a depth on a boundary `near_k` lands in slice `k` and nowhere else (slices are the half-open
//!   intervals `[near_k, near_{k+1})`), and
//! * CPU and GPU produce bit-identical keys even though GPU `log`/division are not correctly
//!   rounded (Vulkan allows 3 ULP / 2.5 ULP): comparisons are exact everywhere.
//!
//! ## Out-of-range depths (documented clamping, never NaN or garbage)
//! `d ≤ near` (including `z ≥ 0`, behind the camera) and NaN → slice 0; `d ≥ near_{S-1}` (the last
//! slice, including beyond `far`) → slice `S − 1`. Pixels are clamped into the image, so the last
//! row/column of a resolution that is not a multiple of the tile size maps to the last (partial)
//! tile.
//!
//! ## Bit layout
//! `key = i | j << bits_i | k << (bits_i + bits_j)` with `bits_x = ceil(log2(count_x))`: the widths
//! follow the resolution. At 3840×2160 with 32 px tiles this is the seed's 7 + 7 bits for `(i, j)`
//! (120 × 68 tiles); 7680×4320 needs 8 + 8 (240 × 135). [`ClusterGrid::new`] refuses grids whose
//! key would not fit in 32 bits. Keys of one slice are contiguous, which is what the page table
//! (512 keys per page) exploits.
#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

pub use crate::layout::ClusterGrid;

/// Bits needed to store values `0..count` (0 for `count <= 1`).
#[inline]
pub const fn bits_for(count: u32) -> u32 {
    if count <= 1 {
        0
    } else {
        32 - (count - 1).leading_zeros()
    }
}

impl ClusterGrid {
    /// Tile of a pixel; pixels outside the image are clamped to its border tiles.
    #[inline]
    pub fn tile_of_pixel(&self, px: u32, py: u32) -> (u32, u32) {
        let x = if px < self.width { px } else { self.width - 1 };
        let y = if py < self.height { py } else { self.height - 1 };
        (x / self.tile_size, y / self.tile_size)
    }

    /// Distance from the eye at which slice `k` begins (`k = 0..=num_slices`): the single
    /// definition of slice boundaries. Evaluate on the host into [`slice_bounds`].
    #[inline]
    pub fn slice_near_depth(&self, k: u32) -> f32 {
        self.near * (k as f32 * self.log_growth).exp()
    }

    /// The closed-form slice of distance `d` (may be off by one near boundaries because of
    /// rounding in `ln` and the division; [`Self::slice_of_depth`] corrects it).
    #[inline]
    pub fn slice_guess(&self, d: f32) -> u32 {
        let last = self.num_slices - 1;
        if !(d > self.near) {
            return 0;
        }
        let g = (d / self.near).ln() * self.inv_log_growth;
        if !(g >= 0.0) {
            0
        } else if g >= last as f32 {
            last
        } else {
            g as u32
        }
    }

    /// Exact slice of distance `d = −z_view`, consistent with the `bounds` table
    /// (`bounds[k] = slice_near_depth(k)`): `bounds[k] <= d < bounds[k+1]`, clamped to the grid.
    #[inline]
    pub fn slice_of_depth(&self, bounds: &[f32], d: f32) -> u32 {
        let last = self.num_slices - 1;
        if !(d > self.near) {
            return 0;
        }
        let mut k = self.slice_guess(d);
        while k > 0 && d < bounds[k as usize] {
            k -= 1;
        }
        while k < last && d >= bounds[k as usize + 1] {
            k += 1;
        }
        k
    }

    /// Packs a cluster coordinate (see the module's bit layout).
    #[inline]
    pub fn pack(&self, i: u32, j: u32, k: u32) -> u32 {
        i | (j << self.bits_i) | (k << (self.bits_i + self.bits_j))
    }

    /// Inverse of [`Self::pack`].
    #[inline]
    pub fn unpack(&self, key: u32) -> (u32, u32, u32) {
        let mask_i = (1u32 << self.bits_i) - 1;
        let mask_j = (1u32 << self.bits_j) - 1;
        (
            key & mask_i,
            (key >> self.bits_i) & mask_j,
            key >> (self.bits_i + self.bits_j),
        )
    }

    /// Key of a pixel at view-space depth `view_z` (negative in front of the camera).
    #[inline]
    pub fn key(&self, bounds: &[f32], px: u32, py: u32, view_z: f32) -> u32 {
        let (i, j) = self.tile_of_pixel(px, py);
        self.pack(i, j, self.slice_of_depth(bounds, -view_z))
    }

    /// Number of distinct keys the layout can hold (`2^(bits_i+bits_j+bits_k)`), as u64.
    #[inline]
    pub fn key_space(&self) -> u64 {
        1u64 << (self.bits_i + self.bits_j + self.bits_k)
    }
}

#[cfg(not(target_arch = "spirv"))]
mod host {
    use super::*;

    /// Why a cluster grid cannot be built.
    #[derive(Clone, Debug, PartialEq)]
    pub enum GridError {
        Resolution { width: u32, height: u32 },
        TileSize(u32),
        DepthRange { near: f32, far: f32 },
        FieldOfView(f32),
        TooManySlices(u64),
        KeyTooWide { bits_i: u32, bits_j: u32, bits_k: u32 },
    }

    impl core::fmt::Display for GridError {
        fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
            match self {
                Self::Resolution { width, height } => write!(
                    f,
                    "resolution {width}x{height} is invalid: width and height must be in 1..={MAX_DIMENSION}"
                ),
                Self::TileSize(t) => write!(f, "tile size {t} px is invalid: must be in 1..={MAX_TILE_SIZE}"),
                Self::DepthRange { near, far } => write!(
                    f,
                    "depth range near={near} far={far} is invalid: need finite 0 < near < far"
                ),
                Self::FieldOfView(v) => {
                    write!(f, "vertical field of view {v} rad is invalid: must be in (0, pi)")
                }
                Self::TooManySlices(s) => write!(
                    f,
                    "{s} depth slices needed (more than {MAX_SLICES}): use larger tiles or a smaller far/near ratio"
                ),
                Self::KeyTooWide { bits_i, bits_j, bits_k } => write!(
                    f,
                    "cluster key needs {bits_i}+{bits_j}+{bits_k} bits > 32: use larger tiles or a smaller far/near ratio"
                ),
            }
        }
    }

    impl std::error::Error for GridError {}

    /// Largest accepted image dimension.
    pub const MAX_DIMENSION: u32 = 1 << 15;
    /// Largest accepted tile edge.
    pub const MAX_TILE_SIZE: u32 = 1024;
    /// Largest accepted slice count (the bounds table stays ≤ 256 KiB).
    pub const MAX_SLICES: u32 = 1 << 16;

    impl ClusterGrid {
        /// Builds the grid for a `width × height` image, `tile_size` px tiles, depth range
        /// `[near, far]` and vertical field of view `fov_y` (radians).
        pub fn new(
            width: u32,
            height: u32,
            tile_size: u32,
            near: f32,
            far: f32,
            fov_y: f32,
        ) -> Result<Self, GridError> {
            if width == 0 || height == 0 || width > MAX_DIMENSION || height > MAX_DIMENSION {
                return Err(GridError::Resolution { width, height });
            }
            if tile_size == 0 || tile_size > MAX_TILE_SIZE {
                return Err(GridError::TileSize(tile_size));
            }
            if !(near.is_finite() && far.is_finite() && near > 0.0 && far > near) {
                return Err(GridError::DepthRange { near, far });
            }
            if !(fov_y > 0.0 && fov_y < core::f32::consts::PI) {
                return Err(GridError::FieldOfView(fov_y));
            }
            let tiles_x = width.div_ceil(tile_size);
            let tiles_y = height.div_ceil(tile_size);
            let tan_half = (0.5 * fov_y).tan();
            let log_growth = (1.0 + 2.0 * tan_half / tiles_y as f32).ln();
            let slices = ((far / near).ln() / log_growth).ceil().max(1.0);
            if !(slices <= MAX_SLICES as f32) {
                return Err(GridError::TooManySlices(slices as u64));
            }
            let mut grid = Self {
                width,
                height,
                tile_size,
                tiles_x,
                tiles_y,
                num_slices: slices as u32,
                bits_i: bits_for(tiles_x),
                bits_j: bits_for(tiles_y),
                bits_k: 0,
                near,
                far,
                log_growth,
                inv_log_growth: 1.0 / log_growth,
                tan_half_fov_y: tan_half,
                samples: 1,
                _pad: 0,
            };
            // Rounding in exp() may leave near_S a hair below far: add slices until covered.
            while grid.slice_near_depth(grid.num_slices) < far {
                grid.num_slices += 1;
            }
            grid.bits_k = bits_for(grid.num_slices);
            if grid.bits_i + grid.bits_j + grid.bits_k > 32 || grid.bits_i + grid.bits_j > 31 {
                return Err(GridError::KeyTooWide {
                    bits_i: grid.bits_i,
                    bits_j: grid.bits_j,
                    bits_k: grid.bits_k,
                });
            }
            Ok(grid)
        }
    }

    /// The slice-boundary table `[near_0 = near, near_1, …, near_S ≥ far]` (S + 1 floats), strictly
    /// increasing (checked: slices narrower than one float step would be empty).
    pub fn slice_bounds(grid: &ClusterGrid) -> Vec<f32> {
        let t: Vec<f32> = (0..=grid.num_slices).map(|k| grid.slice_near_depth(k)).collect();
        assert!(
            t.windows(2).all(|w| w[0] < w[1]),
            "slice bounds are not strictly increasing (grid {grid:?})"
        );
        t
    }
}

#[cfg(not(target_arch = "spirv"))]
pub use host::*;

#[cfg(test)]
#[path = "cluster_key_tests.rs"]
mod tests;
