//! Presets, and the one resolver of profile, preset and explicit settings.
//!
//! A training run is described in three layers, each overriding the one before:
//!
//! 1. the **profile** ([`sim::Profile`]) sets the world (action protocol, start rule,
//!    reward) and the learner as the paper describes it (`spec`) or as its authors coded it
//!    (`original`): [`TrainConfig::for_profile`];
//! 2. a **preset** ([`Preset`]) then sets the learner's recipe: `paper` keeps the profile's
//!    learner, `optimal` puts in the role recipe ([`TrainConfig::role_step_cost`]: the
//!    representation, reward, alpha, gamma, epsilon, initial value and both replays);
//! 3. every **explicit setting** ([`TrainOverrides`]) beats both.
//!
//! Without a preset, `--repr role` under the `spec` profile means `optimal` and everything
//! else `paper`. The CLI's `blockstack train` and Python's `blockstack.train` both call
//! [`TrainConfig::resolve`], so the same settings give the same model file, byte for byte.

use serde::{Deserialize, Serialize};
use sim::{Backend, EnvConfig, Goal, Grid, Profile, RewardModel, StartRule, View};

use crate::assist::{Assist, OracleKind, Oscillation};
use crate::config::{QParams, TrainConfig};
use crate::error::{AgentError, Result};
use crate::profile::LearnerProfile;
use crate::repr::ReprKind;
use crate::schedule::Schedule;

/// A recipe of the learner's hyper-parameters (`train --preset`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// The profile's own learner: under spec the paper's (alpha 1, gamma 0.1, epsilon 0.1,
    /// no replay), under original the paper's as its authors coded it.
    Paper,
    /// The role recipe ([`TrainConfig::role_step_cost`]): the role representation, the
    /// step-cost reward, alpha 1, gamma 1, epsilon 0 (optimistic greedy exploration),
    /// backward and final replay.
    Optimal,
}

sim::names!(Preset { Paper = "paper", Optimal = "optimal" } unknown(name) -> AgentError {
    AgentError::Config(format!("unknown preset {name:?}: choose one of {}", Preset::NAMES.join(", ")))
});

impl Preset {
    /// The preset a run takes when none is named: `optimal` for the role representations
    /// under the `spec` profile, and for goals of towers (`towers`: the side view, or a goal
    /// that is not one tower of every block) when no representation is named; `paper`
    /// otherwise.
    pub fn default_for(profile: Profile, repr: Option<ReprKind>, towers: bool) -> Preset {
        match (profile, repr) {
            (Profile::Spec, Some(ReprKind::Role | ReprKind::RoleTowers)) => Preset::Optimal,
            (Profile::Spec, None) if towers => Preset::Optimal,
            _ => Preset::Paper,
        }
    }
}

/// The settings a user gave explicitly; `None` (or an empty list) keeps what the profile
/// and preset say. The field names are `blockstack train`'s flags and Python's keyword
/// arguments.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrainOverrides {
    /// `--profile` (default `spec`).
    pub profile: Option<Profile>,
    /// `--preset` (default [`Preset::default_for`]).
    pub preset: Option<Preset>,
    /// `--blocks` (default 3).
    pub blocks: Option<usize>,
    /// `--grid` (default 7 x 7).
    pub grid: Option<Grid>,
    /// `--goals` (default every goal of the block count).
    pub goals: Option<Vec<Goal>>,
    /// `--protocol`.
    pub protocol: Option<sim::ActionProtocol>,
    /// `--start`.
    pub start: Option<StartRule>,
    /// `--repr`.
    pub repr: Option<ReprKind>,
    /// `--reward`.
    pub reward: Option<RewardModel>,
    /// `--schedule`.
    pub schedule: Option<Schedule>,
    /// `--oracle`.
    pub oracle: Option<OracleKind>,
    /// `--oscillation`.
    pub oscillation: Option<Oscillation>,
    /// `--games`.
    pub games: Option<u64>,
    /// `--seed` (default 1).
    pub seed: Option<u64>,
    /// `--alpha`.
    pub alpha: Option<f64>,
    /// `--gamma`.
    pub gamma: Option<f64>,
    /// `--epsilon`.
    pub epsilon: Option<f64>,
    /// `--initial-q`.
    pub initial_q: Option<f64>,
    /// `--exploring-starts`.
    pub exploring_starts: Option<bool>,
    /// `--backward-replay`.
    pub backward_replay: Option<bool>,
    /// `--final-replay`.
    pub final_replay: Option<bool>,
    /// `--assist`.
    pub assist: Option<Assist>,
    /// `--horizon` (default the schedule's game length).
    pub horizon: Option<u32>,
    /// `--backend` (default physics).
    pub backend: Option<Backend>,
    /// `--view` (default top). In the side view the goals default to one goal of each
    /// shape ([`Goal::shapes`]), and the optimal preset (the default there) trains
    /// `role-towers` for the recipe's 100,000 games.
    pub view: Option<View>,
}

