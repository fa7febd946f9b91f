//! Experience replay: the agent's recent transitions in a ring buffer, the demonstrations
//! kept for good beside them (DQfD), and seeded uniform sampling from both.
//!
//! A transition stores observations, not network inputs: an [`Observation`] is a few dozen
//! bytes where the paper's input is 30,000, and the input is made again when a batch is
//! drawn (an encoding costs microseconds for planes and tens of microseconds for pixels).
//! Each transition also carries its n-step return (Hester et al.'s n-step loss), made by
//! [`NStep`] as the steps of an episode come in.

use std::collections::VecDeque;

use rand::RngExt;
use sim::seeding::SimRng;
use sim::{Action, Observation};

/// The n-step part of a transition: the discounted rewards of up to `n` steps from it, and
/// where they led.
#[derive(Clone, Debug, PartialEq)]
pub struct NStepReturn {
    /// `r_t + gamma r_(t+1) + ... + gamma^(k-1) r_(t+k-1)`.
    pub rewards: f32,
    /// The observation after those `k` steps.
    pub last: Observation,
    /// `k`, at most `n` (fewer at an episode's end).
    pub steps: u32,
    /// Whether the goal was reached within them (nothing to bootstrap from).
    pub terminal: bool,
}

/// One step, as the learner replays it.
#[derive(Clone, Debug, PartialEq)]
pub struct Transition {
    /// The observation the action was taken in.
    pub obs: Observation,
    /// The action.
    pub action: Action,
    /// The reward.
    pub reward: f32,
    /// The observation after it.
    pub next: Observation,
    /// The goal holds in `next` (a truncated episode's last step is not terminal).
    pub terminal: bool,
    /// The n-step return from this step.
    pub n_step: NStepReturn,
    /// A demonstrator chose the action (the large-margin loss applies).
    pub expert: bool,
}

/// Turns an episode's steps, as they come, into transitions with their n-step returns.
#[derive(Clone, Debug)]
pub struct NStep {
    n: usize,
    gamma: f32,
    pending: VecDeque<(Observation, Action, f32, Observation, bool, bool)>,
}

impl NStep {
    /// A builder for `n`-step returns (`n >= 1`) with discount `gamma`.
    pub fn new(n: usize, gamma: f64) -> NStep {
        NStep {
            n: n.max(1),
            gamma: gamma as f32,
            pending: VecDeque::new(),
        }
    }

    /// Takes the next step of the episode; returns the transition whose n-step return is now
    /// complete, if any. After a step that ends the episode (terminal or truncated), call
    /// [`NStep::finish`].
    pub fn push(
        &mut self,
        obs: Observation,
        action: Action,
        reward: f32,
        next: Observation,
        terminal: bool,
        expert: bool,
    ) -> Option<Transition> {
        self.pending.push_back((obs, action, reward, next, terminal, expert));
        (self.pending.len() == self.n).then(|| self.pop())
    }

    /// The transitions still waiting, the episode having ended: their returns stop at its
    /// end.
    pub fn finish(&mut self) -> Vec<Transition> {
        let mut out = Vec::with_capacity(self.pending.len());
        while !self.pending.is_empty() {
            out.push(self.pop());
        }
        out
    }

    /// The first pending transition, its return over every pending step.
    fn pop(&mut self) -> Transition {
        let mut rewards = 0.0;
        let mut discount = 1.0;
        let mut end = 0;
        for (k, &(_, _, r, _, terminal, _)) in self.pending.iter().enumerate() {
            rewards += discount * r;
            discount *= self.gamma;
            end = k;
            if terminal {
                break;
            }
        }
        let (last, terminal) = (self.pending[end].3.clone(), self.pending[end].4);
        let (obs, action, reward, next, step_terminal, expert) = self.pending.pop_front().expect("pending");
        Transition {
            obs,
            action,
            reward,
            next,
            terminal: step_terminal,
            n_step: NStepReturn {
                rewards,
                last,
                steps: end as u32 + 1,
                terminal,
            },
            expert,
        }
    }
}

