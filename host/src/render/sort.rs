//! GPU key–value radix sort (`shaders::radix`, whose doc describes the design): 8-bit digits,
//! only the passes `key_bits` needs, tiles of `RADIX_TILE` = 2048 keys; and the light sort that
//! picks it or the bitonic sort ([`LightSorter`], `render --sort`).
//!
//! Recorded per sort of `n` pairs:
//! - `n ≤ RADIX_TILE`: one workgroup sorts in place (`radix_sort_tile`): one dispatch;
//! - otherwise: zero the global histogram, `radix_histogram` (every pass's digit counts in one
//!   read), then per pass, ping-ponging between the caller's buffers and scratch:
//!   - reduce-then-scan ([`CrossTile::ReduceThenScan`], every device): `radix_upsweep` (tile
//!     counts), `radix_spine` (1–256 workgroups: global starts of every (digit, tile)) and
//!     `radix_downsweep` (rank, reorder, write);
//!   - chained scan ([`CrossTile::Chained`], where [`DeviceInfo::workgroups_progress`]):
//!     `radix_chained` alone (claim a tile, rank, look back, write), after one zero fill of
//!     the status words per sort.
//!
//!   An odd pass count ends with a copy of the scratch pair into the caller's buffers: a copy
//!   moves 16 B per pair where an extra identity pass would move more than 20. On lavapipe
//!   (1M pairs of 24-bit keys, wall clock, medians of 7, a loaded 2-core machine) three passes
//!   and the copy took 20–45 % less time than four passes in four of five paired runs (the
//!   first, right after start-up, 8 % more); no GPU measurement yet.
//!
//! Scratch memory: `8 · capacity` B (keys + values) when `capacity > RADIX_TILE`, 4 KiB of
//! histogram, and `2 · 4 · 256 · ⌈capacity / 2048⌉` B of tile counts and starts
//! (reduce-then-scan) or half that of status words (chained): ≈ 9 B per pair.
use super::bitonic::BitonicSort;
use crate::gpu::Gpu;
use crate::vk::fold;
use crate::vk::{Buffer, DeviceInfo, Recorder, VkError, VkResult};
use shaders::layout::RadixParams;
use shaders::radix::chained::{status_words, CHAINED_MAX_PAIRS};
use shaders::radix::{fits_one_tile, passes, spine_digits, HISTOGRAM_KEYS, MAX_PASSES, RADIX, RADIX_TILE};

/// How the passes of inputs larger than one tile find each tile's place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CrossTile {
    /// Upsweep, spine, downsweep: no workgroup waits on another (every device).
    ReduceThenScan,
    /// One dispatch per pass with decoupled look-back (`shaders::radix::chained`): needs
    /// forward progress between workgroups.
    Chained,
}

/// Largest sort the chained scan is chosen for. Measured on an NVIDIA H200 (`benches/sort.rs`,
/// uniform 30-bit keys, GPU ms chained / reduce-then-scan): 64k 0.157 / 0.245, 1M 0.239 / 0.299,
/// 4M 0.695 / 0.669, 10M 1.504 / 1.388, 16M 2.255 / 2.101 — one dispatch per pass wins while
/// launch and spine costs dominate, the two-read reduce-then-scan from a few million pairs on.
pub const CHAINED_UP_TO_PAIRS: u32 = 1 << 21;

impl CrossTile {
    /// Chained where the device keeps waiting workgroups progressing and the sort is at most
    /// [`CHAINED_UP_TO_PAIRS`] (within its status words), reduce-then-scan elsewhere.
    pub fn for_device(info: &DeviceInfo, capacity: u32) -> Self {
        let chained = info.workgroups_progress() && capacity <= CHAINED_UP_TO_PAIRS.min(CHAINED_MAX_PAIRS);
        if chained { Self::Chained } else { Self::ReduceThenScan }
    }
}

/// The cross-tile buffers of each variant.
enum Tables {
    /// Tile counts of the pass, digit-major (`256 × tiles`), and every (digit, tile)'s start.
    ReduceThenScan { counts: Buffer, starts: Buffer },
    /// Status words and tile counters (`shaders::radix::chained::status_words`).
    Chained { status: Buffer },
}

pub struct RadixSort {
    pub capacity: u32,
    keys_tmp: Buffer,
    values_tmp: Buffer,
    /// Global histogram, `MAX_PASSES × 256` counts.
    hist: Buffer,
    /// Boxed: a variant's buffers would make `LightSorter::Radix` much larger than `Bitonic`.
    tables: Box<Tables>,
}

