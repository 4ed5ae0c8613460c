//! Running the `manylights` binary (validation on) and checking how it answers bad input.
use std::ffi::OsStr;

/// What a run of the binary printed and whether it succeeded.
pub struct Run {
    pub ok: bool,
    pub stdout: String,
    pub stderr: String,
}

/// Runs `manylights <args>` with `MANYLIGHTS_VALIDATION=true`.
pub fn manylights<S: AsRef<OsStr>>(args: impl IntoIterator<Item = S>) -> Run {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(args)
        .env("MANYLIGHTS_VALIDATION", "true")
        .output()
        .expect("running manylights");
    Run { ok: out.status.success(), stdout: String::from_utf8_lossy(&out.stdout).into(), stderr: String::from_utf8_lossy(&out.stderr).into() }
}

/// Asserts that `run` (described by `what`) failed without a panic, with exactly one line
/// starting `error: `, and that its stderr mentions `needle`.
pub fn assert_one_line_error(run: &Run, what: &str, needle: &str) {
    let err = &run.stderr;
    assert!(!run.ok, "{what} must fail");
    assert!(!err.contains("panicked"), "{what} panicked:\n{err}");
    let error_lines = err.lines().filter(|l| l.starts_with("error: ")).count();
    assert_eq!(error_lines, 1, "{what}: one error line expected:\n{err}");
    assert!(err.contains(needle), "{what}: error should mention {needle:?}:\n{err}");
}