/// The agent's transitions (a ring of `capacity`, the oldest replaced first) and the
/// demonstrations (kept for good).
#[derive(Clone, Debug)]
pub struct ReplayBuffer {
    capacity: usize,
    agent: Vec<Transition>,
    next: usize,
    demos: Vec<Transition>,
}

impl ReplayBuffer {
    /// An empty buffer holding up to `capacity` of the agent's transitions (at least 1).
    pub fn new(capacity: usize) -> ReplayBuffer {
        ReplayBuffer {
            capacity: capacity.max(1),
            agent: Vec::new(),
            next: 0,
            demos: Vec::new(),
        }
    }

    /// Stores one of the agent's transitions, replacing the oldest when full.
    pub fn push(&mut self, t: Transition) {
        if self.agent.len() < self.capacity {
            self.agent.push(t);
        } else {
            self.agent[self.next] = t;
        }
        self.next = (self.next + 1) % self.capacity;
    }

    /// Stores a demonstration transition for good.
    pub fn push_demo(&mut self, t: Transition) {
        self.demos.push(t);
    }

    /// The agent's transitions held.
    pub fn agent_len(&self) -> usize {
        self.agent.len()
    }

    /// The demonstration transitions held.
    pub fn demo_len(&self) -> usize {
        self.demos.len()
    }

    /// The agent's transitions in the order they are stored, and where the next one goes
    /// (the ring's state, as a checkpoint keeps it).
    pub(crate) fn agent_ring(&self) -> (&[Transition], usize) {
        (&self.agent, self.next)
    }

    /// The demonstration transitions, in the order they came.
    pub(crate) fn demos(&self) -> &[Transition] {
        &self.demos
    }

    /// A buffer of `capacity` holding these transitions, the agent's stored as
    /// [`ReplayBuffer::agent_ring`] gives them; an error unless they fit the capacity.
    pub(crate) fn restore(
        capacity: usize,
        agent: Vec<Transition>,
        next: usize,
        demos: Vec<Transition>,
    ) -> Result<ReplayBuffer, String> {
        let capacity = capacity.max(1);
        let full = agent.len() == capacity;
        if agent.len() > capacity || next >= capacity || (!full && next != agent.len() % capacity) {
            return Err(format!(
                "its buffer holds {} of the agent's transitions, the next at {next}, in a ring of {capacity}",
                agent.len()
            ));
        }
        Ok(ReplayBuffer {
            capacity,
            agent,
            next,
            demos,
        })
    }

    /// `batch` transitions drawn uniformly with replacement: `round(demo_share * batch)` of
    /// them from the demonstrations and the rest from the agent's (all from whichever part
    /// is not empty when the other is). Empty if both parts are.
    pub fn sample(&self, batch: usize, demo_share: f64, rng: &mut SimRng) -> Vec<&Transition> {
        let from_demos = match (self.demos.is_empty(), self.agent.is_empty()) {
            (true, true) => return Vec::new(),
            (true, false) => 0,
            (false, true) => batch,
            (false, false) => ((demo_share.clamp(0.0, 1.0) * batch as f64).round() as usize).min(batch),
        };
        let mut out = Vec::with_capacity(batch);
        for _ in 0..from_demos {
            out.push(&self.demos[rng.random_range(0..self.demos.len())]);
        }
        for _ in from_demos..batch {
            out.push(&self.agent[rng.random_range(0..self.agent.len())]);
        }
        out
    }

