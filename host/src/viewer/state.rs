//! The viewer's state apart from its window: the scene, its lights (generated and animated), the
//! settings of `render`, the fly camera and the [`Renderer`] that draws every frame with the
//! same passes as `render`. Key actions change it ([`Viewer::apply`]); each frame
//! ([`Viewer::render`]) uploads what moved and renders.
use super::controls::{Action, FlyCamera, Input};
use super::overlay::{Lists, OverlayText};
use crate::args::view_name;
use crate::bad_input::bad_input;
use crate::gpu::Gpu;
use crate::preflight;
use crate::render::{self, FrameTimes, Renderer, Settings, Technique};
use crate::render_cmd::RenderArgs;
use crate::scene::bookmark::Bookmark;
use crate::scene::flatten::{flatten, scene_input, Flattened};
use crate::scene::{lights, Camera, Scene};
use anyhow::{Context as _, Result};
use shaders::layout::{PointLight, View};
use std::collections::VecDeque;
use std::path::Path;

/// Frames whose times a screenshot's statistics take medians over.
/// Frames between two read-backs of the light-list statistics for the overlay.
const LISTS_EVERY: u64 = 15;

pub struct Viewer {
    pub scene: Scene,
    /// The scene's own camera: near, far and field of view of every frame.
    scene_camera: Camera,
    flat: Flattened,
    /// Lights before the animation (generated with `seed`, or the description's); their cones
    /// are `scene.spots`.
    base_lights: Vec<PointLight>,
    /// The share of spots the lights were generated with (`--spot-fraction`, `[lights]
    /// spot_fraction`): a new light count gets its cones alike. `None`: no generated spots.
    spot_share: Option<lights::SpotShare>,
    /// The lights of the current frame: `lights::animate(base_lights, time)`.
    lights: Vec<PointLight>,
    /// Which lights cast shadows (empty: none), whether they do now (G), and the share they
    /// were generated with (`--shadow-fraction`: a new light count gets its casters alike).
    casters: Vec<bool>,
    shadows_on: bool,
    shadow_share: Option<f32>,
    seed: u64,
    /// `--light-order`: lights generated anew (+ and −) are stored in it as well.
    light_order: lights::LightOrder,
    pub settings: Settings,
    pub camera: FlyCamera,
    renderer: Option<Renderer>,
    /// Animation time, seconds; it stands still while `paused`.
    pub time: f32,
    pub paused: bool,
    pub text: OverlayText,
    /// Frames rendered.
    pub frames: u64,
    /// Frames whose timings a report takes the medians of (`--frames`, at least 1).
    stats_frames: usize,
    /// Adaptive NURBS levels within this many pixels (`--tess-error`).
    nurbs_tolerance: Option<f32>,
    recent: VecDeque<FrameTimes>,
    camera_moved: bool,
}