/// Kernel name in the errors of [`RadixSort::record`].
const SORT: &str = "radix sort";

impl RadixSort {
    /// A sort for up to `capacity` pairs with the device's variant ([`CrossTile::for_device`]).
    pub fn new(gpu: &Gpu, capacity: u32) -> VkResult<Self> {
        Self::with_cross_tile(gpu, capacity, CrossTile::for_device(&gpu.ctx.info, capacity))
    }

    /// A sort for up to `capacity` pairs with the given variant; the chained one only where
    /// the device can run it.
    pub fn with_cross_tile(gpu: &Gpu, capacity: u32, cross: CrossTile) -> VkResult<Self> {
        let ctx = &gpu.ctx;
        if cross == CrossTile::Chained && !ctx.info.workgroups_progress() {
            return Err(VkError::Kernel { entry: SORT, what: format!("the chained scan needs forward progress between workgroups, which {} does not promise", ctx.info.name) });
        }
        if cross == CrossTile::Chained && capacity > CHAINED_MAX_PAIRS {
            return Err(VkError::Kernel { entry: SORT, what: format!("the chained scan sorts at most {CHAINED_MAX_PAIRS} pairs, {capacity} asked") });
        }
        // One tile sorts in place: no scratch beyond a word per buffer.
        let (pairs, tiles) = if fits_one_tile(capacity) { (1, 1) } else { (capacity, capacity.div_ceil(RADIX_TILE)) };
        let table = 4 * (RADIX * tiles) as u64;
        let tables = match cross {
            CrossTile::ReduceThenScan => Tables::ReduceThenScan {
                counts: Buffer::storage(ctx, "sort tile counts", table)?,
                starts: Buffer::storage(ctx, "sort tile starts", table)?,
            },
            CrossTile::Chained => Tables::Chained { status: Buffer::storage(ctx, "sort tile status", 4 * status_words(tiles) as u64)? },
        };
        Ok(Self {
            capacity,
            keys_tmp: Buffer::storage(ctx, "sort keys (scratch)", 4 * pairs as u64)?,
            values_tmp: Buffer::storage(ctx, "sort values (scratch)", 4 * pairs as u64)?,
            hist: Buffer::storage(ctx, "sort histogram", 4 * (MAX_PASSES * RADIX) as u64)?,
            tables: Box::new(tables),
        })
    }

    /// The variant this sort records.
    pub fn cross_tile(&self) -> CrossTile {
        match *self.tables {
            Tables::ReduceThenScan { .. } => CrossTile::ReduceThenScan,
            Tables::Chained { .. } => CrossTile::Chained,
        }
    }

    /// Bytes of scratch memory.
    pub fn bytes(&self) -> u64 {
        let tables = match &*self.tables {
            Tables::ReduceThenScan { counts, starts } => counts.size + starts.size,
            Tables::Chained { status } => status.size,
        };
        self.keys_tmp.size + self.values_tmp.size + self.hist.size + tables
    }

    /// Records a stable sort of `keys[..n]` (values follow) for keys below `2^key_bits`
    /// (`key_bits ≤ 32`); bits at and above `key_bits` are ignored.
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, keys: &Buffer, values: &Buffer, n: u32, key_bits: u32) -> VkResult<()> {
        if n > self.capacity {
            return Err(VkError::Kernel { entry: SORT, what: format!("sorting {n} pairs with buffers for {}", self.capacity) });
        }
        if key_bits > 32 {
            return Err(VkError::Kernel { entry: SORT, what: format!("keys of {key_bits} bits: at most 32") });
        }
        let passes = passes(key_bits);
        if n <= 1 || passes == 0 {
            return Ok(());
        }
        let k = &gpu.kernels;
        let tiles = n.div_ceil(RADIX_TILE);
        let mut p = RadixParams { count: n, key_bits, pass: 0, tiles, spine_digits: spine_digits(tiles), _pad: [0; 3] };
        if fits_one_tile(n) {
            return rec.dispatch(&k.radix_sort_tile, &[keys, values], &p, [1, 1, 1]);
        }
        rec.fill(&self.hist, 0);
        if let Tables::Chained { status } = &*self.tables {
            rec.fill(status, 0);
        }
        rec.dispatch(&k.radix_histogram, &[keys, &self.hist], &p, fold(n.div_ceil(HISTOGRAM_KEYS)))?;
        let (mut src, mut dst) = ((keys, values), (&self.keys_tmp, &self.values_tmp));
        for pass in 0..passes {
            p.pass = pass;
            match &*self.tables {
                Tables::ReduceThenScan { counts, starts } => {
                    rec.dispatch(&k.radix_upsweep, &[src.0, counts], &p, fold(tiles))?;
                    rec.dispatch(&k.radix_spine, &[&self.hist, counts, starts], &p, [RADIX / p.spine_digits, 1, 1])?;
                    rec.dispatch(&k.radix_downsweep, &[src.0, src.1, starts, dst.0, dst.1], &p, fold(tiles))?;
                }
                Tables::Chained { status } => {
                    rec.dispatch(&k.radix_chained, &[src.0, src.1, &self.hist, status, dst.0, dst.1], &p, fold(tiles))?;
                }
            }
            (src, dst) = (dst, src);
        }
        if passes % 2 == 1 {
            rec.copy(src.0, keys, 4 * n as u64)?;
            rec.copy(src.1, values, 4 * n as u64)?;
        }
        Ok(())
    }
}

