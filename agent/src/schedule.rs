//! Learner schedules: how training games are laid out, and how each step updates the table.
//!
//! Two schedules, one per world:
//!
//! - [`Schedule::Spec`] (ours, the default; unchanged): game `k` plays goal
//!   `goals[k % goals.len()]` for at most the config's horizon, alpha stays as set, and a
//!   step updates `Q(s,a) <- (1 - alpha) Q(s,a) + alpha (r + gamma max_a' Q(s',a'))`, the max
//!   over every column of `s'` (the initial values count), 0 when the step reached the goal.
//! - [`Schedule::PaperCode`]: the authors' learner as coded (docs/world.md section 10, "The learner";
//!   their `RL.py:192-299`, `q_learning_real`):
//!   - a game is up to [`PAPER_GAME_STEPS`] steps long ([`PAPER_GAME_STEPS_TWO_BLOCKS`] with
//!     two blocks), on a goal drawn uniformly from the training goals by the game's own
//!     seeded generator;
//!   - it ends when a step's reward is above 70 ([`sim::Termination::paper_training`]);
//!   - after step `k` of a game, if `k > 4000`, `k % 250 == 0` and the training epsilon is
//!     above 0.05, alpha falls by 0.1 (their `if cnt > 4000 and cnt % 250 == 0 and nu >
//!     0.05: alpha -= 0.1`): with alpha 1, steps 4251-4500 learn at 0.9, 4501-4750 at 0.8,
//!     4751-5000 at 0.7. Alpha never goes below 0 (a horizon past 6500 steps would take it
//!     there; the authors' games never ran that long);
//!   - the update reads only the entries the table has *seen* (ever written): the taken
//!     entry is first marked seen (at its initial value, 0), then
//!     `Q(s,a) <- Q(s,a) + alpha (r + gamma M - Q(s,a))` with `M` the largest seen value of
//!     `s'` (0 if none is seen), and `M = 0` after a Drop (the authors' next-state tuple
//!     after a Drop never equals a real state key, so nothing is ever seen there);
//!   - at the step that ends the game (reward above 70) `Q(s,a) <- (1 - alpha) Q(s,a) +
//!     alpha r`, that is `Q(s,a) = r` at alpha 1.
//!
//!   The greedy choice reads every legal entry, unseen ones at their initial value (0), as
//!   the authors' `get_best_action` did (`q[state].get(a, 0)`).
//!
//! The SPEC learners never track seen entries, so they compute and store exactly what they
//! did before this module existed.

use serde::{Deserialize, Serialize};
use sim::Termination;

use crate::error::AgentError;

/// Steps of a training game under [`Schedule::PaperCode`] (the authors' `iteration_count`).
pub const PAPER_GAME_STEPS: u32 = 5000;

/// Steps of a 2-block training game under [`Schedule::PaperCode`] (the paper's 2-block
/// experiments).
pub const PAPER_GAME_STEPS_TWO_BLOCKS: u32 = 1000;

/// The step of a game after which alpha starts to fall under [`Schedule::PaperCode`].
pub const ALPHA_DECAY_AFTER: u32 = 4000;

/// Every how many steps alpha falls, past [`ALPHA_DECAY_AFTER`].
pub const ALPHA_DECAY_EVERY: u32 = 250;

/// By how much alpha falls each time.
pub const ALPHA_DECAY_STEP: f64 = 0.1;

/// The training epsilon alpha decays only above (the authors' `nu > 0.05`).
pub const ALPHA_DECAY_MIN_EPSILON: f64 = 0.05;

/// Which schedule a learner trains and updates by (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Schedule {
    /// Ours: goals in turn, constant alpha, bootstrap over every column.
    #[default]
    Spec,
    /// The authors' learner as coded.
    PaperCode,
}

sim::names!(Schedule { Spec = "spec", PaperCode = "paper-code" } unknown(text) -> AgentError {
    AgentError::Config(format!("unknown schedule {text:?}: choose {}", Schedule::NAMES.join(" or ")))
});

