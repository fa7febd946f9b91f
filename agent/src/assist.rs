//! Oracle assistance in training (paper section VI-B2, Table I): *when* the oracle takes a
//! step ([`Assist`]), *which* oracle ([`OracleKind`]), and how oscillation is spotted
//! ([`Oscillation`], watched by an [`OscillationWatch`]).
//!
//! The table learns from the executed action, whoever chose it.
//!
//! # Oscillation, two readings
//!
//! - [`Oscillation::Actions`] (ours): the last six actions are one pair `a, b` (`a != b`)
//!   three times in a row, `a, b, a, b, a, b`; the oracle chooses the next action.
//! - [`Oscillation::Distances`] (the authors' code, docs/world.md section 10 "Oracle"; their
//!   `RL.py:246-252`): the first entry of the authors' state tuple
//!   ([`sim::CodedState::distance`]: the held pair's `d`, or every pair's `d` with nothing
//!   held) is recorded for every state a game meets, the current one included; when the
//!   last six are known and the even-indexed ones are all equal and the odd-indexed ones
//!   are all equal (period 2, or constant), the oracle chooses the action for the current
//!   state.

use std::fmt;

use serde::{Deserialize, Serialize};
use sim::coded_state::{CodedState, Distance};
use sim::{Action, Observation};

use crate::error::{AgentError, Result};

/// How many recent actions or distances oscillation is read from.
pub const OSCILLATION_WINDOW: usize = 6;

/// When the oracle chooses the action during training (paper section VI-B2). The table
/// learns from the executed action, whoever chose it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Assist {
    /// Never: the learner alone.
    #[default]
    None,
    /// When the learner oscillates (by the config's [`Oscillation`] test), the oracle
    /// chooses the next action.
    Oscillation,
    /// On oscillation as above, and besides at every step with probability `p`.
    OscillationOrChance {
        /// The probability of handing a step to the oracle (paper: 0.1).
        p: f64,
    },
}

impl Assist {
    /// An error unless `p` is a probability.
    pub fn validate(&self) -> Result<()> {
        match self {
            Assist::OscillationOrChance { p } if !(0.0..=1.0).contains(p) => Err(AgentError::Config(format!(
                "the oracle's probability {p} is not in [0, 1]"
            ))),
            _ => Ok(()),
        }
    }
}

impl fmt::Display for Assist {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Assist::None => f.write_str("none"),
            Assist::Oscillation => f.write_str("oscillation"),
            Assist::OscillationOrChance { p } => write!(f, "oscillation+{p}"),
        }
    }
}

impl std::str::FromStr for Assist {
    type Err = AgentError;

    /// Reads `none`, `oscillation`, or `oscillation+P` (e.g. `oscillation+0.1`).
    fn from_str(text: &str) -> Result<Assist> {
        let bad = || {
            AgentError::Config(format!(
                "unknown assistance {text:?}: choose none, oscillation or oscillation+P (e.g. oscillation+0.1)"
            ))
        };
        let assist = match text {
            "none" => Assist::None,
            "oscillation" => Assist::Oscillation,
            _ => {
                let p = text.strip_prefix("oscillation+").ok_or_else(bad)?;
                Assist::OscillationOrChance {
                    p: p.parse().map_err(|_| bad())?,
                }
            }
        };
        assist.validate()?;
        Ok(assist)
    }
}

/// Which oracle assists (and plays `run --agent oracle`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OracleKind {
    /// Ours: the centroid + A* planner ([`oracle::Oracle`]), sound from every state.
    #[default]
    Astar,
    /// The paper's: the greedy centroid walker as its authors coded it
    /// ([`oracle::CentroidWalker`]).
    Paper,
}

sim::names!(OracleKind { Astar = "astar", Paper = "paper" } unknown(text) -> AgentError {
    AgentError::Config(format!("unknown oracle {text:?}: choose astar (ours) or paper (the authors' greedy walker)"))
});

/// How oscillation is read (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Oscillation {
    /// Ours: the last six actions are `a, b, a, b, a, b` with `a != b`.
    #[default]
    Actions,
    /// The authors': the last six values of the state tuple's first entry have period 2
    /// (or are constant).
    Distances,
}

sim::names!(Oscillation { Actions = "actions", Distances = "distances" } unknown(text) -> AgentError {
    AgentError::Config(format!("unknown oscillation test {text:?}: choose actions (ours) or distances (the authors')"))
});

/// What one game has shown of oscillation so far, by one [`Oscillation`] test.
#[derive(Clone, Copy, Debug)]
pub struct OscillationWatch {
    test: Oscillation,
    /// The last actions (for [`Oscillation::Actions`]), oldest first.
    actions: [Option<Action>; OSCILLATION_WINDOW],
    /// The last distances (for [`Oscillation::Distances`]), oldest first.
    distances: [Option<Distance>; OSCILLATION_WINDOW],
}

impl OscillationWatch {
    /// A watch by `test`, for a game about to begin.
    pub fn new(test: Oscillation) -> Self {
        Self {
            test,
            actions: [None; OSCILLATION_WINDOW],
            distances: [None; OSCILLATION_WINDOW],
        }
    }

    /// Forgets the game so far.
    pub fn clear(&mut self) {
        *self = OscillationWatch::new(self.test);
    }

    /// Records the state about to be acted in (the distance test reads it).
    pub fn see_state(&mut self, obs: &Observation) {
        if self.test == Oscillation::Distances {
            self.distances.rotate_left(1);
            self.distances[OSCILLATION_WINDOW - 1] = Some(CodedState::of(obs.grid, &obs.goal, &obs.state).distance);
        }
    }

    /// Records the action taken (the action test reads it).
    pub fn see_action(&mut self, action: Action) {
        if self.test == Oscillation::Actions {
            self.actions.rotate_left(1);
            self.actions[OSCILLATION_WINDOW - 1] = Some(action);
        }
    }

