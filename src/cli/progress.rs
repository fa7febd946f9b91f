//! Progress bars on the long commands (`eval`, `run`, `correct`): drawn on standard error
//! when it is a terminal, hidden otherwise, so that pipes, logs and tests see no bar.

use std::io::IsTerminal;

use agent::{DemoRecord, DemoSink};
use indicatif::{ProgressBar, ProgressStyle};

/// A bar of `len` `unit`s (e.g. "episodes"), hidden unless stderr is a terminal.
pub fn bar(len: u64, unit: &str) -> ProgressBar {
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(len)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{{bar:30}} {{pos}}/{{len}} {unit}  {{msg}}  [{{elapsed_precise}}, eta {{eta}}]"
        ))
        .expect("a valid template"),
    );
    bar
}

/// A demonstration sink that moves `bar` on at every episode a session opens and passes
/// every line on to `sink`.
pub struct TickingSink<S> {
    /// Where the lines go.
    pub sink: S,
    /// The bar, one step an episode.
    pub bar: ProgressBar,
}

impl<S: DemoSink> DemoSink for TickingSink<S> {
    fn record(&mut self, line: &DemoRecord) -> agent::Result<()> {
        if matches!(line, DemoRecord::Episode(_)) {
            self.bar.inc(1);
        }
        self.sink.record(line)
    }
}