impl Viewer {
    /// Loads the scene and its lights as `render` does (`a`'s flags; `--camera` places the fly
    /// camera, else the scene's camera does).
    pub fn new(gpu: &Gpu, a: &RenderArgs) -> Result<Self> {
        crate::render_cmd::check_args(gpu, a)?;
        if a.shadow_reference {
            crate::bail_input!("view does not take --shadow-reference: the ray-cast reference shades one frame on the CPU (use render)");
        }
        let mut scene = Scene::load(&a.scene, &a.assets)?;
        for w in &scene.warnings {
            eprintln!("warning: {w}");
        }
        // The lights as `render` makes them (with their cones in `scene.spots` and their shadow
        // flags in `scene.shadows`).
        let mut shadow_share = None;
        let generated = scene.lights.is_empty();
        let spot_share = match scene.lights.is_empty() {
            true => {
                if a.lights == 0 {
                    crate::bail_input!("--lights 0: nothing to light (give at least 1, or lights in a scene description)");
                }
                let generated =
                    lights::uniform(&scene, a.lights as usize, a.seed).with_context(|| format!("generating --lights {} in scene {:?}", a.lights, a.scene)).map_err(bad_input)?;
                let share = lights::SpotShare { fraction: a.spot_fraction, seed: a.seed };
                let cones = share.cones(generated.len()).map_err(bad_input)?;
                let n = generated.len();
                scene.add_lights(generated.into_iter().zip(cones.into_iter().chain(std::iter::repeat(None)).take(n)));
                if a.shadow_fraction > 0.0 {
                    scene.shadows = lights::shadow_casters(n, a.shadow_fraction).map_err(bad_input)?;
                    shadow_share = Some(a.shadow_fraction);
                }
                (a.spot_fraction > 0.0).then_some(share)
            }
            false if a.shadow_fraction > 0.0 => {
                crate::bail_input!("--shadow-fraction applies to the --lights the command generates; this scene has its own lights (use [lights] shadow_fraction or shadows = true in its description, or --shadows all)")
            }
            false if a.spot_fraction > 0.0 => {
                crate::bail_input!("--spot-fraction applies to the --lights the command generates; this scene has its own lights (use [lights] spot_fraction in its description)")
            }
            false => scene.spot_share,
        };
        crate::render_cmd::apply_shadow_casters(&mut scene, a)?;
        if a.shadows == crate::render_cmd::ShadowCasters::All && generated {
            // Generated lights keep every light a caster when + and − make them anew.
            shadow_share = Some(1.0);
        }
        if let Some(level) = a.tess_level {
            scene.set_tess_level(level);
        }
        let scene_camera = scene.camera;
        let at = a.camera.unwrap_or_else(|| Bookmark { fov_y_degrees: None, ..Bookmark::of_camera(&scene_camera) });
        scene.camera = at.apply(&scene_camera);
        scene.validate().with_context(|| format!("scene {:?}", a.scene)).map_err(bad_input)?;
        if a.light_order == lights::LightOrder::Spatial {
            scene.order_lights_spatially();
        }
        let base_lights = std::mem::take(&mut scene.lights);
        let flat = flatten(&scene, a.normal_precision).map_err(bad_input)?;
        let (lo, hi) = scene.bounds;
        let speed = ((hi - lo).length() / 30.0).max(0.1);
        let settings = a.settings(0, false);
        let time = a.time.unwrap_or(0.0);
        let lights = lights::animate(&base_lights, time);
        Ok(Self {
            casters: scene.shadows.clone(),
            shadows_on: true,
            shadow_share,
            scene,
            scene_camera,
            flat,
            base_lights,
            spot_share,
            lights,
            seed: a.seed,
            light_order: a.light_order,
            settings,
            camera: FlyCamera { at, speed },
            renderer: None,
            time,
            paused: false,
            text: OverlayText::default(),
            frames: 0,
            stats_frames: a.frames.max(1) as usize,
            nurbs_tolerance: a.tess_error,
            recent: VecDeque::new(),
            camera_moved: false,
        })
    }

    /// Renders at `width × height` from now on (a new renderer when the size changed).
    pub fn ensure_size(&mut self, gpu: &Gpu, width: u32, height: u32) -> Result<()> {
        if self.renderer.as_ref().is_some_and(|r| (r.settings().width, r.settings().height) == (width, height)) {
            return Ok(());
        }
        preflight::check_frame(&gpu.ctx.info, width, height, self.settings.tile_size, self.settings.normal_precision)
            .with_context(|| format!("the window's size {width}x{height}"))?;
        self.renderer = None; // frees the old targets first
        self.settings.width = width;
        self.settings.height = height;
        self.scene.camera = self.camera.at.apply(&self.scene_camera);
        let mut input = scene_input(&self.scene, &self.flat, &self.lights);
        input.nurbs_tolerance = self.nurbs_tolerance;
        render::renderer::check_shadow_scene(&input, &self.settings).map_err(bad_input)?;
        self.renderer = Some(Renderer::new(gpu, &input, &self.settings).context("creating the renderer")?);
        self.recent.clear();
        self.text.reset();
        Ok(())
    }

