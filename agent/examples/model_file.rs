//! How big a model file is and how long `QAgent::load` takes to read it.
//!
//! Run: `cargo run --release -p agent --example model_file -- MODEL [LOADS]`
//!
//! Prints the file's size, the table's shape and written rows, and the minimum and median
//! wall-clock time of `LOADS` loads (default 20), each from the page cache after a first
//! untimed load.

use std::path::PathBuf;
use std::time::Instant;

use agent::QAgent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(args.next().ok_or("usage: model_file MODEL [LOADS]")?);
    let loads: usize = args.next().map_or(Ok(20), |n| n.parse())?;
    let bytes = std::fs::metadata(&path)?.len();
    let agent = QAgent::load(&path)?;
    let mut times: Vec<f64> = (0..loads.max(1))
        .map(|_| {
            let clock = Instant::now();
            let loaded = QAgent::load(&path).expect("the model loaded once");
            let ms = clock.elapsed().as_secs_f64() * 1e3;
            assert!(loaded == agent, "every load gives the same agent");
            ms
        })
        .collect();
    times.sort_by(f64::total_cmp);
    let table = agent.table();
    println!(
        "{}: {} bytes ({:.2} MB), {} {} table of {} keys x {} columns, {} rows written",
        path.display(),
        bytes,
        bytes as f64 / 1e6,
        agent.name(),
        if table.is_dense() { "dense" } else { "sparse" },
        table.key_count(),
        table.columns(),
        table.written_rows().len()
    );
    println!(
        "QAgent::load over {} loads: min {:.1} ms, median {:.1} ms",
        times.len(),
        times[0],
        times[times.len() / 2]
    );
    Ok(())
}
