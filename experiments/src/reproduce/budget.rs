//! The reproduction's budget: how much every experiment measures, chosen once from the
//! command line's `--quick` and `--long` and read by each experiment (E8's training runs,
//! E9's and E10's problems), none of which owns it.

use serde::Serialize;

use super::Options;

/// How much the reproduction measures: `--quick`, the default run, or `--long`. Each
/// experiment says what its budget buys (E8 its training runs, E9 and E10 their problems).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Budget {
    /// Tiny runs: the pipeline works (`--quick`).
    Quick,
    /// What the default run affords: minutes for the whole report.
    Default,
    /// Everything at full size (`--long`): E8's every arm at its preset's budget.
    Long,
}

impl Budget {
    /// The budget `options` ask for.
    pub fn of(options: &Options) -> Budget {
        if options.quick {
            Budget::Quick
        } else if options.long {
            Budget::Long
        } else {
            Budget::Default
        }
    }

    /// The budget's name, as the report prints it.
    pub fn name(self) -> &'static str {
        match self {
            Budget::Quick => "quick",
            Budget::Default => "default",
            Budget::Long => "long",
        }
    }
}
