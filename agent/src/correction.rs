//! Learning from a demonstrator's corrections (paper section VI-C), and the session loop that
//! people (`blockstack demo`) and simulated demonstrators (`blockstack correct`) share.
//!
//! # The learning rule
//!
//! A demonstrator watches the agent play and may replace the action the agent proposes with
//! its own, `a_E`. Each executed step `(s, a, r, s')` is learnt from as follows:
//!
//! 1. **Q-update.** The ordinary Q-learning update of [`QAgent::update`] with the executed
//!    action: `Q(s,a) <- (1 - alpha) Q(s,a) + alpha (r + gamma max_a' Q(s',a'))`. For a
//!    correction `a = a_E`, the demonstrator's action. The agent's own steps are learnt from
//!    too when [`CorrectionRule::learn_agent_steps`] is set (the default: the paper's table
//!    "is updated during the demonstrations").
//! 2. **Large margin** (corrections only, when the rule has a margin), in the spirit of
//!    DQfD (Hester et al. 2018), whose loss `max_a [Q(s,a) + l(a_E,a)] - Q(s,a_E)` is zero
//!    exactly when the demonstrator's action beats every other by the margin `l`. A table
//!    can meet that directly: after the update, `Q(s,a_E) <- max(Q(s,a_E), max_{a != a_E}
//!    Q(s,a) + margin)`. Only `Q(s,a_E)` moves, and only upward, so the greedy action in `s`
//!    becomes `a_E` and stays so until later learning says otherwise. The margin is
//!    [`CorrectionRule::margin`] (default [`DEFAULT_MARGIN`], 0.8; 0 only breaks ties in
//!    `a_E`'s favour).
//!
//! The Q-update is the agent's own ([`QAgent::update`]): an agent trained under the
//! `paper-code` schedule updates as the authors' code did.
//!
//! # As the authors coded it (the `original` profile)
//!
//! In the authors' code (docs/world.md section 10, "Demonstrations"; their
//! `Demonstrations/Demonstrations.py:102-287`) the person's action simply replaces the
//! agent's and gets the ordinary update, the same as the agent's own steps: no margin
//! ([`CorrectionRule::as_coded`]), and the update of the `paper-code` schedule at the
//! agent's alpha (1; their demonstrations lower it at no step). A demonstration runs until a
//! step's reward is above 70 or for 5000 steps ([`session_world`] of a `paper-code` agent),
//! on one goal, with the agent proposing at epsilon 0.1; what the agent learns carries over
//! from one demonstration to the next. Their goals were `[0,1,2] [2,1,0] [1,2,0] [1,0,2]`
//! ([`DEMONSTRATED_GOALS`]).
//!
//! Their people paused the agent, clicked a block and moved it with the arrows: a click
//! picked that block even while another was held. The `paper` protocol lets no one pick
//! while holding, so [`person_steps`] carries such a click out as the protocol's way of
//! changing blocks: a Drop, then the Pick, two corrections. A move or Drop with nothing held
//! is refused (their people had no Drop key and moved only a block they had clicked). The
//! simulated demonstrators keep to the protocol by themselves.
//!
//! With the paper's `chasing` representation many world states share one table row, so a
//! correction in one state changes the agent's choice in every state that looks the same to
//! it, on other goals too (Tables III and IV measure that).
//!
//! # Sessions
//!
//! [`CorrectionSession`] plays episodes of an agent, proposes the agent's action for each
//! state, executes it or a correction, learns by the rule above, and records every step to a
//! [`DemoSink`] (a JSON Lines file: [`crate::demos`]). [`correct`] runs a session with a
//! simulated [`Demonstrator`] headless, fixed by a seed.

use serde::{Deserialize, Serialize};
use sim::seeding::{SimRng, episode_seed};
use sim::{Action, BlockMove, Env, EnvConfig, Goal, GoalSpec, Grid, Observation, Profile, RewardModel, Termination};

use crate::demonstrator::{Demonstrator, DemonstratorProfile};
use crate::demos::{DemoRecord, DemoSink, EpisodeLine, ParticipantLine, SessionLine, StepLine};
use crate::error::{AgentError, Result};
use crate::qlearning::{QAgent, check_epsilon};
use crate::rollout::policy_rng;
pub use crate::rule::{CorrectionRule, DEFAULT_MARGIN, Experience};
use crate::schedule::Schedule;

/// The goals the authors' people demonstrated on (docs/world.md section 10, "Demonstrations"); the
/// other two, `0,2,1` and `2,0,1`, were never demonstrated.
pub const DEMONSTRATED_GOALS: [&str; 4] = ["0,1,2", "2,1,0", "1,2,0", "1,0,2"];

/// The authors' demonstrated goals ([`DEMONSTRATED_GOALS`]).
pub fn demonstrated_goals() -> Vec<Goal> {
    DEMONSTRATED_GOALS
        .iter()
        .map(|g| g.parse().expect("a goal of three blocks"))
        .collect()
}

impl CorrectionRule {
    /// An error unless the margin, if any, is at least 0 and fits the table's floats
    /// ([`crate::qlearning::check_fits_table`]).
    pub fn validate(&self) -> Result<()> {
        match self.margin {
            None => Ok(()),
            Some(m) if m >= 0.0 => crate::qlearning::check_fits_table("the margin", m),
            Some(m) => Err(AgentError::Config(format!(
                "the margin {m} is not a finite number at least 0"
            ))),
        }
    }

