//! How the light buffer stores each point light (`--light-record`): full 32-byte
//! [`PointLight`]s, or 16-byte compact records (`shaders::compact_light`: fixed-point position in
//! the lights' view-space box, 24-bit radius, shared-exponent colour) so that one binding below
//! 2^31 bytes holds 2^27 − 4 lights instead of 2^26 − 1.
//!
//! Compact records are a light-type bit (`EFFECT_COMPACT_LIGHTS`): the pipelines that read them
//! are specialised on it, the full-record pipelines hold no decode. They hold point lights only
//! (spot and directional lights have full-record sections): a scene with other light types is
//! refused in one line. The CPU side keeps the lights *as decoded* (what every kernel sees), so
//! the CPU references and the statistics describe the lights that were rendered; the accuracy
//! study (`bench accuracy`, knob `light-record`) measures the image against full records.
use super::light_types::{light_records, Directional, Spot};
use super::ViewTransform;
use anyhow::{bail, Result};
use shaders::compact_light::{self, records_for, MAX_COMPACT_LIGHTS};
use shaders::layout::PointLight;

/// `--light-record`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LightRecord {
    /// 32-byte records, exact (at most 2^26 − 1 lights in a binding below 2^31 bytes).
    #[default]
    Full,
    /// 16-byte records (`shaders::compact_light`): up to 2^27 − 4 lights, point lights only.
    Compact,
}

impl LightRecord {
    pub fn name(self) -> &'static str {
        match self {
            LightRecord::Full => "full",
            LightRecord::Compact => "compact",
        }
    }

    /// Bytes of light buffer per light.
    pub fn bytes_per_light(self) -> u64 {
        match self {
            LightRecord::Full => std::mem::size_of::<PointLight>() as u64,
            LightRecord::Compact => std::mem::size_of::<PointLight>() as u64 / 2,
        }
    }

    /// The effect bit of the records (a light-type specialisation).
    pub fn effects(self) -> u32 {
        match self {
            LightRecord::Full => 0,
            LightRecord::Compact => compact_light::EFFECT_COMPACT_LIGHTS,
        }
    }

    /// Most lights one binding of `range` bytes holds in these records.
    pub fn max_lights_in(self, range: u64) -> u64 {
        let records = range / std::mem::size_of::<PointLight>() as u64;
        match self {
            LightRecord::Full => records,
            LightRecord::Compact => (2 * records.saturating_sub(1)).min(MAX_COMPACT_LIGHTS as u64),
        }
    }
}

/// The light buffer in `record`s (`light_types::light_records` for full records: point lights,
/// cone and directional sections), the point lights as the kernels will see them, and the
/// farthest any of them moved in the records (view-space distance; 0 for full records).
pub fn light_buffer(record: LightRecord, view: &ViewTransform, lights_view: Vec<PointLight>, spots: &[Option<Spot>], directional: &[Directional]) -> Result<(Vec<PointLight>, Vec<PointLight>, f32)> {
    match record {
        LightRecord::Full => Ok((light_records(view, &lights_view, spots, directional)?, lights_view, 0.0)),
        LightRecord::Compact => {
            if spots.iter().any(Option::is_some) || !directional.is_empty() {
                bail!("--light-record compact holds point lights only: this scene has spot or directional lights (use --light-record full)");
            }
            if lights_view.len() > MAX_COMPACT_LIGHTS as usize {
                bail!("{} lights: compact records hold at most {MAX_COMPACT_LIGHTS} in one buffer", lights_view.len());
            }
            let frame = compact_light::frame_of(&lights_view);
            let packed = compact_light::pack(&frame, &lights_view);
            debug_assert_eq!(packed.len(), records_for(lights_view.len() as u32) as usize);
            let seen = compact_light::decoded(&packed, lights_view.len() as u32);
            let moved = lights_view.iter().zip(&seen).map(|(a, b)| (glam::Vec3::from(a.position) - glam::Vec3::from(b.position)).length()).fold(0.0, f32::max);
            Ok((packed, seen, moved))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_per_binding() {
        let range = i32::MAX as u64;
        assert_eq!(LightRecord::Full.max_lights_in(range), (1 << 26) - 1);
        assert_eq!(LightRecord::Compact.max_lights_in(range), (1 << 27) - 4);
        assert_eq!(LightRecord::Full.max_lights_in(u32::MAX as u64), (1 << 27) - 1);
        assert_eq!(LightRecord::Compact.max_lights_in(u32::MAX as u64), MAX_COMPACT_LIGHTS as u64);
        assert_eq!(MAX_COMPACT_LIGHTS, (1 << 28) - 4);
        assert_eq!(LightRecord::Compact.max_lights_in(32 << 10), 2 * 1023, "the header takes one record");
        assert_eq!(LightRecord::Compact.max_lights_in(0), 0);
    }

    #[test]
    fn compact_refuses_other_light_types_and_keeps_the_decoded_lights() {
        let view = ViewTransform::look_at(glam::DVec3::new(0.0, 0.0, 5.0), glam::DVec3::ZERO, glam::DVec3::Y);
        let l = PointLight { position: [1.0, 2.0, -3.0], radius: 2.0, colour: [0.5, 0.25, 1.0], intensity: 3.0 };
        let spot = Some(Spot { direction: glam::Vec3::NEG_Y, inner: 0.1, outer: 0.5 });
        let e = light_buffer(LightRecord::Compact, &view, vec![l], &[spot], &[]).unwrap_err().to_string();
        assert!(e.starts_with("--light-record compact holds point lights only") && !e.contains('\n'), "{e}");
        let sun = Directional { direction: glam::Vec3::NEG_Y, colour: [1.0; 3], intensity: 1.0 };
        assert!(light_buffer(LightRecord::Compact, &view, vec![l], &[], &[sun]).is_err());
        let (records, seen, moved) = light_buffer(LightRecord::Compact, &view, vec![l, l], &[None, None], &[]).unwrap();
        assert_eq!((records.len(), moved), (2, 0.0), "one position is the grid's origin");
        assert_eq!(seen, vec![compact_light::compact_at(&records, 2, 0); 2]);
        assert_eq!(seen[0].colour, [1.5, 0.75, 3.0]);
        let (full, seen, moved) = light_buffer(LightRecord::Full, &view, vec![l], &[], &[]).unwrap();
        assert_eq!((full, seen, moved), (vec![l], vec![l], 0.0));
    }
}
