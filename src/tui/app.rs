//! The state machine of `blockstack demo`, with no terminal in it: what each key does and
//! what the agent does on each tick.

use std::path::PathBuf;
use std::time::Duration;

use agent::correction::{CorrectionSession, PersonRole, PersonTurn, SessionStep};
use agent::{DemoSink, QAgent};
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};
use sim::render::label;
use sim::{Action, BlockId};

/// The agent's paces, in steps per second, slowest first.
pub const PACES: [f64; 8] = [0.5, 1.0, 2.0, 4.0, 8.0, 15.0, 30.0, 60.0];

/// The pace a session starts at (an index into [`PACES`]): 2 steps per second.
pub const DEFAULT_PACE: usize = 2;

/// What a person can ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// Let the agent play faster (`+`).
    Faster,
    /// Slower (`-`).
    Slower,
    /// Pause or resume the agent (space).
    TogglePause,
    /// Take this action instead of the agent's (arrows, a block's label, `d`).
    Override(Action),
    /// Pick a block that does not exist (a label too large): explained, nothing done.
    NoSuchBlock(u32),
    /// A lower-case `a`-`f` but `d`: blocks 10 to 15 are picked with capitals, explained.
    CapitalsPick(char),
    /// Abandon the episode and begin the next (`n`).
    NextEpisode,
    /// Save and quit (`q`, Esc, Ctrl-C).
    Quit,
}

/// The command a key press asks for, if any. A block is picked by its label
/// ([`sim::render::label`]): `0`-`9`, then `A`-`F` for blocks 10 to 15 (`d` drops).
pub fn command_for(key: KeyEvent, blocks: usize) -> Option<Command> {
    if key.kind == KeyEventKind::Release {
        return None;
    }
    Some(match key.code {
        KeyCode::Char('c') if key.modifiers.contains(KeyModifiers::CONTROL) => Command::Quit,
        KeyCode::Char('+' | '=') => Command::Faster,
        KeyCode::Char('-' | '_') => Command::Slower,
        KeyCode::Char(' ') | KeyCode::Char('p') => Command::TogglePause,
        KeyCode::Up => Command::Override(Action::Up),
        KeyCode::Down => Command::Override(Action::Down),
        KeyCode::Left => Command::Override(Action::Left),
        KeyCode::Right => Command::Override(Action::Right),
        KeyCode::Char('d') => Command::Override(Action::Drop),
        KeyCode::Char(c @ ('0'..='9' | 'A'..='F')) => {
            let i = c.to_digit(16).expect("a label");
            if (i as usize) < blocks {
                Command::Override(Action::Pick(BlockId::of(i as usize)))
            } else {
                Command::NoSuchBlock(i)
            }
        }
        KeyCode::Char(c @ ('a'..='c' | 'e' | 'f')) => Command::CapitalsPick(c),
        KeyCode::Char('n') => Command::NextEpisode,
        KeyCode::Char('q') | KeyCode::Esc => Command::Quit,
        _ => return None,
    })
}

/// Where and how often the corrected model is saved.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SavePolicy {
    /// The model file written (atomically).
    pub path: PathBuf,
    /// Save after every this many corrections (and on quitting); 0: only on quitting.
    pub every: u64,
}

/// A demonstration session in a terminal: the session, the pace, and what to tell the
/// person.
pub struct DemoApp<S: DemoSink> {
    session: CorrectionSession<S>,
    save: SavePolicy,
    pace: usize,
    paused: bool,
    /// The terminal is too small to show the world: the agent waits, and so do the keys
    /// that act in a world no one can see.
    hidden: bool,
    quit: bool,
    /// Corrections when the model was last saved.
    saved_at: u64,
    /// Corrections in the current episode.
    episode_corrections: u64,
    /// One line about the last thing that happened.
    message: String,
}