    /// Moves the camera by `input`'s held keys and `look`, and the animation by `dt` seconds.
    pub fn advance(&mut self, input: &Input, look: (f32, f32), dt: f32) {
        self.camera_moved |= self.camera.update(input, look, dt);
        if !self.paused {
            self.time += dt;
        }
    }

    /// Applies a key action (those of the window — quit, screenshot, overlay — are the
    /// window's). A change the technique cannot take (too many lights, a scene it refuses) is a
    /// note on the overlay, and the viewer keeps what it had.
    pub fn apply(&mut self, gpu: &Gpu, action: Action) {
        let done = match action {
            Action::NextTechnique => {
                let i = Technique::ALL.iter().position(|&t| t == self.settings.technique).unwrap_or(0);
                self.set_technique(gpu, Technique::ALL[(i + 1) % Technique::ALL.len()])
            }
            Action::Technique(i) => match Technique::ALL.get(i) {
                Some(&t) => self.set_technique(gpu, t),
                None => Ok(()),
            },
            Action::MoreLights => self.set_light_count(gpu, self.base_lights.len().saturating_mul(2)),
            Action::FewerLights => self.set_light_count(gpu, (self.base_lights.len() / 2).max(1)),
            Action::ToggleShadows => self.toggle_shadows(gpu),
            Action::ToggleHeatmap => self.set_view(gpu, if self.settings.view == View::Heatmap { View::Shaded } else { View::Heatmap }),
            Action::NextView => {
                let i = View::FRAME.iter().position(|&v| v == self.settings.view).unwrap_or(0);
                self.set_view(gpu, View::FRAME[(i + 1) % View::FRAME.len()])
            }
            Action::TogglePause => {
                self.paused = !self.paused;
                Ok(())
            }
            Action::Screenshot | Action::PrintCamera | Action::ToggleOverlay | Action::Quit => Ok(()),
        };
        if let Err(e) = done {
            let line = crate::bad_input::one_line(&e);
            eprintln!("warning: {line}");
            self.text.note(line);
        }
    }

    fn set_technique(&mut self, gpu: &Gpu, t: Technique) -> Result<()> {
        let info = &gpu.ctx.info;
        preflight::check_tile_for(t, self.settings.tile_size)?;
        preflight::check_lights(info, t, self.settings.light_record, self.settings.tile_size, self.base_lights.len() as u64, &format!("{} lights", self.base_lights.len()))?;
        let s = Settings { technique: t, ..self.settings.clone() };
        if let Some(r) = self.renderer.as_mut() {
            r.set_settings(gpu, &s)?;
        }
        self.settings = s;
        self.text.reset();
        Ok(())
    }

    fn set_view(&mut self, gpu: &Gpu, view: View) -> Result<()> {
        let s = Settings { view, ..self.settings.clone() };
        if let Some(r) = self.renderer.as_mut() {
            r.set_settings(gpu, &s)?;
        }
        self.settings = s;
        Ok(())
    }

