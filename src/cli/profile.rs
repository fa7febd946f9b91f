//! `--profile` and the flags that override its parts, shared by the subcommands.
//!
//! A profile (`spec`, our world, the default; `original`, the paper's world as its authors
//! coded it) sets the action protocol, the start rule and the reward of the world, and, for
//! learners, the representation, schedule, oracle and oscillation test
//! ([`agent::LearnerProfile`]). Each part also has its own flag, which wins over the
//! profile. A command that reads a model file starts from the world the model was trained
//! in (its protocol and start rule, its profile's reward) unless `--profile` or a part's
//! flag says otherwise.

use anyhow::Result;
use clap::Args;
use sim::{ActionProtocol, Profile, RewardModel, StartRule};

/// `--profile`.
#[derive(Debug, Clone, Copy, Args)]
pub struct ProfileArg {
    /// The world and learner: spec (ours) or original (the paper's as its authors coded it);
    /// sets the protocol, start rule, reward and the learner's parts, each of which its own
    /// flag overrides [default: spec, or a model's own]
    #[arg(long)]
    pub profile: Option<Profile>,
}

/// `--protocol` and `--start`: the rules of play that a profile sets.
#[derive(Debug, Clone, Copy, Args)]
pub struct PlayRulesArgs {
    /// Action protocol: free (every action legal) or paper (nothing held: only pick; holding:
    /// only moves and drop) [default: the profile's]
    #[arg(long)]
    pub protocol: Option<ActionProtocol>,
    #[command(flatten)]
    pub start: StartArg,
}

/// `--start` alone (for commands where only the start matters).
#[derive(Debug, Clone, Copy, Args)]
pub struct StartArg {
    /// Start rule: uniform (ours) or paper (the 6 x 6 corner, a start meeting the goal kept)
    /// [default: the profile's]
    #[arg(long)]
    pub start: Option<StartRule>,
}

/// The world's parts a profile sets, as resolved for one command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rules {
    /// The profile they came from.
    pub profile: Profile,
    /// The action protocol.
    pub protocol: ActionProtocol,
    /// The start rule.
    pub start: StartRule,
    /// The world's reward.
    pub reward: RewardModel,
}

impl Rules {
    /// `profile`'s parts.
    pub fn of(profile: Profile) -> Rules {
        Rules {
            profile,
            protocol: profile.protocol(),
            start: profile.start_rule(),
            reward: profile.reward(),
        }
    }

    /// The rules of a model's training world: a tabular model's protocol and start rule
    /// with its profile's reward ([`Rules::of`] the `spec` profile for a model that does not
    /// say); a network's protocol and reward in the `spec` profile's world (`blockstack dqn`
    /// trains there, from uniform starts).
    pub fn of_model(model: &neural::AnyModel) -> Rules {
        let world = model.world();
        match model {
            neural::AnyModel::Q(_) => Rules {
                protocol: world.protocol,
                start: world.start,
                ..Rules::of(model.profile())
            },
            neural::AnyModel::Dqn(_) => Rules {
                protocol: world.protocol,
                reward: world.reward,
                ..Rules::of(Profile::Spec)
            },
        }
    }

    /// These rules under the command line's choices: `--profile` replaces them all with
    /// its own, then each part given (`reward` by a reward model's name) replaces that part.
    pub fn overridden(
        self,
        profile: ProfileArg,
        protocol: Option<ActionProtocol>,
        start: Option<StartRule>,
        reward: Option<&str>,
    ) -> Result<Rules> {
        let mut rules = profile.profile.map_or(self, Rules::of);
        rules.protocol = protocol.unwrap_or(rules.protocol);
        rules.start = start.unwrap_or(rules.start);
        if let Some(name) = reward {
            rules.reward = name.parse()?;
        }
        Ok(rules)
    }

    /// [`Rules::overridden`] by `--protocol` and `--start`.
    pub fn played(self, profile: ProfileArg, play: PlayRulesArgs, reward: Option<&str>) -> Result<Rules> {
        self.overridden(profile, play.protocol, play.start.start, reward)
    }
}

/// The world of a correction session of `agent` (`demo`, `correct`): the one it was trained
/// in under `--profile` ([`agent::correction::session_world_under`]), then each part's own
/// flag. Also the profile whose correction rule applies: `--profile`,
/// else the one the agent was trained under.
pub fn session_world(
    agent: &agent::QAgent,
    profile: ProfileArg,
    play: PlayRulesArgs,
    reward: Option<&str>,
) -> Result<(sim::EnvConfig, Profile)> {
    let (mut world, profile) = agent::correction::session_world_under(agent, profile.profile);
    world.protocol = play.protocol.unwrap_or(world.protocol);
    world.start = play.start.start.unwrap_or(world.start);
    if let Some(name) = reward {
        world.reward = name.parse()?;
    }
    Ok((world, profile))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_override_the_profile_part_by_part() {
        let spec = Rules::of(Profile::Spec);
        let original = ProfileArg {
            profile: Some(Profile::Original),
        };
        let none = ProfileArg { profile: None };
        let rules = spec.overridden(original, None, None, None).unwrap();
        assert_eq!(rules, Rules::of(Profile::Original));
        let play = PlayRulesArgs {
            protocol: Some(ActionProtocol::Free),
            start: StartArg { start: None },
        };
        let rules = spec.played(original, play, Some("sparse")).unwrap();
        assert_eq!(
            (rules.profile, rules.protocol, rules.start, rules.reward.name()),
            (Profile::Original, ActionProtocol::Free, StartRule::Paper, "sparse")
        );
        assert_eq!(spec.overridden(none, None, None, None).unwrap(), spec);
        assert!(spec.overridden(none, None, None, Some("lots")).is_err());
    }
}
