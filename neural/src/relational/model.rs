//! A trained relational policy with its training config: played as block moves, as a
//! side-view agent ([`RelationalPolicy`]), saved and read as a network file.
//!
//! # Network files
//!
//! The project's model container (`files::container`: safetensors with blockstack's
//! metadata and a CRC-32), format [`FORMAT`] version [`VERSION`]: one `F32` tensor per
//! parameter, named as [`RelationalNet::tensors`] names them (`up.linear1.weight`,
//! `goal_table`, `pair.linear2.weight`, ...; a linear layer's weight is `[in, out]`), and as
//! metadata `{"config": the RelationalConfig, "report": [one IterationReport per DAgger
//! iteration]}`. The config is stored as it is: changing `RelationalConfig` is changing the
//! format. A reader refuses a file that is missing, too large ([`MAX_FILE_BYTES`]),
//! truncated, corrupt, of another format or version, or whose tensors do not fit the
//! network its config describes, each with a message that says which.

use std::path::Path;

use agent::Policy;
use files::container::Expect;
use oracle::towers::{BlockPlanner, Move, Table, TowerGoal, TowerPlan, Towers, TowersError};
use rand::RngExt;
use serde::{Deserialize, Serialize};
use sim::block_move::{self, BlockMove};
use sim::seeding::SimRng;
use sim::{Action, Observation, View};

use crate::error::{NeuralError, Result};
use crate::netfile::{self, NetFile};

use super::incremental::LivePass;
use super::move_policy::MovePolicy;
use super::net::RelationalNet;
use super::train::{IterationReport, RelationalConfig};

/// The format name of a relational network file.
pub const FORMAT: &str = "blockstack-relational";

/// The relational network file version this build writes and reads.
pub const VERSION: u32 = 1;

/// The largest relational network file read: the preset's network is about 40 KB.
pub const MAX_FILE_BYTES: u64 = 1 << 26;

const EXPECT: Expect<'static> = Expect {
    format: FORMAT,
    version: VERSION,
    max_bytes: MAX_FILE_BYTES,
    what: "a relational network file",
};

/// The JSON metadata of a relational network file.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Metadata {
    config: RelationalConfig,
    report: Vec<IterationReport>,
}

/// A trained relational policy: its network, how it was trained, and the training's
/// iterations.
#[derive(Clone, Debug)]
pub struct RelationalModel {
    net: RelationalNet,
    config: RelationalConfig,
    report: Vec<IterationReport>,
}

/// How a game of block moves went.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Game {
    /// The moves made, first to last.
    pub moves: Vec<Move>,
    /// Whether the goal held after them, within the move limit ([`super::move_limit`]).
    pub reached: bool,
}

impl RelationalModel {
    /// Trains a policy as `config` says ([`super::train::train`]); `progress` after every
    /// iteration.
    pub fn train(config: &RelationalConfig, progress: &mut dyn FnMut(&IterationReport)) -> Result<RelationalModel> {
        let (net, report) = super::train::train(config, progress)?;
        Ok(RelationalModel {
            net,
            config: *config,
            report,
        })
    }

    /// The network.
    pub fn net(&self) -> &RelationalNet {
        &self.net
    }

    /// How it was trained.
    pub fn config(&self) -> &RelationalConfig {
        &self.config
    }

    /// The training's iterations.
    pub fn report(&self) -> &[IterationReport] {
        &self.report
    }

    /// Its name in reports.
    pub fn name(&self) -> String {
        let s = self.config.shape;
        format!(
            "relational policy ({} rounds, width {}; trained on up to {} blocks)",
            s.rounds, s.width, self.config.max_blocks
        )
    }

