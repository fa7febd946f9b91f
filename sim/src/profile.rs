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

use serde::{Deserialize, Serialize};

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

    /// What ends a training game: the goal, or (the authors' code) a step reward above 70.
    /// Test games end at the goal under both profiles.
    pub const fn training_termination(self) -> Termination {
        match self {
            Profile::Spec => Termination::Goal,
            Profile::Original => Termination::paper_training(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
