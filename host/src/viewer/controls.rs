//! The viewer's controls, apart from any window system: keys and mouse buttons by name (what
//! `--script` files and the README use), the held-key state, the fly camera and the actions a
//! key press asks for. The window (`viewer::window`) and scripts (`viewer::script`) feed the same
//! [`Input`].
use crate::scene::bookmark::{Bookmark, MAX_PITCH};
use glam::Vec3;

/// A key the viewer reacts to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Key {
    W,
    A,
    S,
    D,
    Q,
    E,
    Ctrl,
    Shift,
    Tab,
    /// `1`–`9`: a technique by its number in the registry (`render::Technique::ALL`).
    Digit(u8),
    Plus,
    Minus,
    G,
    H,
    V,
    C,
    Space,
    F1,
    F12,
    Escape,
}

/// Key names as scripts write them (case-insensitive), with the key.
pub const KEY_NAMES: [(&str, Key); 28] = [
    ("w", Key::W),
    ("a", Key::A),
    ("s", Key::S),
    ("d", Key::D),
    ("q", Key::Q),
    ("e", Key::E),
    ("ctrl", Key::Ctrl),
    ("shift", Key::Shift),
    ("tab", Key::Tab),
    ("1", Key::Digit(1)),
    ("2", Key::Digit(2)),
    ("3", Key::Digit(3)),
    ("4", Key::Digit(4)),
    ("5", Key::Digit(5)),
    ("6", Key::Digit(6)),
    ("7", Key::Digit(7)),
    ("8", Key::Digit(8)),
    ("9", Key::Digit(9)),
    ("plus", Key::Plus),
    ("minus", Key::Minus),
    ("g", Key::G),
    ("h", Key::H),
    ("v", Key::V),
    ("c", Key::C),
    ("space", Key::Space),
    ("f1", Key::F1),
    ("f12", Key::F12),
    ("escape", Key::Escape),
];

impl Key {
    /// The key a script names (`W`, `Tab`, `1`, `Plus`, `F12`, `Escape`, …).
    pub fn named(name: &str) -> Option<Key> {
        let lower = name.to_ascii_lowercase();
        let lower = if lower == "esc" { "escape".to_string() } else { lower };
        KEY_NAMES.iter().find(|(n, _)| *n == lower).map(|&(_, k)| k)
    }
}

/// A mouse button the viewer reacts to (the right one: held, it turns the camera).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Button {
    Left,
    Right,
}

/// What a key press asks the viewer to do (held keys move the camera instead).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Tab: the next technique.
    NextTechnique,
    /// `1`–`9`: technique `i` (0-based) of `Technique::ALL` (a number past the registry's
    /// techniques does nothing).
    Technique(usize),
    /// `+` / `-`: twice / half the lights.
    MoreLights,
    FewerLights,
    /// G: shadows on or off (the lights that cast them).
    ToggleShadows,
    /// H: heatmap on or off.
    ToggleHeatmap,
    /// V: the next view (shaded, heatmap, clusters, normals, depth).
    NextView,
    /// Space: pause or resume the light animation.
    TogglePause,
    /// F12: PNG + stats JSON of the current frame.
    Screenshot,
    /// C: print the camera bookmark.
    PrintCamera,
    /// F1: overlay on or off.
    ToggleOverlay,
    Quit,
}

impl Action {
    /// The action of pressing `key` (`None`: a movement key, held rather than pressed).
    pub fn of(key: Key) -> Option<Action> {
        Some(match key {
            Key::Tab => Action::NextTechnique,
            Key::Digit(d) => Action::Technique(d.saturating_sub(1) as usize),
            Key::Plus => Action::MoreLights,
            Key::Minus => Action::FewerLights,
            Key::G => Action::ToggleShadows,
            Key::H => Action::ToggleHeatmap,
            Key::V => Action::NextView,
            Key::Space => Action::TogglePause,
            Key::F12 => Action::Screenshot,
            Key::C => Action::PrintCamera,
            Key::F1 => Action::ToggleOverlay,
            Key::Escape => Action::Quit,
            Key::W | Key::A | Key::S | Key::D | Key::Q | Key::E | Key::Ctrl | Key::Shift => return None,
        })
    }
}

/// Keys and buttons held, mouse motion and key presses since the last frame.
#[derive(Debug, Default)]
pub struct Input {
    held: Vec<Key>,
    right_held: bool,
    /// Mouse motion (pixels) while the right button was held, since the last frame.
    look: (f32, f32),
    /// Actions of the keys pressed since the last frame, in order.
    pub actions: Vec<Action>,
}

impl Input {
    pub fn key_down(&mut self, key: Key) {
        if self.held.contains(&key) {
            return; // auto-repeat
        }
        self.held.push(key);
        if let Some(a) = Action::of(key) {
            self.actions.push(a);
        }
    }

    pub fn key_up(&mut self, key: Key) {
        self.held.retain(|&k| k != key);
    }

