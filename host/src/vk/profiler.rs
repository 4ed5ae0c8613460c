//! GPU timestamp profiler: per-pass milliseconds from `vkCmdWriteTimestamp`.
//!
//! A pass is bracketed by a top-of-pipe and a bottom-of-pipe timestamp; the difference times the
//! device's `timestampPeriod` is the pass's GPU time. The submission's span (first to last
//! timestamp, gaps and waits between passes included) is what a frame costs a queue. Devices whose
//! queue reports no valid timestamp bits get a disabled profiler (no timings, never a wrong one).
use super::context::Context;
use super::error::{CallContext, VkResult};
use ash::vk;

/// The queue a pass ran on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Queue {
    /// The graphics + compute queue.
    Main,
    /// The async-compute queue (overlapping the main queue's work).
    AsyncCompute,
}

/// A submission's first and last timestamp, milliseconds on the device's time line.
pub type Span = (f64, f64);

/// One timed pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    pub name: String,
    pub ms: f64,
    pub queue: Queue,
    /// The pass recorded raster work (it began rendering).
    pub raster: bool,
    /// One dispatch, fill or copy inside the pass named before ` · ` (profilers with
    /// [`Profiler::with_parts`]); its time is also inside the pass's.
    pub part: bool,
}

pub struct Profiler {
    ctx: Context,
    pool: vk::QueryPool,
    capacity: u32,
    /// Valid timestamp bits of the queue family this profiler's command buffers run on.
    bits: u32,
    queue: Queue,
    names: Vec<String>,
    /// Per pass: whether it recorded raster work.
    raster: Vec<bool>,
    /// Per pass: whether it is one command inside a pass.
    part: Vec<bool>,
    /// The pass being recorded.
    open: Option<usize>,
    /// Time each dispatch, fill and copy inside a pass as well ([`Profiler::with_parts`]).
    parts: bool,
}

impl Profiler {
    /// Room for `passes` timed passes per submission on the graphics+compute queue.
    pub fn new(ctx: &Context, passes: u32) -> VkResult<Self> {
        Self::with_bits(ctx, passes, ctx.info.timestamp_valid_bits, Queue::Main)
    }

    /// A profiler for command buffers of the async-compute queue (disabled where that family has
    /// no timestamps, or where there is no such queue).
    pub fn new_async(ctx: &Context, passes: u32) -> VkResult<Self> {
        Self::with_bits(ctx, passes, ctx.info.async_timestamp_valid_bits, Queue::AsyncCompute)
    }

    fn with_bits(ctx: &Context, passes: u32, bits: u32, queue: Queue) -> VkResult<Self> {
        let mut pool = vk::QueryPool::null();
        if bits > 0 {
            let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(2 * passes);
            pool = unsafe { ctx.device.create_query_pool(&info, None) }.call("vkCreateQueryPool")?;
            ctx.set_name(pool, "profiler timestamps");
        }
        Ok(Self { ctx: ctx.clone(), pool, capacity: passes, bits, queue, names: Vec::new(), raster: Vec::new(), part: Vec::new(), open: None, parts: false })
    }

    /// This profiler, also timing every dispatch, fill and copy inside a pass as a part named
    /// `pass · command` (the commands' own timestamps: where a pass's time goes). Its capacity
    /// must cover the parts too.
    pub fn with_parts(mut self, parts: bool) -> Self {
        self.parts = parts;
        self
    }

    pub fn enabled(&self) -> bool {
        self.pool != vk::QueryPool::null()
    }

