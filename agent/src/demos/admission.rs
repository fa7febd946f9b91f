//! Which recordings a reader takes: one of the run's world, and not a withdrawn
//! participant's. Every reader of recordings asks here (`learn-from-demos`, `dqn
//! --demos-file`, Python's `read_recording` and `to_minari`), so they refuse the same files
//! with the same line, and the front ends only pass the flag through.
//!
//! - **The world.** A recording of another view, action protocol (the profile's: `free`
//!   under `spec`, `paper` under `original`), grid or block count than the run's teaches
//!   steps under other rules: refused at its session line, in one line naming both
//!   worlds. A recording made before version 3 does not name its protocol, and a
//!   trajectory file never does: their protocol is not compared.
//! - **Withdrawal.** A participant who withdrew was promised that their recording is left
//!   out of every analysis. By default a withdrawn recording is refused, naming the
//!   withdrawal; [`Admission::include_withdrawn`] reads it all the same, for a lab that
//!   must audit (the reader then says so in one line: [`Admitted::note`]).

use std::fmt;
use std::path::Path;

use sim::{ActionProtocol, EnvConfig, Grid, View};

use super::format::{SessionLine, demos_error};
use crate::error::Result;

/// The world a run plays: what a recording it reads must be of. A part left `None` is
/// not compared (a run that does not fix it, or a recording that does not name it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunWorld {
    /// The view.
    pub view: Option<View>,
    /// The grid.
    pub grid: Option<Grid>,
    /// The block count.
    pub blocks: Option<usize>,
    /// The action protocol.
    pub protocol: Option<ActionProtocol>,
}

impl RunWorld {
    /// The world of `config`, every part named.
    pub fn of(config: &EnvConfig) -> RunWorld {
        RunWorld {
            view: Some(config.view),
            grid: Some(config.grid),
            blocks: Some(config.blocks),
            protocol: Some(config.protocol),
        }
    }

    /// The world a session line names (its protocol when it names one: version 3).
    pub fn of_session(header: &SessionLine) -> RunWorld {
        RunWorld {
            view: Some(header.view),
            grid: Grid::new(header.grid[0], header.grid[1]).ok(),
            blocks: Some(header.blocks),
            protocol: header.world.as_ref().map(|w| w.protocol),
        }
    }

    /// Whether a recording of `recorded` may be read by a run of `self`: every part both
    /// name the same.
    pub fn admits(&self, recorded: &RunWorld) -> bool {
        fn same<T: PartialEq>(a: Option<T>, b: Option<T>) -> bool {
            a.zip(b).is_none_or(|(a, b)| a == b)
        }
        same(self.view, recorded.view)
            && same(self.grid, recorded.grid)
            && same(self.blocks, recorded.blocks)
            && same(self.protocol, recorded.protocol)
    }
}

impl fmt::Display for RunWorld {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = Vec::new();
        if let Some(view) = self.view {
            parts.push(format!("the {view} view"));
        }
        match (self.blocks, self.grid) {
            (Some(b), Some(g)) => parts.push(format!("{b} blocks on a {g} grid")),
            (Some(b), None) => parts.push(format!("{b} blocks")),
            (None, Some(g)) => parts.push(format!("a {g} grid")),
            (None, None) => {}
        }
        if let Some(p) = self.protocol {
            parts.push(format!("the {p} protocol"));
        }
        if parts.is_empty() {
            parts.push("any world".into());
        }
        f.write_str(&parts.join(", "))
    }
}

/// What a reader takes (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Admission {
    /// The run's world (`None`: any world, the recording's own).
    pub world: Option<RunWorld>,
    /// Read a withdrawn participant's recording too, for an audit.
    pub include_withdrawn: bool,
}

impl Admission {
    /// An error unless a session of `header` is of the run's world (module docs), naming
    /// both worlds.
    pub fn check_session(&self, header: &SessionLine) -> std::result::Result<(), String> {
        let (Some(run), recorded) = (self.world, RunWorld::of_session(header)) else {
            return Ok(());
        };
        if run.admits(&recorded) {
            Ok(())
        } else {
            Err(format!("the recording is of {recorded}; this run is of {run}"))
        }
    }

    /// What a reader says of the file at `path` whose participant `withdrew` (or not): no
    /// line for one who did not, the note of an audit's read, or the error refusing it
    /// (module docs). For readers that read the withdrawal themselves (the researcher's
    /// exports).
    pub fn withdrawal(&self, path: &Path, withdrew: bool) -> Result<Option<String>> {
        if !withdrew {
            Ok(None)
        } else if self.include_withdrawn {
            Ok(Some(format!(
                "{}: the participant withdrew from the study; read all the same, for an audit (include withdrawn)",
                path.display()
            )))
        } else {
            Err(demos_error(
                path,
                "the participant withdrew from the study, and their recording is left out of every analysis \
                 (--include-withdrawn, in Python include_withdrawn=True, reads it for an audit)",
            ))
        }
    }
}

