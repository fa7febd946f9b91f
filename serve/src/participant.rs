//! One participant's state, with no network in it: what each message does.
//!
//! Play and correct mode drive one [`CorrectionSession`], the library session
//! `blockstack demo` drives, so the rules (a person's pick while holding under the `paper`
//! protocol is a Drop and then the Pick, the learning rule, the recording) are that
//! session's: in play mode every step is the person's, in correct mode the person accepts
//! the agent's proposal or overrides it. One session per participant makes one recording
//! that `learn-from-demos` replays from the condition's model. Watch mode plays the
//! condition's model (tabular or network) through its [`agent::Policy`] in an
//! environment of its own, greedy, and records nothing.
//!
//! Every message either changes the state and gets a [`View`], or changes nothing and gets
//! an error line.

use std::sync::Arc;

use agent::correction::{CorrectionSession, EpisodeEnd, PersonRole, PersonTurn, SessionLabels};
use agent::demos::{DemoSink, ParticipantLine};
use agent::{DemoRecord, DemoWriter};
use files::{Output, OutputPath};
use oracle::ExactSolver;
use sim::render::{colour, label};
use sim::seeding::{SimRng, episode_seed};
use sim::{Action, BlockMove, Env, EnvConfig, Observation};

use crate::config::{Condition, StudyPath};
use crate::protocol::{ActionValue, ClientMessage, Completion, Mode, Progress, View};

/// The agent's probability of a random proposal in correct mode: the paper's test policy,
/// as `blockstack demo`'s default.
const PROPOSAL_EPSILON: f64 = agent::profile::TEST_EPSILON;

/// Where a participant's lines go: the recording file, or nowhere; counts what it wrote.
///
/// A new participant's file is made only with their first step: until then the session
/// and episode lines wait in memory, so a join that never acts (a script's) leaves nothing
/// on disk and counts towards nothing.
pub struct Recorder {
    /// Where the file is made at the first step, until it is.
    target: Option<OutputPath>,
    writer: Option<DemoWriter<Output>>,
    pending: Vec<DemoRecord>,
    lines: u64,
}

impl Recorder {
    /// Records to `writer` at once (none: nothing is recorded): a recording taken up again.
    pub fn new(writer: Option<DemoWriter<Output>>) -> Self {
        Recorder {
            target: None,
            writer,
            pending: Vec::new(),
            lines: 0,
        }
    }

    /// Records into `out`, made at the first step line (type docs).
    pub fn at_first_step(out: OutputPath) -> Self {
        Recorder {
            target: Some(out),
            ..Recorder::new(None)
        }
    }

    /// Lines written and flushed.
    pub fn lines(&self) -> u64 {
        self.lines
    }

    /// Whether lines are recorded (now, or from the first step).
    pub fn is_recording(&self) -> bool {
        self.writer.is_some() || self.target.is_some()
    }

    /// Whether the recording's file exists (the participant took a step).
    pub fn is_on_disk(&self) -> bool {
        self.writer.is_some()
    }

    fn write(&mut self, line: &DemoRecord) -> agent::Result<()> {
        if let Some(w) = &mut self.writer {
            w.record(line)?;
            self.lines += 1;
        }
        Ok(())
    }
}

impl DemoSink for Recorder {
    fn record(&mut self, line: &DemoRecord) -> agent::Result<()> {
        if self.writer.is_none()
            && let Some(out) = &self.target
        {
            if !matches!(line, DemoRecord::Step(_)) {
                self.pending.push(line.clone());
                return Ok(());
            }
            self.writer = Some(DemoWriter::append(out)?);
            self.target = None;
            for waiting in std::mem::take(&mut self.pending) {
                self.write(&waiting)?;
            }
        }
        self.write(line)
    }
}

/// Watch mode's episode: the environment, its number, the policy's generator and the
/// action the model takes next.
struct Watching {
    k: u64,
    env: Env,
    rng: SimRng,
    next: Option<Action>,
    shortest: Option<u32>,
}

/// Where a participant's session goes on from: what an earlier session of the same
/// recording left (a participant who returned after the server let their session go, or
/// after a restart).
#[derive(Clone, Debug)]
pub struct Resumed {
    /// The agent as the earlier sessions left it (the condition's, replayed).
    pub agent: agent::QAgent,
    /// The number the next episode gets: one past the last begun.
    pub next_episode: u64,
    /// The totals so far: episodes done, steps, corrections.
    pub progress: Progress,
}