    /// Whether the game oscillates now, by the watch's test.
    pub fn oscillating(&self) -> bool {
        match self.test {
            Oscillation::Actions => {
                let h = &self.actions;
                h[0].is_some() && h[0] != h[1] && h[0] == h[2] && h[2] == h[4] && h[1] == h[3] && h[3] == h[5]
            }
            Oscillation::Distances => {
                let h = &self.distances;
                h[0].is_some() && h[0] == h[2] && h[2] == h[4] && h[1] == h[3] && h[3] == h[5]
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::{BlockId, Cell, Goal, Grid, State};

    fn actions(seen: &[Action]) -> OscillationWatch {
        let mut w = OscillationWatch::new(Oscillation::Actions);
        for &a in seen {
            w.see_action(a);
        }
        w
    }

    #[test]
    fn action_oscillation_is_one_pair_three_times_in_a_row() {
        let (u, d, p, x) = (Action::Up, Action::Down, Action::Pick(BlockId(1)), Action::Drop);
        assert!(actions(&[u, d, u, d, u, d]).oscillating());
        assert!(actions(&[x, x, p, x, p, x, p, x]).oscillating());
        assert!(!actions(&[u, d, u, d, u]).oscillating(), "only two and a half pairs");
        assert!(!actions(&[u, d, u, d, u, u]).oscillating());
        assert!(
            !actions(&[u, u, u, u, u, u]).oscillating(),
            "six moves one way are progress"
        );
        assert!(actions(&[x, u, d, u, d, u, d, u]).oscillating(), "d, u three times");
        assert!(!actions(&[u, d, u, d, u, d, x]).oscillating(), "the window moved on");
    }

    /// The observation of 2 blocks on 7 x 7, goal 0,1, block 0 at (3, 2), block 1 at `top`,
    /// holding `held`.
    fn obs(top: (u16, u16), held: Option<u16>) -> Observation {
        Observation {
            grid: Grid::default(),
            state: State::new(&[Cell::new(3, 2), Cell::new(top.0, top.1)], held.map(BlockId)).unwrap(),
            goal: "0,1".parse::<Goal>().unwrap(),
            protocol: sim::ActionProtocol::Paper,
            view: sim::View::Top,
        }
    }

    fn distances(seen: &[Observation]) -> OscillationWatch {
        let mut w = OscillationWatch::new(Oscillation::Distances);
        for o in seen {
            w.see_state(o);
        }
        w
    }

    #[test]
    fn distance_oscillation_is_period_two_in_the_tuple_s_first_entry() {
        // Block 1 held; its pair (0, 1), block 0 at (3, 2). Block 1 at (4, 2) stands beside
        // it, d = 3125; at (4, 3) diagonally above, 3125 too; at (3, 3) on it, 625.
        let (beside, diagonal, stacked) = (obs((4, 2), Some(1)), obs((4, 3), Some(1)), obs((3, 3), Some(1)));
        let back_and_forth = [
            beside.clone(),
            stacked.clone(),
            beside.clone(),
            stacked.clone(),
            beside.clone(),
            stacked.clone(),
        ];
        assert!(distances(&back_and_forth).oscillating());
        // The same d in two places is the same value: left-right between two cells at
        // 3125 is "constant".
        assert!(
            distances(&[
                beside.clone(),
                diagonal.clone(),
                beside.clone(),
                diagonal.clone(),
                beside.clone(),
                diagonal
            ])
            .oscillating()
        );
        assert!(!distances(&back_and_forth[..5]).oscillating(), "six values are needed");
        let far = obs((6, 6), Some(1));
        assert!(
            !distances(&[
                beside.clone(),
                stacked.clone(),
                beside.clone(),
                stacked.clone(),
                beside.clone(),
                far
            ])
            .oscillating()
        );
        // Nothing held: the tuple's first entry lists every pair's d; a held and an empty
        // state never compare equal.
        let empty = obs((3, 3), None);
        assert!(
            distances(&[
                empty.clone(),
                stacked.clone(),
                empty.clone(),
                stacked.clone(),
                empty.clone(),
                stacked.clone()
            ])
            .oscillating()
        );
        assert!(
            !distances(&[
                empty.clone(),
                empty.clone(),
                stacked.clone(),
                stacked,
                empty.clone(),
                empty
            ])
            .oscillating()
        );
        // The action test ignores states, and the distance test actions.
        let mut w = distances(&back_and_forth);
        w.see_action(Action::Up);
        assert!(w.oscillating());
        w.clear();
        assert!(!w.oscillating());
        let mut a = actions(&[]);
        a.see_state(&beside);
        assert!(!a.oscillating());
    }

    #[test]
    fn names_read_and_write() {
        for text in ["none", "oscillation", "oscillation+0.1", "oscillation+1"] {
            let a: Assist = text.parse().unwrap();
            assert_eq!(a.to_string().parse::<Assist>().unwrap(), a);
        }
        assert_eq!(
            "oscillation+0.1".parse::<Assist>().unwrap(),
            Assist::OscillationOrChance { p: 0.1 }
        );
        for bad in ["always", "oscillation+", "oscillation+x", "oscillation+1.5"] {
            assert!(bad.parse::<Assist>().is_err(), "{bad}");
        }
        for name in OracleKind::NAMES {
            assert_eq!(name.parse::<OracleKind>().unwrap().to_string(), name);
        }
        for name in Oscillation::NAMES {
            assert_eq!(name.parse::<Oscillation>().unwrap().to_string(), name);
        }
        assert!("a*".parse::<OracleKind>().is_err());
        assert!("pairs".parse::<Oscillation>().is_err());
    }
}
