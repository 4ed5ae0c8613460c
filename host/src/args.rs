//! Command-line pieces shared by several commands: the frame's size and output ([`FrameArgs`]),
//! and the command-line names of the shader crate's option types — [`Precision`] (G-buffer
//! normal encoding) and [`View`] (what a frame shows) — with their clap value parsers.
//!
//! The shader crate's types are the only ones: clap's `ValueEnum` cannot be implemented for a
//! foreign type, so each type has one name table here ([`PRECISIONS`], [`VIEWS`]) that parsing,
//! `--help` and reports all read.
use crate::bail_input;
use anyhow::Result;
use clap::builder::{PossibleValue, TypedValueParser};
use clap::error::{ContextKind, ContextValue, ErrorKind};
use shaders::layout::View;
use shaders::octahedral::Precision;
use std::path::{Path, PathBuf};

/// Size, cluster tile and output file of a frame (shared by `render` and `debug-frame`).
#[derive(clap::Args, Debug, Clone)]
pub struct FrameArgs {
    // Negative numbers are read as values, so that `--width -5` is refused as a width.
    #[arg(long, default_value_t = 1280, allow_negative_numbers = true)]
    pub width: u32,
    #[arg(long, default_value_t = 720, allow_negative_numbers = true)]
    pub height: u32,
    /// Cluster tile edge in pixels.
    #[arg(long, default_value_t = 32, allow_negative_numbers = true)]
    pub tile_size: u32,
    /// Output PNG.
    #[arg(long, default_value = "frame.png")]
    pub out: PathBuf,
}

/// An output file's directory must exist (the file is written after the frame).
pub fn check_output_dir(flag: &str, path: &Path) -> Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !dir.is_dir() {
        bail_input!("{flag} {}: the directory {} does not exist", path.display(), dir.display());
    }
    Ok(())
}

/// A value's command-line name, the other names it is accepted by, and its `--help` line.
#[derive(Clone, Copy, Debug)]
pub struct Named<T: 'static> {
    pub value: T,
    pub name: &'static str,
    pub aliases: &'static [&'static str],
    pub help: &'static str,
}

/// Normal encodings, lowest precision first (`--normal-precision`, `--precision`).
pub const PRECISIONS: [Named<Precision>; 4] = [
    Named { value: Precision::Oct8, name: "oct8", aliases: &[], help: "octahedral 2×8 bits in a 32-bit target" },
    Named { value: Precision::Oct12, name: "oct12", aliases: &[], help: "octahedral 2×12 bits in a 32-bit target" },
    Named { value: Precision::Oct16, name: "oct16", aliases: &[], help: "octahedral 2×16 bits in a 32-bit target" },
    Named { value: Precision::F32, name: "f32", aliases: &[], help: "three float32 components in a 128-bit target (lossless)" },
];

/// Every view; a command accepts those of its kind ([`View::FRAME`], [`View::DEBUG`]).
pub const VIEWS: [Named<View>; 6] = [
    Named { value: View::Shaded, name: "shaded", aliases: &[], help: "the lit, tonemapped image" },
    Named { value: View::Heatmap, name: "heatmap", aliases: &[], help: "lights evaluated per pixel (0 black … 64+ white)" },
    Named { value: View::Clusters, name: "clusters", aliases: &[], help: "cluster keys hashed to colours" },
    Named { value: View::Normals, name: "normals", aliases: &[], help: "decoded G-buffer normals" },
    Named { value: View::Depth, name: "depth", aliases: &["slices"], help: "exponential depth slices on a colour ramp" },
    Named { value: View::OctaError, name: "octa-error", aliases: &[], help: "normal-encoding error over its proven bound" },
];

/// The command-line name of a precision.
pub fn precision_name(p: Precision) -> &'static str {
    PRECISIONS.iter().find(|n| n.value == p).map_or("?", |n| n.name)
}

/// The command-line name of a view.
pub fn view_name(v: View) -> &'static str {
    VIEWS.iter().find(|n| n.value == v).map_or("?", |n| n.name)
}

/// A clap value parser over a subset of a name table: `--help` lists the names, and a wrong
/// value is a one-line error listing them.
#[derive(Clone)]
pub struct NamedParser<T: 'static> {
    names: Vec<Named<T>>,
}

impl<T: Copy + Send + Sync + 'static> NamedParser<T> {
    pub fn new(names: impl IntoIterator<Item = Named<T>>) -> Self {
        Self { names: names.into_iter().collect() }
    }

    fn possible(n: &Named<T>) -> PossibleValue {
        PossibleValue::new(n.name).aliases(n.aliases.iter().copied()).help(n.help)
    }

    /// The value `s` names (exact match of a name or an alias).
    pub fn lookup(&self, s: &str) -> Option<T> {
        self.names.iter().find(|n| Self::possible(n).matches(s, false)).map(|n| n.value)
    }
}

impl<T: Copy + Send + Sync + 'static> TypedValueParser for NamedParser<T> {
    type Value = T;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &std::ffi::OsStr) -> Result<T, clap::Error> {
        let text = value.to_string_lossy();
        self.lookup(&text).ok_or_else(|| {
            let mut e = clap::Error::new(ErrorKind::InvalidValue).with_cmd(cmd);
            if let Some(arg) = arg {
                e.insert(ContextKind::InvalidArg, ContextValue::String(arg.to_string()));
            }
            e.insert(ContextKind::InvalidValue, ContextValue::String(text.into_owned()));
            e.insert(ContextKind::ValidValue, ContextValue::Strings(self.names.iter().map(|n| n.name.to_owned()).collect()));
            e
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(self.names.iter().map(Self::possible)))
    }
}

/// `--normal-precision` / `--precision`: oct8 | oct12 | oct16 | f32.
pub fn precision_parser() -> NamedParser<Precision> {
    NamedParser::new(PRECISIONS)
}

/// `render --view`: the views of [`View::FRAME`].
pub fn frame_view_parser() -> NamedParser<View> {
    NamedParser::new(VIEWS.into_iter().filter(|n| View::FRAME.contains(&n.value)))
}

/// `debug-frame --view`: the views of [`View::DEBUG`].
pub fn debug_view_parser() -> NamedParser<View> {
    NamedParser::new(VIEWS.into_iter().filter(|n| View::DEBUG.contains(&n.value)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_value_has_one_name_and_parses_back() {
        for p in Precision::ALL {
            assert_eq!(precision_parser().lookup(precision_name(p)), Some(p));
        }
        assert_eq!(PRECISIONS.len(), Precision::ALL.len());
        for v in View::FRAME {
            assert_eq!(frame_view_parser().lookup(view_name(v)), Some(v));
        }
        for v in View::DEBUG {
            assert_eq!(debug_view_parser().lookup(view_name(v)), Some(v));
        }
        assert_eq!(debug_view_parser().lookup("slices"), Some(View::Depth), "the debug frame's old name");
        assert_eq!(frame_view_parser().lookup("octa-error"), None, "a debug-only view");
        assert_eq!(debug_view_parser().lookup("shaded"), None, "a frame-only view");
        assert_eq!(precision_parser().lookup("OCT8"), None, "names are exact");
        let codes: std::collections::HashSet<u32> = VIEWS.iter().map(|n| n.value.code()).collect();
        assert_eq!(codes.len(), VIEWS.len(), "one code per view");
    }
}
