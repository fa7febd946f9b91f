//! Termination rules: what ends an episode before its horizon.
//!
//! docs/world.md section 3 ends an episode when the goal holds ([`Termination::Goal`], the default).
//! The authors' *training* games did not end at the goal: a training game ended when a
//! step's reward exceeded 70 (docs/world.md section 10, "Reward as coded"; with the `paper-code` reward
//! that is both pairs of a 3-block stack in place, and never happens with 2 blocks, whose
//! training games run their full length). Their test games ended at the goal.
//! [`Termination::RewardAbove`] is that training rule; [`Termination::paper_training`] gives
//! it with the authors' threshold.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError};

/// What makes a step end its episode (`terminated`), besides the horizon (`truncated`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Termination {
    /// docs/world.md section 3: the goal holds after the step. A start in which the goal already
    /// holds ends the episode at once, unless the start rule keeps such starts (then the
    /// first step ends it, if the goal still holds after it).
    #[default]
    Goal,
    /// The step's reward is above this threshold; reaching the goal alone ends nothing,
    /// and a start in which the goal holds runs like any other.
    RewardAbove(f64),
}

impl Termination {
    /// The threshold of the authors' training games (docs/world.md section 10, "Reward as coded").
    pub const PAPER_TRAINING_THRESHOLD: f64 = 70.0;

    /// The authors' training rule: a step's reward above 70 ends the game.
    pub const fn paper_training() -> Termination {
        Termination::RewardAbove(Self::PAPER_TRAINING_THRESHOLD)
    }

    /// Whether a step with reward `reward`, after which the goal does (`goal_holds`) or does
    /// not hold, ends the episode.
    #[inline]
    pub fn ends(self, reward: f64, goal_holds: bool) -> bool {
        match self {
            Termination::Goal => goal_holds,
            Termination::RewardAbove(threshold) => reward > threshold,
        }
    }
}

impl fmt::Display for Termination {
    /// `goal`, or `reward-above:T`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Termination::Goal => f.write_str("goal"),
            Termination::RewardAbove(t) => write!(f, "reward-above:{t}"),
        }
    }
}

impl std::str::FromStr for Termination {
    type Err = SimError;

    /// Reads `goal` or `reward-above:T` (e.g. `reward-above:70`).
    fn from_str(text: &str) -> Result<Termination> {
        let err = |reason: &str| SimError::Parse {
            what: "termination rule",
            text: text.to_string(),
            reason: reason.to_string(),
        };
        if text == "goal" {
            return Ok(Termination::Goal);
        }
        let threshold = text
            .strip_prefix("reward-above:")
            .ok_or_else(|| err("choose goal or reward-above:T, e.g. reward-above:70"))?;
        match threshold.trim().parse::<f64>() {
            Ok(t) if t.is_finite() => Ok(Termination::RewardAbove(t)),
            _ => Err(err("the threshold is not a finite number")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_parse_print_and_serialise() {
        for rule in [
            Termination::Goal,
            Termination::paper_training(),
            Termination::RewardAbove(-0.5),
        ] {
            assert_eq!(rule.to_string().parse::<Termination>().unwrap(), rule);
            let json = serde_json::to_string(&rule).unwrap();
            assert_eq!(serde_json::from_str::<Termination>(&json).unwrap(), rule);
        }
        assert_eq!(Termination::paper_training().to_string(), "reward-above:70");
        assert_eq!(serde_json::to_string(&Termination::Goal).unwrap(), "\"goal\"");
        assert!("reward-above:x".parse::<Termination>().is_err());
        assert!("reward-above:inf".parse::<Termination>().is_err());
        assert!("never".parse::<Termination>().is_err());
    }

    #[test]
    fn reward_above_reads_the_reward_not_the_goal() {
        let rule = Termination::paper_training();
        assert!(!rule.ends(70.0, true));
        assert!(rule.ends(100.0, false));
        assert!(Termination::Goal.ends(0.0, true));
        assert!(!Termination::Goal.ends(1e9, false));
    }
}