    pub fn button(&mut self, button: Button, down: bool) {
        if button == Button::Right {
            self.right_held = down;
        }
    }

    /// Mouse motion by `(dx, dy)` pixels: turns the camera while the right button is held.
    pub fn mouse_motion(&mut self, dx: f32, dy: f32) {
        if self.right_held {
            self.look.0 += dx;
            self.look.1 += dy;
        }
    }

    pub fn is_held(&self, key: Key) -> bool {
        self.held.contains(&key)
    }

    /// Forgets every held key and button (the window lost focus).
    pub fn release_all(&mut self) {
        self.held.clear();
        self.right_held = false;
    }

    /// Takes the frame's mouse look and actions.
    pub fn take(&mut self) -> ((f32, f32), Vec<Action>) {
        (std::mem::take(&mut self.look), std::mem::take(&mut self.actions))
    }
}

/// Degrees of turn per pixel of mouse motion.
pub const LOOK_DEGREES_PER_PIXEL: f32 = 0.2;
/// Speed factors of Ctrl (slower) and Shift (faster).
pub const SLOW: f32 = 0.2;
pub const FAST: f32 = 5.0;

/// A fly camera: a bookmark moved by held keys and turned by the mouse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    pub at: Bookmark,
    /// World units per second without Ctrl or Shift.
    pub speed: f32,
}

impl FlyCamera {
    /// Advances by `dt` seconds of `input`'s held keys and `look` (pixels of mouse motion);
    /// returns whether the camera changed. W/S move along the view, A/D sideways, Q/E down/up.
    pub fn update(&mut self, input: &Input, look: (f32, f32), dt: f32) -> bool {
        let before = self.at;
        if look != (0.0, 0.0) {
            self.at.yaw = (self.at.yaw + look.0 * LOOK_DEGREES_PER_PIXEL).rem_euclid(360.0);
            self.at.pitch = (self.at.pitch - look.1 * LOOK_DEGREES_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
        }
        let forward = self.at.direction();
        let right = forward.cross(Vec3::Y).normalize_or_zero();
        let axis = |plus: Key, minus: Key| f32::from(u8::from(input.is_held(plus))) - f32::from(u8::from(input.is_held(minus)));
        let step = forward * axis(Key::W, Key::S) + right * axis(Key::D, Key::A) + Vec3::Y * axis(Key::E, Key::Q);
        if step != Vec3::ZERO {
            let mut speed = self.speed;
            if input.is_held(Key::Ctrl) {
                speed *= SLOW;
            }
            if input.is_held(Key::Shift) {
                speed *= FAST;
            }
            self.at.eye += step.normalize() * speed * dt;
        }
        self.at != before
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> FlyCamera {
        FlyCamera { at: Bookmark { eye: Vec3::ZERO, yaw: 0.0, pitch: 0.0, fov_y_degrees: Some(60.0) }, speed: 10.0 }
    }

    #[test]
    fn keys_have_names_and_actions() {
        assert_eq!(Key::named("TAB"), Some(Key::Tab));
        assert_eq!(Key::named("esc"), Some(Key::Escape));
        assert_eq!(Key::named("7"), Some(Key::Digit(7)));
        assert_eq!(Key::named("9"), Some(Key::Digit(9)));
        assert_eq!(Key::named("0"), None);
        assert_eq!(Action::of(Key::Digit(3)), Some(Action::Technique(2)));
        assert_eq!(Action::of(Key::W), None);
        let mut input = Input::default();
        input.key_down(Key::H);
        input.key_down(Key::H); // auto-repeat: one press
        input.key_up(Key::H);
        input.key_down(Key::H);
        assert_eq!(input.take().1, [Action::ToggleHeatmap, Action::ToggleHeatmap]);
    }

    #[test]
    fn held_keys_fly_and_the_right_button_turns() {
        let mut c = camera();
        let mut input = Input::default();
        assert!(!c.update(&input, (0.0, 0.0), 1.0), "nothing held: no change");
        input.key_down(Key::W);
        assert!(c.update(&input, (0.0, 0.0), 0.5));
        assert!(c.at.eye.abs_diff_eq(Vec3::new(0.0, 0.0, -5.0), 1e-5), "{:?}", c.at.eye);
        input.key_down(Key::Shift);
        input.key_up(Key::W);
        input.key_down(Key::E);
        c.update(&input, (0.0, 0.0), 0.1);
        assert!(c.at.eye.abs_diff_eq(Vec3::new(0.0, 5.0, -5.0), 1e-4), "E up, Shift ×5: {:?}", c.at.eye);
        input.mouse_motion(100.0, 0.0);
        assert_eq!(input.take().0, (0.0, 0.0), "no look without the right button");
        input.button(Button::Right, true);
        input.mouse_motion(450.0, -1000.0);
        let (look, _) = input.take();
        input.release_all();
        c.update(&input, look, 0.0);
        assert_eq!(c.at.yaw, 90.0);
        assert_eq!(c.at.pitch, MAX_PITCH, "pitch is clamped");
    }
}