    /// Resets the queries; record before the first pass of a submission.
    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        self.names.clear();
        self.raster.clear();
        self.part.clear();
        self.open = None;
        if self.enabled() {
            unsafe { self.ctx.device.cmd_reset_query_pool(cmd, self.pool, 0, 2 * self.capacity) };
        }
    }

    /// Starts a pass; returns its slot (None when disabled or full).
    pub fn begin(&mut self, cmd: vk::CommandBuffer, name: &str) -> Option<u32> {
        let slot = self.start(cmd, name, false)?;
        self.open = Some(slot as usize);
        Some(slot)
    }

    /// Starts a part (a command inside the open pass `pass`) when parts are timed.
    pub fn begin_part(&mut self, cmd: vk::CommandBuffer, command: &str) -> Option<u32> {
        let pass = self.open.filter(|_| self.parts).map(|i| self.names[i].clone())?;
        // The n-th use of a kernel in a pass is `pass · kernel #n`: names stay keys.
        let name = format!("{pass} · {command}");
        let n = self.names.iter().filter(|m| **m == name || m.strip_prefix(name.as_str()).is_some_and(|r| r.starts_with(" #"))).count();
        self.start(cmd, &if n == 0 { name.clone() } else { format!("{name} #{}", n + 1) }, true)
    }

    fn start(&mut self, cmd: vk::CommandBuffer, name: &str, part: bool) -> Option<u32> {
        if !self.enabled() || self.names.len() as u32 >= self.capacity {
            return None;
        }
        let slot = self.names.len() as u32;
        self.names.push(name.to_owned());
        self.raster.push(false);
        self.part.push(part);
        unsafe { self.ctx.device.cmd_write_timestamp(cmd, vk::PipelineStageFlags::TOP_OF_PIPE, self.pool, 2 * slot) };
        Some(slot)
    }

    /// Ends a part [`Profiler::begin_part`] started.
    pub fn end_part(&mut self, cmd: vk::CommandBuffer, slot: Option<u32>) {
        self.write_end(cmd, slot);
    }

    pub fn end(&mut self, cmd: vk::CommandBuffer, slot: Option<u32>) {
        self.open = None;
        self.write_end(cmd, slot);
    }

    fn write_end(&mut self, cmd: vk::CommandBuffer, slot: Option<u32>) {
        if let Some(s) = slot {
            unsafe { self.ctx.device.cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, self.pool, 2 * s + 1) };
        }
    }

    /// Notes that the open pass records raster work.
    pub(crate) fn mark_raster(&mut self) {
        if let Some(i) = self.open {
            self.raster[i] = true;
        }
    }

    /// The raw timestamps of the last submission's passes (begin, end per pass), masked to the
    /// valid bits; empty when disabled or nothing was timed. Call after the submission completed.
    fn raw(&self) -> VkResult<Vec<u64>> {
        if !self.enabled() || self.names.is_empty() {
            return Ok(Vec::new());
        }
        let mut raw = vec![0u64; 2 * self.names.len()];
        unsafe {
            self.ctx
                .device
                .get_query_pool_results(self.pool, 0, &mut raw, vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT)
        }
        .call("vkGetQueryPoolResults")?;
        let mask = self.mask();
        Ok(raw.into_iter().map(|t| t & mask).collect())
    }

    fn mask(&self) -> u64 {
        if self.bits >= 64 { u64::MAX } else { (1u64 << self.bits) - 1 }
    }

    /// The timings of the last submission (call after it completed).
    pub fn results(&self) -> VkResult<Vec<PassTiming>> {
        Ok(self.results_and_span()?.0)
    }

    /// The timings of the last submission and its span on the device's time line: (first
    /// timestamp, last timestamp) in milliseconds of device ticks, `None` when nothing was timed.
    /// The end is unwrapped past the start where the counter wrapped. Spans of different queues
    /// are comparable only where
    /// [`DeviceInfo::timestamps_across_queues`](super::DeviceInfo::timestamps_across_queues).
    /// One read of the queries serves both.
    pub fn results_and_span(&self) -> VkResult<(Vec<PassTiming>, Option<Span>)> {
        let raw = self.raw()?;
        let (mask, period) = (self.mask(), self.ctx.info.timestamp_period_ns as f64 * 1e-6);
        let passes = self
            .names
            .iter()
            .enumerate()
            .take(raw.len() / 2)
            .map(|(i, n)| {
                let ticks = raw[2 * i + 1].wrapping_sub(raw[2 * i]) & mask;
                PassTiming { name: n.clone(), ms: ticks as f64 * period, queue: self.queue, raster: self.raster[i], part: self.part[i] }
            })
            .collect();
        let span = raw.first().map(|&start| {
            let longest = raw.iter().map(|&t| t.wrapping_sub(start) & mask).max().unwrap_or(0);
            (start as f64 * period, (start as f64 + longest as f64) * period)
        });
        Ok((passes, span))
    }
}

impl Drop for Profiler {
    fn drop(&mut self) {
        if self.enabled() {
            unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
        }
    }
}
