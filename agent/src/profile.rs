//! The learner-level parts of each profile: what [`sim::Profile`] means for an agent.
//!
//! `sim` holds a profile's world (action protocol, start rule, reward of the world,
//! training termination); this module holds the rest, keyed by the same enum:
//!
//! | part | `spec` (default) | `original` (docs/world.md section 10) |
//! |---|---|---|
//! | representation | `chasing` | `chasing-code` |
//! | the learner's reward | `paper` (our reading of the prose) | `paper-code` |
//! | schedule ([`Schedule`]) | `spec` | `paper-code` |
//! | oracle ([`OracleKind`]) | `astar` | `paper` (the greedy centroid walker) |
//! | oscillation test ([`Oscillation`]) | `actions` | `distances` |
//! | test epsilon | 0.1 | 0.1 |
//! | correction rule ([`CorrectionRule`]) | margin 0.8 | no margin (the plain update) |
//!
//! Under `spec` these are the defaults blockstack had before profiles existed (the paper's
//! learner in our world), so nothing changes for a caller that names no profile.

use sim::{Profile, RewardModel};

use crate::assist::{OracleKind, Oscillation};
use crate::repr::ReprKind;
use crate::rule::CorrectionRule;
use crate::schedule::Schedule;

/// The paper's test policy: a random (legal) action with probability 0.1, in both
/// profiles (the authors' test `nu`).
pub const TEST_EPSILON: f64 = 0.1;

/// A profile's learner-level parts (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LearnerProfile {
    /// The profile these are the parts of.
    pub profile: Profile,
    /// The state representation.
    pub repr: ReprKind,
    /// The reward the learner trains on.
    pub reward: RewardModel,
    /// The training schedule and update rule.
    pub schedule: Schedule,
    /// The oracle that assists (and that `run --agent oracle` plays).
    pub oracle: OracleKind,
    /// How oscillation is spotted for assistance.
    pub oscillation: Oscillation,
    /// The probability of a random action in test games.
    pub test_epsilon: f64,
    /// How a demonstrator's corrections are learnt.
    pub correction: CorrectionRule,
}

impl LearnerProfile {
    /// The parts of `profile`.
    pub fn of(profile: Profile) -> LearnerProfile {
        match profile {
            Profile::Spec => LearnerProfile {
                profile,
                repr: ReprKind::Chasing,
                reward: RewardModel::from_name("paper").expect("a known model"),
                schedule: Schedule::Spec,
                oracle: OracleKind::Astar,
                oscillation: Oscillation::Actions,
                test_epsilon: TEST_EPSILON,
                correction: CorrectionRule::default(),
            },
            Profile::Original => LearnerProfile {
                profile,
                repr: ReprKind::ChasingCode,
                reward: profile.reward(),
                schedule: Schedule::PaperCode,
                oracle: OracleKind::Paper,
                oscillation: Oscillation::Distances,
                test_epsilon: TEST_EPSILON,
                correction: CorrectionRule::as_coded(),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_original_profile_is_the_authors_learner() {
        let o = LearnerProfile::of(Profile::Original);
        assert_eq!(
            (o.repr, o.reward.name(), o.schedule, o.oracle, o.oscillation),
            (
                ReprKind::ChasingCode,
                "paper-code",
                Schedule::PaperCode,
                OracleKind::Paper,
                Oscillation::Distances
            )
        );
        assert_eq!(o.correction.margin, None);
        let s = LearnerProfile::of(Profile::Spec);
        assert_eq!(
            (s.repr, s.reward.name(), s.schedule, s.oracle, s.oscillation),
            (
                ReprKind::Chasing,
                "paper",
                Schedule::Spec,
                OracleKind::Astar,
                Oscillation::Actions
            )
        );
        assert_eq!(s.correction, CorrectionRule::default());
        assert_eq!((s.test_epsilon, o.test_epsilon), (0.1, 0.1));
    }
}
