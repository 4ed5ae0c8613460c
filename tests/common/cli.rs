//! Running the `manylights` binary (validation on) and checking how it answers bad input: one
//! line `error: …`, no panic, exit status [`BAD_INPUT`] (other failures exit with 1).
use std::ffi::OsStr;

/// Exit status of a run refused for its input.
pub const BAD_INPUT: i32 = 2;

/// What a run of the binary printed and how it exited.
pub struct Run {
    pub ok: bool,
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

/// Runs `manylights <args>` with `MANYLIGHTS_VALIDATION=true` and the extra environment `env`.
pub fn manylights_env<S: AsRef<OsStr>>(args: impl IntoIterator<Item = S>, env: &[(&str, &str)]) -> Run {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(args)
        .env("MANYLIGHTS_VALIDATION", "true")
        .envs(env.iter().copied())
        .output()
        .expect("running manylights");
    Run {
        ok: out.status.success(),
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into(),
        stderr: String::from_utf8_lossy(&out.stderr).into(),
    }
}

/// Runs `manylights <args>` with `MANYLIGHTS_VALIDATION=true`.
pub fn manylights<S: AsRef<OsStr>>(args: impl IntoIterator<Item = S>) -> Run {
    manylights_env(args, &[])
}

/// Asserts that `run` (described by `what`) exited with `status` without a panic, printed
/// exactly one line starting `error: ` (besides the device line and warnings), and that this line
/// mentions each of `needles`.
pub fn assert_refused(run: &Run, what: &str, status: i32, needles: &[&str]) {
    let err = &run.stderr;
    assert_eq!(run.code, Some(status), "{what}: exit status\n{err}");
    assert!(!err.contains("panicked") && !err.contains("RUST_BACKTRACE"), "{what} panicked:\n{err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("device: ") && !l.starts_with("warning: ")).collect();
    assert_eq!(lines.len(), 1, "{what}: one error line expected:\n{err}");
    assert!(lines[0].starts_with("error: "), "{what}:\n{err}");
    for needle in needles {
        assert!(lines[0].contains(needle), "{what}: error should mention {needle:?}:\n{err}");
    }
}

/// Bad input answered by exit status [`BAD_INPUT`], no panic, exactly one line starting
/// `error: ` (other output, e.g. the device line, may stand beside it), mentioning `needle`.
pub fn assert_one_line_error(run: &Run, what: &str, needle: &str) {
    let err = &run.stderr;
    assert_eq!(run.code, Some(BAD_INPUT), "{what}: exit status\n{err}");
    assert!(!err.contains("panicked"), "{what} panicked:\n{err}");
    let error_lines = err.lines().filter(|l| l.starts_with("error: ")).count();
    assert_eq!(error_lines, 1, "{what}: one error line expected:\n{err}");
    assert!(err.contains(needle), "{what}: error should mention {needle:?}:\n{err}");
}
