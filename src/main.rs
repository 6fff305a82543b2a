//! The `metamer` command: parses arguments and calls the library (see `cli/`).

mod cli;

fn main() -> std::process::ExitCode {
    // Rust ignores SIGPIPE, so `metamer … | head` would panic on the next print; restore the
    // default so the command ends quietly like any Unix filter when its reader goes away.
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is always valid.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    cli::main()
}