    /// Learns from one executed step; returns the new Q(obs, action).
    pub fn learn(&self, agent: &mut QAgent, step: &Experience) -> Result<f32> {
        let Experience {
            obs,
            action,
            reward,
            next,
            terminated,
            corrected,
            ..
        } = step.clone();
        if corrected || self.learn_agent_steps {
            agent.update(&obs, action, reward, &next, terminated)?;
        }
        match self.margin {
            Some(margin) if corrected => raise_to_margin(agent, &obs, action, margin),
            _ => agent.q(&obs, action),
        }
    }
}

/// The large-margin step: raises `Q(obs, action)` to at least `max_{a != action} Q(obs, a) +
/// margin` (computed in f64, stored as f32) and returns it. Other entries are untouched.
pub fn raise_to_margin(agent: &mut QAgent, obs: &Observation, action: Action, margin: f64) -> Result<f32> {
    let key = agent.key(obs)?;
    let column = agent.column(&obs.goal, action)?;
    let row = agent.table_mut().row_mut(key);
    let best_other = row
        .iter()
        .enumerate()
        .filter(|&(c, _)| c != column)
        .map(|(_, &v)| v)
        .fold(f32::NEG_INFINITY, f32::max);
    let floor = (f64::from(best_other) + margin) as f32;
    if row[column] < floor {
        row[column] = floor;
    }
    Ok(row[column])
}

/// The world a session of `agent` plays in: the one it was trained in (its grid, block
/// count, reward, backend, protocol and start rule), or the paper's reward and physics in
/// our world for an agent that does not say. An agent of the `spec` schedule plays
/// episodes of 1000 steps that end at the goal; one of `paper-code` plays the authors'
/// demonstrations: up to 5000 steps (1000 with two blocks), ended by a reward above 70.
/// Each episode fixes its own goal.
pub fn session_world(agent: &QAgent) -> EnvConfig {
    let schedule = agent.schedule();
    let (horizon, termination) = match schedule {
        Schedule::Spec => (sim::DEFAULT_HORIZON, Termination::Goal),
        Schedule::PaperCode => (schedule.game_steps(agent.blocks()), schedule.training_termination()),
    };
    let trained = match agent.training() {
        Some(t) => t.world.clone(),
        None => EnvConfig {
            reward: RewardModel::from_name("paper").expect("a known model"),
            ..EnvConfig::default()
        },
    };
    EnvConfig {
        grid: agent.grid(),
        blocks: agent.blocks(),
        goal: GoalSpec::Random,
        horizon,
        termination,
        ..trained
    }
}

/// The world of a session of `agent` under `profile` ([`session_world`], then the
/// profile's protocol, start rule and learner's reward), and the profile whose correction
/// rule applies: `profile`, else the one the agent was trained under. What `blockstack
/// demo --profile` and `blockstack serve --profile` play.
pub fn session_world_under(agent: &QAgent, profile: Option<Profile>) -> (EnvConfig, Profile) {
    let mut world = session_world(agent);
    if let Some(p) = profile {
        // The profile's rules (`ProfileParts::apply`, their one application), with the
        // reward its learner learns from.
        let parts = sim::ProfileParts {
            reward: crate::LearnerProfile::of(p).reward,
            ..sim::ProfileParts::of(p)
        };
        world = parts.apply(world);
    }
    let trained_under = agent.training().map_or(Profile::Spec, |t| t.profile);
    (world, profile.unwrap_or(trained_under))
}

/// The goals a session in `world` plays when none are given: every goal of its world
/// ([`Goal::all_in`]: of towers in the side view), or under the `original` profile with 3
/// blocks from above the authors' four ([`DEMONSTRATED_GOALS`]).
pub fn default_goals(world: &EnvConfig, profile: Profile) -> Result<Vec<Goal>> {
    match profile {
        Profile::Original if world.blocks == 3 && world.view == sim::View::Top => Ok(demonstrated_goals()),
        _ => Ok(Goal::all_in(world.view, world.blocks)?),
    }
}

/// A person's command as the steps the session's protocol allows (module docs): the
/// action itself when it is legal in `obs`; in the top view under a protocol that forbids
/// picking while holding, a pick of another block becomes a Drop and then the Pick, and a
/// pick of the block held changes nothing (no step). Any other action outside the legal
/// ones is the view's error, which names what is allowed (in the side view, whatever the
/// protocol: a dropped block falls, so a pick while holding is refused, not carried out).
pub fn person_steps(obs: &Observation, action: Action) -> Result<Vec<Action>> {
    let legal = obs.legal_actions();
    if legal.contains(action) {
        return Ok(vec![action]);
    }
    match (action, obs.held_block()) {
        (Action::Pick(b), Some(h))
            if obs.view == sim::View::Top && b.index() < obs.state.block_count() && legal.contains(Action::Drop) =>
        {
            Ok(if b == h { Vec::new() } else { vec![Action::Drop, action] })
        }
        // The view's rules name what is wrong (the side view's, whatever the protocol).
        _ => match obs.view.check(obs.protocol, &obs.state, action) {
            Err(e) => Err(e.into()),
            // Outside the mask but taken as it is: under `free` in the side view the rules
            // make it change nothing, as `Env::step` does.
            Ok(()) => Ok(vec![action]),
        },
    }
}

/// Who the person is in a turn: correcting the agent (its proposal was shown) or playing
/// alone (the agent's proposal was not shown, so choosing is not overriding it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PersonRole {
    /// The agent's proposal was shown: a choice confirms or overrides it.
    Corrector,
    /// The person plays every step; the proposal was not shown.
    Player,
}

/// Why a person's command was not carried out; nothing changed.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Refusal {
    /// No episode is under way: the next one must begin first.
    #[error("the episode is over: n begins the next")]
    EpisodeOver,
    /// The world's rules forbid the command now (the message names what is allowed).
    #[error("not now: {0}")]
    NotAllowed(String),
}

