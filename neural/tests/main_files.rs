//! Network files written by an earlier build (main before the engine was rewritten: the
//! candle one) still load, and play the same greedy actions as that build played.
//!
//! The fixtures (`tests/fixtures/`) were made with main's binary:
//!
//! ```text
//! blockstack dqn --preset dqfd-planes --blocks 2 --demos exact:10 --pretrain 30 --steps 50 \
//!     --hidden 16 --seed 3 --out small.safetensors
//! blockstack dqn --preset paper-dqfd --blocks 2 --demos exact:20 --pretrain 40 --steps 0 \
//!     --batch 8 --hidden 4 --seed 3 --lr 0.003 --out paper.safetensors
//! blockstack run --agent dqn --model M.safetensors --blocks 2 --episodes 30 --seed 7 \
//!     --epsilon 0 --horizon 3 --backend grid --trajectory M.traj.jsonl
//! ```

use std::path::PathBuf;

use neural::Dqn;
use sim::{BlockId, Cell, Goal, Grid, Observation, State};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn cells(value: &serde_json::Value) -> Vec<Cell> {
    value
        .as_array()
        .unwrap()
        .iter()
        .map(|c| Cell::new(c[0].as_u64().unwrap() as u16, c[1].as_u64().unwrap() as u16))
        .collect()
}

/// Replays every recorded step: the observation before it, and the action main chose.
fn recorded_choices(trajectory: &str) -> Vec<(Observation, usize)> {
    let text = std::fs::read_to_string(fixture(trajectory)).unwrap();
    let mut out = Vec::new();
    let mut current: Option<Observation> = None;
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        match v["type"].as_str().unwrap() {
            "episode" => {
                let order: Vec<BlockId> = v["goal"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|b| BlockId::of(b.as_u64().unwrap() as usize))
                    .collect();
                current = Some(Observation {
                    grid: Grid::default(),
                    state: State::new(&cells(&v["start"]), None).unwrap(),
                    protocol: sim::ActionProtocol::Free,
                    goal: Goal::new(&order).unwrap(),
                    view: sim::View::Top,
                });
            }
            "step" => {
                let obs = current.as_mut().unwrap();
                out.push((obs.clone(), v["action"].as_u64().unwrap() as usize));
                let held = v["held"].as_u64().map(|b| BlockId::of(b as usize));
                obs.state = State::new(&cells(&v["blocks"]), held).unwrap();
            }
            other => panic!("unexpected record {other}"),
        }
    }
    out
}

#[test]
fn networks_written_by_main_play_as_they_did_there() {
    for name in ["small", "paper"] {
        let dqn = Dqn::load(&fixture(&format!("{name}.safetensors"))).unwrap();
        let choices = recorded_choices(&format!("{name}.traj.jsonl"));
        assert_eq!(choices.len(), 90, "{name}");
        for (i, (obs, action)) in choices.iter().enumerate() {
            let got = dqn.greedy_action(obs).unwrap();
            assert_eq!(got.index(), *action, "{name}: step {i}: {obs:?}");
        }
        // A copy saved by this build loads back to the same values.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("again.safetensors");
        dqn.save(&path).unwrap();
        let again = Dqn::load(&path).unwrap();
        let values = |d: &Dqn| d.net().tensors().map(|t| t.values.to_vec()).collect::<Vec<_>>();
        assert_eq!(values(&again), values(&dqn), "{name}");
    }
}
