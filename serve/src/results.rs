//! The researcher's figures, read from the recordings on disk (every run's, the one
//! serving included), so that they are the data and not a tally the server keeps: one row
//! per episode ([`EpisodeRow`], the CSV download), the figures per condition
//! ([`ConditionRow`]), and any episode step by step for the replay.
//!
//! A recording whose participant withdrew is left out of all of them, and the table counts
//! how many were (the page says so in a line). A participant who finished every episode
//! asked for has their completion code in the CSV, so that the lab can check the codes
//! claimed on the platform (each their own with `code_per_participant`). Each file is read
//! once per change (its length and time of change are remembered), and each start's
//! shortest plan is searched once, so the page can ask every two seconds.
//!
//! - *Reaction time*: for each step the person chose, the milliseconds since the step
//!   before it (or the episode's first view); the second step of one command (the Drop
//!   and Pick of a pick while holding, the gripper steps of a block move) has none.
//! - *Duration*: the last step's time since the episode's first view.
//! - *Steps against the shortest plan*: over the episodes that reached the goal, the mean
//!   of steps / the exact solver's shortest plan from the start, in the condition's world.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::SystemTime;

use agent::demos::{DemoEpisode, read_demonstrations};
use oracle::ExactSolver;
use serde::Serialize;
use sim::render::{colour, label};
use sim::{EnvConfig, Goal, State, View};

use crate::config::Condition;
use crate::ledger::Codes;
use crate::registry::{lock, recordings_in};

/// One episode of one recording: a row of the CSV.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EpisodeRow {
    /// The participant's number.
    pub participant: u64,
    /// The code they typed, if any.
    pub code: Option<String>,
    /// Their platform id (the study's first `participant_ids`), if any.
    pub participant_id: Option<String>,
    /// The condition.
    pub condition: String,
    /// `top` or `side`.
    pub view: View,
    /// The goal, as `blockstack` writes goals (`1,0,2`, `0,1/2`).
    pub goal: String,
    /// The episode's number in the recording.
    pub episode: u64,
    /// When its first view was shown (Unix milliseconds), in a timed recording.
    pub started_ms: Option<u64>,
    /// Steps taken.
    pub steps: u32,
    /// The shortest plan from its start, when the solver found it within its budget.
    pub optimum: Option<u32>,
    /// It ended (the goal reached, or cut off at the horizon); an episode the person left
    /// for another mode, or a crash cut short, did not.
    pub ended: bool,
    /// It reached the goal.
    pub success: bool,
    /// Steps the person chose.
    pub corrections: u32,
    /// The last step's time since the episode's first view.
    pub duration_ms: Option<u64>,
    /// The median of the person's reaction times in it (module docs).
    pub median_rt_ms: Option<u64>,
    /// The recording's file name.
    pub recording: String,
    /// The completion code the participant was given, when they finished every episode
    /// asked for.
    pub completion_code: Option<String>,
}

/// The figures of one condition.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConditionRow {
    /// The condition.
    pub condition: String,
    /// Its view.
    pub view: View,
    /// Participants with a recording (withdrawn ones left out).
    pub participants: usize,
    /// Episodes that ended.
    pub episodes: usize,
    /// Of those, the share that reached the goal.
    pub success: Option<f64>,
    /// Over those that reached it: the mean of steps / the shortest plan.
    pub steps_to_optimum: Option<f64>,
    /// Steps the people chose, in all.
    pub corrections: u64,
    /// The median reaction time over every step the people chose (module docs).
    pub median_rt_ms: Option<u64>,
}

/// The researcher's table: per condition, and per episode.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Table {
    /// Per condition, in the study's order.
    pub conditions: Vec<ConditionRow>,
    /// Every episode with a step, by recording then episode.
    pub episodes: Vec<EpisodeRow>,
    /// Recordings left out of every figure because their participant withdrew.
    pub withdrawn: usize,
}

/// One recording read: its episodes' rows and reaction times, and the episodes to replay.
struct Read {
    len: u64,
    modified: Option<SystemTime>,
    withdrawn: bool,
    rows: Vec<EpisodeRow>,
    reaction_times: Vec<(String, u64)>,
    episodes: Arc<Vec<DemoEpisode>>,
}