/// What a person's command did in a session ([`CorrectionSession::person`]): the one turn
/// the terminal UI and the page both draw.
#[derive(Clone, Debug, PartialEq)]
pub enum PersonTurn {
    /// Nothing was done, and why.
    Refused(Refusal),
    /// A pick of the block already held: nothing to do.
    AlreadyHeld(Action),
    /// A block move (side view), carried out as the gripper actions that make it, each a
    /// correction.
    Moved {
        /// The move asked for.
        mv: BlockMove,
        /// The steps executed, in order.
        steps: Vec<SessionStep>,
    },
    /// The steps carried out for the command (a Drop and the Pick for a pick while holding
    /// under the `paper` protocol), each a correction.
    Taken {
        /// What the person asked for.
        command: Action,
        /// The agent's proposal the person saw, if any ([`PersonRole::Corrector`]).
        proposed: Option<Action>,
        /// The steps executed, in order.
        steps: Vec<SessionStep>,
    },
}

impl PersonTurn {
    /// One line saying what happened, for the person.
    pub fn message(&self) -> String {
        match self {
            PersonTurn::Refused(r) => capitalised(&format!("{r}.")),
            PersonTurn::AlreadyHeld(action) => format!("{action}: that block is held already."),
            PersonTurn::Moved { mv, steps } => {
                format!("{}: {} gripper steps.", capitalised(&mv.to_string()), steps.len())
            }
            PersonTurn::Taken {
                command,
                proposed,
                steps,
            } => {
                let done = steps
                    .iter()
                    .map(|s| s.action.to_string())
                    .collect::<Vec<_>>()
                    .join(", then ");
                let actions: Vec<Action> = steps.iter().map(|s| s.action).collect();
                match proposed {
                    Some(p) if actions == [*p] => format!("You confirmed {command}; the agent learnt it."),
                    Some(p) => format!("You chose {done} instead of {p}; the agent learnt it."),
                    None => format!("You chose {done}."),
                }
            }
        }
    }

    /// The corrections the turn made (steps the person chose).
    pub fn corrections(&self) -> u64 {
        self.steps().iter().filter(|s| s.corrected).count() as u64
    }

    /// The steps the turn executed (none when it was refused or changed nothing).
    pub fn steps(&self) -> &[SessionStep] {
        match self {
            PersonTurn::Taken { steps, .. } | PersonTurn::Moved { steps, .. } => steps,
            _ => &[],
        }
    }
}

fn capitalised(text: &str) -> String {
    let mut chars = text.chars();
    chars
        .next()
        .map_or(String::new(), |c| c.to_uppercase().chain(chars).collect())
}

/// How an episode of a session ended ([`CorrectionSession::episode_end`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EpisodeEnd {
    /// It ended by its termination rule (the goal reached); otherwise it was cut off at
    /// the horizon.
    pub reached: bool,
    /// Steps taken in it.
    pub steps: u32,
}

impl EpisodeEnd {
    /// One line saying how the episode ended, with the length of a shortest plan from its
    /// start when known.
    pub fn message(&self, shortest: Option<u32>) -> String {
        let steps = self.steps;
        let shortest = shortest.map_or(String::new(), |s| format!("; the shortest plan takes {s}"));
        if self.reached {
            format!("Goal reached in {steps} steps{shortest}.")
        } else {
            format!("Cut off after {steps} steps{shortest}.")
        }
    }
}

/// What one step of a session did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SessionStep {
    /// The agent's proposal.
    pub proposed: Action,
    /// The action executed.
    pub action: Action,
    /// Whether a demonstrator chose `action`.
    pub corrected: bool,
    /// The reward.
    pub reward: f64,
    /// The goal holds after the step.
    pub terminated: bool,
    /// The horizon was reached without the goal.
    pub truncated: bool,
}

/// Totals of a session.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SessionReport {
    /// Episodes begun.
    pub episodes: u64,
    /// Of those, episodes that reached the goal.
    pub successes: u64,
    /// Steps executed.
    pub steps: u64,
    /// Of those, steps a demonstrator chose.
    pub corrections: u64,
}

/// An agent playing episodes under a demonstrator's eye, learning as it goes (module docs).
///
/// Episode `k` of a session with seed `seed` plays `goals[k % goals.len()]` from the start
/// `reset(episode_seed(seed, k))`, and the agent draws its proposals from
/// [`policy_rng`]`(episode_seed(seed, k))` with probability `epsilon` of a random action.
/// Every line is handed to the sink as it happens.
pub struct CorrectionSession<S: DemoSink> {
    /// Shared with whoever gave it (a server's many participants start from one model)
    /// until the session's first lesson copies it.
    agent: std::sync::Arc<QAgent>,
    rule: CorrectionRule,
    world: EnvConfig,
    goals: Vec<Goal>,
    seed: u64,
    epsilon: f64,
    sink: S,
    report: SessionReport,
    /// The current episode: its number, environment and the agent's generator.
    episode: Option<(u64, Env, SimRng)>,
    /// The agent's proposal for the current state, drawn once per state.
    proposal: Option<Action>,
    /// The current episode's last step.
    last: Option<SessionStep>,
    /// Whether the session keeps time ([`SessionLabels::timed`]).
    timed: bool,
    /// The first episode's number.
    first_episode: u64,
    /// In a timed session, when the current episode's first view was shown.
    shown: Option<std::time::Instant>,
    /// The time recorded for the episode's last step.
    last_ms: Option<u64>,
}

