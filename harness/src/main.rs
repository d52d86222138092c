//! `harness`: the bvhlab command line. Renders images now; runs experiment sweeps (issue 3) next.

mod cli;
mod error;
mod list;
mod render;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = cli::Cli::parse();
    let result = match cli.command {
        cli::Command::Render(args) => render::run(&args),
        cli::Command::List => {
            list::run();
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
