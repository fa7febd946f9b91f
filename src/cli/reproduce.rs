//! `blockstack reproduce` and `blockstack benchmark`: run the paper's experiments E1-E8, or
//! the Blocks World benchmark's E9 and E10, and write the report.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use experiments::reproduce::{self, Options, ProgressSink, Report};
use indicatif::{ProgressBar, ProgressStyle};

use super::stdout::line;

/// Arguments of `blockstack reproduce` and `blockstack benchmark`.
#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// Directory to write the report to (README.md, results.json, summary.md, pictures);
    /// made if missing, checked to be writable before the run [default: report for
    /// reproduce, benchmark for benchmark].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Small counts, to check the pipeline in a minute; not the real figures.
    #[arg(long)]
    pub quick: bool,
    /// The long budgets: for reproduce, E8's paper pixel runs, `dqfd-screen` arms and whole
    /// ablation (about an hour on 2 cores, against minutes for the default run, which trains
    /// E8's plane arms only); for benchmark, E9's and E10's full problem counts.
    #[arg(long, conflicts_with = "quick")]
    pub long: bool,
    /// Run only these experiments, e.g. E8 or E1,E5 (the agents experiments share are
    /// trained only when one asked for needs them).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// The seed every training, start and random choice derives from.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Threads to run on (default: one per core). The results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    pub jobs: Option<u16>,
}

/// One progress bar for the whole run; drawn only when stderr is a terminal.
struct Bar(ProgressBar);

impl ProgressSink for Bar {
    fn begin(&self, jobs: u64) {
        self.0.set_length(jobs);
    }

    fn advance(&self, stage: &str) {
        self.0.set_message(stage.to_string());
        self.0.inc(1);
    }
    /// One line on stderr, above the bar when it is drawn: a long run's log of where its
    /// time went.
    fn finished(&self, stage: &str, part: &str, took: std::time::Duration) {
        let secs = took.as_secs();
        let line = format!("{stage}: {part}: {} min {:02} s", secs / 60, secs % 60);
        self.0.suspend(|| eprintln!("{line}"));
    }
}

/// Runs `report`'s experiments and writes its report.
pub fn reproduce(args: ReproduceArgs, report: Report) -> Result<()> {
    let out = args.out.clone().unwrap_or_else(|| match report {
        Report::Paper => "report".into(),
        Report::BlocksWorld => "benchmark".into(),
    });
    report.check(&args.only)?;
    // Before minutes of work, not after.
    files::prepare_folder(&out)?;
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = args.jobs {
        pool = pool.num_threads(usize::from(n));
    }
    let pool = pool.build().context("cannot start the worker threads")?;
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(0)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} jobs  {msg}  [{elapsed_precise}]")
            .expect("a valid template"),
    );
    let options = Options {
        report,
        seed: args.seed,
        quick: args.quick,
        long: args.long,
        only: args.only.clone(),
    };
    let clock = Instant::now();
    let sink = Bar(bar);
    let results = pool.install(|| reproduce::reproduce(&options, &sink))?;
    sink.0.finish_and_clear();
    let ran = reproduce::Ran::here(pool.current_num_threads());
    let written = reproduce::write_report(&results, &ran, &out)?;
    let ids: Vec<&str> = results.experiments.iter().map(|e| e.id.as_str()).collect();
    line(format_args!(
        "{} {} ({} run, seed {}, {} thread{}) in {:.0} s",
        match report {
            Report::Paper => "reproduced",
            Report::BlocksWorld => "benchmarked",
        },
        ids.join(", "),
        if args.quick {
            "quick"
        } else if args.long {
            "long"
        } else {
            "full"
        },
        args.seed,
        pool.current_num_threads(),
        if pool.current_num_threads() == 1 { "" } else { "s" },
        clock.elapsed().as_secs_f64()
    ))?;
    for e in &results.experiments {
        line(format_args!("{}: {}", e.id, e.reading))?;
    }
    line(format_args!(
        "report: {} (results: {}, summary: {}, {} pictures)",
        written.readme.display(),
        written.results.display(),
        written.summary.display(),
        written.pictures.len()
    ))
}