/// What a reader was given: the episodes, and the line it says about them, if any (a
/// withdrawn participant's recording read for an audit).
#[derive(Clone, Debug, PartialEq)]
pub struct Admitted<T> {
    /// What was read.
    pub read: T,
    /// One line for the reader to say (module docs).
    pub note: Option<String>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demos::read_admitted;

    fn world(view: View, blocks: usize, protocol: Option<ActionProtocol>) -> RunWorld {
        RunWorld {
            view: Some(view),
            grid: Some(Grid::default()),
            blocks: Some(blocks),
            protocol,
        }
    }

    #[test]
    fn a_world_admits_its_own_and_names_both_otherwise() {
        let top = world(View::Top, 3, Some(ActionProtocol::Free));
        assert!(top.admits(&top));
        assert!(
            top.admits(&world(View::Top, 3, None)),
            "an older recording names no protocol"
        );
        for other in [
            world(View::Side, 3, Some(ActionProtocol::Free)),
            world(View::Top, 4, Some(ActionProtocol::Free)),
            world(View::Top, 3, Some(ActionProtocol::Paper)),
        ] {
            assert!(!top.admits(&other), "{other}");
        }
        assert_eq!(
            world(View::Side, 3, Some(ActionProtocol::Paper)).to_string(),
            "the side view, 3 blocks on a 7x7 grid, the paper protocol"
        );
        // A run that fixes the protocol alone (Python's read_recording with a profile).
        let paper = RunWorld {
            protocol: Some(ActionProtocol::Paper),
            ..RunWorld::default()
        };
        assert!(paper.admits(&world(View::Side, 5, Some(ActionProtocol::Paper))));
        assert!(!paper.admits(&world(View::Top, 3, Some(ActionProtocol::Free))));
        assert_eq!(paper.to_string(), "the paper protocol");
    }

    /// A side-view session played to its goal by a person, recorded to `path`.
    fn side_recording(path: &Path) {
        use crate::correction::{CorrectionSession, PersonRole, session_world};
        use crate::{CorrectionRule, QAgent, QParams, ReprKind};
        let agent = QAgent::new(ReprKind::RoleTowers, Grid::default(), 3, QParams::default()).unwrap();
        let world = EnvConfig {
            view: View::Side,
            reward: "step-cost".parse().unwrap(),
            ..session_world(&agent)
        };
        let out = files::OutputPath::check(path).unwrap();
        let writer = crate::DemoWriter::append(&out).unwrap();
        let goal: sim::Goal = "0,1/2".parse().unwrap();
        let mut session = CorrectionSession::new(
            agent,
            CorrectionRule::default(),
            world.clone(),
            vec![goal],
            3,
            0.0,
            "person",
            None,
            writer,
        )
        .unwrap();
        let obs = session.next_episode().unwrap();
        let plan = oracle::ExactSolver::for_world(&world)
            .solve(&obs.state, &obs.goal)
            .unwrap();
        for &a in &plan.actions {
            session.person(a, PersonRole::Player).unwrap();
        }
    }

    #[test]
    fn a_reader_refuses_another_worlds_recording_and_a_withdrawn_one_unless_audited() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("side.jsonl");
        side_recording(&path);
        let side = RunWorld {
            protocol: Some(ActionProtocol::Free),
            ..world(View::Side, 3, None)
        };
        let as_side = Admission {
            world: Some(side),
            include_withdrawn: false,
        };
        let read = read_admitted(&path, &as_side).unwrap();
        assert!(read.note.is_none() && !read.read.is_empty());
        // The top view's run: refused at the session line, both worlds named.
        let as_top = Admission {
            world: Some(RunWorld {
                view: Some(View::Top),
                ..side
            }),
            ..as_side
        };
        let err = read_admitted(&path, &as_top).unwrap_err().to_string();
        assert!(
            err.contains("line 1: the recording is of the side view") && err.contains("this run is of the top view"),
            "{err}"
        );
        // Withdrawn: refused by default, naming the withdrawal; read for an audit, with a note.
        let mut text = std::fs::read_to_string(&path).unwrap();
        text.push_str("{\"type\":\"withdrawn\",\"at_ms\":1}\n");
        std::fs::write(&path, text).unwrap();
        let err = read_admitted(&path, &as_side).unwrap_err().to_string();
        assert!(err.contains("withdrew") && err.contains("--include-withdrawn"), "{err}");
        let audit = Admission {
            include_withdrawn: true,
            ..as_side
        };
        let read = read_admitted(&path, &audit).unwrap();
        assert!(read.note.unwrap().contains("for an audit"));
        assert!(!read.read.is_empty());
    }
}