/// What a session's header line says about who corrects, from which model, and, in a
/// study, whose session it is.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SessionLabels {
    /// Who corrects: `person`, or a simulated demonstrator's name.
    pub demonstrator: String,
    /// The model file the agent came from, when known.
    pub model: Option<String>,
    /// The study participant, when the session is one's.
    pub participant: Option<ParticipantLine>,
    /// Whether the session keeps time (a person's): each episode's wall-clock start and
    /// each step's time since the episode's first view are recorded. A simulated
    /// demonstrator's session is not timed, so its recording is fixed by its seed.
    pub timed: bool,
    /// The number of the first episode: 0, or past the episodes of an earlier session of
    /// the same recording that this one goes on from (a participant resumed).
    pub first_episode: u64,
}

impl<S: DemoSink> CorrectionSession<S> {
    /// A session of `agent` on `goals`; writes the session header to `sink`. `demonstrator`
    /// and `model` are recorded as given (who corrects, which model file).
    #[allow(clippy::too_many_arguments, reason = "each is one documented setting of the session")]
    pub fn new(
        agent: impl Into<std::sync::Arc<QAgent>>,
        rule: CorrectionRule,
        world: EnvConfig,
        goals: Vec<Goal>,
        seed: u64,
        epsilon: f64,
        demonstrator: &str,
        model: Option<&str>,
        sink: S,
    ) -> Result<Self> {
        let labels = SessionLabels {
            demonstrator: demonstrator.into(),
            model: model.map(Into::into),
            participant: None,
            timed: false,
            first_episode: 0,
        };
        Self::labelled(agent, rule, world, goals, seed, epsilon, labels, sink)
    }

    /// [`CorrectionSession::new`] with the header's `labels` (a study's participant among
    /// them).
    #[allow(clippy::too_many_arguments, reason = "each is one documented setting of the session")]
    pub fn labelled(
        agent: impl Into<std::sync::Arc<QAgent>>,
        rule: CorrectionRule,
        world: EnvConfig,
        goals: Vec<Goal>,
        seed: u64,
        epsilon: f64,
        labels: SessionLabels,
        mut sink: S,
    ) -> Result<Self> {
        let agent = agent.into();
        rule.validate()?;
        check_epsilon(epsilon)?;
        if goals.is_empty() {
            return Err(AgentError::Config("no goals to demonstrate on".into()));
        }
        for goal in &goals {
            env_config(&agent, &world, goal.clone()).validate()?;
        }
        let mut header = SessionLine::new(
            agent.grid(),
            agent.blocks(),
            agent.identity(),
            rule,
            &labels.demonstrator,
            labels.model.as_deref(),
        );
        header.view = world.view;
        header.participant = labels.participant;
        header.first_episode = labels.first_episode;
        header.world = Some(crate::demos::WorldLine::of(&world));
        sink.record(&DemoRecord::Session(header))?;
        Ok(CorrectionSession {
            agent,
            rule,
            world,
            goals,
            seed,
            epsilon,
            sink,
            report: SessionReport::default(),
            episode: None,
            proposal: None,
            last: None,
            timed: labels.timed,
            first_episode: labels.first_episode,
            shown: None,
            last_ms: None,
        })
    }

    /// The agent as corrected so far.
    pub fn agent(&self) -> &QAgent {
        &self.agent
    }

    /// The rule.
    pub fn rule(&self) -> &CorrectionRule {
        &self.rule
    }

    /// The goals, played in turn.
    pub fn goals(&self) -> &[Goal] {
        &self.goals
    }

    /// Totals so far.
    pub fn report(&self) -> &SessionReport {
        &self.report
    }

    /// The number of the current episode (from 0), if one has begun.
    pub fn episode_number(&self) -> Option<u64> {
        self.episode.as_ref().map(|(k, _, _)| *k)
    }

    /// The current observation, if an episode has begun.
    pub fn observation(&self) -> Option<Observation> {
        self.episode.as_ref().map(|(_, env, _)| env.observation())
    }

    /// Steps taken in the current episode.
    pub fn steps(&self) -> u32 {
        self.episode.as_ref().map_or(0, |(_, env, _)| env.steps())
    }

    /// Whether no episode is under way (none begun, or the current one ended).
    pub fn is_over(&self) -> bool {
        self.episode.as_ref().is_none_or(|(_, env, _)| env.is_over())
    }

    /// The sink the session records to (e.g. to count the lines written so far).
    pub fn sink(&self) -> &S {
        &self.sink
    }

    /// The agent's proposal for the current state (`None` when no episode is under way).
    pub fn proposal(&self) -> Option<Action> {
        self.proposal
    }

    /// Begins the next episode (abandoning the current one, if any) and returns its first
    /// observation.
    pub fn next_episode(&mut self) -> Result<Observation> {
        let k = self.episode.as_ref().map_or(self.first_episode, |(k, _, _)| k + 1);
        let goal = self.goals[(k % self.goals.len() as u64) as usize].clone();
        let seed = episode_seed(self.seed, k);
        let mut env = Env::new(env_config(&self.agent, &self.world, goal))?;
        let obs = env.reset(seed);
        let mut line = EpisodeLine::new(k, seed, &obs);
        if self.timed {
            self.shown = Some(std::time::Instant::now());
            line.started_ms = Some(crate::demos::unix_ms());
        }
        self.sink.record(&DemoRecord::Episode(line))?;
        self.episode = Some((k, env, policy_rng(seed)));
        self.last = None;
        self.last_ms = None;
        self.report.episodes += 1;
        self.propose()?;
        Ok(obs)
    }

    /// Draws the agent's proposal for the current state.
    fn propose(&mut self) -> Result<()> {
        self.proposal = match &mut self.episode {
            Some((_, env, rng)) if !env.is_over() => {
                Some(self.agent.choose_action(&env.observation(), self.epsilon, rng)?)
            }
            _ => None,
        };
        Ok(())
    }