    /// `n` lights generated anew with the same seed (a description's own lights are replaced),
    /// generated spots with the same share and seed ([`lights::SpotShare`]). Spot lights listed
    /// one by one (`[[light]]`, glTF) keep their count.
    fn set_light_count(&mut self, gpu: &Gpu, n: usize) -> Result<()> {
        let what = format!("{n} lights");
        let spots = match self.spot_share {
            Some(share) => share.cones(n).with_context(|| format!("generating the spot cones of {what}"))?,
            None if self.scene.spots.iter().any(Option::is_some) => anyhow::bail!(
                "{what}: this scene's spot lights are listed one by one (a description's [[light]], glTF), so their count stays; generated spots (--spot-fraction, [lights] spot_fraction) follow a new count"
            ),
            None => vec![],
        };
        let casters = match self.shadow_share {
            Some(share) => lights::shadow_casters(n, share)?,
            None if self.casters.contains(&true) => anyhow::bail!(
                "{what}: this scene's shadow-casting lights are listed one by one (a description's [[light]] or shadow_fraction), so their count stays; generated casters (--shadow-fraction) follow a new count"
            ),
            None => vec![],
        };
        preflight::check_lights(&gpu.ctx.info, self.settings.technique, self.settings.light_record, self.settings.tile_size, n as u64, &what)?;
        let base = lights::uniform(&self.scene, n, self.seed).with_context(|| format!("generating {what}"))?;
        let (base, spots, casters) = match self.light_order {
            lights::LightOrder::Spatial => {
                let order = lights::spatial_order(&base);
                (lights::permuted(&base, &order), lights::permuted(&spots, &order), lights::permuted(&casters, &order))
            }
            lights::LightOrder::Given => (base, spots, casters),
        };
        let animated = lights::animate(&base, self.time);
        if casters.contains(&true) || self.scene.shadows.contains(&true) {
            // Shadow flags are per light: the renderer is made anew for the new count.
            let old = self.scene.shadows.clone();
            self.scene.shadows = if self.shadows_on { casters.clone() } else { vec![] };
            let old_spots = std::mem::replace(&mut self.scene.spots, spots);
            let old_lights = std::mem::replace(&mut self.lights, animated);
            if let Err(e) = self.rebuild(gpu) {
                (self.scene.shadows, self.scene.spots, self.lights) = (old, old_spots, old_lights);
                return Err(e);
            }
            (self.base_lights, self.casters) = (base, casters);
            return Ok(());
        }
        if let Some(r) = self.renderer.as_mut() {
            r.set_lights(gpu, &animated, &spots)?;
        }
        (self.base_lights, self.lights, self.scene.spots) = (base, animated, spots);
        self.text.reset();
        Ok(())
    }

    /// Shadows on or off: the renderer made anew with the casters' flags or without them (a
    /// technique that renders no shadows refuses, and the viewer keeps what it had).
    fn toggle_shadows(&mut self, gpu: &Gpu) -> Result<()> {
        if !self.casters.contains(&true) {
            anyhow::bail!("no light casts shadows (--shadow-fraction, [[light]] shadows = true, [lights] shadow_fraction)");
        }
        let old = std::mem::replace(&mut self.scene.shadows, if self.shadows_on { vec![] } else { self.casters.clone() });
        if let Err(e) = self.rebuild(gpu) {
            self.scene.shadows = old;
            return Err(e);
        }
        self.shadows_on = !self.shadows_on;
        Ok(())
    }

    /// A new renderer for the scene as it stands (its lights, shadow flags and camera), where
    /// the window has a size; on an error the old one stays.
    fn rebuild(&mut self, gpu: &Gpu) -> Result<()> {
        if self.renderer.is_none() {
            return Ok(());
        }
        self.scene.camera = self.camera.at.apply(&self.scene_camera);
        let mut input = scene_input(&self.scene, &self.flat, &self.lights);
        input.nurbs_tolerance = self.nurbs_tolerance;
        self.renderer = Some(Renderer::new(gpu, &input, &self.settings).context("creating the renderer")?);
        self.recent.clear();
        self.text.reset();
        Ok(())
    }

    /// Renders a frame: uploads the camera and the lights where they moved, then every pass.
    pub fn render(&mut self, gpu: &Gpu) -> Result<&FrameTimes> {
        let r = self.renderer.as_mut().context("no renderer: the window has no size")?;
        let lights_moved = !self.paused || self.camera_moved;
        if lights_moved {
            self.lights = lights::animate(&self.base_lights, self.time);
        }
        if self.camera_moved {
            self.scene.camera = self.camera.at.apply(&self.scene_camera);
            let view = scene_input(&self.scene, &self.flat, &self.lights).view;
            r.set_view(gpu, view, &self.flat.positions, &self.lights)?;
        } else if lights_moved {
            r.set_lights(gpu, &self.lights, &self.scene.spots)?;
        }
        self.camera_moved = false;
        let times = r.frame(gpu)?;
        if self.frames.is_multiple_of(LISTS_EVERY) {
            self.text.lists = Some(list_summary(r)?);
        }
        self.text.add(&times);
        if self.recent.len() >= self.stats_frames {
            self.recent.pop_front();
        }
        self.recent.push_back(times);
        self.frames += 1;
        Ok(self.recent.back().expect("pushed above"))
    }