impl TrainConfig {
    /// The paper's learner (section VI): `chasing` representation, `paper` reward, alpha 1,
    /// gamma 0.1, epsilon 0.1, 3 blocks on 7 x 7, horizon 1000, physics, on `goals`, 5000
    /// games, seed 1.
    pub fn paper(goals: Vec<Goal>) -> TrainConfig {
        TrainConfig {
            world: EnvConfig {
                blocks: goals.first().map_or(3, Goal::block_count),
                reward: RewardModel::from_name("paper").expect("a known model"),
                ..EnvConfig::default()
            },
            goals,
            repr: ReprKind::Chasing,
            params: QParams::default(),
            games: 5000,
            seed: 1,
            exploring_starts: false,
            backward_replay: false,
            final_replay: false,
            assist: Assist::None,
            profile: Profile::Spec,
            schedule: Schedule::Spec,
            oracle: OracleKind::Astar,
            oscillation: Oscillation::Actions,
        }
    }

    /// The paper's learner as its authors coded it, in their world: `chasing-code`
    /// representation, `paper-code` reward, the `paper` action protocol and start rule, the
    /// `paper-code` schedule (games of up to 5000 steps, 1000 with two blocks, each on a
    /// goal drawn from `goals`, ended by a reward above 70), alpha 1, gamma 0.1, epsilon
    /// 0.1, physics, 100 games (the most of the paper's Fig. 3 and E3), seed 1; assistance,
    /// when asked for, by the authors' oracle on their oscillation test.
    pub fn original(goals: Vec<Goal>) -> TrainConfig {
        let parts = LearnerProfile::of(Profile::Original);
        let paper = TrainConfig::paper(goals);
        let blocks = paper.world.blocks;
        TrainConfig {
            world: EnvConfig {
                reward: parts.reward,
                horizon: parts.schedule.game_steps(blocks),
                protocol: parts.profile.protocol(),
                start: parts.profile.start_rule(),
                ..paper.world
            },
            repr: parts.repr,
            games: 100,
            profile: parts.profile,
            oracle: parts.oracle,
            oscillation: parts.oscillation,
            ..paper
        }
        .with_schedule(parts.schedule)
    }

    /// The paper's learner of `profile`: [`TrainConfig::paper`] in our world (`spec`),
    /// [`TrainConfig::original`] in the authors' (`original`).
    pub fn for_profile(profile: Profile, goals: Vec<Goal>) -> TrainConfig {
        match profile {
            Profile::Spec => TrainConfig::paper(goals),
            Profile::Original => TrainConfig::original(goals),
        }
    }

    /// Our learner: `role` representation, `step-cost` reward, alpha 1 and gamma 1 (the
    /// world is deterministic and the return is minus the steps to go), epsilon 0 (every
    /// value starts at 0, above any true value, so untried actions look best and the
    /// greedy learner tries them: optimism in place of random exploration), backward
    /// replay after each game and a final replay of everything seen, 100,000 games against
    /// the physics world from the paper's starts (nothing held), seed 1. Trained on one
    /// goal it plays all of them.
    pub fn role_step_cost(goals: Vec<Goal>) -> TrainConfig {
        let paper = TrainConfig::paper(goals);
        TrainConfig {
            world: EnvConfig {
                reward: RewardModel::from_name("step-cost").expect("a known model"),
                ..paper.world
            },
            repr: ReprKind::Role,
            params: QParams {
                alpha: 1.0,
                gamma: 1.0,
                epsilon: 0.0,
                initial_q: 0.0,
            },
            games: 100_000,
            backward_replay: true,
            final_replay: true,
            ..paper
        }
    }