    /// Executes one step: the demonstrator's `correction` if given, the agent's proposal
    /// otherwise; learns from it and records it. An error if no episode is under way.
    pub fn step(&mut self, correction: Option<Action>) -> Result<SessionStep> {
        self.step_at(correction, None)
    }

    /// [`CorrectionSession::step`], in a timed session at `page_ms` milliseconds since the
    /// episode's first view by the clock of the page that showed it (none: the session's
    /// own clock). A page's time earlier than the episode's last step's, or later than the
    /// session's own clock allows, is not believed: the session's clock is recorded.
    pub fn step_at(&mut self, correction: Option<Action>, page_ms: Option<u64>) -> Result<SessionStep> {
        let time = self.step_time(page_ms);
        let (Some((k, env, _)), Some(proposed)) = (&mut self.episode, self.proposal) else {
            return Err(AgentError::Config(
                "no episode is under way: begin the next one first".into(),
            ));
        };
        let obs = env.observation();
        let action = correction.unwrap_or(proposed);
        let step = env.step(action)?;
        let corrected = correction.is_some();
        self.rule.learn(
            std::sync::Arc::make_mut(&mut self.agent),
            &Experience {
                obs: obs.clone(),
                action,
                reward: step.reward,
                next: step.observation.clone(),
                terminated: step.terminated,
                truncated: step.truncated,
                corrected,
            },
        )?;
        let mut line = StepLine::new(*k, &obs, proposed, action, corrected, &step);
        (line.t_ms, line.received_ms) = time;
        self.last_ms = line.t_ms;
        self.sink.record(&DemoRecord::Step(line))?;
        self.report.steps += 1;
        self.report.corrections += u64::from(corrected);
        self.report.successes += u64::from(step.terminated);
        self.propose()?;
        let step = SessionStep {
            proposed,
            action,
            corrected,
            reward: step.reward,
            terminated: step.terminated,
            truncated: step.truncated,
        };
        self.last = Some(step);
        Ok(step)
    }

    /// The time recorded with a step taken now: milliseconds since the episode's first
    /// view, and the wall-clock time; none in an untimed session.
    fn step_time(&self, page_ms: Option<u64>) -> (Option<u64>, Option<u64>) {
        let Some(shown) = self.shown.filter(|_| self.timed) else {
            return (None, None);
        };
        let own = shown.elapsed().as_millis() as u64;
        let floor = self.last_ms.unwrap_or(0);
        // The page's clock is finer for a reaction time (no network in it), but only a time
        // between the last step's and the session's own clock can be the page's.
        let t = page_ms.filter(|&p| p >= floor && p <= own).unwrap_or(own.max(floor));
        (Some(t), Some(crate::demos::unix_ms()))
    }

    /// The sink the session records to, to add a line of the caller's (a withdrawal).
    pub fn sink_mut(&mut self) -> &mut S {
        &mut self.sink
    }

    /// The current episode's last step, if it has taken one.
    pub fn last_step(&self) -> Option<&SessionStep> {
        self.last.as_ref()
    }

    /// How the current episode ended, once it has ([`EpisodeEnd`]).
    pub fn episode_end(&self) -> Option<EpisodeEnd> {
        self.last.filter(|s| s.terminated || s.truncated).map(|s| EpisodeEnd {
            reached: s.terminated,
            steps: self.steps(),
        })
    }

    /// Carries out a person's `command` (module docs: under the `paper` protocol a pick
    /// while holding is a Drop and then the Pick; a pick of the held block does nothing):
    /// every step a correction, learnt and recorded. A command the rules refuse, or one
    /// given when no episode is under way, is [`PersonTurn::Refused`] and changes nothing.
    /// An error only from the session itself (a recording that cannot be written).
    pub fn person(&mut self, command: Action, role: PersonRole) -> Result<PersonTurn> {
        self.person_at(command, role, None)
    }

    /// [`CorrectionSession::person`] at `page_ms` by the page's clock
    /// ([`CorrectionSession::step_at`]).
    pub fn person_at(&mut self, command: Action, role: PersonRole, page_ms: Option<u64>) -> Result<PersonTurn> {
        let obs = match self.observation() {
            Some(obs) if !self.is_over() => obs,
            _ => return Ok(PersonTurn::Refused(Refusal::EpisodeOver)),
        };
        let steps = match person_steps(&obs, command) {
            Err(e) => return Ok(PersonTurn::Refused(Refusal::NotAllowed(e.to_string()))),
            Ok(steps) if steps.is_empty() => return Ok(PersonTurn::AlreadyHeld(command)),
            Ok(steps) => steps,
        };
        let proposed = self.proposal.filter(|_| role == PersonRole::Corrector);
        let mut taken = Vec::with_capacity(steps.len());
        for action in steps {
            if self.is_over() {
                break;
            }
            taken.push(self.step_at(Some(action), page_ms)?);
        }
        Ok(PersonTurn::Taken {
            command,
            proposed,
            steps: taken,
        })
    }