/// The recordings of a record folder, read as they change.
pub struct Figures {
    dir: Option<PathBuf>,
    conditions: Vec<Arc<Condition>>,
    solver_budget: usize,
    /// The study's first `participant_ids`: the one shown as the participant's id.
    primary: Option<String>,
    /// The participants' completion codes.
    codes: Codes,
    read: Mutex<HashMap<PathBuf, Arc<Read>>>,
    optimum: Mutex<HashMap<(String, State, Goal), Option<u32>>>,
}

impl Figures {
    /// The figures of the recordings in `dir`, for `conditions` (whose worlds the
    /// shortest plans are searched in, within `solver_budget` states); `primary` names the
    /// id parameter shown as the participant's id; `codes` gives each participant's
    /// completion code.
    pub(crate) fn new(
        dir: Option<PathBuf>,
        conditions: Vec<Arc<Condition>>,
        solver_budget: usize,
        primary: Option<String>,
        codes: Codes,
    ) -> Figures {
        Figures {
            dir,
            conditions,
            solver_budget,
            primary,
            codes,
            read: Mutex::new(HashMap::new()),
            optimum: Mutex::new(HashMap::new()),
        }
    }

    /// The table now (reads the recordings that changed since the last call).
    pub fn table(&self) -> Table {
        let Some(dir) = &self.dir else {
            return Table::default();
        };
        let mut episodes = Vec::new();
        let mut times: HashMap<String, Vec<u64>> = HashMap::new();
        let mut people: HashMap<String, std::collections::BTreeSet<u64>> = HashMap::new();
        let mut withdrawn = 0;
        for found in recordings_in(dir) {
            let Some(read) = self.read(&found.path) else {
                continue;
            };
            if read.withdrawn {
                withdrawn += 1;
                continue;
            }
            if let Some(p) = &found.participant {
                people.entry(p.condition.clone()).or_default().insert(found.number);
            }
            episodes.extend(read.rows.iter().cloned());
            for (condition, rt) in &read.reaction_times {
                times.entry(condition.clone()).or_default().push(*rt);
            }
        }
        let conditions = self
            .conditions
            .iter()
            .map(|c| {
                let rows: Vec<&EpisodeRow> = episodes.iter().filter(|e| e.condition == c.name && e.ended).collect();
                let successes: Vec<&&EpisodeRow> = rows.iter().filter(|e| e.success).collect();
                let ratios: Vec<f64> = successes
                    .iter()
                    .filter_map(|e| e.optimum.filter(|&o| o > 0).map(|o| f64::from(e.steps) / f64::from(o)))
                    .collect();
                ConditionRow {
                    condition: c.name.clone(),
                    view: c.world.view,
                    participants: people.get(&c.name).map_or(0, |p| p.len()),
                    episodes: rows.len(),
                    success: (!rows.is_empty()).then(|| successes.len() as f64 / rows.len() as f64),
                    steps_to_optimum: (!ratios.is_empty()).then(|| ratios.iter().sum::<f64>() / ratios.len() as f64),
                    corrections: episodes
                        .iter()
                        .filter(|e| e.condition == c.name)
                        .map(|e| u64::from(e.corrections))
                        .sum(),
                    median_rt_ms: median(times.remove(&c.name).unwrap_or_default()),
                }
            })
            .collect();
        Table {
            conditions,
            episodes,
            withdrawn,
        }
    }

