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

/// Uniformly random legal actions: the paper's baseline.
///
/// One draw per action, uniform over [`Observation::legal_actions`] in index order. Under
/// the `free` protocol every action is legal and the draw is the action's index itself, so
/// a seeded run is the same as when this policy drew from all `5 + N` actions. Under the
/// `paper` protocol it is the authors' random agent: a uniformly random block when nothing
/// is held, then uniform over the four moves and Drop.
#[derive(Clone, Copy, Debug, Default)]
pub struct RandomPolicy;

impl Policy for RandomPolicy {
    fn name(&self) -> String {
        "random".into()
    }

    fn act(&mut self, obs: &Observation, rng: &mut SimRng) -> Result<Action> {
        let legal = obs.legal_actions();
        let k = rng.random_range(0..legal.count());
        Ok(legal.nth(k).expect("k is below the number of legal actions"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::{ActionProtocol, BlockId, Cell, Grid, State};

    fn obs(held: Option<u16>, protocol: ActionProtocol) -> Observation {
        Observation {
            grid: Grid::default(),
            state: State::new(&[Cell::new(0, 0), Cell::new(3, 3), Cell::new(6, 6)], held.map(BlockId)).unwrap(),
            goal: "0,1,2".parse().unwrap(),
            protocol,
            view: sim::View::Top,
        }
    }

    #[test]
    fn under_free_the_draw_is_the_action_index_as_before() {
        // The draw the policy made before protocols existed: an index in 0..5+N.
        let (mut a, mut b) = (sim::seeding::rng(11), sim::seeding::rng(11));
        for held in [None, Some(1)] {
            let o = obs(held, ActionProtocol::Free);
            for _ in 0..500 {
                let index = b.random_range(0..Action::count(3));
                assert_eq!(
                    RandomPolicy.act(&o, &mut a).unwrap(),
                    Action::from_index(index, 3).unwrap()
                );
            }
        }
    }

    #[test]
    fn under_paper_every_legal_action_is_drawn_and_nothing_else() {
        let mut rng = sim::seeding::rng(3);
        for held in [None, Some(2)] {
            let o = obs(held, ActionProtocol::Paper);
            let mut counts = [0u32; 8];
            for _ in 0..4000 {
                counts[RandomPolicy.act(&o, &mut rng).unwrap().index()] += 1;
            }
            let legal = o.legal_actions();
            for (i, &c) in counts.iter().enumerate() {
                // Uniform over 3 or 5 actions: each about 1333 or 800 of 4000.
                let expected = 4000 / legal.count() as u32;
                if legal.contains_index(i) {
                    assert!(
                        c.abs_diff(expected) < expected / 5,
                        "{held:?}: action {i} drawn {c} times"
                    );
                } else {
                    assert_eq!(c, 0, "{held:?}: illegal action {i} drawn");
                }
            }
        }
    }
}
