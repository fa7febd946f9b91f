//! Hindsight experience replay (HER, Andrychowicz et al. 2017) for goals that are stacks.
//!
//! A game that misses its goal still shows what it achieved: wherever a stack stands in a
//! state of the game, that stack is a goal ([`sim::Goal::standing`]) the game reached
//! there. Once a game is over, every step is stored again with up to `k` goals that stood
//! later in the same game (HER's `future` strategy), drawn uniformly with replacement among
//! the later states where a stack stood. A relabelled step is the step as it would have
//! been under that goal: the observations name the goal (the network reads it through the
//! role planes), and its reward and end are the world's own ([`sim::RewardModel`] on the
//! step, [`sim::Goal::holds`]), not a copy of them. A step taken after its new goal already
//! stood is left out: a game on that goal would have ended there.
//!
//! Without demonstrations, epsilon exploration rarely reaches the one goal a game is on; it
//! reaches some stack far more often, and every such game then teaches how to reach it.

use rand::RngExt;
use sim::reward::Transition as RewardTransition;
use sim::seeding::SimRng;
use sim::{Action, Goal, Observation};

use crate::config::DqnConfig;
use crate::replay::{NStepReturn, Transition};

/// One step of a game, as it was played.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// The observation the action was taken in.
    pub obs: Observation,
    /// The action.
    pub action: Action,
    /// The observation after it.
    pub next: Observation,
}

/// The relabelled transitions of a finished game (module docs): up to `k` per step, drawn
/// from `rng`, with the reward model, discount and n-step of `config`.
pub fn relabel(steps: &[Step], k: usize, config: &DqnConfig, rng: &mut SimRng) -> Vec<Transition> {
    // The goal standing after step `i`, and the steps after which one stood.
    let achieved: Vec<Option<Goal>> = steps.iter().map(|s| Goal::standing(&s.next.state)).collect();
    let stood: Vec<usize> = (0..steps.len()).filter(|&i| achieved[i].is_some()).collect();
    let mut out = Vec::new();
    if k == 0 {
        return out;
    }
    for t in 0..steps.len() {
        // Later states: after step t itself or any step after it.
        let first = stood.partition_point(|&i| i < t);
        let later = &stood[first..];
        if later.is_empty() {
            continue;
        }
        for _ in 0..k {
            let goal = achieved[later[rng.random_range(0..later.len())]]
                .clone()
                .expect("a state where a goal stood");
            if goal.holds(&steps[t].obs.state) {
                continue;
            }
            out.push(transition(steps, t, goal, config));
        }
    }
    out
}