    /// Episode `episode` of the recording `file` (a name in the record folder) for the
    /// replay, or the line saying why not: there is no such, or its participant withdrew.
    pub fn replay(&self, file: &str, episode: u64) -> Result<Replay, &'static str> {
        const NONE: &str = "no such episode";
        let dir = self.dir.as_ref().ok_or(NONE)?;
        let found = recordings_in(dir)
            .into_iter()
            .find(|f| f.path.file_name().is_some_and(|n| n == file))
            .ok_or(NONE)?;
        let read = self.read(&found.path).ok_or(NONE)?;
        if read.withdrawn {
            return Err("this participant withdrew: their recording is left out of every analysis");
        }
        let e = read.episodes.iter().find(|e| e.episode == episode).ok_or(NONE)?;
        let row = read.rows.iter().find(|r| r.episode == episode).ok_or(NONE)?;
        let cells = |s: &State| s.cells().iter().map(|c| [c.x, c.y]).collect::<Vec<_>>();
        Ok(Replay {
            recording: file.to_string(),
            row: row.clone(),
            grid: [e.grid.width(), e.grid.height()],
            view: e.view,
            goal: e.goal.clone(),
            colours: e
                .start
                .blocks()
                .map(|b| {
                    let [r, g, bl] = colour(b);
                    format!("#{r:02x}{g:02x}{bl:02x}")
                })
                .collect(),
            labels: e.start.blocks().map(|b| label(b).to_string()).collect(),
            start: ReplayState {
                blocks: cells(&e.start),
                held: e.start.held_block().map(|b| b.0),
            },
            steps: e
                .steps
                .iter()
                .map(|s| ReplayStep {
                    action: s.action.to_string(),
                    person: s.demonstrated,
                    t_ms: s.time.t_ms,
                    reward: s.reward,
                    state: ReplayState {
                        blocks: cells(&s.state),
                        held: s.state.held_block().map(|b| b.0),
                    },
                })
                .collect(),
        })
    }

    /// The recording at `path`, read again if it changed since the last time.
    fn read(&self, path: &Path) -> Option<Arc<Read>> {
        let meta = std::fs::metadata(path).ok()?;
        let (len, modified) = (meta.len(), meta.modified().ok());
        if let Some(r) = lock(&self.read)
            .get(path)
            .filter(|r| r.len == len && r.modified == modified)
        {
            return Some(r.clone());
        }
        let demos = read_demonstrations(path, None).ok()?;
        let file = path.file_name()?.to_string_lossy().into_owned();
        let code = self.code_of_finished(&demos.episodes);
        let mut rows = Vec::new();
        let mut reaction_times = Vec::new();
        for e in demos.episodes.iter().filter(|e| !e.steps.is_empty()) {
            let who = e.participant.as_ref();
            let condition = who.map_or_else(|| "-".to_string(), |p| p.condition.clone());
            let rts = reaction_times_of(e);
            reaction_times.extend(rts.iter().map(|&rt| (condition.clone(), rt)));
            let last = e.steps.last().expect("an episode with a step");
            rows.push(EpisodeRow {
                participant: who.map_or(0, |p| p.number),
                code: who.and_then(|p| p.code.clone()),
                participant_id: self.primary_id(who),
                optimum: self.optimum(&condition, e),
                condition,
                view: e.view,
                goal: e.goal.to_string(),
                episode: e.episode,
                started_ms: e.started_ms,
                steps: e.steps.len() as u32,
                ended: last.terminated || last.truncated,
                success: last.terminated,
                corrections: e.steps.iter().filter(|s| s.demonstrated).count() as u32,
                duration_ms: last.time.t_ms,
                median_rt_ms: median(rts),
                recording: file.clone(),
                completion_code: code.clone(),
            });
        }
        let read = Arc::new(Read {
            len,
            modified,
            withdrawn: demos.withdrawn,
            rows,
            reaction_times,
            episodes: Arc::new(demos.episodes),
        });
        lock(&self.read).insert(path.to_path_buf(), read.clone());
        Some(read)
    }

    /// The completion code of the participant whose episodes are `episodes`, when they
    /// ended every episode their condition asks for (as the page counts them).
    fn code_of_finished(&self, episodes: &[DemoEpisode]) -> Option<String> {
        let who = episodes.iter().find_map(|e| e.participant.as_ref())?;
        let asked = self.conditions.iter().find(|c| c.name == who.condition)?.episodes;
        let ended = episodes
            .iter()
            .filter(|e| e.steps.last().is_some_and(|s| s.terminated || s.truncated))
            .count() as u64;
        (asked > 0 && ended >= asked)
            .then(|| self.codes.of(who.number))
            .flatten()
    }

    /// The participant's platform id: the study's first id parameter's value (none when
    /// the recording names no id).
    fn primary_id(&self, who: Option<&agent::demos::ParticipantLine>) -> Option<String> {
        let ids = &who?.ids;
        self.primary.as_ref().and_then(|key| ids.get(key)).cloned()
    }

    /// The shortest plan from `e`'s start, in the world of `condition` (the recorded view
    /// and the free protocol when the study has no such condition), searched once.
    fn optimum(&self, condition: &str, e: &DemoEpisode) -> Option<u32> {
        let key = (condition.to_string(), e.start.clone(), e.goal.clone());
        if let Some(found) = lock(&self.optimum).get(&key) {
            return *found;
        }
        let world = self.conditions.iter().find(|c| c.name == condition).map_or(
            EnvConfig {
                grid: e.grid,
                view: e.view,
                ..EnvConfig::default()
            },
            |c| c.world.clone(),
        );
        let found = ExactSolver::for_world(&EnvConfig { grid: e.grid, ..world })
            .with_node_budget(self.solver_budget)
            .distance(&e.start, &e.goal)
            .ok();
        lock(&self.optimum).insert(key, found);
        found
    }
}

