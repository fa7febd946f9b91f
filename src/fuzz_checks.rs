//! The checks the fuzz targets make, one function per target, each on one input.
//!
//! Two callers share them, so that what the fuzzer found stays found: the `cargo fuzz`
//! targets in `fuzz/` (libFuzzer, instrumented, on nightly features) and the ordinary test
//! `tests/fuzz_corpus.rs`, which replays every input kept in `fuzz/corpus/` on stable Rust.
//! Each reader must answer any bytes with a value or an error, never a panic, and never
//! memory beyond its bound; where a reader's output can be written back, writing and
//! reading it again must give it back.

use std::io::BufReader;

use agent::demos::{BadLines, Replay};
use agent::{QAgent, QParams, ReprKind, Representation};
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

/// The recording reader ([`Replay`]), into a fresh 3-block agent of the paper's
/// representation on the default grid (the world of the kept recordings), under both
/// bad-line policies.
pub fn recording(data: &[u8]) {
    for policy in [BadLines::Skip, BadLines::Fail] {
        let mut agent = QAgent::new(ReprKind::Chasing, Grid::default(), 3, QParams::default())
            .expect("the paper's agent on the default grid");
        let mut replay = Replay::new(&mut agent, policy, "fuzz input");
        let _ = replay.read(data);
    }
}

/// The trajectory reader ([`TrajectoryReader`]): episodes it hands out keep their horizon.
pub fn trajectory(data: &[u8]) {
    for episode in TrajectoryReader::new(BufReader::new(data), "fuzz input").map_while(Result::ok) {
        assert!(episode.steps.len() <= episode.horizon as usize);
    }
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
