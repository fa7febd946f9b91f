//! The messages between the page and the server, one JSON object per WebSocket text
//! message (docs/serve.md, "The message protocol").
//!
//! The page sends [`ClientMessage`]s; the server answers each with a [`View`] of the new
//! state, or with an [`ErrorMessage`] that leaves the state as it was. A message carries
//! an optional `id` that the answer repeats, so a client can tell which answer is whose.
//! Unknown fields and unknown types are refused: the protocol is small and closed.

use serde::{Deserialize, Serialize};
use sim::Goal;

/// What a person is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// The person solves episodes; the agent only watches (and learns, as in
    /// `blockstack demo` with the agent paused).
    Play,
    /// The agent plays at the person's pace, its greedy choice and Q-values shown.
    Watch,
    /// The paper's loop: the agent proposes, the person accepts or overrides.
    Correct,
}

// Every mode, in the order the page offers them (`Mode::ALL`), and its name in messages and
// study files.
sim::names!(Mode { Play = "play", Watch = "watch", Correct = "correct" } unknown(text) -> String {
    format!("{text:?} is not a mode: play, watch or correct")
});

/// A message from the page.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ClientMessage {
    /// Switch to another of the offered modes (play and correct begin a new episode).
    Mode {
        /// Repeated in the answer.
        id: Option<u64>,
        /// The mode.
        mode: Mode,
    },
    /// The person's action, named as `blockstack solve` prints it (`up`, `pick 2`, ...):
    /// in play mode the move itself, in correct mode a correction.
    Act {
        /// Repeated in the answer.
        id: Option<u64>,
        /// The action's name.
        action: String,
        /// Milliseconds since the page showed the episode's first view, by the page's
        /// monotonic clock (recorded as the step's `t_ms` when believable).
        #[serde(default)]
        t_ms: Option<u64>,
    },
    /// Side view: the person's block move, `block` onto the top of column `to` (onto the
    /// block there, or the table when the column is empty).
    Move {
        /// Repeated in the answer.
        id: Option<u64>,
        /// The block moved.
        block: u16,
        /// The destination column.
        to: u16,
        /// As for `act`.
        #[serde(default)]
        t_ms: Option<u64>,
    },
    /// Correct mode: take the agent's proposal.
    Accept {
        /// Repeated in the answer.
        id: Option<u64>,
        /// As for `act`.
        #[serde(default)]
        t_ms: Option<u64>,
    },
    /// Watch mode: the agent's next step (the next episode once one has ended).
    Step {
        /// Repeated in the answer.
        id: Option<u64>,
    },
    /// Begin the next episode of the current mode.
    Next {
        /// Repeated in the answer.
        id: Option<u64>,
    },
}

impl ClientMessage {
    /// The message's `id`.
    pub fn id(&self) -> Option<u64> {
        match self {
            ClientMessage::Mode { id, .. }
            | ClientMessage::Act { id, .. }
            | ClientMessage::Move { id, .. }
            | ClientMessage::Accept { id, .. }
            | ClientMessage::Step { id }
            | ClientMessage::Next { id } => *id,
        }
    }
}

/// An action and its Q-value, shown beside the world.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ActionValue {
    /// The action's name.
    pub action: String,
    /// Its Q-value.
    pub q: f32,
}

/// A participant's totals, also listed on the researcher's page.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Progress {
    /// Episodes of play and correct mode that ended (goal reached or cut off).
    pub episodes_done: u64,
    /// Episodes the participant is asked for; 0: no limit.
    pub episodes_total: u64,
    /// Steps executed in play and correct mode.
    pub steps: u64,
    /// Of those, the person's (every step of play mode, the overrides of correct mode).
    pub corrections: u64,
    /// Lines written to the participant's recording (0 when nothing is recorded): every
    /// line counted here is on disk, flushed, before the answer that counts it is sent.
    pub recorded_lines: u64,
}

/// The state shown to the person: the world, what the agent thinks, and what happened.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct View {
    /// Always `view`.
    #[serde(rename = "type")]
    pub kind: String,
    /// The `id` of the message this answers.
    pub id: Option<u64>,
    /// The current mode.
    pub mode: Mode,
    /// The modes offered.
    pub modes: Vec<Mode>,
    /// The condition's name.
    pub condition: String,
    /// `[W, H]`.
    pub grid: [usize; 2],
    /// Every block's cell `[x, y]` (y up), by block id.
    pub blocks: Vec<[u16; 2]>,
    /// The held block.
    pub held: Option<u16>,
    /// The world's view: `top` (seen from above) or `side` (gravity, towers on a table).
    pub view: sim::View,
    /// The goal as recordings write it: one tower of every block as its list of block ids,
    /// bottom to top (`[1,0,2]`); a goal of towers as `{"towers":[[0,1],[2]],"blocks":3}`.
    pub goal: Goal,
    /// Every block's colour as `#rrggbb` (`sim::render`'s palette).
    pub colours: Vec<String>,
    /// Every block's label (`sim::render::label`).
    pub labels: Vec<String>,
    /// The actions legal now, by name.
    pub legal: Vec<String>,
    /// The episode's number in this mode, from 0.
    pub episode: u64,
    /// Steps taken in the episode.
    pub steps: u32,
    /// Whether the episode has ended.
    pub over: bool,
    /// How it ended: `goal` or `cut off`.
    pub outcome: Option<String>,
    /// Once the episode has ended: the length of a shortest plan from its start.
    pub shortest: Option<u32>,
    /// Correct mode: the agent's proposal.
    pub proposal: Option<String>,
    /// Watch mode: the agent's greedy choice, the action it takes next.
    pub greedy: Option<String>,
    /// Watch and correct mode: the Q-values of the legal actions.
    pub q: Vec<ActionValue>,
    /// One line about the last thing that happened.
    pub message: String,
    /// Totals.
    pub progress: Progress,
    /// Every episode asked for is done.
    pub done: bool,
    /// Whether play and correct mode are recorded.
    pub recording: bool,
    /// Once every episode asked for is done: the study's completion code and link.
    pub completion: Option<Completion>,
    /// Whether the participant may withdraw (the study says what that does).
    pub withdrawal: bool,
}

/// What the page shows, and where it goes, at the end of a study.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Completion {
    /// The code the participant gives the platform.
    pub code: Option<String>,
    /// The platform's completion link.
    pub url: Option<String>,
}

/// An answer that changed nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorMessage {
    /// Always `error`.
    #[serde(rename = "type")]
    pub kind: String,
    /// The `id` of the message this answers, when it could be read.
    pub id: Option<u64>,
    /// What was wrong, in one line.
    pub message: String,
}

impl ErrorMessage {
    /// The error `message`, answering `id`.
    pub fn new(id: Option<u64>, message: impl Into<String>) -> Self {
        ErrorMessage {
            kind: "error".into(),
            id,
            message: message.into(),
        }
    }
}