/// The person's reaction times in `e` (module docs).
fn reaction_times_of(e: &DemoEpisode) -> Vec<u64> {
    let mut before = Some(0);
    let mut out = Vec::new();
    for s in &e.steps {
        let t = s.time.t_ms;
        if let (true, Some(t), Some(b)) = (s.demonstrated, t, before)
            && t > b
        {
            out.push(t - b);
        }
        if t.is_some() {
            before = t;
        }
    }
    out
}

/// The median of `values` (the lower of the middle two for an even count).
fn median(mut values: Vec<u64>) -> Option<u64> {
    if values.is_empty() {
        return None;
    }
    values.sort_unstable();
    Some(values[(values.len() - 1) / 2])
}

/// The table's episodes as CSV, one row per episode (a header first).
pub fn csv(table: &Table) -> String {
    let mut out = String::from(
        "participant,code,participant_id,condition,view,goal,episode,started_ms,steps,optimum,ended,success,corrections,duration_ms,median_rt_ms,recording,completion_code\n",
    );
    let opt = |v: Option<u64>| v.map_or(String::new(), |v| v.to_string());
    for e in &table.episodes {
        let fields = [
            e.participant.to_string(),
            e.code.clone().unwrap_or_default(),
            e.participant_id.clone().unwrap_or_default(),
            e.condition.clone(),
            e.view.to_string(),
            e.goal.clone(),
            e.episode.to_string(),
            opt(e.started_ms),
            e.steps.to_string(),
            opt(e.optimum.map(u64::from)),
            e.ended.to_string(),
            e.success.to_string(),
            e.corrections.to_string(),
            opt(e.duration_ms),
            opt(e.median_rt_ms),
            e.recording.clone(),
            e.completion_code.clone().unwrap_or_default(),
        ];
        let quoted: Vec<String> = fields.iter().map(|f| csv_field(f)).collect();
        out.push_str(&quoted.join(","));
        out.push('\n');
    }
    out
}

/// A CSV field, quoted when it holds a comma, a quote or a line break (RFC 4180); one that
/// a spreadsheet would take for a formula is prefixed with `'`.
fn csv_field(text: &str) -> String {
    let text = if text.starts_with(['=', '+', '-', '@']) && text.parse::<f64>().is_err() {
        format!("'{text}")
    } else {
        text.to_string()
    };
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text
    }
}

/// One episode for the replay page.
#[derive(Clone, Debug, Serialize)]
pub struct Replay {
    /// The recording's file name.
    pub recording: String,
    /// Its row of the table.
    pub row: EpisodeRow,
    /// `[W, H]`.
    pub grid: [usize; 2],
    /// The view.
    pub view: View,
    /// The goal, as the participant page's view writes it.
    pub goal: Goal,
    /// Every block's colour.
    pub colours: Vec<String>,
    /// Every block's label.
    pub labels: Vec<String>,
    /// The start.
    pub start: ReplayState,
    /// The steps, in order.
    pub steps: Vec<ReplayStep>,
}

/// A state on the replay page.
#[derive(Clone, Debug, Serialize)]
pub struct ReplayState {
    /// Every block's cell `[x, y]`.
    pub blocks: Vec<[u16; 2]>,
    /// The held block.
    pub held: Option<u16>,
}

/// A step on the replay page.
#[derive(Clone, Debug, Serialize)]
pub struct ReplayStep {
    /// The action's name.
    pub action: String,
    /// The person chose it.
    pub person: bool,
    /// Its time since the episode's first view.
    pub t_ms: Option<u64>,
    /// Its reward.
    pub reward: f64,
    /// The state after it.
    pub state: ReplayState,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_fields_are_quoted_and_formulas_defused() {
        assert_eq!(csv_field("0,1/2"), "\"0,1/2\"");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(csv_field("=cmd()"), "'=cmd()");
        assert_eq!(csv_field("-3"), "-3");
        assert_eq!(median(vec![5, 1, 9, 3]), Some(3));
        assert_eq!(median(vec![]), None);
    }
}