/// Step `t` of `steps` under `goal`, with its n-step return (which stops where the goal
/// holds or the game ends).
fn transition(steps: &[Step], t: usize, goal: Goal, config: &DqnConfig) -> Transition {
    let under = |obs: &Observation| Observation {
        grid: obs.grid,
        state: obs.state.clone(),
        goal: goal.clone(),
        protocol: obs.protocol,
        view: obs.view,
    };
    let reward = |i: usize| {
        let s = &steps[i];
        config.world.reward.reward(&RewardTransition {
            grid: s.obs.grid,
            view: s.obs.view,
            goal: &goal,
            before: &s.obs.state,
            action: s.action,
            previous_action: i.checked_sub(1).map(|p| steps[p].action),
            after: &s.next.state,
        }) as f32
    };
    let step = &steps[t];
    let first = reward(t);
    let terminal = goal.holds(&step.next.state);
    let gamma = config.gamma as f32;
    let (mut rewards, mut discount, mut last, mut count, mut ended) = (first, gamma, t, 1, terminal);
    while !ended && count < config.n_step && last + 1 < steps.len() {
        last += 1;
        rewards += discount * reward(last);
        discount *= gamma;
        count += 1;
        ended = goal.holds(&steps[last].next.state);
    }
    Transition {
        obs: under(&step.obs),
        action: step.action,
        reward: first,
        next: under(&step.next),
        terminal,
        n_step: NStepReturn {
            rewards,
            last: under(&steps[last].next),
            steps: count as u32,
            terminal: ended,
        },
        expert: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::{GridWorld, State};

    /// The game from `start` under `goal` playing `actions`, as steps.
    fn game(start: &str, goal: &str, actions: &[Action]) -> Vec<Step> {
        let grid = sim::Grid::default();
        let start = State::parse(start, None, grid).unwrap();
        let goal: Goal = goal.parse().unwrap();
        let states = GridWorld::new(grid, start).unwrap().replay(actions).unwrap();
        let obs = |state| Observation {
            grid,
            state,
            protocol: sim::ActionProtocol::Free,
            view: sim::View::Top,
            goal: goal.clone(),
        };
        (0..actions.len())
            .map(|i| Step {
                obs: obs(states[i].clone()),
                action: actions[i],
                next: obs(states[i + 1].clone()),
            })
            .collect()
    }

    #[test]
    fn a_game_that_missed_its_goal_is_stored_again_under_the_stack_it_built() {
        let config = DqnConfig::preset(crate::preset::Preset::DqnPlanes, 3).unwrap();
        // Block 2 is carried onto block 1, which stands on block 0: the stack 0,1,2 stands
        // after the third step, then block 2 is carried off again. The game's goal is 2,1,0.
        use sim::BlockId;
        let actions = [
            Action::Pick(BlockId(2)),
            Action::Left,
            Action::Left,
            Action::Up,
            Action::Up,
        ];
        let steps = game("3,0;3,1;5,2", "2,1,0", &actions);
        let stack: Goal = "0,1,2".parse().unwrap();
        assert_eq!(Goal::standing(&steps[2].next.state), Some(stack.clone()));
        let mut rng = sim::seeding::rng(1);
        let relabelled = relabel(&steps, 4, &config, &mut rng);
        // Steps 0-2 come before the stack stood (4 each); none stood after steps 3 and 4.
        assert_eq!(relabelled.len(), 12);
        for t in &relabelled {
            assert_eq!(
                (t.obs.goal.clone(), t.next.goal.clone()),
                (stack.clone(), stack.clone())
            );
            assert!(!t.expert);
        }
        let last = relabelled.iter().filter(|t| t.terminal).collect::<Vec<_>>();
        assert_eq!(last.len(), 4, "the step that built the stack ends the relabelled game");
        assert!(last.iter().all(|t| t.reward == 10.0 && t.action == Action::Left));
        assert!(relabelled.iter().filter(|t| !t.terminal).all(|t| t.reward == 0.0));
        // The n-step return of the first step reaches the stack 2 steps later.
        let first = relabelled
            .iter()
            .find(|t| {
                t.obs
                    == Observation {
                        goal: stack.clone(),
                        ..steps[0].obs.clone()
                    }
            })
            .unwrap();
        let g = config.gamma as f32;
        assert_eq!((first.n_step.steps, first.n_step.terminal), (3, true));
        assert!((first.n_step.rewards - g * g * 10.0).abs() < 1e-5);
        assert_eq!(first.n_step.last.state, steps[2].next.state);
        // Same seed, same draws.
        assert_eq!(relabelled, relabel(&steps, 4, &config, &mut sim::seeding::rng(1)));
    }

    #[test]
    fn no_stack_no_relabelling_and_k_zero_none() {
        let config = DqnConfig::preset(crate::preset::Preset::DqnPlanes, 3).unwrap();
        let steps = game("0,0;2,0;4,0", "0,1,2", &[Action::Pick(sim::BlockId(0)), Action::Up]);
        assert!(relabel(&steps, 4, &config, &mut sim::seeding::rng(0)).is_empty());
        let stacked = game("1,0;1,1;5,5", "0,1,2", &[Action::Pick(sim::BlockId(2)), Action::Left]);
        assert!(relabel(&stacked, 0, &config, &mut sim::seeding::rng(0)).is_empty());
    }
}
