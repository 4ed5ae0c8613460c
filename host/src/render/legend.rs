//! The heatmap legend: a colour bar of `lighting::heat_ramp` (the very function the shading
//! kernels use) from 0 to `max` lights, with tick labels, drawn into the bottom-left corner of
//! the frame. Digits use a 3×5 bitmap font scaled ×2 (no font dependency).
use shaders::lighting::{encode_srgb8, heat_ramp};

const GLYPHS: [[u8; 5]; 11] = [
    [0b111, 0b101, 0b101, 0b101, 0b111], // 0
    [0b010, 0b110, 0b010, 0b010, 0b111], // 1
    [0b111, 0b001, 0b111, 0b100, 0b111], // 2
    [0b111, 0b001, 0b111, 0b001, 0b111], // 3
    [0b101, 0b101, 0b111, 0b001, 0b001], // 4
    [0b111, 0b100, 0b111, 0b001, 0b111], // 5
    [0b111, 0b100, 0b111, 0b101, 0b111], // 6
    [0b111, 0b001, 0b001, 0b001, 0b001], // 7
    [0b111, 0b101, 0b111, 0b101, 0b111], // 8
    [0b111, 0b101, 0b111, 0b001, 0b111], // 9
    [0b000, 0b010, 0b111, 0b010, 0b000], // +
];
const SCALE: u32 = 2;
const BAR_W: u32 = 256;
const BAR_H: u32 = 12;
const MARGIN: u32 = 8;
/// Height of the legend box: bar, gap, digits.
pub const LEGEND_H: u32 = BAR_H + 4 + 5 * SCALE + 2 * MARGIN;
const WHITE: u32 = 0xffff_ffff;
const BOX: u32 = 0xff20_1818;

fn put(px: &mut [u32], w: u32, x: u32, y: u32, c: u32) {
    if let Some(p) = px.get_mut((y * w + x) as usize) {
        *p = c;
    }
}

fn text(px: &mut [u32], w: u32, x0: u32, y0: u32, s: &str) {
    for (n, ch) in s.chars().enumerate() {
        let g = match ch {
            '0'..='9' => GLYPHS[ch as usize - '0' as usize],
            '+' => GLYPHS[10],
            _ => continue,
        };
        for (row, bits) in g.iter().enumerate() {
            for col in 0..3 {
                if bits & (0b100 >> col) != 0 {
                    for dy in 0..SCALE {
                        for dx in 0..SCALE {
                            let x = x0 + (n as u32 * 4 + col) * SCALE + dx;
                            put(px, w, x, y0 + row as u32 * SCALE + dy, WHITE);
                        }
                    }
                }
            }
        }
    }
}

/// Draws the legend for counts `0..=max` (the top colour means `max` or more). Frames smaller
/// than the legend are left untouched (returns false).
pub fn draw(px: &mut [u32], w: u32, h: u32, max: u32) -> bool {
    let box_w = BAR_W + 2 * MARGIN + 8 * SCALE;
    if w < box_w || h < LEGEND_H || px.len() != (w * h) as usize {
        return false;
    }
    let y_box = h - LEGEND_H;
    for y in y_box..h {
        for x in 0..box_w {
            put(px, w, x, y, BOX);
        }
    }
    let y_bar = y_box + MARGIN;
    for x in 0..BAR_W {
        let count = ((x as f32 + 0.5) / BAR_W as f32 * max as f32) as u32;
        let c = encode_srgb8(heat_ramp(count, max));
        for y in y_bar..y_bar + BAR_H {
            put(px, w, MARGIN + x, y, c);
        }
    }
    for t in 0..=4u32 {
        let value = max * t / 4;
        let label = if t == 4 { format!("{value}+") } else { value.to_string() };
        let x = MARGIN + (BAR_W - 1) * t / 4;
        for y in y_bar + BAR_H..y_bar + BAR_H + 3 {
            put(px, w, x, y, WHITE);
        }
        let text_w = label.len() as u32 * 4 * SCALE;
        text(px, w, x.saturating_sub(text_w / 2).max(MARGIN / 2), y_bar + BAR_H + 4, &label);
    }
    true
}

#[cfg(test)]
mod tests {
    #[test]
    fn legend_draws_the_ramp_and_labels_only_when_it_fits() {
        let (w, h) = (320, 120);
        let mut px = vec![0u32; (w * h) as usize];
        assert!(super::draw(&mut px, w, h, 64));
        let y = h - super::LEGEND_H + 8 + 6;
        let first = px[(y * w + 8) as usize];
        let last = px[(y * w + 8 + 255) as usize];
        assert_ne!(first, last, "the bar spans the ramp");
        assert!(px.contains(&super::WHITE), "labels are drawn");
        let mut tiny = vec![0u32; 100];
        assert!(!super::draw(&mut tiny, 10, 10, 64), "a 10x10 frame has no room for a legend");
        assert!(tiny.iter().all(|&p| p == 0));
    }
}
