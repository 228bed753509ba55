//! host-sim: the host-side simulator and harness.
//!
//! `host-sim` with no command runs `run` on the built-in default scene; see `host-sim --help`.
//! The commands are in `host_sim::cmd`.

use clap::Parser;
use host_sim::cmd::Cli;
use host_sim::run::Interrupted;
use std::process::ExitCode;

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.run() {
        Ok(()) => ExitCode::SUCCESS,
        // A closed pipe (e.g. `| head`) is not an error of ours.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<Interrupted>().is_some() => {
            eprintln!("host-sim: {e:#}");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("host-sim: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
