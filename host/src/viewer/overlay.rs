//! The overlay's content and layout (egui; drawn by `vk::Overlay`): technique, lights, view,
//! per-pass GPU milliseconds as rolling medians, clusters and lights per cluster, notes, and a
//! graph of the last frames' GPU times. F1 hides it; screenshots never hold it (it is drawn into
//! the window's image, not the frame).
use crate::render::frame_time;
use crate::render::FrameTimes;
use std::collections::VecDeque;

/// Frames the rolling medians and the graph span.
pub const WINDOW: usize = 120;

/// Frames a note stays on the overlay.
pub const NOTE_FRAMES: u32 = 180;

/// Light lists as the overlay shows them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lists {
    pub clusters: u32,
    pub mean: f64,
    pub max: u32,
}

/// What the overlay shows, gathered frame by frame.
#[derive(Default)]
pub struct OverlayText {
    /// Per pass: its name and its last [`WINDOW`] times (ms).
    passes: Vec<(String, VecDeque<f64>)>,
    /// The last [`WINDOW`] whole-frame GPU times (ms).
    frames: VecDeque<f64>,
    pub lists: Option<Lists>,
    /// Notes shown for a while: (text, frames left).
    notes: Vec<(String, u32)>,
}

fn push(q: &mut VecDeque<f64>, v: f64) {
    if q.len() == WINDOW {
        q.pop_front();
    }
    q.push_back(v);
}

fn median(q: &VecDeque<f64>) -> f64 {
    frame_time::spread(q.iter().copied()).map_or(0.0, |(m, _, _)| m)
}

impl OverlayText {
    /// Adds a frame's times.
    pub fn add(&mut self, t: &FrameTimes) {
        for p in &t.passes {
            match self.passes.iter_mut().find(|(n, _)| *n == p.name) {
                Some((_, q)) => push(q, p.ms),
                None => self.passes.push((p.name.clone(), VecDeque::from([p.ms]))),
            }
        }
        if let Some(s) = t.sample {
            push(&mut self.frames, s.frame_ms);
        }
        for n in &mut self.notes {
            n.1 = n.1.saturating_sub(1);
        }
        self.notes.retain(|n| n.1 > 0);
    }

    /// Forgets the times (a new technique or frame size has other passes).
    pub fn reset(&mut self) {
        self.passes.clear();
        self.frames.clear();
        self.lists = None;
    }

    /// Shows `text` for the next [`NOTE_FRAMES`] frames.
    pub fn note(&mut self, text: String) {
        self.notes.push((text, NOTE_FRAMES));
    }

    /// The overlay's lines: `header` (technique, lights, view, …), then passes, lists and notes.
    pub fn lines(&self, header: &[String]) -> Vec<String> {
        let mut out = header.to_vec();
        if !self.frames.is_empty() {
            out.push(format!("GPU frame {:.3} ms (median of {})", median(&self.frames), self.frames.len()));
        }
        for (name, q) in &self.passes {
            out.push(format!("  {name:<14} {:8.3} ms", median(q)));
        }
        match self.lists {
            Some(l) if l.clusters > 0 => out.push(format!("clusters {}   lights/cluster mean {:.1} max {}", l.clusters, l.mean, l.max)),
            _ => {}
        }
        out.extend(self.notes.iter().map(|n| n.0.clone()));
        out
    }

    /// Lays out the overlay for a window of `size` physical pixels: the tessellated shapes and
    /// texture changes egui asks for.
    pub fn layout(&self, egui: &egui::Context, size: (u32, u32), lines: &[String]) -> (egui::TexturesDelta, Vec<egui::ClippedPrimitive>, f32) {
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(size.0 as f32, size.1 as f32))),
            ..Default::default()
        };
        let frames: Vec<f64> = self.frames.iter().copied().collect();
        let out = egui.run_ui(input, |ui| {
            egui::Area::new(egui::Id::new("manylights overlay")).fixed_pos(egui::pos2(6.0, 6.0)).show(ui.ctx(), |ui| {
                egui::Frame::new().fill(egui::Color32::from_black_alpha(170)).inner_margin(6.0).corner_radius(4.0).show(ui, |ui| {
                    for l in lines {
                        ui.label(egui::RichText::new(l).monospace().size(11.0).color(egui::Color32::from_gray(230)));
                    }
                    graph(ui, &frames);
                });
            });
        });
        let ppp = out.pixels_per_point;
        let primitives = egui.tessellate(out.shapes, ppp);
        (out.textures_delta, primitives, ppp)
    }
}

/// The frame-time graph: one bar per frame, scaled to the slowest shown (named above it).
fn graph(ui: &mut egui::Ui, frames: &[f64]) {
    if frames.is_empty() {
        return;
    }
    let top = frames.iter().copied().fold(f64::MIN_POSITIVE, f64::max);
    ui.label(egui::RichText::new(format!("GPU frame, last {} frames (top {top:.2} ms)", frames.len())).monospace().size(9.0).color(egui::Color32::from_gray(200)));
    let (rect, _) = ui.allocate_exact_size(egui::vec2(WINDOW as f32 * 2.0, 40.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, egui::Color32::from_black_alpha(120));
    for (i, &ms) in frames.iter().enumerate() {
        let h = (ms / top) as f32 * rect.height();
        let x = rect.left() + 2.0 * i as f32 + 1.0;
        painter.line_segment([egui::pos2(x, rect.bottom()), egui::pos2(x, rect.bottom() - h)], egui::Stroke::new(1.5, egui::Color32::from_rgb(120, 200, 120)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::{PassTiming, Queue};

    fn times(ms: f64) -> FrameTimes {
        let pass = |name: &str| PassTiming { name: name.into(), ms, queue: Queue::Main, raster: false, part: false };
        FrameTimes { passes: vec![pass("gbuffer"), pass("shading")], sample: Some(frame_time::FrameSample { frame_ms: 2.0 * ms, main_ms: 2.0 * ms, async_ms: 0.0, overlap_ms: 0.0, non_raster_ms: ms }) }
    }

    #[test]
    fn lines_show_rolling_medians_lists_and_notes() {
        let mut o = OverlayText::default();
        for ms in [1.0, 9.0, 2.0] {
            o.add(&times(ms));
        }
        o.lists = Some(Lists { clusters: 12, mean: 3.25, max: 7 });
        o.note("paused".into());
        let lines = o.lines(&["technique clustered-naive".into()]);
        assert_eq!(lines[0], "technique clustered-naive");
        assert_eq!(lines[1], "GPU frame 4.000 ms (median of 3)");
        assert!(lines[2].contains("gbuffer") && lines[2].ends_with("2.000 ms"), "{lines:?}");
        assert!(lines.contains(&"clusters 12   lights/cluster mean 3.2 max 7".to_string()) || lines.contains(&"clusters 12   lights/cluster mean 3.3 max 7".to_string()), "{lines:?}");
        assert_eq!(lines.last().map(String::as_str), Some("paused"));
        for _ in 0..NOTE_FRAMES {
            o.add(&times(1.0));
        }
        assert_eq!(o.lines(&[])[0], "GPU frame 2.000 ms (median of 120)", "the window rolls");
        assert!(!o.lines(&[]).contains(&"paused".to_string()), "notes expire");
    }
}