    /// Carries out a person's block move `mv` (side view: the gripper actions
    /// [`sim::block_move::expand`] gives, each a correction, learnt and recorded), at
    /// `page_ms` by the page's clock. A move the rules refuse now, or one given when no
    /// episode is under way, is [`PersonTurn::Refused`] and changes nothing.
    pub fn person_move(&mut self, mv: BlockMove, page_ms: Option<u64>) -> Result<PersonTurn> {
        let obs = match self.observation() {
            Some(obs) if !self.is_over() => obs,
            _ => return Ok(PersonTurn::Refused(Refusal::EpisodeOver)),
        };
        if obs.view != sim::View::Side {
            return Ok(PersonTurn::Refused(Refusal::NotAllowed(
                "block moves are the side view's; pick, move and drop here".into(),
            )));
        }
        let actions = match sim::block_move::expand(&obs.state, obs.grid, mv) {
            Ok(actions) => actions,
            Err(e) => return Ok(PersonTurn::Refused(Refusal::NotAllowed(e.to_string()))),
        };
        let mut steps = Vec::with_capacity(actions.len());
        for action in actions {
            if self.is_over() {
                break;
            }
            steps.push(self.step_at(Some(action), page_ms)?);
        }
        Ok(PersonTurn::Moved { mv, steps })
    }

    /// Ends the session: the corrected agent, the sink, and the totals.
    pub fn finish(self) -> (QAgent, S, SessionReport) {
        (std::sync::Arc::unwrap_or_clone(self.agent), self.sink, self.report)
    }
}

/// The environment of an episode on `goal`: the session's world, on the agent's grid and
/// block count.
fn env_config(agent: &QAgent, world: &EnvConfig, goal: Goal) -> EnvConfig {
    EnvConfig {
        grid: agent.grid(),
        blocks: agent.blocks(),
        goal: GoalSpec::Fixed(goal),
        ..*world
    }
}

/// Everything that defines a headless correction run by a simulated demonstrator.
#[derive(Clone, Debug, PartialEq)]
pub struct CorrectionConfig {
    /// Who corrects.
    pub demonstrator: DemonstratorProfile,
    /// The goals demonstrated on, in turn (the paper: 4 of the 6).
    pub goals: Vec<Goal>,
    /// Demonstrations (episodes) to give (the paper: 10 per demonstrator).
    pub demos: u64,
    /// The seed of the starts, the agent's proposals and the demonstrator's choices.
    pub seed: u64,
    /// How the agent learns (`None`: the rule of the profile the agent was trained under,
    /// [`CorrectionRule::for_profile`]).
    pub rule: Option<CorrectionRule>,
    /// The agent's probability of a random proposal (the paper's test policy: 0.1).
    pub epsilon: f64,
    /// The world's reward, horizon and backend (`None`: [`session_world`] of the agent).
    pub world: Option<EnvConfig>,
    /// The model file the agent came from, for the recording's session line.
    pub model: Option<String>,
}

impl CorrectionConfig {
    /// `demos` demonstrations by `demonstrator` on `goals`, seed `seed`, the rule of the
    /// agent's profile, proposals with epsilon 0.1, in the agent's own world.
    pub fn new(demonstrator: DemonstratorProfile, goals: Vec<Goal>, demos: u64, seed: u64) -> Self {
        CorrectionConfig {
            demonstrator,
            goals,
            demos,
            seed,
            rule: None,
            epsilon: 0.1,
            world: None,
            model: None,
        }
    }
}

/// The outcome of [`correct`].
#[derive(Clone, Debug)]
pub struct Corrected<S> {
    /// The corrected agent.
    pub agent: QAgent,
    /// Totals of the session.
    pub report: SessionReport,
    /// The sink the session was recorded to, e.g. a `Vec<DemoRecord>` holding every line.
    pub sink: S,
}