/// One participant.
pub struct Participant {
    condition: Arc<Condition>,
    study: Arc<StudyPath>,
    /// What the last view gives a participant who finished: their code and link.
    completion: Completion,
    /// Totals of the earlier sessions of this participant's recording.
    before: Progress,
    mode: Mode,
    session: CorrectionSession<Recorder>,
    /// The shortest plan from the session episode's start.
    shortest: Option<u32>,
    watching: Option<Watching>,
    progress: Progress,
    message: String,
}

/// A message's outcome: the new view, or a line saying why nothing changed.
pub type Outcome = std::result::Result<View, String>;

impl Participant {
    /// A participant in `condition` of `study`, recording to `recorder` (its session line
    /// naming `who`, a study's participant), in the condition's first mode; going on from
    /// `resumed` when an earlier session of the recording is taken up again. `completion`
    /// is what their last view gives them once every episode is done.
    pub fn new(
        condition: Arc<Condition>,
        study: Arc<StudyPath>,
        recorder: Recorder,
        who: Option<ParticipantLine>,
        resumed: Option<Resumed>,
        completion: Completion,
    ) -> agent::Result<Participant> {
        let c = &condition;
        let (agent, first_episode, before) = match resumed {
            Some(r) => (Arc::new(r.agent), r.next_episode, r.progress),
            None => (c.agent.clone(), 0, Progress::default()),
        };
        let labels = SessionLabels {
            demonstrator: "person".into(),
            model: c.model_file.clone().filter(|_| c.agent_is_model),
            participant: who,
            timed: true,
            first_episode,
        };
        let session = CorrectionSession::labelled(
            agent,
            c.rule,
            c.world.clone(),
            c.goals.clone(),
            c.seed,
            PROPOSAL_EPSILON,
            labels,
            recorder,
        )?;
        let mode = c.modes[0];
        let mut p = Participant {
            progress: Progress {
                episodes_total: c.episodes,
                episodes_done: before.episodes_done,
                ..Progress::default()
            },
            before,
            study,
            completion,
            condition,
            mode,
            session,
            shortest: None,
            watching: None,
            message: String::new(),
        };
        p.enter(mode)?;
        Ok(p)
    }

    /// The condition.
    pub fn condition(&self) -> &Condition {
        &self.condition
    }

    /// The current mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Totals, the earlier sessions of the recording included.
    pub fn progress(&self) -> Progress {
        Progress {
            steps: self.before.steps + self.session.report().steps,
            corrections: self.before.corrections + self.session.report().corrections,
            ..self.progress.clone()
        }
    }

    /// Appends a line of the server's to the recording (a withdrawal), when the recording
    /// is on disk: a participant who never took a step has none to mark.
    pub fn record(&mut self, line: &agent::DemoRecord) -> agent::Result<()> {
        if !self.session.sink().is_on_disk() {
            return Ok(());
        }
        self.session.sink_mut().record(line)
    }

    /// What the participant is given at the end: their code and link.
    pub fn completion(&self) -> &Completion {
        &self.completion
    }

    /// Whether every episode asked for is done.
    pub fn is_done(&self) -> bool {
        self.progress.episodes_total > 0 && self.progress.episodes_done >= self.progress.episodes_total
    }

    /// Carries out `message`: the new view, or why nothing changed. An error of the
    /// session itself (a recording that cannot be written) is also returned as a line.
    pub fn handle(&mut self, message: &ClientMessage) -> Outcome {
        let id = message.id();
        match message {
            ClientMessage::Mode { mode, .. } => {
                if !self.condition.modes.contains(mode) {
                    return Err(format!("the {} mode is not offered here", mode.name()));
                }
                if *mode != self.mode {
                    self.enter(*mode).map_err(|e| e.to_string())?;
                }
            }
            ClientMessage::Act { action, t_ms, .. } => self.act(action, *t_ms)?,
            ClientMessage::Move { block, to, t_ms, .. } => self.block_move(*block, *to, *t_ms)?,
            ClientMessage::Accept { t_ms, .. } => self.accept(*t_ms)?,
            ClientMessage::Step { .. } => self.watch_step()?,
            ClientMessage::Next { .. } => match self.mode {
                Mode::Watch => self.begin_watch().map_err(|e| e.to_string())?,
                _ => {
                    self.refuse_when_done()?;
                    self.begin_session_episode().map_err(|e| e.to_string())?;
                    self.message = "Next episode.".into();
                }
            },
        }
        Ok(self.view(id))
    }

