//! `view --script FILE`: timed input and screenshots, for driving the viewer without a person.
//!
//! One event per line, `FRAME COMMAND [ARGUMENTS]`; `#` starts a comment, blank lines are
//! skipped. `FRAME` is the frame the event happens before (0 is the first frame), nondecreasing.
//! With a script each frame advances time by exactly 1/60 s (camera motion and the light
//! animation), so a script replays the same frames on any machine.
//!
//! | command | what |
//! |---|---|
//! | `down KEY` / `up KEY` | press / release a key (held keys move the camera) |
//! | `key KEY` | press a key, release it a frame later |
//! | `mouse-down right` / `mouse-up right` | the right mouse button (`left` too) |
//! | `mouse-move DX DY` | mouse motion in pixels (turns the camera while the right button is held) |
//! | `resize W H` | ask the window for `W × H` physical pixels; the script waits until it has them |
//! | `shot FILE.png` | write the frame (without the overlay) as PNG, and `FILE.json` beside it: the stats of `render --stats` and the viewer's state (camera bookmark, animation time, overlay text) |
//! | `presented FILE.png` | write the next frame as the window shows it: the swapchain image read back after the overlay, before it is presented |
//!
//! Keys: `W A S D Q E Ctrl Shift Tab 1`…`9` `Plus Minus H V C Space F1 F12 Escape`
//! (case-insensitive). E.g. `0 key Space` (pause the lights), `10 down W`, `40 up W`,
//! `41 shot a.png`, `42 key Tab`, `50 shot b.png`, `60 key Escape`.
use super::controls::{Button, Key};
use anyhow::{bail, Context as _, Result};
use std::path::{Path, PathBuf};

/// One scripted event.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    KeyDown(Key),
    KeyUp(Key),
    Button(Button, bool),
    MouseMove(f32, f32),
    Resize(u32, u32),
    Shot(PathBuf),
    /// The next presented swapchain image, read back.
    Presented(PathBuf),
}

/// A parsed script: events by frame, in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    events: Vec<(u64, Event)>,
    next: usize,
}

