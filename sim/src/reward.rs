//! Reward models (docs/world.md section 5, and `paper-code`, the authors' code). Each is a named type whose fields are its constants;
//! [`RewardModel`] picks one by name.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::action::Action;
use crate::coded_state::CodedState;
use crate::error::{Result, SimError};
use crate::goal::Goal;
use crate::grid::Grid;
use crate::state::State;
use crate::view::View;

/// One step, as a reward model sees it.
#[derive(Clone, Copy, Debug)]
pub struct Transition<'a> {
    /// The grid.
    pub grid: Grid,
    /// The world: seen from above or from the side (where the goal asks more).
    pub view: View,
    /// The goal of the episode.
    pub goal: &'a Goal,
    /// The state before the action.
    pub before: &'a State,
    /// The action taken.
    pub action: Action,
    /// The action taken just before this one in the episode, if any.
    pub previous_action: Option<Action>,
    /// The state after the action.
    pub after: &'a State,
}

impl Transition<'_> {
    /// Whether the goal holds after the action.
    pub fn reaches_goal(&self) -> bool {
        self.goal.holds_in(self.view, self.after)
    }
}

/// `sparse`: a bonus on reaching the goal, nothing otherwise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sparse {
    /// Reward on the step that reaches the goal (SPEC: +10).
    pub goal_bonus: f64,
}

impl Default for Sparse {
    fn default() -> Self {
        Self { goal_bonus: 10.0 }
    }
}

impl Sparse {
    fn reward(&self, t: &Transition) -> f64 {
        if t.reaches_goal() { self.goal_bonus } else { 0.0 }
    }
}

/// `dense` (the paper's DQN reward): every step `-d / d_max`, where `d` is the sum of the
/// Manhattan distances between goal-consecutive blocks after the step and `d_max` its
/// largest value on the grid, `(N - 1)(W - 1 + H - 1)`; the step that reaches the goal gets
/// `goal_bonus` on top.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dense {
    /// Added on the step that reaches the goal (SPEC: +10).
    pub goal_bonus: f64,
}

impl Default for Dense {
    fn default() -> Self {
        Self { goal_bonus: 10.0 }
    }
}

impl Dense {
    fn reward(&self, t: &Transition) -> f64 {
        let n = t.goal.block_count() as f64;
        let d_max = (n - 1.0) * (t.grid.width() + t.grid.height() - 2).max(1) as f64;
        let shaped = -f64::from(t.goal.chain_distance(t.after)) / d_max;
        if t.reaches_goal() {
            shaped + self.goal_bonus
        } else {
            shaped
        }
    }
}

/// `paper`: the paper's tuned Q-learning reward (section IV.6), summed per step:
///
/// - the held block's distance to the cell it chases (docs/world.md section 6): `closer` when it
///   fell, `farther` when it grew, 0 when equal. Counted only when the same block is held
///   before and after the step (a move); a pick or a drop changes no distance. A chased cell
///   outside the grid (below a block on the bottom row) still has a distance.
/// - `adjacent_pair` for every goal-consecutive pair whose blocks are neighbours.
/// - `drop_far` for a Drop of a block whose distance to its chased cell is at least
///   `drop_far_distance` (the paper: "greater than 5000", squared pixels, under one cell:
///   read as "not on the chased cell").
/// - `pick_then_drop` for a Drop straight after a Pick.
/// - `pair_in_place` for every goal pair in place.
///
/// The paper's text lost signs; this is the reading that rewards progress, and it is a
/// reading.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Paper {
    /// The chased distance fell (+1).
    pub closer: f64,
    /// The chased distance grew (-5).
    pub farther: f64,
    /// Per goal-consecutive pair of neighbouring blocks (+5).
    pub adjacent_pair: f64,
    /// A Drop away from the chased cell (-0.1).
    pub drop_far: f64,
    /// Distance to the chased cell from which a Drop counts as far (1).
    pub drop_far_distance: u32,
    /// A Drop straight after a Pick (-0.1).
    pub pick_then_drop: f64,
    /// Per goal pair in place (+50).
    pub pair_in_place: f64,
}

