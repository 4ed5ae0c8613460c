//! The whole GPU frame's time, across both queues.
//!
//! A frame is what the GPU spends from the first timestamp of the frame to the last, on every
//! queue it used: the async-compute queue's light sort and BVH build start beside the G-buffer
//! raster, and the main queue waits for them before it shades, so neither queue's passes alone
//! (nor the sum of one queue's pass times, which leaves out waits and gaps) is the frame.
//!
//! Per timed frame ([`sample`]):
//! 1. each queue's span, first to last timestamp of its submission (`vk::Profiler::results_and_span`);
//! 2. the frame: from the earlier start to the later end of both spans — where the device's
//!    timestamps share one time line across queues (`DeviceInfo::timestamps_across_queues`).
//!    Elsewhere the spans cannot be compared, and the frame is the longer span: a lower bound,
//!    reported as such ([`FrameTime::across_queues`] false);
//! 3. the overlap: `main + async − frame`, the time both queues' spans ran at once;
//! 4. the frame outside raster passes: frame − the main queue's raster pass times (a GPU may run
//!    raster work on only part of the chip, so raster and the rest are reported apart).
//!
//! Over the timed frames each quantity's median ([`median`]), and the frame's min and max.

/// One frame's times, milliseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSample {
    pub frame_ms: f64,
    pub main_ms: f64,
    pub async_ms: f64,
    pub overlap_ms: f64,
    pub non_raster_ms: f64,
}

/// The frame time of a rendered frame: medians over the timed frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTime {
    /// The whole GPU frame, both queues: first to last timestamp.
    pub ms: f64,
    /// Fastest and slowest timed frame.
    pub min_ms: f64,
    pub max_ms: f64,
    /// The main queue's span (raster, compute and its waits for the async queue).
    pub main_ms: f64,
    /// The async-compute queue's span (0 when the frame used one queue).
    pub async_ms: f64,
    /// Time both queues ran at once (`main + async − frame`).
    pub overlap_ms: f64,
    /// The frame without the main queue's raster passes, with its fastest and slowest frame.
    pub non_raster_ms: f64,
    pub non_raster_min_ms: f64,
    pub non_raster_max_ms: f64,
    /// Whether the two queues' spans were compared on one time line (else `ms` is the longer
    /// span: a lower bound of the frame).
    pub across_queues: bool,
    /// Whether any frame was timed (devices without timestamps time none).
    pub timed: bool,
}

/// One frame's times from its queues' spans (`(start, end)` ms on each queue's time line) and the
/// sum of the main queue's raster pass times; `None` when the main queue was not timed.
pub fn sample(main: Option<(f64, f64)>, asynchronous: Option<(f64, f64)>, across_queues: bool, raster_ms: f64) -> Option<FrameSample> {
    let (m0, m1) = main?;
    let main_ms = m1 - m0;
    let (frame_ms, async_ms) = match asynchronous {
        None => (main_ms, 0.0),
        Some((a0, a1)) if across_queues => (m1.max(a1) - m0.min(a0), a1 - a0),
        Some((a0, a1)) => (main_ms.max(a1 - a0), a1 - a0),
    };
    Some(FrameSample { frame_ms, main_ms, async_ms, overlap_ms: (main_ms + async_ms - frame_ms).max(0.0), non_raster_ms: (frame_ms - raster_ms).max(0.0) })
}

/// (median, min, max) of `values` (the upper median of an even count); `None` for none. The
/// frame loop's per-pass medians use it too.
pub fn spread(values: impl IntoIterator<Item = f64>) -> Option<(f64, f64, f64)> {
    let mut v: Vec<f64> = values.into_iter().collect();
    v.sort_by(f64::total_cmp);
    Some((*v.get(v.len() / 2)?, v[0], v[v.len() - 1]))
}

/// Medians over the timed frames (and the frame's extremes).
pub fn median(samples: &[FrameSample], across_queues: bool) -> FrameTime {
    let of = |f: fn(&FrameSample) -> f64| spread(samples.iter().map(f));
    let (Some(frame), Some(non_raster)) = (of(|s| s.frame_ms), of(|s| s.non_raster_ms)) else {
        return FrameTime { across_queues, ..FrameTime::default() };
    };
    let med = |f: fn(&FrameSample) -> f64| of(f).map_or(0.0, |m| m.0);
    FrameTime {
        ms: frame.0,
        min_ms: frame.1,
        max_ms: frame.2,
        non_raster_ms: non_raster.0,
        non_raster_min_ms: non_raster.1,
        non_raster_max_ms: non_raster.2,
        main_ms: med(|s| s.main_ms),
        async_ms: med(|s| s.async_ms),
        overlap_ms: med(|s| s.overlap_ms),
        across_queues,
        timed: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The async queue outlasting the main queue's raster is the frame's tail: the frame runs from
    /// the earlier start to the later end, and the overlap is what both spans share.
    #[test]
    fn frame_spans_both_queues() {
        // Main 0–6 ms (raster 4 ms), async 0.5–9 ms.
        let s = sample(Some((100.0, 106.0)), Some((100.5, 109.0)), true, 4.0).unwrap();
        assert_eq!((s.frame_ms, s.main_ms, s.async_ms, s.overlap_ms, s.non_raster_ms), (9.0, 6.0, 8.5, 5.5, 5.0));
        // Without a shared time line: the longer span, a lower bound.
        let s = sample(Some((100.0, 106.0)), Some((7.0, 15.5)), false, 4.0).unwrap();
        assert_eq!((s.frame_ms, s.overlap_ms), (8.5, 6.0));
        // One queue.
        let s = sample(Some((3.0, 5.0)), None, true, 0.5).unwrap();
        assert_eq!((s.frame_ms, s.async_ms, s.overlap_ms, s.non_raster_ms), (2.0, 0.0, 0.0, 1.5));
        assert!(sample(None, Some((0.0, 1.0)), true, 0.0).is_none());
    }

    #[test]
    fn medians_and_extremes() {
        let f = |ms: f64| FrameSample { frame_ms: ms, main_ms: ms, async_ms: 0.0, overlap_ms: 0.0, non_raster_ms: ms / 2.0 };
        let t = median(&[f(3.0), f(1.0), f(2.0)], true);
        assert_eq!((t.ms, t.min_ms, t.max_ms, t.non_raster_ms, t.non_raster_min_ms, t.non_raster_max_ms, t.timed), (2.0, 1.0, 3.0, 1.0, 0.5, 1.5, true));
        assert!(!median(&[], false).timed);
        assert_eq!(spread([4.0, 1.0, 3.0, 2.0]), Some((3.0, 1.0, 4.0)));
        assert_eq!(spread([]), None);
    }
}