impl Script {
    /// Reads and parses `path`; errors name the file and line.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("--script {}: cannot read it", path.display()))?;
        Self::parse(&text).with_context(|| format!("--script {}", path.display()))
    }

    pub fn parse(text: &str) -> Result<Self> {
        let mut events = Vec::new();
        let mut last = 0;
        for (i, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let n = i + 1;
            let words: Vec<&str> = line.split_whitespace().collect();
            let frame: u64 = words[0].parse().map_err(|_| anyhow::anyhow!("line {n}: {:?} is not a frame number", words[0]))?;
            if frame < last {
                bail!("line {n}: frame {frame} comes before frame {last} of an earlier line");
            }
            last = frame;
            let args = &words[1..];
            let want = |count: usize| -> Result<()> {
                if args.len() != count + 1 {
                    bail!("line {n}: {:?} takes {count} argument(s)", args.first().copied().unwrap_or(""));
                }
                Ok(())
            };
            let key = |name: &str| Key::named(name).with_context(|| format!("line {n}: unknown key {name:?} (W A S D Q E Ctrl Shift Tab 1-9 Plus Minus G H V C Space F1 F12 Escape)"));
            let button = |name: &str| match name.to_ascii_lowercase().as_str() {
                "right" => Ok(Button::Right),
                "left" => Ok(Button::Left),
                _ => bail!("line {n}: unknown mouse button {name:?} (left, right)"),
            };
            let number = |s: &str| -> Result<f32> {
                s.parse::<f32>().ok().filter(|v| v.is_finite()).with_context(|| format!("line {n}: {s:?} is not a finite number"))
            };
            let size = |s: &str| -> Result<u32> {
                s.parse::<u32>().ok().filter(|&v| (1..=16384).contains(&v)).with_context(|| format!("line {n}: window size {s:?} is not in 1..=16384"))
            };
            match args.first().copied().unwrap_or("") {
                "down" => {
                    want(1)?;
                    events.push((frame, Event::KeyDown(key(args[1])?)));
                }
                "up" => {
                    want(1)?;
                    events.push((frame, Event::KeyUp(key(args[1])?)));
                }
                "key" => {
                    want(1)?;
                    let k = key(args[1])?;
                    events.push((frame, Event::KeyDown(k)));
                    events.push((frame + 1, Event::KeyUp(k)));
                }
                "mouse-down" | "mouse-up" => {
                    want(1)?;
                    events.push((frame, Event::Button(button(args[1])?, args[0] == "mouse-down")));
                }
                "mouse-move" => {
                    want(2)?;
                    events.push((frame, Event::MouseMove(number(args[1])?, number(args[2])?)));
                }
                "resize" => {
                    want(2)?;
                    events.push((frame, Event::Resize(size(args[1])?, size(args[2])?)));
                }
                "shot" | "presented" => {
                    want(1)?;
                    if !args[1].to_ascii_lowercase().ends_with(".png") {
                        bail!("line {n}: {} {:?}: the file must end in .png", args[0], args[1]);
                    }
                    let path = PathBuf::from(args[1]);
                    events.push((frame, if args[0] == "shot" { Event::Shot(path) } else { Event::Presented(path) }));
                }
                other => bail!("line {n}: unknown command {other:?} (down, up, key, mouse-down, mouse-up, mouse-move, resize, shot)"),
            }
        }
        // `key` adds its release a frame later: keep the events in frame order.
        events.sort_by_key(|e| e.0);
        Ok(Self { events, next: 0 })
    }

    /// The events due before frame `frame` that were not taken yet.
    pub fn due(&mut self, frame: u64) -> Vec<Event> {
        let start = self.next;
        while self.next < self.events.len() && self.events[self.next].0 <= frame {
            self.next += 1;
        }
        self.events[start..self.next].iter().map(|(_, e)| e.clone()).collect()
    }

    /// Every event was taken.
    pub fn finished(&self) -> bool {
        self.next == self.events.len()
    }

    /// The directories of the shots, to check before the window opens.
    pub fn shot_paths(&self) -> impl Iterator<Item = &Path> {
        self.events.iter().filter_map(|(_, e)| match e {
            Event::Shot(p) | Event::Presented(p) => Some(p.as_path()),
            _ => None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scripts_parse_into_frame_ordered_events() {
        let mut s = Script::parse("# fly\n0 key Space\n\n2 down w  # forward\n2 mouse-down right\n3 mouse-move 4 -2.5\n5 resize 1 1\n6 shot out/a.png\n").unwrap();
        assert_eq!(s.due(0), [Event::KeyDown(Key::Space)]);
        assert_eq!(s.due(2), [Event::KeyUp(Key::Space), Event::KeyDown(Key::W), Event::Button(Button::Right, true)]);
        assert_eq!(s.due(4), [Event::MouseMove(4.0, -2.5)]);
        assert!(!s.finished());
        assert_eq!(s.due(100), [Event::Resize(1, 1), Event::Shot("out/a.png".into())]);
        assert!(s.finished());
        assert_eq!(s.due(101), []);
    }

    #[test]
    fn bad_lines_are_one_line_errors_naming_the_line() {
        for (text, needle) in [
            ("x key W", "line 1: \"x\" is not a frame number"),
            ("5 key W\n3 key W", "line 2: frame 3 comes before frame 5"),
            ("0 key Banana", "unknown key \"Banana\""),
            ("0 key", "\"key\" takes 1 argument"),
            ("0 jump", "unknown command \"jump\""),
            ("0 resize 0 10", "window size \"0\""),
            ("0 mouse-move 1 nan", "\"nan\" is not a finite number"),
            ("0 shot a.jpg", "must end in .png"),
            ("0 mouse-down middle", "unknown mouse button"),
        ] {
            let e = format!("{:#}", Script::parse(text).unwrap_err());
            assert!(e.contains(needle) && !e.contains('\n'), "{text:?}: {e}");
        }
    }
}
