//! Demonstration recordings: every step of a correction session as JSON Lines, written as it
//! happens ([`format`](mod@format)), and their replay into a learner ([`replay`]).
//!
//! The two halves are apart so that reading a recording needs no learner: [`format`](mod@format) holds
//! the records, the writer and the bounded reader; [`replay`] checks each line against the
//! world's rules and hands the steps to a [`DemoLearner`]; [`episodes`] reads a file of
//! either kind (recording or trajectory) into checked episodes for learners that are not
//! the tabular agent (`neural`, the Python package).

pub mod admission;
pub mod episodes;
pub mod format;
pub mod replay;

pub use admission::{Admission, Admitted, RunWorld};
pub use episodes::{
    DemoEpisode, DemoStep, Demonstrations, episodes_of, read_admitted, read_demonstrations, read_episodes,
};
pub use format::{
    DEMOS_FORMAT, DEMOS_VERSION, DemoFile, DemoRecord, DemoSink, DemoWriter, EpisodeLine, MAX_LINE_BYTES,
    MAX_RECORDING_BYTES, ParticipantLine, SessionLine, StateLine, StepLine, WithdrawnLine, WorldLine, open, unix_ms,
};
pub use replay::{
    BadLine, BadLines, DemoLearner, Replay, ReplayReport, StepTime, learn_admitted, learn_from_file, learn_from_reader,
    learn_from_records,
};