impl Schedule {
    /// The length of a training game of `blocks` blocks when nothing else says:
    /// [`sim::DEFAULT_HORIZON`] under `spec`, 5000 (1000 with two blocks) under
    /// `paper-code`.
    pub const fn game_steps(self, blocks: usize) -> u32 {
        match self {
            Schedule::Spec => sim::DEFAULT_HORIZON,
            Schedule::PaperCode if blocks <= 2 => PAPER_GAME_STEPS_TWO_BLOCKS,
            Schedule::PaperCode => PAPER_GAME_STEPS,
        }
    }

    /// What ends a training game besides its length: the goal under `spec`, a step reward
    /// above 70 under `paper-code`.
    pub const fn training_termination(self) -> Termination {
        match self {
            Schedule::Spec => Termination::Goal,
            Schedule::PaperCode => Termination::paper_training(),
        }
    }

    /// Whether each game draws its goal from the training goals (otherwise they take turns).
    pub const fn draws_goal_per_game(self) -> bool {
        matches!(self, Schedule::PaperCode)
    }

    /// Whether the table remembers which entries were written.
    pub const fn tracks_seen(self) -> bool {
        matches!(self, Schedule::PaperCode)
    }

    /// The learning rate of step `step` (from 1) of a training game whose alpha starts at
    /// `alpha`, with training epsilon `epsilon` (module docs). Under `spec`, `alpha`.
    pub fn alpha_at(self, alpha: f64, epsilon: f64, step: u32) -> f64 {
        match self {
            Schedule::Spec => alpha,
            Schedule::PaperCode => {
                if epsilon <= ALPHA_DECAY_MIN_EPSILON {
                    return alpha;
                }
                // Decrements made after steps 1..step-1: those past 4000 that are multiples
                // of 250.
                let done = step.saturating_sub(1) / ALPHA_DECAY_EVERY;
                let decrements = done.saturating_sub(ALPHA_DECAY_AFTER / ALPHA_DECAY_EVERY);
                // Subtracted one at a time, as the authors' `alpha -= 0.1` did.
                let mut a = alpha;
                for _ in 0..decrements {
                    a -= ALPHA_DECAY_STEP;
                }
                a.max(0.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alpha_falls_by_a_tenth_every_250_steps_after_step_4000() {
        let s = Schedule::PaperCode;
        let at = |step| s.alpha_at(1.0, 0.1, step);
        assert_eq!(at(1), 1.0);
        assert_eq!(at(4000), 1.0);
        assert_eq!(at(4250), 1.0, "the decrement after step 4250 applies from step 4251");
        assert_eq!(at(4251), 0.9);
        assert_eq!(at(4500), 0.9);
        assert_eq!(at(4501), 0.8);
        assert_eq!(at(4751), 1.0 - 0.1 - 0.1 - 0.1);
        assert_eq!(at(5000), at(4751));
        // The authors' condition on nu: no decay at epsilon 0.05 or below.
        assert_eq!(s.alpha_at(1.0, 0.05, 5000), 1.0);
        // Never below 0.
        assert_eq!(s.alpha_at(0.25, 0.1, 5000), 0.0);
        assert_eq!(Schedule::Spec.alpha_at(0.5, 0.1, 5000), 0.5);
    }

    #[test]
    fn games_and_their_end() {
        assert_eq!(Schedule::PaperCode.game_steps(3), 5000);
        assert_eq!(Schedule::PaperCode.game_steps(2), 1000);
        assert_eq!(Schedule::Spec.game_steps(3), 1000);
        assert_eq!(
            Schedule::PaperCode.training_termination(),
            Termination::RewardAbove(70.0)
        );
        assert_eq!(Schedule::Spec.training_termination(), Termination::Goal);
    }

    #[test]
    fn schedules_parse_print_and_serialise_by_name() {
        for name in Schedule::NAMES {
            let s: Schedule = name.parse().unwrap();
            assert_eq!(s.to_string(), name);
            assert_eq!(serde_json::to_string(&s).unwrap(), format!("\"{name}\""));
        }
        assert!(
            "paper"
                .parse::<Schedule>()
                .unwrap_err()
                .to_string()
                .contains("spec or paper-code")
        );
    }
}
