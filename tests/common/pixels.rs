//! Comparing frames of packed RGBA8 pixels (`0xAABBGGRR`).

/// The largest difference of one 8-bit channel between two pixels.
pub fn channel_diff(a: u32, b: u32) -> u32 {
    (0..4).map(|s| ((a >> (8 * s)) & 255).abs_diff((b >> (8 * s)) & 255)).max().unwrap()
}

/// The largest channel difference over two frames; panics when their sizes differ (a shorter
/// frame must not pass by comparing only its pixels).
pub fn worst_channel(a: &[u32], b: &[u32]) -> u32 {
    assert_eq!(a.len(), b.len(), "frames of different sizes");
    a.iter().zip(b).map(|(a, b)| channel_diff(*a, *b)).max().unwrap_or(0)
}

/// Pixels brighter than a dim grey (packed RGB above `0x040404`): how much of a frame is lit.
pub fn lit(pixels: &[u32]) -> usize {
    pixels.iter().filter(|&&p| p & 0x00ff_ffff > 0x0004_0404).count()
}
