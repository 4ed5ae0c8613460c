//! `manylights` — see `manylights --help` and the README. Exit status: 0 on success, 2 for bad
//! input, 1 for any other failure; an error is one line on stderr (`host::bad_input`).
fn main() -> std::process::ExitCode {
    let cli = host::cli::parse_or_exit();
    match host::cli::run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", host::bad_input::one_line(&e));
            std::process::ExitCode::from(host::bad_input::exit_status(&e))
        }
    }
}
