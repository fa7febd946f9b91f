//! `--profile` and the flags that override its parts, shared by the subcommands.
//!
//! A profile (`spec`, our world, the default; `original`, the paper's world as its authors
//! coded it) sets the action protocol, the start rule and the reward of the world, and, for
//! learners, the representation, schedule, oracle and oscillation test
//! ([`agent::LearnerProfile`]). Each part also has its own flag, which wins over the
//! profile. A command that reads a model file starts from the world the model was trained
//! in (its protocol and start rule, its profile's reward) unless `--profile` or a part's
//! flag says otherwise.

use clap::Args;
use sim::{ActionProtocol, Profile, ProfileParts, RewardModel, StartRule};

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

/// `parts` under the command line's choices ([`ProfileParts::overridden`]): `--profile`
/// replaces them all with its own, then each part given replaces that part.
pub fn overridden(
    parts: ProfileParts,
    profile: ProfileArg,
    protocol: Option<ActionProtocol>,
    start: Option<StartRule>,
    reward: Option<RewardModel>,
) -> ProfileParts {
    parts.overridden(profile.profile, protocol, start, reward)
}

/// [`overridden`] by `--profile`, `--protocol`, `--start` and `--reward`.
pub fn played(
    parts: ProfileParts,
    profile: ProfileArg,
    play: PlayRulesArgs,
    reward: Option<RewardModel>,
) -> ProfileParts {
    overridden(parts, profile, play.protocol, play.start.start, reward)
}

/// The world of a correction session of `agent` (`demo`, `correct`): the one it was trained
/// in under `--profile` ([`agent::correction::session_world_under`]), then each part's own
/// flag ([`ProfileParts::overridden`]). Also the profile whose correction rule applies:
/// `--profile`, else the one the agent was trained under.
pub fn session_world(
    agent: &agent::QAgent,
    profile: ProfileArg,
    play: PlayRulesArgs,
    reward: Option<RewardModel>,
) -> (sim::EnvConfig, Profile) {
    let (world, profile) = agent::correction::session_world_under(agent, profile.profile);
    let parts = ProfileParts {
        profile,
        protocol: world.protocol,
        start: world.start,
        reward: world.reward,
    }
    .overridden(None, play.protocol, play.start.start, reward);
    (parts.apply(world), profile)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_override_the_profile_part_by_part() {
        let spec = ProfileParts::of(Profile::Spec);
        let original = ProfileArg {
            profile: Some(Profile::Original),
        };
        let none = ProfileArg { profile: None };
        let play = PlayRulesArgs {
            protocol: Some(ActionProtocol::Free),
            start: StartArg { start: None },
        };
        let parts = played(spec, original, play, Some("sparse".parse().unwrap()));
        assert_eq!(
            (parts.profile, parts.protocol, parts.start, parts.reward.name()),
            (Profile::Original, ActionProtocol::Free, StartRule::Paper, "sparse")
        );
        assert_eq!(overridden(spec, none, None, None, None), spec);
    }
}
