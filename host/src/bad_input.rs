//! Errors in what the user gave — a scene file, a flag's value — told apart from failures of the
//! machine (no device, an allocation or a Vulkan call failing, a validation message).
//!
//! The CLI exits with [`EXIT_BAD_INPUT`] (2, as clap does for a malformed command line) when the
//! error chain holds a [`BadInput`], and with [`EXIT_FAILURE`] (1) otherwise. Either way it prints
//! exactly one line ([`one_line`]): no panic, no backtrace, no multi-line snippet.
use std::fmt;

/// Exit status of a run refused because of its input (files, flags).
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit status of any other failure.
pub const EXIT_FAILURE: u8 = 1;

/// The user's input is at fault; the message names the file and line, or the flag or key, and the
/// limit it broke.
#[derive(Debug)]
pub struct BadInput(pub String);

impl fmt::Display for BadInput {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// Marks `e` (with its whole context chain, flattened to one line) as bad input.
pub fn bad_input(e: impl Into<anyhow::Error>) -> anyhow::Error {
    anyhow::Error::new(BadInput(one_line(&e.into())))
}

/// `anyhow::bail!`, marking the error as [`BadInput`].
#[macro_export]
macro_rules! bail_input {
    ($($arg:tt)*) => {
        return Err($crate::bad_input::bad_input(anyhow::anyhow!($($arg)*)))
    };
}

/// Whether the error, or anything it wraps, is [`BadInput`].
pub fn is_bad_input(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.is::<BadInput>())
}

/// The exit status for `e`: [`EXIT_BAD_INPUT`] or [`EXIT_FAILURE`].
pub fn exit_status(e: &anyhow::Error) -> u8 {
    if is_bad_input(e) {
        EXIT_BAD_INPUT
    } else {
        EXIT_FAILURE
    }
}

/// The error and its context chain on one line: `outer: inner: cause`. Lines of a multi-line
/// message are joined with `; `, and control characters that came from the input (a name or a
/// path holding a tab or a carriage return) are escaped, so the result is one terminal line.
pub fn one_line(e: &anyhow::Error) -> String {
    flatten_lines(&format!("{e:#}"))
}

/// `text` as one line: non-empty lines trimmed and joined with `; ` (a space after a colon),
/// control characters escaped.
pub fn flatten_lines(text: &str) -> String {
    let mut joined = String::new();
    for line in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if !joined.is_empty() {
            joined.push_str(if joined.ends_with(':') { " " } else { "; " });
        }
        joined.push_str(line);
    }
    joined.chars().flat_map(|c| if c.is_control() { c.escape_default().collect::<Vec<_>>() } else { vec![c] }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::{anyhow, Context as _};

    #[test]
    fn bad_input_survives_context_and_prints_on_one_line() {
        let e: anyhow::Result<()> = Err(bad_input(anyhow!("file x.obj: line 3: not a number\n  detail")));
        let e = e.context("loading scene").unwrap_err();
        assert!(is_bad_input(&e));
        assert_eq!(exit_status(&e), EXIT_BAD_INPUT);
        assert_eq!(one_line(&e), "loading scene: file x.obj: line 3: not a number; detail");
        let other = anyhow!("vkCreateBuffer failed").context("allocating");
        assert_eq!((is_bad_input(&other), exit_status(&other)), (false, EXIT_FAILURE));
        assert_eq!(flatten_lines("a\tb\r\n\nc\u{7}"), "a\\tb; c\\u{7}");
        assert_eq!(flatten_lines("devices present:\n  gpu 1\n  gpu 2"), "devices present: gpu 1; gpu 2");
    }
}
