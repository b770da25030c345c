//! `haptloop`: see the library docs (`src/lib.rs`) and `haptloop --help`.

use std::process::ExitCode;

fn main() -> ExitCode {
    match haptloop::cli::run() {
        Ok(code) => code,
        Err(err) => {
            eprintln!("haptloop: error: {err:#}");
            ExitCode::from(1)
        }
    }
}
