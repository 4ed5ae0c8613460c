//! `manylights view`: an interactive window rendering every frame with the passes of `render`
//! (the same [`crate::render::Renderer`]); only the last step differs — the frame buffer is
//! copied into the window's swapchain image (`vk::present`) instead of read back into a PNG.
//!
//! Parts: `controls.rs` (keys, the fly camera, actions), `state.rs` (scene, lights, settings,
//! renderer), `script.rs` (`--script`), `overlay.rs` (the overlay's text and graph, drawn by
//! `vk::overlay`), and here the window (winit, X11) and its event loop: one frame per redraw,
//! continuously; nothing is rendered while the window has no extent (minimised).
pub mod controls;
pub mod overlay;
pub mod script;
pub mod state;

use crate::bad_input::{bad_input, one_line};
use crate::cli::DeviceArgs;
use crate::gpu::Gpu;
use crate::render_cmd::RenderArgs;
use crate::vk::{Overlay, PresentMode, Presented, Presenter};
use anyhow::{anyhow, bail, Context as _, Result};
use controls::{Action, Button, Input, Key};
use raw_window_handle::HasDisplayHandle;
use script::{Event, Script};
use state::Viewer;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// Arguments of `view`: every flag of `render` (its `--width`/`--height` size the window; `--out`
/// names the F12 screenshots, numbered: `frame-0001.png`, …; `--frames N`: a screenshot's and
/// `--stats`' timings are medians of the last N frames; `--stats FILE`: the last frame's
/// statistics, written when the viewer exits; `--tess-level` / `--tess-error` as in `render`)
/// and the viewer's own.
#[derive(clap::Args, Debug, Clone)]
pub struct ViewArgs {
    #[command(flatten)]
    pub render: RenderArgs,
    /// How frames reach the screen; a mode the window system lacks falls back to fifo with a
    /// warning.
    #[arg(long, value_enum, default_value_t = PresentMode::Fifo)]
    pub present_mode: PresentMode,
    /// Drive the viewer from a file of timed key, mouse, resize and screenshot events
    /// (`viewer::script` documents the format); frames then advance time by 1/60 s each.
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Exit (status 0) after this many frames.
    #[arg(long)]
    pub exit_after: Option<u64>,
    /// Start with the overlay hidden (F1 shows it).
    #[arg(long)]
    pub no_overlay: bool,
}

/// Seconds a scripted resize may take before the run fails.
const RESIZE_TIMEOUT: Duration = Duration::from_secs(10);
/// Longest time step of an interactive frame (a stall does not fling the camera away).
const MAX_DT: f32 = 0.25;

pub fn run(dev: &DeviceArgs, a: &ViewArgs) -> Result<()> {
    let script = a.script.as_deref().map(Script::load).transpose().map_err(bad_input)?;
    if let Some(s) = &script {
        for p in s.shot_paths() {
            crate::args::check_output_dir("--script shot", p)?;
        }
    }
    let event_loop = EventLoop::new().map_err(|e| anyhow!("cannot open a window: {}", window_system_error(&e.to_string())))?;
    let display = event_loop.display_handle().map_err(|e| anyhow!("cannot open a window: {e}"))?.as_raw();
    let gpu = crate::cli::open_for_display(dev, display)?;
    let viewer = Viewer::new(&gpu, &a.render)?;
    let mut app = App {
        overlay: None,
        presenter: None,
        window: None,
        viewer,
        egui: egui::Context::default(),
        gpu,
        args: a.clone(),
        script,
        input: Input::default(),
        show_overlay: !a.no_overlay,
        cursor: None,
        last: None,
        pending_resize: None,
        shots: 0,
        steps: 0,
        presented_shot: None,
        error: None,
    };
    event_loop.run_app(&mut app).map_err(|e| anyhow!("the window's event loop failed: {e}"))?;
    if let (None, Some(path)) = (&app.error, &a.render.stats) {
        let lines = app.overlay_lines();
        if let Err(e) = app.viewer.write_stats(&app.gpu, path, &lines) {
            app.error = Some(e.context(format!("--stats {}", path.display())));
        }
    }
    let App { overlay, presenter, window, viewer, gpu, error, .. } = app;
    // The swapchain and surface go before the window; the renderer before the device.
    drop((overlay, presenter, window, viewer));
    if let Some(e) = error {
        crate::cli::finish(&gpu).map_err(|v| anyhow!("{}: {v}", one_line(&e)))?;
        return Err(e);
    }
    crate::cli::finish(&gpu)
}

