//! The `energywave` binary: see `energywave --help`.

fn main() -> std::process::ExitCode {
    energywave::cli::main()
}