/// Which GPU sort orders the lights' Morton keys (`render --sort`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum SortKind {
    /// By size: the bitonic sort up to [`SMALL_SORT_PAIRS`] (not stable), the radix sort
    /// above.
    #[default]
    Auto,
    /// LSD radix sort ([`RadixSort`]), stable.
    Radix,
    /// Bitonic-warp merge sort ([`BitonicSort`]).
    Bitonic,
}

/// Most pairs [`SortKind::Auto`] gives the bitonic sort. Measured on an NVIDIA H200
/// (`benches/sort.rs`, uniform 30-bit keys, GPU ms bitonic / radix, two runs alike): 1 000 0.029 /
/// 0.044 (both one workgroup: the bitonic network's fixed steps beat four ranked radix passes),
/// 2 048 0.045 / 0.045, 4 096 0.061 / 0.092, 10 000 0.095 / 0.107, 32 768 0.113 / 0.123, 65 536
/// 0.132 / 0.126, 1M 0.49 / 0.19: the radix sort's fixed cost per pass (one dispatch each) wins
/// once its work per pass outgrows the bitonic's extra merge levels.
pub const SMALL_SORT_PAIRS: u32 = 1 << 15;

/// The light sort of `clustered-bvh`: one of the two GPU key–value sorts, or both picked by size
/// ([`SortKind::Auto`]); same interface.
pub enum LightSorter {
    Radix(Box<RadixSort>),
    Bitonic(Box<BitonicSort>),
    /// The bitonic sort for at most [`SMALL_SORT_PAIRS`] (planned for no more), the radix sort
    /// above.
    Auto { small: Box<BitonicSort>, large: Box<RadixSort> },
}

impl LightSorter {
    pub fn new(gpu: &Gpu, kind: SortKind, capacity: u32) -> VkResult<Self> {
        Ok(match kind {
            SortKind::Radix => Self::Radix(Box::new(RadixSort::new(gpu, capacity)?)),
            SortKind::Bitonic => Self::Bitonic(Box::new(BitonicSort::new(gpu, capacity)?)),
            SortKind::Auto => Self::Auto {
                small: Box::new(BitonicSort::new(gpu, capacity.min(SMALL_SORT_PAIRS))?),
                large: Box::new(RadixSort::new(gpu, capacity)?),
            },
        })
    }

    /// Bytes of scratch memory.
    pub fn bytes(&self) -> u64 {
        match self {
            Self::Radix(s) => s.bytes(),
            Self::Bitonic(s) => s.bytes(),
            Self::Auto { small, large } => small.bytes() + large.bytes(),
        }
    }

    /// Whether equal keys keep their input order for a sort of `n` pairs.
    pub fn stable(&self, n: u32) -> bool {
        match self {
            Self::Radix(_) => true,
            Self::Bitonic(_) => false,
            Self::Auto { small, .. } => n > small.capacity,
        }
    }

    /// Records a sort of `keys[..n]` (values follow) for keys below `2^key_bits`.
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, keys: &Buffer, values: &Buffer, n: u32, key_bits: u32) -> VkResult<()> {
        match self {
            Self::Radix(s) => s.record(gpu, rec, keys, values, n, key_bits),
            Self::Bitonic(s) => s.record(gpu, rec, keys, values, n, key_bits),
            // `small` is planned for min(capacity, SMALL_SORT_PAIRS): past that the radix sort
            // records (or refuses a count beyond its buffers).
            Self::Auto { small, .. } if n <= small.capacity => small.record(gpu, rec, keys, values, n, key_bits),
            Self::Auto { large, .. } => large.record(gpu, rec, keys, values, n, key_bits),
        }
    }
}