impl Default for Paper {
    fn default() -> Self {
        Self {
            closer: 1.0,
            farther: -5.0,
            adjacent_pair: 5.0,
            drop_far: -0.1,
            drop_far_distance: 1,
            pick_then_drop: -0.1,
            pair_in_place: 50.0,
        }
    }
}

impl Paper {
    fn reward(&self, t: &Transition) -> f64 {
        let mut r = 0.0;
        if let (Some(h), Some(h2)) = (t.before.held_block(), t.after.held_block())
            && h == h2
        {
            let d0 = t.goal.chased_distance(h, t.before);
            let d1 = t.goal.chased_distance(h, t.after);
            r += match d1.cmp(&d0) {
                std::cmp::Ordering::Less => self.closer,
                std::cmp::Ordering::Greater => self.farther,
                std::cmp::Ordering::Equal => 0.0,
            };
        }
        let adjacent = t
            .goal
            .pairs()
            .filter(|&(a, b)| t.after.cell(a).manhattan(t.after.cell(b)) == 1)
            .count();
        r += self.adjacent_pair * adjacent as f64;
        if t.action == Action::Drop {
            if let Some(h) = t.before.held_block()
                && t.goal.chased_distance(h, t.before) >= self.drop_far_distance
            {
                r += self.drop_far;
            }
            if matches!(t.previous_action, Some(Action::Pick(_))) {
                r += self.pick_then_drop;
            }
        }
        r + self.pair_in_place * t.goal.pairs_in_place(t.after) as f64
    }
}

/// `paper-code`: the reward as the authors coded it (docs/world.md section 10, "Reward as coded"; their
/// `BlockWorld_t.py:104-159`, `get_sparse_reward_for_state_pramodith` plus
/// `get_reward_for_state_action_pramodith`), where `paper` is our reading of their prose.
/// Per step, the sum of:
///
/// - a move term, when the same block is held before and after the step: `closer` if the
///   `d` of its pair (the first entry of the [`CodedState`]) fell, 0 if equal, `farther` if
///   it grew. Pick and Drop change the held block and get 0.
/// - if the [`CodedState`] changed: `pair_in_place` times the number of goal pairs in place
///   after the step, when that number is above 0 (paid on **every** state-changing step
///   while pairs stand, not once). If it did not change (a blocked move): `unchanged`.
/// - `drop_far` for a Drop of a block whose pair's `d` exceeds `drop_far_above` squared
///   pixels (5000: not stacked, beside, or diagonally above).
///
/// The paper's "+5 per adjacent pair" never fires in their code (a 55 px^2 threshold no
/// two blocks meet) and there is no "pick then drop" penalty; neither is here. Under the
/// `free` protocol, which the authors' agents never used, the same definitions apply to
/// our tuple: an action that changes nothing (a move or a Drop with nothing held, a Pick of
/// the held block) gets `unchanged`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PaperCode {
    /// The held pair's `d` fell (+1).
    pub closer: f64,
    /// The held pair's `d` grew (-5).
    pub farther: f64,
    /// Per goal pair in place, on a step that changed the tuple (+50).
    pub pair_in_place: f64,
    /// A step that left the tuple as it was (-0.1).
    pub unchanged: f64,
    /// A Drop of a block whose pair's `d` exceeds `drop_far_above` (-0.1).
    pub drop_far: f64,
    /// Squared pixels above which a Drop is far (5000).
    pub drop_far_above: u32,
}

impl Default for PaperCode {
    fn default() -> Self {
        Self {
            closer: 1.0,
            farther: -5.0,
            pair_in_place: 50.0,
            unchanged: -0.1,
            drop_far: -0.1,
            drop_far_above: 5000,
        }
    }
}