    /// The renderer, once the window has a size.
    pub fn renderer(&self) -> Option<&Renderer> {
        self.renderer.as_ref()
    }

    /// The camera as `render --camera` and `--time` reproduce it.
    pub fn bookmark_flags(&self) -> String {
        format!("--camera {} --time {}", self.camera.at, self.time)
    }

    /// The overlay's first lines.
    pub fn header(&self, present_mode: &str) -> Vec<String> {
        let s = &self.settings;
        let i = Technique::ALL.iter().position(|&t| t == s.technique).unwrap_or(0);
        vec![
            format!("{}  {}x{}  present {present_mode}", self.scene.name, s.width, s.height),
            format!("technique {} ({}/{})   view {}", s.technique.name(), i + 1, Technique::ALL.len(), view_name(s.view)),
            format!("lights {}{}", self.lights.len(), if self.paused { "   (animation paused)" } else { "" }),
        ]
    }

    /// Writes the last frame as `png` (the heatmap with its legend, as `render` writes it) and
    /// its statistics beside it (`.json`: [`Viewer::write_stats`]'s).
    pub fn screenshot(&mut self, gpu: &Gpu, png: &Path, overlay: &[String]) -> Result<()> {
        let (mut frame, json) = self.report(gpu, overlay)?;
        let (w, h) = (self.settings.width, self.settings.height);
        if self.settings.view == View::Heatmap {
            render::legend::draw(&mut frame.pixels, w, h, render::HEAT_MAX);
        }
        crate::debug_frame::save_png(png, w, h, &frame.pixels)?;
        write_json(&png.with_extension("json"), &json)
    }

    /// Writes the statistics of the last frame to `path` (`view --stats`): `render --stats`'s
    /// over the last `--frames` frames, plus the viewer's camera, time, frame count, technique,
    /// view and `overlay` lines.
    pub fn write_stats(&mut self, gpu: &Gpu, path: &Path, overlay: &[String]) -> Result<()> {
        let (_, json) = self.report(gpu, overlay)?;
        write_json(path, &json)
    }

    /// The last frame and its statistics.
    fn report(&mut self, gpu: &Gpu, overlay: &[String]) -> Result<(render::Frame, serde_json::Value)> {
        let r = self.renderer.as_mut().context("no frame to report: nothing was rendered yet")?;
        let times: Vec<FrameTimes> = self.recent.iter().cloned().collect();
        let frame = r.report(&times, true)?;
        let settings = Settings { frames: times.len() as u32, read_back: true, ..self.settings.clone() };
        let mut json = render::stats::stats_json(&gpu.ctx.info, &self.scene.name, self.lights.len(), &settings, &frame);
        json["viewer"] = serde_json::json!({
            "camera": self.camera.at.to_string(),
            "time": self.time,
            "paused": self.paused,
            "frame": self.frames,
            "technique": self.settings.technique.name(),
            "view": view_name(self.settings.view),
            "overlay": overlay,
        });
        Ok((frame, json))
    }
}

fn write_json(path: &Path, json: &serde_json::Value) -> Result<()> {
    std::fs::write(path, serde_json::to_string_pretty(json)?).with_context(|| format!("writing {}", path.display()))
}

/// Clusters and lights per cluster of the last frame (the clustered techniques' longest list
/// read back from their lists; the others report theirs).
fn list_summary(r: &mut Renderer) -> Result<Lists> {
    let s = r.list_stats(true)?;
    let mean = if s.clusters > 0 { s.light_refs as f64 / s.clusters as f64 } else { 0.0 };
    Ok(Lists { clusters: s.clusters, mean, max: s.max_list })
}
