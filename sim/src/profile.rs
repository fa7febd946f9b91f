//! Profiles: our SPEC world, or the paper's world as its authors coded it.
//!
//! A profile names a whole set of rules at once. `sim` holds its world-level parts (the
//! action protocol, the start rule, the reward, and what ends a training game); the
//! learner-level parts (representation, training schedule, oracle) are keyed by the same
//! enum in the crates that own them.
//!
//! | part | `spec` (default) | `original` (docs/world.md section 10) |
//! |---|---|---|
//! | action protocol | `free` | `paper` |
//! | start rule | `uniform` | `paper` |
//! | reward | `sparse` | `paper-code` |
//! | training games end | at the goal | at a step reward above 70 |
//!
//! A profile is applied to a world in one place, [`ProfileParts::apply`] ([`Profile::world`]
//! is the default world under a profile).
//!
//! A run takes a profile's parts and then any part named on its own in its place
//! (`--profile original --protocol free`): [`ProfileParts::overridden`] is that one
//! resolution, which the CLI's commands and Python's environments both call.

use serde::{Deserialize, Serialize};

use crate::env::EnvConfig;
use crate::error::SimError;
use crate::protocol::ActionProtocol;
use crate::reward::{PaperCode, RewardModel};
use crate::start::StartRule;
use crate::termination::Termination;

/// Which world: ours (docs/world.md) or the authors' code (docs/world.md section 10).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Profile {
    /// Our world, the contract of docs/world.md.
    #[default]
    Spec,
    /// The paper's world as its authors coded it.
    Original,
}

crate::names!(Profile { Spec = "spec", Original = "original" } unknown(name) -> SimError {
    SimError::Parse {
        what: "profile",
        text: name.to_string(),
        reason: format!("choose one of {}", Profile::NAMES.join(", ")),
    }
});

impl Profile {
    /// The action protocol: `free` or `paper`.
    pub const fn protocol(self) -> ActionProtocol {
        match self {
            Profile::Spec => ActionProtocol::Free,
            Profile::Original => ActionProtocol::Paper,
        }
    }

    /// The start rule: `uniform` or `paper`.
    pub const fn start_rule(self) -> StartRule {
        match self {
            Profile::Spec => StartRule::Uniform,
            Profile::Original => StartRule::Paper,
        }
    }

    /// The reward model: `sparse` (the SPEC world's default) or `paper-code`.
    pub fn reward(self) -> RewardModel {
        match self {
            Profile::Spec => RewardModel::default(),
            Profile::Original => RewardModel::PaperCode(PaperCode::default()),
        }
    }

    /// The default world ([`EnvConfig::default`]) under this profile's protocol, start rule
    /// and reward ([`ProfileParts::apply`]).
    pub fn world(self) -> EnvConfig {
        ProfileParts::of(self).apply(EnvConfig::default())
    }

    /// What ends a training game: the goal, or (the authors' code) a step reward above 70.
    /// Test games end at the goal under both profiles.
    pub const fn training_termination(self) -> Termination {
        match self {
            Profile::Spec => Termination::Goal,
            Profile::Original => Termination::paper_training(),
        }
    }
}

/// The world-level parts of a profile, as resolved for one run (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProfileParts {
    /// The profile they came from (reported, and keying the learner-level parts).
    pub profile: Profile,
    /// The action protocol.
    pub protocol: ActionProtocol,
    /// The start rule.
    pub start: StartRule,
    /// The reward.
    pub reward: RewardModel,
}

impl ProfileParts {
    /// `profile`'s parts.
    pub fn of(profile: Profile) -> ProfileParts {
        ProfileParts {
            profile,
            protocol: profile.protocol(),
            start: profile.start_rule(),
            reward: profile.reward(),
        }
    }

    /// These parts under a run's choices: `profile`, if given, replaces them all with its
    /// own; then each part given replaces that part.
    pub fn overridden(
        self,
        profile: Option<Profile>,
        protocol: Option<ActionProtocol>,
        start: Option<StartRule>,
        reward: Option<RewardModel>,
    ) -> ProfileParts {
        let parts = profile.map_or(self, ProfileParts::of);
        ProfileParts {
            protocol: protocol.unwrap_or(parts.protocol),
            start: start.unwrap_or(parts.start),
            reward: reward.unwrap_or(parts.reward),
            ..parts
        }
    }

    /// `config` with these parts' protocol, start rule and reward.
    pub fn apply(self, config: EnvConfig) -> EnvConfig {
        EnvConfig {
            protocol: self.protocol,
            start: self.start,
            reward: self.reward,
            ..config
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_part_named_on_its_own_replaces_the_profiles() {
        let spec = ProfileParts::of(Profile::Spec);
        assert_eq!(
            spec.overridden(Some(Profile::Original), None, None, None),
            ProfileParts::of(Profile::Original)
        );
        let mixed = spec.overridden(
            Some(Profile::Original),
            Some(ActionProtocol::Free),
            None,
            Some(RewardModel::default()),
        );
        assert_eq!(
            (mixed.profile, mixed.protocol, mixed.start, mixed.reward),
            (
                Profile::Original,
                ActionProtocol::Free,
                StartRule::Paper,
                RewardModel::default()
            )
        );
        assert_eq!(spec.overridden(None, None, None, None), spec);
        let config = mixed.apply(EnvConfig::default());
        assert_eq!(
            (config.protocol, config.start),
            (ActionProtocol::Free, StartRule::Paper)
        );
    }

    #[test]
    fn profiles_parse_print_and_serialise_by_name() {
        for name in Profile::NAMES {
            let p: Profile = name.parse().unwrap();
            assert_eq!(p.to_string(), name);
            assert_eq!(serde_json::to_string(&p).unwrap(), format!("\"{name}\""));
        }
        let err = "paper".parse::<Profile>().unwrap_err().to_string();
        assert!(err.contains("spec, original"), "{err}");
    }

    #[test]
    fn the_original_profile_is_the_authors_world() {
        let p = Profile::Original;
        assert_eq!(
            (p.protocol(), p.start_rule(), p.reward().name()),
            (ActionProtocol::Paper, StartRule::Paper, "paper-code")
        );
        assert_eq!(p.training_termination(), Termination::RewardAbove(70.0));
        let s = Profile::default();
        assert_eq!(
            (s.protocol(), s.start_rule(), s.reward(), s.training_termination()),
            (
                ActionProtocol::Free,
                StartRule::Uniform,
                RewardModel::default(),
                Termination::Goal
            )
        );
    }
}
