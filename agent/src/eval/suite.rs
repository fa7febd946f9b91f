//! Seeded test suites: the games every arm of a comparison plays, and their optimum.
//!
//! A [`Suite`] is a world, its goals (each of a list, or drawn with every start), a number of
//! games and a seed. Game `k` of a goal is reset with [`sim::seeding::episode_seed`]`(seed,
//! k)`, the way `blockstack run` and `blockstack eval` number games, and the agent draws its
//! random actions from its own stream of that seed ([`crate::rollout::policy_rng`]), so game
//! `k` of two agents starts from the same state with the same goal and their results pair up.
//! The experiments play every arm on suites; [`evaluate`](super::evaluate) plays one per goal.

use oracle::ExactSolver;
use sim::seeding::episode_seed;
use sim::{Env, EnvConfig, Goal, GoalSpec, Observation, Termination};

use crate::error::Result;
use crate::policy::Policy;
use crate::rollout::{EpisodeResult, play_episode};

/// The goals of a suite's games.
#[derive(Clone, Debug, PartialEq)]
pub enum Goals {
    /// Every goal in the list, each played from the same `episodes` starts.
    Each(Vec<Goal>),
    /// A goal drawn with each start (uniformly, from the start's seed).
    Drawn,
}

/// A set of test games, fixed by a seed (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Suite {
    /// The world (its goal is the suite's; games end at the goal or its horizon).
    pub world: EnvConfig,
    /// The goals.
    pub goals: Goals,
    /// Games per goal (or in all, for drawn goals).
    pub episodes: u64,
    /// The seed of the starts.
    pub seed: u64,
}

impl Suite {
    /// Games in all.
    pub fn games(&self) -> u64 {
        match &self.goals {
            Goals::Each(goals) => self.episodes * goals.len() as u64,
            Goals::Drawn => self.episodes,
        }
    }

    /// The games' environments: one per goal, or one drawing its goals.
    fn envs(&self) -> Result<Vec<Env>> {
        let specs: Vec<GoalSpec> = match &self.goals {
            Goals::Each(goals) => goals.iter().map(|g| GoalSpec::Fixed(g.clone())).collect(),
            Goals::Drawn => vec![GoalSpec::Random],
        };
        let world = |goal| EnvConfig {
            goal,
            termination: Termination::Goal,
            ..self.world
        };
        Ok(specs
            .into_iter()
            .map(|g| Env::new(world(g)))
            .collect::<sim::Result<_>>()?)
    }

    /// `policy`'s games, goal by goal.
    pub fn play(&self, policy: &mut dyn Policy) -> Result<Vec<EpisodeResult>> {
        self.play_with(policy, &mut || Ok(()))
    }

    /// [`Suite::play`], calling `tick` after every game (a progress bar's hook); an error it
    /// returns (say, Ctrl-C seen) stops the games.
    pub fn play_with(
        &self,
        policy: &mut dyn Policy,
        tick: &mut dyn FnMut() -> Result<()>,
    ) -> Result<Vec<EpisodeResult>> {
        let mut results = Vec::with_capacity(self.games() as usize);
        for mut env in self.envs()? {
            for k in 0..self.episodes {
                results.push(play_episode(&mut env, policy, k, episode_seed(self.seed, k), &mut ())?);
                tick()?;
            }
        }
        Ok(results)
    }

    /// The observations of game `index` (in [`Suite::play`]'s order) played by `policy`,
    /// the start first: the same game as in [`Suite::play`].
    pub fn record(&self, policy: &mut dyn Policy, index: usize) -> Result<Vec<Observation>> {
        let per_env = self.episodes as usize;
        let mut env = self.envs()?.swap_remove(index / per_env);
        let k = (index % per_env) as u64;
        let mut observations = Vec::new();
        play_episode(&mut env, policy, k, episode_seed(self.seed, k), &mut observations)?;
        Ok(observations)
    }

    /// Every game's first observation (start and goal), in [`Suite::play`]'s order.
    pub fn starts(&self) -> Result<Vec<Observation>> {
        let mut starts = Vec::with_capacity(self.games() as usize);
        for mut env in self.envs()? {
            starts.extend((0..self.episodes).map(|k| env.reset(episode_seed(self.seed, k))));
        }
        Ok(starts)
    }

    /// The length of a shortest plan from every game's start (the exact solver's of the
    /// suite's world, [`ExactSolver::for_world`]), in [`Suite::play`]'s order: 0 from a
    /// start that already meets the goal (the paper's start rule keeps them; such games have
    /// no ratio to the optimum, see [`crate::optimality`]).
    pub fn optimum(&self) -> Result<Vec<u32>> {
        let solver = ExactSolver::for_world(&self.world);
        self.starts()?
            .iter()
            .map(|obs| Ok(solver.distance(&obs.state, &obs.goal)?))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RandomPolicy;

    /// Two policies meet the same starts; the optimum is measured from them.
    #[test]
    fn every_policy_meets_the_same_starts_and_the_optimum_is_theirs() {
        let suite = Suite {
            world: EnvConfig {
                blocks: 2,
                backend: sim::Backend::Grid,
                ..EnvConfig::default()
            },
            goals: Goals::Each(vec!["0,1".parse().unwrap(), "1,0".parse().unwrap()]),
            episodes: 3,
            seed: 9,
        };
        let random = suite.play(&mut RandomPolicy).unwrap();
        let exact = suite.play(&mut crate::ExactPolicy::new(suite.world.grid)).unwrap();
        assert_eq!(random.len(), 6);
        let optimum = suite.optimum().unwrap();
        for ((r, e), best) in random.iter().zip(&exact).zip(&optimum) {
            assert_eq!((&r.start, &r.goal), (&e.start, &e.goal));
            assert_eq!(e.steps, *best);
        }
        let drawn = Suite {
            goals: Goals::Drawn,
            ..suite.clone()
        };
        assert_eq!(drawn.starts().unwrap().len(), 3);
        let recorded = suite.record(&mut RandomPolicy, 4).unwrap();
        assert_eq!(recorded[0].state, random[4].start);
    }
}
