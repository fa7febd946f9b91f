//! The interface every agent offers the episode runner, and the random agent.

use rand::RngExt;
use sim::seeding::SimRng;
use sim::{Action, Observation};

use crate::error::Result;

/// Something that chooses actions.
///
/// Randomness comes only from the `rng` the caller passes, so an episode is fixed by its
/// seed whatever the policy.
pub trait Policy {
    /// A short name for reports (`random`, `oracle`, ...).
    fn name(&self) -> String;

    /// Called once at the start of every episode, before the first [`Policy::act`].
    fn begin_episode(&mut self, _obs: &Observation) {}

    /// The next action for `obs`.
    fn act(&mut self, obs: &Observation, rng: &mut SimRng) -> Result<Action>;
}

/// Uniformly random actions: the paper's baseline.
#[derive(Clone, Copy, Debug, Default)]
pub struct RandomPolicy;

impl Policy for RandomPolicy {
    fn name(&self) -> String {
        "random".into()
    }

    fn act(&mut self, obs: &Observation, rng: &mut SimRng) -> Result<Action> {
        let n = obs.state.block_count();
        Ok(Action::from_index(rng.random_range(0..Action::count(n)), n)?)
    }
}