    /// A chooser of block moves ([`MovePolicy`]).
    pub fn move_policy(&self) -> MovePolicy<'_> {
        MovePolicy::new(&self.net)
    }

    /// Plays the policy greedily from `start` to `goal` on an unbounded table, for at most
    /// [`super::move_limit`] moves; an error if the goal names a block the state lacks.
    ///
    /// One pass over the blocks, then each move updates only what it changed
    /// ([`LivePass`]).
    pub fn play(&self, start: &Towers, goal: &TowerGoal) -> Result<Game> {
        let mut live = LivePass::new(&self.net, start, goal)?;
        let mut moves = Vec::new();
        while moves.len() < super::move_limit(start.blocks()) && !live.goal_holds() {
            let Some(mv) = live.best_move(true) else {
                break;
            };
            live.apply(mv, Table::Unbounded)?;
            moves.push(mv);
        }
        Ok(Game {
            reached: live.goal_holds(),
            moves,
        })
    }

    /// The policy as a side-view agent, taking a random legal block move with probability
    /// `epsilon`.
    pub fn policy(&self, epsilon: f64) -> Result<RelationalPolicy<'_>> {
        agent::qlearning::check_epsilon(epsilon)?;
        Ok(RelationalPolicy {
            chooser: self.move_policy(),
            epsilon,
            pending: Vec::new(),
        })
    }

    /// Writes the network file (module docs) through the project's output helper:
    /// atomically for a regular file.
    pub fn save(&self, path: &Path) -> Result<()> {
        let metadata = Metadata {
            config: self.config,
            report: self.report.clone(),
        };
        netfile::save(path, &EXPECT, &metadata, self.net.tensors())
    }

    /// Reads a relational network file; an error saying what is wrong if it is missing, too
    /// large, truncated, corrupt, of another format or version, or if its tensors do not fit
    /// its config.
    pub fn load(path: &Path) -> Result<RelationalModel> {
        RelationalModel::from_file(&NetFile::open(path, &EXPECT)?)
    }

    /// Reads a relational network from the bytes of its file, named `name` in errors, with
    /// the checks of [`RelationalModel::load`] (the fuzz target `relational_file` feeds it).
    pub fn read_from(input: impl std::io::Read, name: &str) -> Result<RelationalModel> {
        RelationalModel::from_file(&NetFile::read_from(input, name, &EXPECT)?)
    }

    /// The network a file read as a container holds, checked against its config.
    fn from_file(file: &NetFile) -> Result<RelationalModel> {
        let Metadata { config, report } = file.metadata()?;
        file.config_checked(config.validate())?;
        let mut net = RelationalNet::new(config.shape, &mut sim::seeding::rng(0))?;
        let expected = net.tensor_count();
        file.fill("its network", expected, |name, shape, values| {
            net.set_tensor(name, shape, values)
        })?;
        Ok(RelationalModel { net, config, report })
    }
}

/// The policy as a planner: played greedily ([`RelationalModel::play`]); a game that does
/// not reach the goal within [`super::move_limit`] moves is an error that says so.
impl BlockPlanner for RelationalModel {
    fn name(&self) -> &str {
        "relational policy"
    }

    fn plan(&self, start: &Towers, goal: &TowerGoal) -> oracle::Result<TowerPlan> {
        let game = self.play(start, goal).map_err(|e| match e {
            NeuralError::Oracle(e) => e,
            other => TowersError::NoPlan {
                planner: "relational policy".into(),
                reason: other.to_string(),
            }
            .into(),
        })?;
        if !game.reached {
            return Err(TowersError::NoPlan {
                planner: "relational policy".into(),
                reason: format!(
                    "it did not reach the goal within {} block moves ({} blocks)",
                    super::move_limit(start.blocks()),
                    start.blocks()
                ),
            }
            .into());
        }
        Ok(TowerPlan { moves: game.moves })
    }
}

/// The relational policy as a side-view agent: at each block-move boundary (nothing held,
/// no gripper action pending) it reads the towers and the goal's towers from what it sees,
/// chooses a block move (or, with probability `epsilon`, a random legal one) and carries it
/// out as the gripper actions [`sim::block_move::expand`] gives, a move to the table going
/// to the leftmost empty column. The table is as wide as the grid.
pub struct RelationalPolicy<'n> {
    chooser: MovePolicy<'n>,
    epsilon: f64,
    /// The gripper actions left of the current move, last first.
    pending: Vec<Action>,
}

impl RelationalPolicy<'_> {
    /// The block move for `obs` (in the side view, nothing held); `rng` draws the random
    /// moves.
    pub fn block_move(&mut self, obs: &Observation, rng: &mut SimRng) -> Result<BlockMove> {
        if obs.view != View::Side {
            return Err(NeuralError::Mismatch(format!(
                "the relational policy plays the side view (block moves on towers), not the {} view",
                obs.view
            )));
        }
        let state = Towers::new(&sim::view::towers(&obs.state)?)?;
        let goal = TowerGoal::new(&obs.goal.tower_lists())?;
        goal.check_blocks(state.blocks())?;
        let table = Table::Columns(obs.grid.width());
        let mv = if self.epsilon > 0.0 && rng.random_bool(self.epsilon) {
            let legal = state.moves(table);
            legal.get(rng.random_range(0..legal.len().max(1))).copied()
        } else {
            self.chooser.choose(&state, &goal, table)
        };
        let mv = mv.ok_or_else(|| {
            NeuralError::Oracle(oracle::OracleError::GoalAlreadyHolds {
                goal: obs.goal.to_string(),
            })
        })?;
        Ok(oracle::towers::block_move_of(&obs.state, obs.grid, mv)?)
    }
}

impl Policy for RelationalPolicy<'_> {
    fn name(&self) -> String {
        "relational".into()
    }

    fn begin_episode(&mut self, _obs: &Observation) {
        self.pending.clear();
    }

    fn act(&mut self, obs: &Observation, rng: &mut SimRng) -> agent::Result<Action> {
        if self.pending.is_empty() {
            let mv = self.block_move(obs, rng)?;
            self.pending = block_move::expand(&obs.state, obs.grid, mv)?;
            self.pending.reverse();
        }
        self.pending
            .pop()
            .ok_or_else(|| agent::AgentError::Config("a block move expanded into no gripper action".into()))
    }
}
