//! The `shadelab` command: a thin shell that turns flags into library calls.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