    /// Switches to `mode`: play and correct begin a fresh episode of the session (an
    /// episode belongs to one mode), watch one of its own.
    fn enter(&mut self, mode: Mode) -> agent::Result<()> {
        self.mode = mode;
        match mode {
            Mode::Watch => {
                self.begin_watch()?;
                self.message = "The agent plays: step it, or let it run at your pace.".into();
            }
            Mode::Play | Mode::Correct => {
                // A participant resumed when done still sees a world (the last thank-you).
                if !self.is_done() || self.session.observation().is_none() {
                    self.begin_session_episode()?;
                }
                self.message = match mode {
                    Mode::Play => "Solve it: click a block (or press its label), move it with the arrows, drop with d.",
                    _ => "The agent proposes: accept (Enter) or choose another action yourself.",
                }
                .into();
            }
        }
        Ok(())
    }

    fn begin_session_episode(&mut self) -> agent::Result<()> {
        let obs = self.session.next_episode()?;
        self.shortest = shortest(&self.condition.world, &obs, self.condition.solver_budget);
        Ok(())
    }

    fn begin_watch(&mut self) -> agent::Result<()> {
        let c = &self.condition;
        let model = c
            .model
            .as_ref()
            .ok_or_else(|| agent::AgentError::Config("no model to watch".into()))?;
        let k = self.watching.as_ref().map_or(0, |w| w.k + 1);
        let goals = c.watch_goals(model);
        let world = EnvConfig {
            goal: goals[(k % goals.len() as u64) as usize].clone(),
            ..c.watch_world.clone()
        };
        let seed = episode_seed(c.seed, k);
        let mut env = Env::new(world.clone())?;
        let obs = env.reset(seed);
        let mut w = Watching {
            k,
            env,
            rng: agent::rollout::policy_rng(seed),
            next: None,
            shortest: shortest(&world, &obs, c.solver_budget),
        };
        w.next = Some(model.policy(0.0)?.act(&obs, &mut w.rng)?);
        self.watching = Some(w);
        Ok(())
    }

    fn refuse_when_done(&self) -> std::result::Result<(), String> {
        if self.is_done() {
            Err("you have finished every episode of this session: thank you".into())
        } else {
            Ok(())
        }
    }

    /// The session's current observation in play or correct mode, or why not.
    fn live(&self, what: &str) -> std::result::Result<Observation, String> {
        if self.mode == Mode::Watch {
            return Err(format!("{what} is not part of watch mode: choose play or correct"));
        }
        self.refuse_when_done()?;
        match self.session.observation() {
            Some(obs) if !self.session.is_over() => Ok(obs),
            _ => Err("the episode is over: press n for the next".into()),
        }
    }

    fn act(&mut self, name: &str, t_ms: Option<u64>) -> std::result::Result<(), String> {
        let obs = self.live("an action of your own")?;
        // The parser's error names the text and what is allowed: said once.
        let action = Action::parse(name, obs.state.block_count()).map_err(|e| e.to_string())?;
        let role = match self.mode {
            Mode::Correct => PersonRole::Corrector,
            _ => PersonRole::Player,
        };
        let turn = self.session.person_at(action, role, t_ms).map_err(|e| e.to_string())?;
        self.take(turn)
    }

    /// Side view: `block` onto the top of column `to` (the block there, or the table).
    fn block_move(&mut self, block: u16, to: u16, t_ms: Option<u64>) -> std::result::Result<(), String> {
        let obs = self.live("a block move")?;
        if usize::from(block) >= obs.state.block_count() || usize::from(to) >= obs.grid.width() {
            return Err(format!(
                "block {block} onto column {to} is not a move here: the blocks are 0 to {}, the columns 0 to {}",
                obs.state.block_count() - 1,
                obs.grid.width() - 1
            ));
        }
        let block = sim::BlockId(block);
        let top = obs
            .state
            .blocks()
            .filter(|&b| b != block && obs.state.cell(b).x == to)
            .max_by_key(|&b| obs.state.cell(b).y);
        let mv = match top {
            Some(target) => BlockMove::Onto { block, target },
            None => BlockMove::ToTable { block, column: to },
        };
        let turn = self.session.person_move(mv, t_ms).map_err(|e| e.to_string())?;
        self.take(turn)
    }