    /// Only demonstrations, `batch` of them uniformly with replacement (pre-training).
    pub fn sample_demos(&self, batch: usize, rng: &mut SimRng) -> Vec<&Transition> {
        if self.demos.is_empty() {
            return Vec::new();
        }
        (0..batch)
            .map(|_| &self.demos[rng.random_range(0..self.demos.len())])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::{Cell, Goal, Grid, State};

    fn obs(x: u16) -> Observation {
        Observation {
            grid: Grid::default(),
            state: State::new(&[Cell::new(x % 7, 0), Cell::new(x % 7, 3)], None).unwrap(),
            protocol: sim::ActionProtocol::Free,
            goal: Goal::identity(2).unwrap(),
            view: sim::View::Top,
        }
    }

    fn transition(i: u16) -> Transition {
        let mut n = NStep::new(1, 0.9);
        n.push(obs(i), Action::Up, f32::from(i), obs(i + 1), false, false)
            .unwrap()
    }

    #[test]
    fn n_step_returns_discount_and_stop_at_the_goal() {
        let mut n = NStep::new(3, 0.5);
        assert!(n.push(obs(0), Action::Up, 1.0, obs(1), false, true).is_none());
        assert!(n.push(obs(1), Action::Up, 2.0, obs(2), false, true).is_none());
        let t = n.push(obs(2), Action::Up, 4.0, obs(3), false, true).unwrap();
        assert_eq!(
            (t.n_step.rewards, t.n_step.steps, t.n_step.terminal),
            (1.0 + 1.0 + 1.0, 3, false)
        );
        assert_eq!(t.n_step.last, obs(3));
        let t = n.push(obs(3), Action::Up, 8.0, obs(4), true, true).unwrap();
        assert_eq!(
            (t.n_step.rewards, t.n_step.steps, t.n_step.terminal),
            (2.0 + 2.0 + 2.0, 3, true)
        );
        let rest = n.finish();
        assert_eq!(rest.len(), 2);
        assert_eq!((rest[0].n_step.rewards, rest[0].n_step.steps), (4.0 + 4.0, 2));
        assert_eq!((rest[1].n_step.rewards, rest[1].n_step.last.clone()), (8.0, obs(4)));
        assert!(rest.iter().all(|t| t.n_step.terminal && t.expert));
    }

    #[test]
    fn the_ring_keeps_the_newest() {
        let mut b = ReplayBuffer::new(3);
        for i in 0..5 {
            b.push(transition(i));
        }
        let mut rewards: Vec<f32> = b.agent.iter().map(|t| t.reward).collect();
        rewards.sort_by(f32::total_cmp);
        assert_eq!(rewards, vec![2.0, 3.0, 4.0]);
    }

    #[test]
    fn sampling_is_uniform_and_seeded() {
        let mut b = ReplayBuffer::new(10);
        for i in 0..10 {
            b.push(transition(i));
        }
        let draw = |seed| -> Vec<f32> {
            let mut rng = sim::seeding::rng(seed);
            b.sample(20_000, 0.0, &mut rng).iter().map(|t| t.reward).collect()
        };
        let a = draw(3);
        assert_eq!(a, draw(3), "same seed, same draws");
        assert_ne!(a, draw(4));
        // Chi-square against uniform over 10 cells, 9 degrees of freedom: 27.9 is p = 0.001.
        let mut counts = [0f64; 10];
        a.iter().for_each(|&r| counts[r as usize] += 1.0);
        let expected = 2000.0;
        let chi2: f64 = counts.iter().map(|c| (c - expected).powi(2) / expected).sum();
        assert!(chi2 < 27.9, "chi-square {chi2}: {counts:?}");
    }

    #[test]
    fn the_demo_share_of_a_batch_is_kept() {
        let mut b = ReplayBuffer::new(10);
        assert!(b.sample(8, 0.5, &mut sim::seeding::rng(0)).is_empty());
        b.push(transition(1));
        b.push_demo(Transition {
            expert: true,
            ..transition(2)
        });
        let batch = b.sample(8, 0.25, &mut sim::seeding::rng(0));
        assert_eq!(batch.iter().filter(|t| t.expert).count(), 2);
        assert!(b.sample_demos(5, &mut sim::seeding::rng(0)).iter().all(|t| t.expert));
    }
}