impl<S: DemoSink> DemoApp<S> {
    /// Begins the first episode of `session`, the agent playing at [`DEFAULT_PACE`].
    pub fn new(mut session: CorrectionSession<S>, save: SavePolicy) -> agent::Result<Self> {
        session.next_episode()?;
        Ok(DemoApp {
            session,
            save,
            pace: DEFAULT_PACE,
            paused: false,
            hidden: false,
            quit: false,
            saved_at: 0,
            episode_corrections: 0,
            message: "The agent plays; step in with the arrows, a digit or d.".into(),
        })
    }

    /// The session.
    pub fn session(&self) -> &CorrectionSession<S> {
        &self.session
    }

    /// The agent as corrected so far.
    pub fn agent(&self) -> &QAgent {
        self.session.agent()
    }

    /// The agent's pace in steps per second.
    pub fn pace(&self) -> f64 {
        PACES[self.pace]
    }

    /// The time between two of the agent's steps.
    pub fn tick_interval(&self) -> Duration {
        Duration::from_secs_f64(1.0 / self.pace())
    }

    /// Whether the agent is paused.
    pub fn is_paused(&self) -> bool {
        self.paused
    }

    /// Whether the world is hidden (the terminal is too small to show it).
    pub fn is_hidden(&self) -> bool {
        self.hidden
    }

    /// Says whether the terminal shows the world: while it does not, the agent does not
    /// step ([`DemoApp::tick`]) and the keys that act are ignored.
    pub fn set_hidden(&mut self, hidden: bool) {
        self.hidden = hidden;
    }

    /// Whether the person asked to quit.
    pub fn should_quit(&self) -> bool {
        self.quit
    }

    /// Corrections in the current episode.
    pub fn episode_corrections(&self) -> u64 {
        self.episode_corrections
    }

    /// The last step taken in the episode.
    pub fn last_step(&self) -> Option<&SessionStep> {
        self.session.last_step()
    }

    /// One line about the last thing that happened.
    pub fn message(&self) -> &str {
        &self.message
    }

    /// Where the model is saved.
    pub fn save_policy(&self) -> &SavePolicy {
        &self.save
    }

    /// Carries out a person's command. Errors are the session's (a recording that cannot
    /// be written, a model that cannot be saved).
    pub fn handle(&mut self, command: Command) -> agent::Result<()> {
        if self.hidden && matches!(command, Command::Override(_) | Command::NextEpisode) {
            return Ok(());
        }
        match command {
            Command::Faster => {
                self.pace = (self.pace + 1).min(PACES.len() - 1);
                self.message = format!("Pace: {} steps per second.", self.pace());
            }
            Command::Slower => {
                self.pace = self.pace.saturating_sub(1);
                self.message = format!("Pace: {} steps per second.", self.pace());
            }
            Command::TogglePause => {
                self.paused = !self.paused;
                self.message = if self.paused {
                    "Paused: step in with the arrows, a digit or d; space resumes.".into()
                } else {
                    "Resumed.".into()
                };
            }
            Command::NoSuchBlock(i) => {
                let last = BlockId::of(self.agent().blocks() - 1);
                self.message = format!(
                    "There is no block {}: the blocks are 0 to {}.",
                    label(BlockId::of(i as usize)),
                    label(last)
                );
            }
            Command::CapitalsPick(c) => {
                self.message = format!(
                    "Blocks 10 to 15 are labelled A to F: press {} (with Shift) to pick block {}.",
                    c.to_ascii_uppercase(),
                    c.to_digit(16).expect("a hex letter")
                );
            }
            Command::Override(action) => {
                let turn = self.session.person(action, PersonRole::Corrector)?;
                self.message = turn.message();
                if let PersonTurn::Taken { steps, .. } = &turn {
                    self.after_steps(steps)?;
                    self.describe_end();
                }
            }
            Command::NextEpisode => {
                self.begin_next()?;
                self.message = "Next episode.".into();
            }
            Command::Quit => {
                self.save_model()?;
                self.quit = true;
            }
        }
        Ok(())
    }