    /// Shows what a person's turn did, or refuses it.
    fn take(&mut self, turn: PersonTurn) -> std::result::Result<(), String> {
        if let PersonTurn::Refused(refusal) = &turn {
            return Err(refusal.to_string());
        }
        self.message = turn.message();
        self.after_session_step();
        Ok(())
    }

    fn accept(&mut self, t_ms: Option<u64>) -> std::result::Result<(), String> {
        if self.mode != Mode::Correct {
            return Err(format!("accept is part of correct mode, not {}", self.mode.name()));
        }
        self.live("accept")?;
        let step = self.session.step_at(None, t_ms).map_err(|e| e.to_string())?;
        self.message = format!("The agent took {}.", step.action);
        self.after_session_step();
        Ok(())
    }

    fn after_session_step(&mut self) {
        if let Some(end) = self.session.episode_end() {
            self.progress.episodes_done += 1;
            self.message = end.message(self.shortest);
            if self.is_done() {
                self.message.push_str(" That was the last episode: thank you.");
            }
        }
    }

    fn watch_step(&mut self) -> std::result::Result<(), String> {
        if self.mode != Mode::Watch {
            return Err(format!("step is part of watch mode, not {}", self.mode.name()));
        }
        let over = self.watching.as_ref().is_none_or(|w| w.env.is_over());
        if over {
            self.begin_watch().map_err(|e| e.to_string())?;
            self.message = "Next episode.".into();
            return Ok(());
        }
        let model = self.condition.model.clone().expect("watch mode has a model");
        let w = self.watching.as_mut().expect("an episode under way");
        let action = w.next.expect("a state not over has a next action");
        let step = w.env.step(action).map_err(|e| e.to_string())?;
        w.next = if w.env.is_over() {
            None
        } else {
            let obs = w.env.observation();
            let mut policy = model.policy(0.0).map_err(|e| e.to_string())?;
            Some(policy.act(&obs, &mut w.rng).map_err(|e| e.to_string())?)
        };
        self.message = if step.terminated || step.truncated {
            let end = EpisodeEnd {
                reached: step.terminated,
                steps: w.env.steps(),
            };
            format!("The agent played. {}", end.message(w.shortest))
        } else {
            format!("The agent took {action}.")
        };
        Ok(())
    }

    /// What the page shows now.
    pub fn view(&self, id: Option<u64>) -> View {
        let c = &self.condition;
        let (obs, episode, steps, over, shortest, proposal, greedy) = match (self.mode, &self.watching) {
            (Mode::Watch, Some(w)) => (
                w.env.observation(),
                w.k,
                w.env.steps(),
                w.env.is_over(),
                w.shortest,
                None,
                w.next.map(|a| a.to_string()),
            ),
            _ => (
                self.session.observation().expect("the session has begun an episode"),
                self.session.episode_number().unwrap_or(0),
                self.session.steps(),
                self.session.is_over(),
                self.shortest,
                self.session
                    .proposal()
                    .filter(|_| self.mode == Mode::Correct)
                    .map(|a| a.to_string()),
                None,
            ),
        };
        let q = match self.mode {
            Mode::Watch => c.model.as_ref().and_then(|m| m.legal_q_values(&obs).ok()),
            Mode::Correct if !over => {
                let agent = self.session.agent();
                agent
                    .q_values(&obs)
                    .ok()
                    .map(|qs| obs.legal_actions().iter().map(|a| (a, qs[a.index()])).collect())
            }
            _ => None,
        };
        let q = q
            .unwrap_or_default()
            .into_iter()
            .map(|(a, q)| ActionValue {
                action: a.to_string(),
                q,
            })
            .collect();
        let outcome = over.then(|| if obs.goal.holds(&obs.state) { "goal" } else { "cut off" }.to_string());
        View {
            kind: "view".into(),
            id,
            mode: self.mode,
            modes: c.modes.clone(),
            condition: c.name.clone(),
            grid: [obs.grid.width(), obs.grid.height()],
            blocks: obs.blocks().iter().map(|cell| [cell.x, cell.y]).collect(),
            held: obs.held_block().map(|b| b.0),
            view: obs.view,
            goal: obs.goal.clone(),
            colours: obs
                .state
                .blocks()
                .map(|b| {
                    let [r, g, bl] = colour(b);
                    format!("#{r:02x}{g:02x}{bl:02x}")
                })
                .collect(),
            labels: obs.state.blocks().map(|b| label(b).to_string()).collect(),
            legal: if over {
                Vec::new()
            } else {
                obs.legal_actions().iter().map(|a| a.to_string()).collect()
            },
            episode,
            steps,
            over,
            outcome,
            shortest: shortest.filter(|_| over),
            proposal,
            greedy,
            q,
            message: self.message.clone(),
            progress: Progress {
                recorded_lines: self.session_lines(),
                ..self.progress()
            },
            done: self.is_done(),
            recording: self.session_recording(),
            // Only in the last view of a participant who finished: never before (issue 46).
            completion: self.is_done().then(|| self.completion.clone()),
            withdrawal: self.study.withdrawal.is_some() && self.session_recording(),
        }
    }