impl PaperCode {
    fn reward(&self, t: &Transition) -> f64 {
        let before = CodedState::of(t.grid, t.goal, t.before);
        let after = CodedState::of(t.grid, t.goal, t.after);
        let mut r = 0.0;
        if let (Some(d0), Some(d1)) = (before.held_distance(), after.held_distance())
            && before.held == after.held
        {
            r += match d1.cmp(&d0) {
                std::cmp::Ordering::Less => self.closer,
                std::cmp::Ordering::Greater => self.farther,
                std::cmp::Ordering::Equal => 0.0,
            };
        }
        if before == after {
            r += self.unchanged;
        } else {
            let pairs = t.goal.pairs_in_place(t.after);
            if pairs > 0 {
                r += self.pair_in_place * pairs as f64;
            }
        }
        if t.action == Action::Drop
            && let Some(d) = before.held_distance()
            && d > self.drop_far_above
        {
            r += self.drop_far;
        }
        r
    }
}

/// `step-cost`: `cost` every step, 0 on the step that reaches the goal; maximising it is
/// finding a shortest plan.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepCost {
    /// Reward of every step that does not reach the goal (SPEC: -1).
    pub cost: f64,
}

impl Default for StepCost {
    fn default() -> Self {
        Self { cost: -1.0 }
    }
}

impl StepCost {
    fn reward(&self, t: &Transition) -> f64 {
        if t.reaches_goal() { 0.0 } else { self.cost }
    }
}

/// A reward model with its constants.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum RewardModel {
    /// See [`Sparse`].
    Sparse(Sparse),
    /// See [`Dense`].
    Dense(Dense),
    /// See [`Paper`].
    Paper(Paper),
    /// See [`StepCost`].
    StepCost(StepCost),
    /// See [`PaperCode`].
    PaperCode(PaperCode),
}

impl Default for RewardModel {
    /// `sparse`: the task itself, with no shaping.
    fn default() -> Self {
        RewardModel::Sparse(Sparse::default())
    }
}

impl RewardModel {
    /// The names the models are chosen by.
    pub const NAMES: [&'static str; 5] = ["sparse", "dense", "paper", "step-cost", "paper-code"];

    /// An error ([`SimError::NotOneTower`]) if this model cannot score `goal`: `paper` and
    /// `paper-code` measure how far a block is from its partner in the one tower, so they
    /// take only a goal of one tower of every block.
    pub fn check_goal(&self, goal: &Goal) -> Result<()> {
        match self {
            RewardModel::Paper(_) => goal.one_tower("the paper reward").map(drop),
            RewardModel::PaperCode(_) => goal.one_tower("the paper-code reward").map(drop),
            _ => Ok(()),
        }
    }

    /// The model called `name`, with the SPEC's constants.
    pub fn from_name(name: &str) -> Result<RewardModel> {
        Ok(match name {
            "sparse" => RewardModel::Sparse(Sparse::default()),
            "dense" => RewardModel::Dense(Dense::default()),
            "paper" => RewardModel::Paper(Paper::default()),
            "step-cost" => RewardModel::StepCost(StepCost::default()),
            "paper-code" => RewardModel::PaperCode(PaperCode::default()),
            _ => {
                return Err(SimError::Parse {
                    what: "reward model",
                    text: name.to_string(),
                    reason: format!("choose one of {}", Self::NAMES.join(", ")),
                });
            }
        })
    }

    /// This model's name.
    pub fn name(&self) -> &'static str {
        match self {
            RewardModel::Sparse(_) => "sparse",
            RewardModel::Dense(_) => "dense",
            RewardModel::Paper(_) => "paper",
            RewardModel::StepCost(_) => "step-cost",
            RewardModel::PaperCode(_) => "paper-code",
        }
    }

    /// The reward of one step.
    pub fn reward(&self, t: &Transition) -> f64 {
        match self {
            RewardModel::Sparse(m) => m.reward(t),
            RewardModel::Dense(m) => m.reward(t),
            RewardModel::Paper(m) => m.reward(t),
            RewardModel::StepCost(m) => m.reward(t),
            RewardModel::PaperCode(m) => m.reward(t),
        }
    }
}

impl fmt::Display for RewardModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for RewardModel {
    type Err = SimError;

    fn from_str(name: &str) -> Result<RewardModel> {
        RewardModel::from_name(name)
    }
}