/// Lets a simulated demonstrator correct `agent` for `config.demos` episodes and returns the
/// corrected agent; every line goes to `sink` (`()` records nothing, a `Vec<DemoRecord>`
/// keeps them, a [`DemoWriter`](crate::demos::DemoWriter) writes a file). Fixed by
/// `config.seed`: the same inputs give the same table, bit for bit. Prints nothing, and
/// runs on the caller's thread, so many can run at once.
pub fn correct<S: DemoSink>(agent: QAgent, config: &CorrectionConfig, sink: S) -> Result<Corrected<S>> {
    config.demonstrator.validate()?;
    let world = config.world.clone().unwrap_or_else(|| session_world(&agent));
    if world.view != sim::View::Top {
        return Err(AgentError::Config(
            "the simulated demonstrators plan the top view; correct a side-view agent in person (blockstack demo)"
                .into(),
        ));
    }
    let rule = config
        .rule
        .unwrap_or_else(|| CorrectionRule::for_profile(agent.training().map_or(Profile::Spec, |t| t.profile)));
    let grid: Grid = agent.grid();
    let mut session = CorrectionSession::new(
        agent,
        rule,
        world,
        config.goals.clone(),
        config.seed,
        config.epsilon,
        &config.demonstrator.name,
        config.model.as_deref(),
        sink,
    )?;
    let mut demonstrator = Demonstrator::new(config.demonstrator.clone(), grid);
    for _ in 0..config.demos {
        let obs = session.next_episode()?;
        let k = session.episode_number().expect("an episode has begun");
        demonstrator.begin_episode(&obs, episode_seed(config.seed, k));
        while !session.is_over() {
            let obs = session.observation().expect("an episode is under way");
            let proposed = session.proposal().expect("an episode is under way");
            let correction = demonstrator.review(&obs, proposed)?;
            session.step(correction)?;
        }
    }
    let (agent, sink, report) = session.finish();
    Ok(Corrected { agent, report, sink })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qlearning::QParams;
    use crate::repr::ReprKind;
    use proptest::prelude::*;
    use sim::BlockId;

    fn agent() -> QAgent {
        QAgent::new(ReprKind::Chasing, Grid::default(), 3, QParams::default()).unwrap()
    }

    fn obs() -> Observation {
        let goal: Goal = "0,1,2".parse().unwrap();
        let mut env = Env::new(EnvConfig::with_goal(goal)).unwrap();
        env.reset(4)
    }

    #[test]
    fn the_margin_puts_the_demonstrators_action_on_top_by_the_margin() {
        let mut a = agent();
        let o = obs();
        a.set_q(&o, Action::Up, 3.0).unwrap();
        a.set_q(&o, Action::Drop, 7.5).unwrap();
        a.set_q(&o, Action::Left, -2.0).unwrap();
        let before = a.q_values(&o).unwrap();
        let q = raise_to_margin(&mut a, &o, Action::Left, 0.8).unwrap();
        assert_eq!(q, 8.3);
        let after = a.q_values(&o).unwrap();
        for (i, (x, y)) in before.iter().zip(&after).enumerate() {
            if i != Action::Left.index() {
                assert_eq!(x, y, "only Q(s, a_E) moves");
            }
        }
        let mut rng = sim::seeding::rng(0);
        assert_eq!(a.greedy_action(&o, &mut rng).unwrap(), Action::Left);
    }

    #[test]
    fn the_margin_never_lowers_a_value_already_ahead() {
        let mut a = agent();
        let o = obs();
        a.set_q(&o, Action::Pick(BlockId(2)), 20.0).unwrap();
        a.set_q(&o, Action::Up, 1.0).unwrap();
        assert_eq!(
            raise_to_margin(&mut a, &o, Action::Pick(BlockId(2)), 0.8).unwrap(),
            20.0
        );
        // A zero margin only breaks the tie with the best other action.
        a.set_q(&o, Action::Down, 1.0).unwrap();
        assert_eq!(raise_to_margin(&mut a, &o, Action::Down, 0.0).unwrap(), 20.0);
    }

    #[test]
    fn a_correction_gets_the_q_update_then_the_margin() {
        let goal: Goal = "0,1,2".parse().unwrap();
        let mut env = Env::new(EnvConfig {
            reward: RewardModel::from_name("paper").unwrap(),
            ..EnvConfig::with_goal(goal)
        })
        .unwrap();
        let o = env.reset(4);
        let step = env.step(Action::Pick(BlockId(0))).unwrap();
        let rule = CorrectionRule::default();
        // Uncorrected with learn_agent_steps off: nothing changes.
        let mut a = agent();
        let quiet = CorrectionRule {
            learn_agent_steps: false,
            ..rule
        };
        let pick = Experience {
            obs: o.clone(),
            action: Action::Pick(BlockId(0)),
            reward: 5.0,
            next: step.observation,
            terminated: false,
            truncated: false,
            corrected: false,
        };
        quiet.learn(&mut a, &pick).unwrap();
        assert_eq!(a, agent());
        // A correction: the update gives r + gamma * 0 = 5, above every other (0) by more
        // than the margin, so the margin changes nothing.
        let q = rule
            .learn(
                &mut a,
                &Experience {
                    corrected: true,
                    ..pick
                },
            )
            .unwrap();
        assert_eq!(q, 5.0);
        // A correction whose update leaves it behind: raised to best other + margin.
        a.set_q(&o, Action::Up, 9.0).unwrap();
        let drop = Experience {
            obs: o.clone(),
            action: Action::Drop,
            reward: -1.0,
            next: o,
            terminated: false,
            truncated: false,
            corrected: true,
        };
        let q = rule.learn(&mut a, &drop).unwrap();
        assert_eq!(q, (9.0f64 + 0.8) as f32);
    }

    #[test]
    fn a_profile_given_replaces_the_world_rules_and_the_rule_of_the_session() {
        let a = agent();
        let (world, profile) = session_world_under(&a, None);
        assert_eq!((world, profile), (session_world(&a), Profile::Spec));
        let (world, profile) = session_world_under(&a, Some(Profile::Original));
        assert_eq!(profile, Profile::Original);
        assert_eq!(world.protocol, sim::ActionProtocol::Paper);
        assert_eq!(world.start, Profile::Original.start_rule());
        assert_eq!(
            world.horizon,
            session_world(&a).horizon,
            "the agent's schedule keeps its horizon"
        );
        let world = |blocks, view| EnvConfig {
            blocks,
            view,
            ..EnvConfig::default()
        };
        assert_eq!(
            default_goals(&world(3, sim::View::Top), Profile::Original).unwrap(),
            demonstrated_goals()
        );
        assert_eq!(
            default_goals(&world(3, sim::View::Top), Profile::Spec).unwrap().len(),
            6
        );
        assert_eq!(
            default_goals(&world(2, sim::View::Top), Profile::Original)
                .unwrap()
                .len(),
            2
        );
        assert_eq!(
            default_goals(&world(3, sim::View::Side), Profile::Spec).unwrap().len(),
            13
        );
    }

    #[test]
    fn a_persons_turn_in_the_side_view_keeps_to_its_rules() {
        // Free protocol, side view: 0 on the table with 1 on it, 2 alone.
        let agent = QAgent::new(ReprKind::RoleTowers, Grid::default(), 3, QParams::default()).unwrap();
        let world = EnvConfig {
            view: sim::View::Side,
            reward: "step-cost".parse().unwrap(),
            ..session_world(&agent)
        };
        let goal: Goal = "0,2/1".parse().unwrap();
        let mut session = CorrectionSession::new(
            agent,
            CorrectionRule::default(),
            world,
            vec![goal],
            5,
            0.0,
            "person",
            None,
            (),
        )
        .unwrap();
        let obs = session.next_episode().unwrap();
        // A move with nothing held: refused with the side view's reason, nothing taken.
        let turn = session.person(Action::Up, PersonRole::Player).unwrap();
        assert!(
            matches!(&turn, PersonTurn::Refused(Refusal::NotAllowed(m)) if m.contains("nothing is held")),
            "{turn:?}"
        );
        assert_eq!(session.steps(), 0);
        // Holding, a pick of another block is refused (a dropped block falls): drop first.
        let clear = obs
            .legal_actions()
            .iter()
            .find(|a| matches!(a, Action::Pick(_)))
            .unwrap();
        let turn = session.person(clear, PersonRole::Corrector).unwrap();
        assert_eq!(turn.corrections(), 1);
        let other = (0..3).map(|b| Action::Pick(BlockId(b))).find(|&a| a != clear).unwrap();
        let turn = session.person(other, PersonRole::Player).unwrap();
        assert!(turn.message().contains("drop it first"), "{}", turn.message());
        assert_eq!(session.steps(), 1);
    }

    #[test]
    fn the_session_line_names_the_world_an_exporter_remakes() {
        let world = EnvConfig {
            reward: "step-cost".parse().unwrap(),
            protocol: sim::ActionProtocol::Paper,
            horizon: 40,
            ..EnvConfig::default()
        };
        let session = CorrectionSession::new(
            agent(),
            CorrectionRule::default(),
            world.clone(),
            vec!["0,1,2".parse().unwrap()],
            4,
            0.0,
            "person",
            None,
            Vec::<DemoRecord>::new(),
        )
        .unwrap();
        let [DemoRecord::Session(header)] = session.sink().as_slice() else {
            panic!("one session line: {:?}", session.sink())
        };
        let line = header.world.clone().unwrap();
        assert_eq!(
            (line.reward.as_str(), line.protocol, line.horizon),
            ("step-cost", sim::ActionProtocol::Paper, 40)
        );
        assert_eq!(line, crate::demos::WorldLine::of(&world));
        // Written and read back as JSON: the same line; a version-2 line without it reads as none.
        let text = serde_json::to_string(&DemoRecord::Session(header.clone())).unwrap();
        assert!(
            text.contains(r#""world":{"reward":"step-cost","protocol":"paper","start":"uniform","horizon":40}"#),
            "{text}"
        );
        let back: DemoRecord = serde_json::from_str(&text).unwrap();
        assert!(matches!(back, DemoRecord::Session(h) if h.world == Some(line.clone())));
        // A version-3 line names no start rule: read as uniform.
        let v3 = text.replace(r#""start":"uniform","#, "");
        assert!(matches!(serde_json::from_str(&v3).unwrap(), DemoRecord::Session(h) if h.world == Some(line.clone())));
        let old = text.replace(
            r#","world":{"reward":"step-cost","protocol":"paper","start":"uniform","horizon":40}"#,
            "",
        );
        let old: DemoRecord = serde_json::from_str(&old).unwrap();
        assert!(matches!(old, DemoRecord::Session(h) if h.world.is_none()));
    }

    #[test]
    fn a_turn_and_an_episodes_end_say_what_happened() {
        let mut session = CorrectionSession::new(
            agent(),
            CorrectionRule::default(),
            EnvConfig::default(),
            vec!["0,1,2".parse().unwrap()],
            4,
            0.0,
            "person",
            None,
            (),
        )
        .unwrap();
        assert_eq!(
            session.person(Action::Up, PersonRole::Player).unwrap().message(),
            "The episode is over: n begins the next."
        );
        session.next_episode().unwrap();
        let proposed = session.proposal().unwrap();
        let turn = session.person(proposed, PersonRole::Corrector).unwrap();
        assert_eq!(
            turn.message(),
            format!("You confirmed {proposed}; the agent learnt it.")
        );
        let turn = session.person(Action::Drop, PersonRole::Player).unwrap();
        assert_eq!(turn.message(), "You chose drop.");
        assert_eq!(session.episode_end(), None);
        let end = EpisodeEnd {
            reached: true,
            steps: 9,
        };
        assert_eq!(
            end.message(Some(7)),
            "Goal reached in 9 steps; the shortest plan takes 7."
        );
        let cut = EpisodeEnd {
            reached: false,
            steps: 1000,
        };
        assert_eq!(cut.message(None), "Cut off after 1000 steps.");
    }

    #[test]
    fn correction_runs_can_go_to_other_threads() {
        fn send<T: Send>() {}
        send::<CorrectionConfig>();
        send::<Corrected<Vec<DemoRecord>>>();
        send::<CorrectionSession<Vec<DemoRecord>>>();
    }

    #[test]
    fn a_negative_or_infinite_margin_is_refused() {
        for margin in [-0.1, f64::INFINITY, f64::NAN] {
            let rule = CorrectionRule {
                margin: Some(margin),
                ..CorrectionRule::default()
            };
            assert!(rule.validate().is_err());
        }
    }

    proptest! {
        #[test]
        fn after_a_correction_the_demonstrators_action_leads_by_the_margin(
            values in proptest::collection::vec(-100.0f32..100.0, 8),
            column in 0usize..8,
            margin in 0.0f64..5.0,
        ) {
            let mut a = agent();
            let o = obs();
            for (i, &v) in values.iter().enumerate() {
                a.set_q(&o, Action::from_index(i, 3).unwrap(), v).unwrap();
            }
            let chosen = Action::from_index(column, 3).unwrap();
            raise_to_margin(&mut a, &o, chosen, margin).unwrap();
            let q = a.q_values(&o).unwrap();
            let best_other = q.iter().enumerate().filter(|&(i, _)| i != column).map(|(_, &v)| v).fold(f32::MIN, f32::max);
            prop_assert!(q[column] >= values[column]);
            prop_assert!(q[column] >= (f64::from(best_other) + margin) as f32);
            prop_assert!(q[column] == values[column] || q[column] == (f64::from(best_other) + margin) as f32);
        }
    }
}
