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

/// The network file reader ([`neural::Dqn::read_from`]): any bytes give a network or an
/// error; a network that reads plays: its forward pass answers an observation of its world
/// with one value per output column.
pub fn network_file(data: &[u8]) {
    let Ok(dqn) = neural::Dqn::read_from(data, "fuzz input") else {
        return;
    };
    plays_its_world(&dqn);
}

/// `dqn`'s forward pass answers an observation of its world with one value per action.
fn plays_its_world(dqn: &neural::Dqn) {
    let config = dqn.config();
    let goal = Goal::identity(config.blocks()).expect("a read config has a valid block count");
    let Ok(mut env) = sim::Env::new(config.env_config(goal)) else {
        return;
    };
    let obs = env.reset(0);
    let values = dqn.q_values(&obs).expect("a network that reads plays its own world");
    assert_eq!(values.len(), Action::count(config.blocks()));
}

/// The relational network file reader ([`neural::relational::RelationalModel::read_from`]):
/// any bytes give a network or an error; a network that reads plays a small problem to its
/// end, reaching the goal or not, never failing.
pub fn relational_file(data: &[u8]) {
    let Ok(model) = neural::relational::RelationalModel::read_from(data, "fuzz input") else {
        return;
    };
    let start = oracle::towers::random_state(5, 1);
    let goal = oracle::towers::random_goal(5, 2, 5, 2).expect("a goal of 5 blocks");
    model.play(&start, &goal).expect("a network that reads plays");
}

/// The PDDL problem reader ([`oracle::pddl::Problem::parse`]): any text gives a problem or an
/// error; a problem that reads writes back (`Display`) to text that reads as the same problem.
pub fn pddl_problem(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(problem) = oracle::pddl::Problem::parse(text) {
        assert_eq!(problem.start().blocks(), problem.block_names().len());
        let again = oracle::pddl::Problem::parse(&problem.to_string());
        assert_eq!(again.as_ref().ok(), Some(&problem), "{again:?}");
    }
}

/// The tabular checkpoint reader ([`agent::Trainer::read_checkpoint`]): any bytes give a run
/// or an error; a run that reads holds a usable agent, as [`model_file`] checks one.
pub fn train_checkpoint(data: &[u8]) {
    let Ok(trainer) = agent::Trainer::read_checkpoint(data, "fuzz input") else {
        return;
    };
    let agent = trainer.agent();
    assert_eq!(agent.table().columns(), Action::count(agent.blocks()));
    assert_eq!(agent.table().key_count(), agent.repr().key_count());
}

/// The network checkpoint reader ([`neural::Trainer::read_checkpoint`]): any bytes give a run
/// or an error; a run that reads is within its plan, and its network plays its own world.
pub fn dqn_checkpoint(data: &[u8]) {
    let Ok(trainer) = neural::Trainer::read_checkpoint(data, "fuzz input") else {
        return;
    };
    assert!(trainer.steps_done() <= trainer.total_steps());
    let dqn = trainer.snapshot().expect("a run that reads has a network");
    plays_its_world(&dqn);
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
            let states = sim::GridWorld::new(e.grid, e.start.clone())
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
