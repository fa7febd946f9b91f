//! The checks the fuzz targets make, one function per target, each on one input.
//!
//! Two callers share them, so that what the fuzzer found stays found: the `cargo fuzz`
//! targets in `fuzz/` (libFuzzer, instrumented, on nightly features) and the ordinary test
//! `tests/fuzz_corpus.rs`, which replays every input kept in `fuzz/corpus/` on stable Rust.
//! Each reader must answer any bytes with a value or an error, never a panic, and never
//! memory beyond its bound; where a reader's output can be written back, writing and
//! reading it again must give it back.

use std::io::BufReader;
use std::path::Path;

use agent::demos::format::{RawLine, RecordingLines};
use agent::demos::{DemoRecord, episodes_of};
use agent::{QAgent, Representation};
use sim::trajectory::TrajectoryReader;
use sim::{Action, Goal, Grid, State};

/// The model file reader ([`QAgent::read_from`]): any bytes give an agent or an error.
pub fn model_file(data: &[u8]) {
    if let Ok(agent) = QAgent::read_from(data, "fuzz input") {
        // A model that loads is usable: its shape is its representation's.
        assert_eq!(agent.table().columns(), Action::count(agent.blocks()));
        assert_eq!(agent.table().key_count(), agent.repr().key_count());
    }
}

/// The recording format's reader (`agent::demos::format`), with no learner: every line
/// it reads that parses as a record writes back to the same record; and the checked reader
/// of demonstrations files.
pub fn recording(data: &[u8]) {
    let mut lines = RecordingLines::new(data);
    while let Ok(Some(line)) = lines.next_line() {
        if let RawLine::Text(text) = line
            && let Ok(record) = serde_json::from_str::<DemoRecord>(text.trim())
        {
            let again = serde_json::to_string(&record).expect("records serialise");
            assert_eq!(serde_json::from_str::<DemoRecord>(&again).ok(), Some(record));
        }
    }
    demonstrations(data);
}

/// The checked reader of demonstrations files (`agent::demos::episodes_of`, what `dqn
/// --demos-file` and Python's `read_recording` run) on `data`: the episodes it gives replay
/// by the rules from their start.
fn demonstrations(data: &[u8]) {
    let name = Path::new("fuzz input");
    let Ok(file) = agent::demos::format::read(Box::new(std::io::Cursor::new(data.to_vec())), name) else {
        return;
    };
    if let Ok(episodes) = episodes_of(file, name, None) {
        for e in episodes {
            let actions: Vec<Action> = e.steps.iter().map(|s| s.action).collect();
            let states = sim::GridWorld::new(e.grid, e.start)
                .expect("a checked start")
                .replay(&actions)
                .expect("checked actions");
            assert_eq!(states, e.states());
        }
    }
}

/// The trajectory reader ([`TrajectoryReader`]), which `dqn --demos-file` and Python's
/// `read_recording` run: episodes it hands out keep their horizon.
pub fn trajectory(data: &[u8]) {
    for episode in TrajectoryReader::new(BufReader::new(data), "fuzz input").map_while(Result::ok) {
        assert!(episode.steps.len() <= episode.horizon as usize);
    }
    demonstrations(data);
}

/// The command line's parsers of grids (`--grid`), goals (`--goal`, `--goals`), states
/// (`solve --start`, `--held`) and actions: what parses prints back to the same value.
pub fn cli_parsers(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let grid = text.parse::<Grid>();
    if let Ok(grid) = grid {
        assert_eq!(grid.to_string().parse::<Grid>().ok(), Some(grid));
    }
    if let Ok(goal) = Goal::parse(text, None) {
        assert_eq!(
            Goal::parse(&goal.to_string(), Some(goal.block_count())).ok(),
            Some(goal)
        );
    }
    for blocks in [2, 3, 8] {
        let _ = Goal::parse_list(text, blocks);
        if let Ok(action) = Action::parse(text, blocks) {
            assert_eq!(Action::parse(&action.to_string(), blocks).ok(), Some(action));
        }
    }
    for held in [None, Some(0), Some(256)] {
        for grid in [Grid::default(), Grid::new(1, 5).expect("a grid")] {
            if let Ok(state) = State::parse(text, held, grid) {
                assert_eq!(state.held_block().map(|b| b.index()), held);
            }
        }
    }
}