    /// The run the settings describe (module docs: profile, then preset, then each
    /// explicit setting), checked.
    pub fn resolve(settings: &TrainOverrides) -> Result<TrainConfig> {
        let s = settings;
        let profile = s.profile.unwrap_or_default();
        let blocks = s.blocks.unwrap_or(3);
        let view = s.view.unwrap_or_default();
        let goals = match &s.goals {
            Some(goals) => goals.clone(),
            // Role-towers names blocks by their place in the goal, so one goal of each shape
            // is every goal, and each shape is trained as often (every goal would play the
            // one-tower shape six times as often as towers of one block each, with 3 blocks).
            None if view == View::Side => Goal::shapes(blocks)?,
            None => Goal::all(blocks)?,
        };
        let towers = view == View::Side || goals.iter().any(|g| !g.is_one_tower());
        let preset = s.preset.unwrap_or(Preset::default_for(profile, s.repr, towers));
        let profile_learner = TrainConfig::for_profile(profile, goals.clone());
        // The preset's parts of the learner over the profile's world and learner.
        let base = match preset {
            Preset::Paper => profile_learner,
            Preset::Optimal => {
                let recipe = TrainConfig::role_step_cost(goals);
                TrainConfig {
                    world: EnvConfig {
                        reward: recipe.world.reward,
                        ..profile_learner.world
                    },
                    repr: if towers { ReprKind::RoleTowers } else { recipe.repr },
                    // Goals of towers are a new world with no earlier results to keep: they
                    // take the recipe's game count too.
                    games: if towers { recipe.games } else { profile_learner.games },
                    params: recipe.params,
                    backward_replay: recipe.backward_replay,
                    final_replay: recipe.final_replay,
                    ..profile_learner
                }
            }
        };
        let schedule = s.schedule.unwrap_or(base.schedule);
        // Without a horizon, games are as long as the schedule's (the profile's unless a
        // schedule is named).
        let horizon = s.horizon.unwrap_or_else(|| {
            if s.schedule.is_some() {
                schedule.game_steps(blocks)
            } else {
                base.world.horizon
            }
        });
        let config = TrainConfig {
            world: EnvConfig {
                grid: s.grid.unwrap_or(base.world.grid),
                blocks,
                horizon,
                reward: s.reward.unwrap_or(base.world.reward),
                backend: s.backend.unwrap_or(base.world.backend),
                protocol: s.protocol.unwrap_or(base.world.protocol),
                start: s.start.unwrap_or(base.world.start),
                view,
                ..base.world
            },
            repr: s.repr.unwrap_or(base.repr),
            params: QParams {
                alpha: s.alpha.unwrap_or(base.params.alpha),
                gamma: s.gamma.unwrap_or(base.params.gamma),
                epsilon: s.epsilon.unwrap_or(base.params.epsilon),
                initial_q: s.initial_q.unwrap_or(base.params.initial_q),
            },
            games: s.games.unwrap_or(base.games),
            seed: s.seed.unwrap_or(base.seed),
            exploring_starts: s.exploring_starts.unwrap_or(base.exploring_starts),
            backward_replay: s.backward_replay.unwrap_or(base.backward_replay),
            final_replay: s.final_replay.unwrap_or(base.final_replay),
            assist: s.assist.unwrap_or(base.assist),
            oracle: s.oracle.unwrap_or(base.oracle),
            oscillation: s.oscillation.unwrap_or(base.oscillation),
            ..base
        }
        .with_schedule(schedule);
        if preset == Preset::Optimal
            && config.schedule != Schedule::Spec
            && (config.backward_replay || config.final_replay)
        {
            return Err(AgentError::Config(format!(
                "--preset optimal replays, which the {} schedule does not: add --schedule spec, or turn the replays \
                 off (--backward-replay=false --final-replay=false)",
                config.schedule
            )));
        }
        config.validate()?;
        Ok(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn goals(text: &str) -> Option<Vec<Goal>> {
        Some(Goal::parse_list(text, 3).unwrap())
    }

    #[test]
    fn role_under_spec_takes_the_optimal_preset_unless_told_otherwise() {
        let role = TrainOverrides {
            repr: Some(ReprKind::Role),
            goals: goals("0,1,2"),
            ..TrainOverrides::default()
        };
        let c = TrainConfig::resolve(&role).unwrap();
        assert_eq!((c.params.gamma, c.params.epsilon, c.backward_replay), (1.0, 0.0, true));
        assert_eq!(c.world.reward.name(), "step-cost");
        let paper = TrainConfig::resolve(&TrainOverrides {
            preset: Some(Preset::Paper),
            ..role.clone()
        })
        .unwrap();
        assert_eq!((paper.params.gamma, paper.backward_replay), (0.1, false));
        // An explicit setting beats the preset.
        let c = TrainConfig::resolve(&TrainOverrides {
            gamma: Some(0.5),
            final_replay: Some(false),
            ..role
        })
        .unwrap();
        assert_eq!((c.params.gamma, c.final_replay, c.backward_replay), (0.5, false, true));
    }

    #[test]
    fn the_profile_sets_the_world_and_a_named_schedule_sets_the_game_length() {
        let c = TrainConfig::resolve(&TrainOverrides {
            profile: Some(Profile::Original),
            ..TrainOverrides::default()
        })
        .unwrap();
        assert_eq!(c, TrainConfig::original(Goal::all(3).unwrap()));
        let c = TrainConfig::resolve(&TrainOverrides {
            profile: Some(Profile::Original),
            schedule: Some(Schedule::Spec),
            ..TrainOverrides::default()
        })
        .unwrap();
        assert_eq!((c.world.horizon, c.world.termination), (1000, sim::Termination::Goal));
    }

    #[test]
    fn the_optimal_preset_needs_the_spec_schedule_when_it_replays() {
        let bad = TrainOverrides {
            preset: Some(Preset::Optimal),
            schedule: Some(Schedule::PaperCode),
            ..TrainOverrides::default()
        };
        let err = TrainConfig::resolve(&bad).unwrap_err().to_string();
        assert!(err.contains("--schedule spec"), "{err}");
        let off = TrainOverrides {
            backward_replay: Some(false),
            final_replay: Some(false),
            ..bad
        };
        assert!(TrainConfig::resolve(&off).is_ok());
    }

    #[test]
    fn presets_parse_and_print_by_name() {
        for name in Preset::NAMES {
            assert_eq!(name.parse::<Preset>().unwrap().to_string(), name);
        }
        assert!(
            "best"
                .parse::<Preset>()
                .unwrap_err()
                .to_string()
                .contains("paper, optimal")
        );
    }
}
