//! The data of learning from demonstrations: the correction rule a session learns by, and
//! the executed step it learns from.
//!
//! A leaf (sim and serde only) because three modules need these values without needing each
//! other: the recording format writes the rule into every session line
//! ([`crate::demos::format`]), a learner profile names one ([`crate::profile`]), and a
//! replay hands the steps to any learner ([`crate::demos::replay`]). What the rule does to a
//! tabular agent stays in [`crate::correction`] (`CorrectionRule::learn`, `validate`).

use serde::{Deserialize, Serialize};
use sim::{Action, Observation, Profile};

/// The default margin by which a demonstrator's action is made to beat every other.
pub const DEFAULT_MARGIN: f64 = 0.8;

/// How an agent learns from a demonstration session ([`crate::correction`]'s docs: the
/// rule). Serialised as a recording's `rule` field: its names are part of the format.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CorrectionRule {
    /// After a correction, `Q(s, a_E)` is raised to at least `max_{a != a_E} Q(s, a) +
    /// margin`; finite and at least 0. `None` (written `null`): no margin, the plain
    /// update alone, as the authors coded it.
    pub margin: Option<f64>,
    /// Whether the agent's own (uncorrected) steps get the Q-update too.
    pub learn_agent_steps: bool,
}

impl Default for CorrectionRule {
    /// Margin 0.8, learning from every step.
    fn default() -> Self {
        CorrectionRule {
            margin: Some(DEFAULT_MARGIN),
            learn_agent_steps: true,
        }
    }
}

impl CorrectionRule {
    /// The rule of the authors' code: no margin, learning from every step.
    pub const fn as_coded() -> Self {
        CorrectionRule {
            margin: None,
            learn_agent_steps: true,
        }
    }

    /// The rule of `profile`: ours (margin 0.8) under `spec`, [`CorrectionRule::as_coded`]
    /// under `original`.
    pub fn for_profile(profile: Profile) -> Self {
        match profile {
            Profile::Spec => CorrectionRule::default(),
            Profile::Original => CorrectionRule::as_coded(),
        }
    }
}

/// One executed step, as the rule learns from it.
#[derive(Clone, Debug, PartialEq)]
pub struct Experience {
    /// The state it was taken in.
    pub obs: Observation,
    /// The executed action.
    pub action: Action,
    /// The reward.
    pub reward: f64,
    /// The state it led to.
    pub next: Observation,
    /// The step ended the episode by its termination rule (the goal holds in `next`, or
    /// under the authors' rule the reward was above 70).
    pub terminated: bool,
    /// The step reached the horizon without the episode ending (learners bootstrap from
    /// `next` all the same; columns of steps keep it).
    pub truncated: bool,
    /// A demonstrator chose `action`.
    pub corrected: bool,
}