    fn session_lines(&self) -> u64 {
        self.session_sink().lines()
    }

    fn session_recording(&self) -> bool {
        self.session_sink().is_recording()
    }

    fn session_sink(&self) -> &Recorder {
        self.session.sink()
    }
}

/// The length of a shortest plan from `obs` in `world` (its view and protocol: in the side
/// view the fewest gripper steps), if the exact solver finds one within `budget` states. It
/// can take seconds on many blocks: callers run participants off the async workers.
fn shortest(world: &EnvConfig, obs: &Observation, budget: usize) -> Option<u32> {
    ExactSolver::for_world(world)
        .with_node_budget(budget)
        .distance(&obs.state, &obs.goal)
        .ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ConditionSpec;
    use sim::Profile;

    fn participant(profile: Profile) -> Participant {
        let c = Condition::prepare(&ConditionSpec {
            name: "c".into(),
            profile: Some(profile),
            goals: Some("0,1,2".into()),
            episodes: 2,
            seed: 7,
            solver_budget: 100_000,
            ..ConditionSpec::default()
        })
        .unwrap();
        Participant::new(
            Arc::new(c),
            Arc::default(),
            Recorder::new(None),
            None,
            None,
            Completion::default(),
        )
        .unwrap()
    }

    fn act(p: &mut Participant, action: &str) -> Outcome {
        p.handle(&ClientMessage::Act {
            id: None,
            action: action.into(),
            t_ms: None,
        })
    }

    #[test]
    fn under_the_paper_protocol_a_pick_while_holding_is_a_drop_and_the_pick() {
        let mut p = participant(Profile::Original);
        let refused = act(&mut p, "up").unwrap_err();
        assert!(refused.contains("only pick"), "{refused}");
        assert_eq!(p.progress().steps, 0);
        act(&mut p, "pick 1").unwrap();
        let view = act(&mut p, "pick 2").unwrap();
        assert_eq!(view.held, Some(2));
        assert_eq!((view.steps, view.progress.corrections), (3, 3));
        assert!(view.message.contains("drop, then pick 2"), "{}", view.message);
    }

    #[test]
    fn an_episode_ends_with_the_shortest_plan_and_the_limit_is_kept() {
        let mut p = participant(Profile::Spec);
        for _ in 0..2 {
            let obs = p.session.observation().unwrap();
            let plan = ExactSolver::new(obs.grid).solve(&obs.state, &obs.goal).unwrap();
            let mut view = None;
            for a in &plan.actions {
                view = Some(act(&mut p, &a.to_string()).unwrap());
            }
            let view = view.unwrap();
            assert_eq!(view.shortest, Some(plan.len() as u32));
            assert_eq!(view.outcome.as_deref(), Some("goal"));
            if !p.is_done() {
                p.handle(&ClientMessage::Next { id: None }).unwrap();
            }
        }
        assert!(p.is_done());
        assert!(
            p.handle(&ClientMessage::Next { id: None })
                .unwrap_err()
                .contains("finished")
        );
        // Watch and correct need a model: not offered.
        let mode = ClientMessage::Mode {
            id: None,
            mode: Mode::Correct,
        };
        assert!(p.handle(&mode).unwrap_err().contains("not offered"));
    }
}
