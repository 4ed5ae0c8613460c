//! Camera bookmarks: one line that `render --camera`, `bench --camera` and `view --camera` read
//! and the viewer's `C` key prints, so a view found interactively renders headless unchanged.
//!
//! Format: `x,y,z,yaw,pitch[,fov]` — the eye in world units, the yaw and pitch of the viewing
//! direction in degrees, and optionally the vertical field of view in degrees (else the scene's).
//! Yaw 0 looks down −z, yaw 90 down +x (turning right seen from above); pitch is positive
//! upwards, within ±89.9°. E.g. `3.2,1.6,8,-84.25,0.5,60`. Near and far planes stay the scene's.
//! The viewer prints f32 values in their shortest exact form, so a printed bookmark parses back
//! to the very same camera.
use super::Camera;
use anyhow::{bail, Result};
use glam::Vec3;

/// Steepest pitch (degrees): the camera's up stays `+y`, which must not be parallel to the view.
pub const MAX_PITCH: f32 = 89.9;

/// A camera position and direction (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bookmark {
    pub eye: Vec3,
    /// Degrees; 0 looks down −z, 90 down +x.
    pub yaw: f32,
    /// Degrees, within ±[`MAX_PITCH`].
    pub pitch: f32,
    /// Vertical field of view in degrees (`None`: the scene's).
    pub fov_y_degrees: Option<f32>,
}

impl Bookmark {
    /// Parses `x,y,z,yaw,pitch[,fov]`; the error (one line) says what is wrong and the format.
    pub fn parse(text: &str) -> Result<Self> {
        const FORMAT: &str = "expected x,y,z,yaw,pitch[,fov] (world position, degrees)";
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        if !(5..=6).contains(&parts.len()) {
            bail!("--camera {text:?}: {} values; {FORMAT}", parts.len());
        }
        let mut v = Vec::with_capacity(6);
        for p in &parts {
            match p.parse::<f32>() {
                Ok(x) if x.is_finite() => v.push(x),
                _ => bail!("--camera {text:?}: {p:?} is not a finite number; {FORMAT}"),
            }
        }
        let (yaw, pitch) = (v[3], v[4]);
        if pitch.abs() > MAX_PITCH {
            bail!("--camera {text:?}: pitch {pitch} is outside ±{MAX_PITCH} degrees");
        }
        let fov = v.get(5).copied();
        if let Some(f) = fov.filter(|f| !(*f > 0.0 && *f < 180.0)) {
            bail!("--camera {text:?}: field of view {f} is outside (0, 180) degrees");
        }
        Ok(Self { eye: Vec3::new(v[0], v[1], v[2]), yaw, pitch, fov_y_degrees: fov })
    }

    /// The bookmark of a camera looking from its position at its target (its field of view
    /// included).
    pub fn of_camera(c: &Camera) -> Self {
        let d = (c.target - c.position).normalize_or_zero();
        let pitch = d.y.clamp(-1.0, 1.0).asin().to_degrees().clamp(-MAX_PITCH, MAX_PITCH);
        let yaw = d.x.atan2(-d.z).to_degrees();
        Self { eye: c.position, yaw, pitch, fov_y_degrees: Some(c.fov_y_degrees) }
    }

    /// The unit viewing direction.
    pub fn direction(&self) -> Vec3 {
        let (yaw, pitch) = (self.yaw.to_radians(), self.pitch.to_radians());
        Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), -yaw.cos() * pitch.cos())
    }

    /// `camera` moved to the bookmark: its eye, a target one unit along the direction, up `+y`,
    /// the bookmark's field of view where it has one; near and far kept.
    pub fn apply(&self, camera: &Camera) -> Camera {
        Camera {
            position: self.eye,
            target: self.eye + self.direction(),
            up: Vec3::Y,
            fov_y_degrees: self.fov_y_degrees.unwrap_or(camera.fov_y_degrees),
            ..*camera
        }
    }
}

/// The clap value parser of `--camera` (a malformed bookmark is a one-line command-line error).
pub fn parse_arg(text: &str) -> std::result::Result<Bookmark, String> {
    Bookmark::parse(text).map_err(|e| e.to_string())
}

impl std::fmt::Display for Bookmark {
    /// `x,y,z,yaw,pitch[,fov]` with every value in its shortest form that parses back exactly.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{},{}", self.eye.x, self.eye.y, self.eye.z, self.yaw, self.pitch)?;
        match self.fov_y_degrees {
            Some(fov) => write!(f, ",{fov}"),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn printed_bookmarks_parse_back_to_the_same_camera() {
        let b = Bookmark { eye: Vec3::new(3.2, 1.6, -8.000_001), yaw: -84.25, pitch: 0.1 + 0.2, fov_y_degrees: Some(60.0) };
        let text = b.to_string();
        assert_eq!(Bookmark::parse(&text).unwrap(), b, "{text}");
        let no_fov = Bookmark { fov_y_degrees: None, ..b };
        assert_eq!(Bookmark::parse(&no_fov.to_string()).unwrap(), no_fov);
        assert_eq!(Bookmark::parse(" 1, 2 ,3,0,0 ").unwrap().eye, Vec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn directions_follow_yaw_and_pitch() {
        let dir = |yaw, pitch| Bookmark { eye: Vec3::ZERO, yaw, pitch, fov_y_degrees: None }.direction();
        assert!(dir(0.0, 0.0).abs_diff_eq(Vec3::NEG_Z, 1e-6));
        assert!(dir(90.0, 0.0).abs_diff_eq(Vec3::X, 1e-6));
        assert!(dir(0.0, 45.0).abs_diff_eq(Vec3::new(0.0, 1.0, -1.0).normalize(), 1e-6));
        let c = Camera { position: Vec3::new(1.0, 2.0, 3.0), target: Vec3::new(4.0, 1.0, -2.0), up: Vec3::Y, fov_y_degrees: 50.0, near: 0.1, far: 100.0 };
        let b = Bookmark::of_camera(&c);
        let applied = b.apply(&c);
        assert!((applied.target - applied.position).abs_diff_eq((c.target - c.position).normalize(), 1e-5));
        assert_eq!((applied.near, applied.far, applied.fov_y_degrees), (0.1, 100.0, 50.0));
        applied.validate().unwrap();
    }

    #[test]
    fn bad_bookmarks_are_one_line_errors() {
        for (text, needle) in [
            ("1,2,3", "3 values"),
            ("1,2,3,4,5,6,7", "7 values"),
            ("1,2,x,0,0", "\"x\" is not a finite number"),
            ("1,2,nan,0,0", "not a finite"),
            ("1,2,3,0,90", "pitch 90"),
            ("1,2,3,0,0,180", "field of view 180"),
            ("", "1 values"),
        ] {
            let e = Bookmark::parse(text).unwrap_err().to_string();
            assert!(e.contains(needle) && !e.contains('\n'), "{text:?}: {e}");
        }
    }
}