    /// What the agent does when its time comes: its proposed step, or the next episode
    /// after one has ended. Nothing while paused or hidden.
    pub fn tick(&mut self) -> agent::Result<()> {
        if self.paused || self.hidden || self.quit {
            return Ok(());
        }
        if self.session.is_over() {
            self.begin_next()?;
            self.message = "Next episode.".into();
        } else {
            self.take(None)?;
            self.describe_end();
        }
        Ok(())
    }

    fn take(&mut self, correction: Option<Action>) -> agent::Result<()> {
        let step = self.session.step(correction)?;
        self.after_steps(&[step])
    }

    /// Counts the corrections among `steps` and saves the model when the policy says so.
    fn after_steps(&mut self, steps: &[SessionStep]) -> agent::Result<()> {
        let corrected = steps.iter().filter(|s| s.corrected).count() as u64;
        self.episode_corrections += corrected;
        let corrections = self.session.report().corrections;
        if corrected > 0 && self.save.every > 0 && corrections - self.saved_at >= self.save.every {
            self.save_model()?;
        }
        Ok(())
    }

    fn begin_next(&mut self) -> agent::Result<()> {
        self.session.next_episode()?;
        self.episode_corrections = 0;
        Ok(())
    }

    fn describe_end(&mut self) {
        if let Some(end) = self.session.episode_end() {
            self.message = format!("{} The next episode follows (n: now).", end.message(None));
        }
    }

    /// Saves the corrected model, atomically.
    pub fn save_model(&mut self) -> agent::Result<()> {
        self.session.agent().save(&self.save.path)?;
        self.saved_at = self.session.report().corrections;
        self.message = format!(
            "Saved the corrected model to {} ({} corrections).",
            self.save.path.display(),
            self.saved_at
        );
        Ok(())
    }