/// What the window system said, without the source location winit puts before it; with no
/// display at all, what to do.
fn window_system_error(text: &str) -> String {
    if std::env::var("DISPLAY").map_or(true, |d| d.is_empty()) {
        return "no X11 display (DISPLAY is not set): run it in a desktop session, or under a virtual display (xvfb-run)".into();
    }
    match text.find(".rs:").and_then(|i| text[i..].find(": ").map(|j| i + j + 2)) {
        Some(start) => text[start..].to_string(),
        None => text.to_string(),
    }
}

/// The window and everything that draws into it. Fields drop in order: the overlay and the
/// swapchain before the window, the renderer before the device.
struct App {
    overlay: Option<Overlay>,
    presenter: Option<Presenter>,
    window: Option<Arc<Window>>,
    viewer: Viewer,
    egui: egui::Context,
    gpu: Gpu,
    args: ViewArgs,
    script: Option<Script>,
    input: Input,
    show_overlay: bool,
    cursor: Option<(f64, f64)>,
    /// When the last frame was rendered (interactive time steps).
    last: Option<Instant>,
    /// A scripted resize the window has not taken yet: size and deadline.
    pending_resize: Option<((u32, u32), Instant)>,
    /// F12 screenshots taken.
    shots: u32,
    /// Frames stepped (the script's clock).
    steps: u64,
    /// Where the presented image a script asked for goes (`presented FILE.png`).
    presented_shot: Option<PathBuf>,
    error: Option<anyhow::Error>,
}

fn key_of(code: KeyCode) -> Option<Key> {
    Some(match code {
        KeyCode::KeyW => Key::W,
        KeyCode::KeyA => Key::A,
        KeyCode::KeyS => Key::S,
        KeyCode::KeyD => Key::D,
        KeyCode::KeyQ => Key::Q,
        KeyCode::KeyE => Key::E,
        KeyCode::ControlLeft | KeyCode::ControlRight => Key::Ctrl,
        KeyCode::ShiftLeft => Key::Shift,
        KeyCode::Tab => Key::Tab,
        KeyCode::Digit1 => Key::Digit(1),
        KeyCode::Digit2 => Key::Digit(2),
        KeyCode::Digit3 => Key::Digit(3),
        KeyCode::Digit4 => Key::Digit(4),
        KeyCode::Digit5 => Key::Digit(5),
        KeyCode::Digit6 => Key::Digit(6),
        KeyCode::Digit7 => Key::Digit(7),
        KeyCode::Digit8 => Key::Digit(8),
        KeyCode::Digit9 => Key::Digit(9),
        KeyCode::Equal | KeyCode::NumpadAdd => Key::Plus,
        KeyCode::Minus | KeyCode::NumpadSubtract => Key::Minus,
        KeyCode::KeyG => Key::G,
        KeyCode::KeyH => Key::H,
        KeyCode::KeyV => Key::V,
        KeyCode::KeyC => Key::C,
        KeyCode::Space => Key::Space,
        KeyCode::F1 => Key::F1,
        KeyCode::F12 => Key::F12,
        KeyCode::Escape => Key::Escape,
        _ => return None,
    })
}

