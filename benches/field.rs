//! `cargo bench --bench field`: the same benchmarks as `energywave bench` (add `-- --quick` for the short run).
//! The table of a full run on the reference machine is recorded in `benches/README.md`.

use energywave::bench::{BenchOptions, run};
use energywave::cli::bench_viewer;

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    match run(
        BenchOptions {
            quick,
            ..Default::default()
        },
        &mut bench_viewer,
        |p| eprintln!("{p}"),
    ) {
        Ok(report) => print!("{}", report.table()),
        Err(e) => {
            eprintln!("benchmark failed: {e}");
            std::process::exit(1);
        }
    }
}