    /// Ends the app: the session's agent, sink and totals.
    pub fn finish(self) -> (QAgent, S, agent::correction::SessionReport) {
        self.session.finish()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use agent::correction::{CorrectionRule, session_world};
    use agent::{DemoRecord, QParams, ReprKind};
    use sim::{Goal, Grid};

    fn key(code: KeyCode) -> KeyEvent {
        KeyEvent::new(code, KeyModifiers::NONE)
    }

    /// A person's session of `agent` in `world` on `goals` (seed 7, epsilon 0, the default
    /// correction rule), saving to `dir` every 2 corrections.
    fn app_in(
        dir: &std::path::Path,
        agent: QAgent,
        world: sim::EnvConfig,
        goals: Vec<Goal>,
    ) -> DemoApp<Vec<DemoRecord>> {
        let session = CorrectionSession::new(
            agent,
            CorrectionRule::default(),
            world,
            goals,
            7,
            0.0,
            "person",
            None,
            Vec::new(),
        )
        .unwrap();
        let save = SavePolicy {
            path: dir.join("corrected.safetensors"),
            every: 2,
        };
        DemoApp::new(session, save).unwrap()
    }

    /// A session of an untrained `role-towers` agent in the side view, on goal 0,1/2.
    pub(crate) fn side_app(dir: &std::path::Path) -> DemoApp<Vec<DemoRecord>> {
        let agent = QAgent::new(ReprKind::RoleTowers, Grid::default(), 3, QParams::default()).unwrap();
        let world = sim::EnvConfig {
            view: sim::View::Side,
            reward: "step-cost".parse().unwrap(),
            ..session_world(&agent)
        };
        app_in(dir, agent, world, vec!["0,1/2".parse().unwrap()])
    }

    pub(crate) fn app(dir: &std::path::Path) -> DemoApp<Vec<DemoRecord>> {
        let agent = QAgent::new(ReprKind::Chasing, Grid::default(), 3, QParams::default()).unwrap();
        let world = session_world(&agent);
        app_in(
            dir,
            agent,
            world,
            vec!["1,0,2".parse().unwrap(), "0,1,2".parse().unwrap()],
        )
    }

    #[test]
    fn keys_map_to_commands() {
        assert_eq!(command_for(key(KeyCode::Up), 3), Some(Command::Override(Action::Up)));
        assert_eq!(
            command_for(key(KeyCode::Left), 3),
            Some(Command::Override(Action::Left))
        );
        assert_eq!(
            command_for(key(KeyCode::Char('2')), 3),
            Some(Command::Override(Action::Pick(BlockId(2))))
        );
        assert_eq!(command_for(key(KeyCode::Char('3')), 3), Some(Command::NoSuchBlock(3)));
        assert_eq!(
            command_for(key(KeyCode::Char('d')), 3),
            Some(Command::Override(Action::Drop))
        );
        assert_eq!(command_for(key(KeyCode::Char(' ')), 3), Some(Command::TogglePause));
        assert_eq!(command_for(key(KeyCode::Char('+')), 3), Some(Command::Faster));
        assert_eq!(command_for(key(KeyCode::Char('-')), 3), Some(Command::Slower));
        assert_eq!(command_for(key(KeyCode::Char('n')), 3), Some(Command::NextEpisode));
        assert_eq!(command_for(key(KeyCode::Char('q')), 3), Some(Command::Quit));
        assert_eq!(
            command_for(KeyEvent::new(KeyCode::Char('c'), KeyModifiers::CONTROL), 3),
            Some(Command::Quit)
        );
        assert_eq!(command_for(key(KeyCode::Char('x')), 3), None);
        // Blocks 10 to 15 by their capital labels; a lower-case one is explained.
        assert_eq!(
            command_for(key(KeyCode::Char('F')), 16),
            Some(Command::Override(Action::Pick(BlockId(15))))
        );
        assert_eq!(
            command_for(key(KeyCode::Char('A')), 11),
            Some(Command::Override(Action::Pick(BlockId(10))))
        );
        assert_eq!(command_for(key(KeyCode::Char('B')), 11), Some(Command::NoSuchBlock(11)));
        assert_eq!(
            command_for(key(KeyCode::Char('c')), 16),
            Some(Command::CapitalsPick('c'))
        );
        assert_eq!(
            command_for(key(KeyCode::Char('d')), 16),
            Some(Command::Override(Action::Drop))
        );
    }

    #[test]
    fn a_hidden_world_stops_the_agent_and_the_keys_that_act() {
        let dir = tempdir();
        let mut app = app(dir.path());
        app.set_hidden(true);
        for _ in 0..5 {
            app.tick().unwrap();
        }
        app.handle(Command::Override(Action::Pick(BlockId(0)))).unwrap();
        app.handle(Command::NextEpisode).unwrap();
        assert_eq!(app.session().steps(), 0);
        assert_eq!(app.session().episode_number(), Some(0));
        app.set_hidden(false);
        app.tick().unwrap();
        assert_eq!(app.session().steps(), 1);
    }

    #[test]
    fn an_override_is_executed_recorded_and_learnt_instead_of_the_proposal() {
        let dir = tempdir();
        let mut app = app(dir.path());
        app.handle(Command::TogglePause).unwrap();
        let before = app.session().observation().unwrap();
        let q_before = app.agent().q(&before, Action::Pick(BlockId(1))).unwrap();
        app.handle(Command::Override(Action::Pick(BlockId(1)))).unwrap();
        let after = app.session().observation().unwrap();
        assert_eq!(after.held_block(), Some(BlockId(1)));
        assert!(app.agent().q(&before, Action::Pick(BlockId(1))).unwrap() >= q_before + 0.8);
        assert_eq!(app.episode_corrections(), 1);
        assert!(app.last_step().unwrap().corrected);
        // Paused: ticks do nothing.
        app.tick().unwrap();
        assert_eq!(app.session().steps(), 1);
        app.handle(Command::TogglePause).unwrap();
        app.tick().unwrap();
        assert_eq!(app.session().steps(), 2);
        assert!(!app.last_step().unwrap().corrected);
    }

    #[test]
    fn the_model_is_saved_every_n_corrections_and_on_quit() {
        let dir = tempdir();
        let mut app = app(dir.path());
        let path = dir.path().join("corrected.safetensors");
        app.handle(Command::Override(Action::Pick(BlockId(0)))).unwrap();
        assert!(!path.exists());
        app.handle(Command::Override(Action::Up)).unwrap();
        assert_eq!(QAgent::load(&path).unwrap(), *app.agent());
        app.handle(Command::Override(Action::Right)).unwrap();
        assert_ne!(QAgent::load(&path).unwrap(), *app.agent());
        app.handle(Command::Quit).unwrap();
        assert!(app.should_quit());
        assert_eq!(QAgent::load(&path).unwrap(), *app.agent());
    }

    #[test]
    fn pace_pause_and_next_episode() {
        let dir = tempdir();
        let mut app = app(dir.path());
        let start = app.tick_interval();
        app.handle(Command::Faster).unwrap();
        assert!(app.tick_interval() < start);
        for _ in 0..20 {
            app.handle(Command::Slower).unwrap();
        }
        assert_eq!(app.pace(), PACES[0]);
        app.handle(Command::NoSuchBlock(5)).unwrap();
        assert!(app.message().contains("no block 5"));
        let goal = app.session().observation().unwrap().goal;
        app.handle(Command::NextEpisode).unwrap();
        assert_eq!(app.session().episode_number(), Some(1));
        assert_ne!(app.session().observation().unwrap().goal, goal);
        let (_, records, _) = app.finish();
        let episodes = records.iter().filter(|r| matches!(r, DemoRecord::Episode(_))).count();
        assert_eq!(episodes, 2);
    }

    #[test]
    fn under_the_paper_protocol_a_person_changes_blocks_by_a_drop_and_a_pick() {
        let dir = tempdir();
        let agent = QAgent::new(ReprKind::ChasingCode, Grid::default(), 3, QParams::default()).unwrap();
        let world = sim::EnvConfig {
            protocol: sim::ActionProtocol::Paper,
            ..session_world(&agent)
        };
        let session = CorrectionSession::new(
            agent,
            CorrectionRule::as_coded(),
            world,
            vec!["0,1,2".parse().unwrap()],
            7,
            0.0,
            "person",
            None,
            Vec::new(),
        )
        .unwrap();
        let save = SavePolicy {
            path: dir.path().join("corrected.json"),
            every: 0,
        };
        let mut app = DemoApp::new(session, save).unwrap();
        app.handle(Command::TogglePause).unwrap();
        // Nothing held: a move is refused, with what is allowed.
        app.handle(Command::Override(Action::Up)).unwrap();
        assert!(app.message().contains("only pick N is allowed"), "{}", app.message());
        assert_eq!(app.session().steps(), 0);
        app.handle(Command::Override(Action::Pick(BlockId(1)))).unwrap();
        app.handle(Command::Override(Action::Pick(BlockId(1)))).unwrap();
        assert!(app.message().contains("held already"), "{}", app.message());
        app.handle(Command::Override(Action::Pick(BlockId(2)))).unwrap();
        assert_eq!(app.session().observation().unwrap().held_block(), Some(BlockId(2)));
        assert_eq!(app.episode_corrections(), 3);
        assert!(app.message().contains("drop, then pick 2"), "{}", app.message());
        let (_, records, _) = app.finish();
        let actions: Vec<String> = records
            .iter()
            .filter_map(|r| match r {
                DemoRecord::Step(s) => Some(s.action.clone()),
                _ => None,
            })
            .collect();
        assert_eq!(actions, ["pick 1", "drop", "pick 2"]);
    }

    /// A fresh folder in the system's temporary directory, removed when dropped.
    pub(crate) fn tempdir() -> tempfile::TempDir {
        tempfile::tempdir().unwrap()
    }
}