impl App {
    fn fail(&mut self, el: &ActiveEventLoop, e: anyhow::Error) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        el.exit();
    }

    fn open_window(&mut self, el: &ActiveEventLoop) -> Result<()> {
        let s = &self.viewer.settings;
        let attributes = Window::default_attributes()
            .with_title(format!("manylights — {}", self.viewer.scene.name))
            .with_inner_size(PhysicalSize::new(s.width, s.height));
        let window = Arc::new(el.create_window(attributes).context("creating the window")?);
        let size = window.inner_size();
        let (presenter, warning) = Presenter::new(&self.gpu.ctx, window.as_ref(), self.args.present_mode, (size.width, size.height)).context("presenting to the window")?;
        if let Some(w) = warning {
            eprintln!("warning: {w}");
            self.viewer.text.note(w);
        }
        self.overlay = Some(Overlay::new(&self.gpu.ctx, &presenter).context("creating the overlay")?);
        self.presenter = Some(presenter);
        self.window = Some(window);
        Ok(())
    }

    /// The overlay's current lines.
    fn overlay_lines(&self) -> Vec<String> {
        let mode = self.presenter.as_ref().map_or_else(String::new, Presenter::mode);
        self.viewer.text.lines(&self.viewer.header(&mode))
    }

    /// Applies the script's events due at this step; `false` while a resize is under way (the
    /// step waits for it).
    fn scripted(&mut self) -> Result<bool> {
        if let Some((size, deadline)) = self.pending_resize {
            let now = self.window.as_ref().map(|w| w.inner_size()).map(|s| (s.width, s.height));
            if now != Some(size) {
                if Instant::now() > deadline {
                    bail!("--script: the window did not take the size {}x{} within {} s (it is {now:?})", size.0, size.1, RESIZE_TIMEOUT.as_secs());
                }
                return Ok(false);
            }
            if let Some(p) = self.presenter.as_mut() {
                p.resize(size);
            }
            self.pending_resize = None;
        }
        let Some(script) = self.script.as_mut() else { return Ok(true) };
        for event in script.due(self.steps) {
            match event {
                Event::KeyDown(k) => self.input.key_down(k),
                Event::KeyUp(k) => self.input.key_up(k),
                Event::Button(b, down) => self.input.button(b, down),
                Event::MouseMove(dx, dy) => self.input.mouse_motion(dx, dy),
                Event::Resize(w, h) => {
                    if let Some(window) = &self.window {
                        let _ = window.request_inner_size(PhysicalSize::new(w, h));
                    }
                    self.pending_resize = Some(((w, h), Instant::now() + RESIZE_TIMEOUT));
                    return Ok(false); // later events wait for the new size
                }
                Event::Shot(path) => {
                    let lines = self.overlay_lines();
                    self.viewer.screenshot(&self.gpu, &path, &lines).with_context(|| format!("--script shot {}", path.display()))?;
                    eprintln!("wrote {}", path.display());
                }
                Event::Presented(path) => {
                    let p = self.presenter.as_mut().context("--script presented: no window to read back")?;
                    p.capture_next().with_context(|| format!("--script presented {}", path.display()))?;
                    self.presented_shot = Some(path);
                }
            }
        }
        Ok(true)
    }

    /// One step: script events, the window's actions, camera and animation, then a frame
    /// rendered and presented. Returns whether the viewer should exit.
    fn step(&mut self) -> Result<bool> {
        if !self.scripted()? {
            return Ok(false);
        }
        if self.window.as_ref().and_then(|w| w.is_minimized()) == Some(true) {
            return Ok(false); // minimised: nothing to render
        }
        let extent = match self.presenter.as_mut() {
            Some(p) => p.prepare()?,
            None => None,
        };
        let Some(extent) = extent else {
            return Ok(false); // no extent: nothing to render
        };
        let now = Instant::now();
        let dt = match (&self.script, self.last) {
            (Some(_), _) => 1.0 / 60.0,
            (None, Some(last)) => now.duration_since(last).as_secs_f32().min(MAX_DT),
            (None, None) => 0.0,
        };
        self.last = Some(now);
        // The renderer first: the actions change it (and are refused where it cannot take them).
        self.viewer.ensure_size(&self.gpu, extent.0, extent.1)?;
        let (look, actions) = self.input.take();
        for action in actions {
            match action {
                Action::Quit => return Ok(true),
                Action::ToggleOverlay => self.show_overlay = !self.show_overlay,
                Action::PrintCamera => {
                    println!("{}", self.viewer.bookmark_flags());
                    self.viewer.text.note(format!("camera: {}", self.viewer.bookmark_flags()));
                }
                Action::Screenshot => {
                    self.shots += 1;
                    let out = &self.args.render.frame.out;
                    let stem = out.file_stem().map_or_else(|| "frame".into(), |s| s.to_string_lossy().into_owned());
                    let path = out.with_file_name(format!("{stem}-{:04}.png", self.shots));
                    let lines = self.overlay_lines();
                    let note = match self.viewer.screenshot(&self.gpu, &path, &lines) {
                        Ok(()) => format!("wrote {}", path.display()),
                        Err(e) => format!("screenshot failed: {}", one_line(&e)),
                    };
                    eprintln!("{note}");
                    self.viewer.text.note(note);
                }
                other => self.viewer.apply(&self.gpu, other),
            }
        }
        self.viewer.advance(&self.input, look, dt);
        self.viewer.render(&self.gpu)?;
        let lines = self.show_overlay.then(|| self.overlay_lines());
        let overlay = match (lines, self.overlay.as_mut()) {
            (Some(lines), Some(o)) => {
                let (textures, primitives, ppp) = self.viewer.text.layout(&self.egui, extent, &lines);
                o.set_frame(textures, primitives, ppp)?;
                Some(o)
            }
            _ => None,
        };
        let (Some(presenter), Some(renderer)) = (self.presenter.as_mut(), self.viewer.renderer()) else { return Ok(false) };
        let s = renderer.settings();
        if presenter.present(renderer.frame_buffer(), s.width, s.height, overlay)? == Presented::Shown {
            self.steps += 1;
        }
        if let Some((w, h, pixels)) = presenter.take_capture() {
            let path = self.presented_shot.take().context("a presented image nobody asked for")?;
            crate::debug_frame::save_png(&path, w, h, &pixels).with_context(|| format!("--script presented {}", path.display()))?;
            eprintln!("wrote {}", path.display());
        }
        let messages = self.gpu.ctx.validation_messages();
        if !messages.is_empty() {
            bail!("stopped at frame {}", self.steps);
        }
        Ok(self.args.exit_after.is_some_and(|n| self.steps >= n))
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        if let Err(e) = self.open_window(el) {
            self.fail(el, e);
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::Resized(size) => {
                if let Some(p) = self.presenter.as_mut() {
                    p.resize((size.width, size.height));
                }
            }
            WindowEvent::Focused(false) => self.input.release_all(),
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    if let Some(k) = key_of(code) {
                        match event.state {
                            ElementState::Pressed => self.input.key_down(k),
                            ElementState::Released => self.input.key_up(k),
                        }
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let b = match button {
                    MouseButton::Right => Button::Right,
                    _ => Button::Left,
                };
                self.input.button(b, state == ElementState::Pressed);
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = self.cursor {
                    self.input.mouse_motion((position.x - x) as f32, (position.y - y) as f32);
                }
                self.cursor = Some((position.x, position.y));
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::RedrawRequested => match self.step() {
                Ok(true) => el.exit(),
                Ok(false) => {}
                Err(e) => self.fail(el, e),
            },
            _ => {}
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        let minimised = self.presenter.as_ref().is_some_and(|p| p.extent().is_none()) && self.pending_resize.is_none();
        if minimised {
            // Poll the window's size now and then instead of spinning.
            el.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(50)));
        } else {
            el.set_control_flow(ControlFlow::Poll);
        }
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }
}
