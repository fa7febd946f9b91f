//! Demonstrations as arrays: expert episodes played by the planners, and recordings the
//! CLI wrote (trajectories of `run --trajectory`, demonstration sessions of `demo` /
//! `correct --record`) read back into the same arrays.

use std::path::PathBuf;

use agent::{EpisodeObserver, PolicyKind, PolicyOptions};
use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods};
use oracle::PlannerKind;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::seeding::episode_seed;
use sim::{Action, Env, EnvConfig, Grid, Observation, Step};

use crate::boundary::{OrValueError, guard, raise_signal, signal_checker, value_error};
use crate::config::{self, ObsKind, World};
use crate::observe;

/// Steps of episodes, column by column.
#[derive(Default)]
struct Columns {
    observations: Vec<Observation>,
    next_observations: Vec<Observation>,
    actions: Vec<i64>,
    rewards: Vec<f64>,
    terminations: Vec<bool>,
    truncations: Vec<bool>,
    episode_starts: Vec<bool>,
    episodes: Vec<i64>,
    /// The next step pushed is an episode's first.
    starting: bool,
}

impl Columns {
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        episode: u64,
        before: Observation,
        action: Action,
        reward: f64,
        after: Observation,
        terminated: bool,
        truncated: bool,
        first: bool,
    ) {
        self.observations.push(before);
        self.next_observations.push(after);
        self.actions.push(action.index() as i64);
        self.rewards.push(reward);
        self.terminations.push(terminated);
        self.truncations.push(truncated);
        self.episode_starts.push(first);
        self.episodes.push(episode as i64);
    }

    /// The columns as a dict of numpy arrays, observations encoded as `kind` for a world of
    /// `blocks` blocks on `grid`. A `ValueError` if an observation is of another world:
    /// arrays hold one shape.
    fn into_dict<'py>(self, py: Python<'py>, kind: ObsKind, grid: Grid, blocks: usize) -> PyResult<Bound<'py, PyDict>> {
        if let Some((t, o)) = self
            .observations
            .iter()
            .chain(&self.next_observations)
            .enumerate()
            .find(|(_, o)| o.grid != grid || o.state.block_count() != blocks || o.goal.block_count() != blocks)
        {
            return Err(value_error(format!(
                "step {} has {} blocks on a {} grid, and the arrays {blocks} blocks on a {grid} grid",
                t % self.observations.len().max(1),
                o.state.block_count(),
                o.grid
            )));
        }
        let d = PyDict::new(py);
        d.set_item("observations", encode(py, kind, &self.observations, grid, blocks)?)?;
        d.set_item(
            "next_observations",
            encode(py, kind, &self.next_observations, grid, blocks)?,
        )?;
        d.set_item("actions", PyArray1::from_vec(py, self.actions))?;
        d.set_item("rewards", PyArray1::from_vec(py, self.rewards))?;
        d.set_item("terminations", PyArray1::from_vec(py, self.terminations))?;
        d.set_item("truncations", PyArray1::from_vec(py, self.truncations))?;
        d.set_item("episode_starts", PyArray1::from_vec(py, self.episode_starts))?;
        d.set_item("episodes", PyArray1::from_vec(py, self.episodes))?;
        let actions = Action::count(blocks);
        let masks = PyArray2::<i8>::zeros(py, [self.observations.len(), actions], false);
        {
            let mut rw = masks.readwrite();
            let out = rw.as_slice_mut().expect("contiguous");
            for (obs, row) in self.observations.iter().zip(out.chunks_mut(actions)) {
                observe::write_action_mask(obs, row);
            }
        }
        d.set_item("action_masks", masks)?;
        Ok(d)
    }
}

/// Bytes of the arrays [`Columns::into_dict`] makes of `steps` steps: two observations
/// and an action mask each, and 27 bytes of the other columns.
fn array_bytes(steps: usize, kind: ObsKind, grid: Grid, blocks: usize) -> u128 {
    let obs = match kind.shape(grid, blocks) {
        Some(shape) => shape.iter().map(|&d| d as u128).product::<u128>(),
        None => 8 * (4 * blocks as u128 + 1),
    };
    steps as u128 * (2 * obs + Action::count(blocks) as u128 + 27)
}

/// `observations` as one array `(T, *shape)` (a dict of such arrays for `state`).
fn encode<'py>(
    py: Python<'py>,
    kind: ObsKind,
    observations: &[Observation],
    grid: Grid,
    blocks: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let t = observations.len();
    let bytes = |shape: Vec<usize>, write: &dyn Fn(&Observation, &mut [u8])| -> Bound<'py, PyAny> {
        let a = PyArrayDyn::<u8>::zeros(py, shape, false);
        {
            let mut rw = a.readwrite();
            let out = rw.as_slice_mut().expect("contiguous");
            let len = out.len() / t.max(1);
            for (obs, chunk) in observations.iter().zip(out.chunks_mut(len.max(1))) {
                write(obs, chunk);
            }
        }
        a.into_any()
    };
    if let Some(shape) = kind.shape(grid, blocks) {
        let write = |o: &Observation, out: &mut [u8]| kind.write(o, out).expect("shaped by the kind's shape");
        return Ok(bytes([&[t][..], &shape[..]].concat(), &write));
    }
    {
        let cells = PyArrayDyn::<i64>::zeros(py, vec![t, blocks, 2], false);
        let held = PyArray1::<i64>::zeros(py, t, false);
        let goal = PyArray2::<i64>::zeros(py, [t, blocks], false);
        let goal_tower = PyArray2::<i64>::zeros(py, [t, blocks], false);
        {
            let (mut c, mut h, mut g, mut gt) = (
                cells.readwrite(),
                held.readwrite(),
                goal.readwrite(),
                goal_tower.readwrite(),
            );
            let (c, h, g, gt) = (
                c.as_slice_mut().expect("contiguous"),
                h.as_slice_mut().expect("contiguous"),
                g.as_slice_mut().expect("contiguous"),
                gt.as_slice_mut().expect("contiguous"),
            );
            for (i, obs) in observations.iter().enumerate() {
                let each = blocks * i..blocks * (i + 1);
                observe::write_state(
                    obs,
                    &mut c[2 * blocks * i..2 * blocks * (i + 1)],
                    observe::GoalOut {
                        goal: &mut g[each.clone()],
                        tower: &mut gt[each],
                    },
                );
                h[i] = observe::held_index(obs);
            }
        }
        let d = PyDict::new(py);
        d.set_item("blocks", cells)?;
        d.set_item("held", held)?;
        d.set_item("goal", goal)?;
        d.set_item("goal_tower", goal_tower)?;
        Ok(d.into_any())
    }
}

/// The columns of the episodes a planner plays (`demonstrations`).
impl EpisodeObserver for Columns {
    fn start(&mut self, _: u64, _: u64, _: &EnvConfig, _: &Observation) -> agent::Result<()> {
        self.starting = true;
        Ok(())
    }

    fn step(&mut self, episode: u64, before: &Observation, action: Action, step: &Step) -> agent::Result<()> {
        let first = std::mem::take(&mut self.starting);
        self.push(
            episode,
            before.clone(),
            action,
            step.reward,
            step.observation.clone(),
            step.terminated,
            step.truncated,
            first,
        );
        Ok(())
    }
}

/// Expert episodes as arrays for behaviour cloning or DQfD: episode `k` starts from
/// `reset(episode_seed(seed, k))`, the start `blockstack run --seed SEED` plays, and the
/// expert acts until the goal holds, as `blockstack run --agent EXPERT` plays it: a planner
/// named as `oracle::PlannerKind` names it (`exact`: the fewest gripper steps in either
/// view; `oracle`; in the side view `exact-moves` and `near-optimal`, block-move plans
/// carried out by the gripper).
///
/// Keys: `observations`, `next_observations` (`(T, *obs shape)`, or dicts of arrays for
/// `state`), `actions` (int64), `rewards` (float64), `terminations`, `truncations`,
/// `episode_starts` (bool, true at each episode's first step), `episodes` (int64, the
/// episode of each step), `action_masks` (int8, `(T, 5 + N)`, the legal actions in each
/// observation).
#[pyfunction]
#[pyo3(signature = (episodes, world, expert="exact", seed=0, obs="planes"))]
pub fn demonstrations<'py>(
    py: Python<'py>,
    episodes: u64,
    world: World,
    expert: &str,
    seed: u64,
    obs: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = config::obs_kind(obs)?;
    let config = world.config()?;
    let blocks = config.blocks;
    // The experts are the planners, by the names `blockstack run --agent` gives them.
    let expert: PlannerKind = expert.parse().or_value_error()?;
    let mut policy = PolicyKind::from(expert)
        .expert(&config, &PolicyOptions::of_profile(config::profile(&world.profile)?))
        .or_value_error()?;
    let columns = py.detach(|| {
        guard(|| {
            // Ctrl-C stops a long run: the checker looks for signals at most every 100 ms,
            // with the GIL taken back only for that.
            let mut signal = None;
            let mut check = signal_checker(&mut signal);
            let mut env = Env::new(config.clone()).or_value_error()?;
            let mut columns = Columns::default();
            let played = (0..episodes).try_for_each(|k| {
                check()?;
                agent::play_episode(&mut env, policy.as_mut(), k, episode_seed(seed, k), &mut columns).map(drop)
            });
            drop(check);
            played.map_err(|e| raise_signal(signal, e))?;
            Ok(columns)
        })
    })?;
    guard(|| columns.into_dict(py, kind, config.grid, blocks))
}

/// Reads a recording the CLI wrote into the arrays [`demonstrations`] gives: a trajectory
/// file (`blockstack run --trajectory`) or a demonstration recording (`blockstack demo` /
/// `correct --record`), told by the first line. Read by `agent::demos::read_admitted`, the
/// checked reader `blockstack dqn --demos-file` uses: a file the CLI refuses is a
/// `ValueError` with the CLI's message, naming the line. A file holds one world (grid and
/// block count). With `profile`, a recording of another protocol than the profile's is
/// refused (naming both) and the `action_masks` are the profile's; without it they are
/// the protocol the recording names (the free one when it names none). A withdrawn
/// participant's recording is refused unless `include_withdrawn`; the second item is the
/// line to say when it was read all the same.
#[pyfunction]
/// Reading happens on a thread of its own while this one looks for Ctrl-C every 100 ms, so
/// a file that never comes (a FIFO with no writer) or a long read stops with
/// `KeyboardInterrupt`; the abandoned reader ends when its file does.
/// `max_bytes` bounds the arrays: a file whose arrays would need more is refused, saying
/// how large they would be, before anything is allocated.
#[pyo3(signature = (path, obs="planes", profile=None, max_bytes=None, include_withdrawn=false))]
pub fn read_recording<'py>(
    py: Python<'py>,
    path: PathBuf,
    obs: &str,
    profile: Option<&str>,
    max_bytes: Option<u64>,
    include_withdrawn: bool,
) -> PyResult<(Bound<'py, PyDict>, Option<String>)> {
    let kind = config::obs_kind(obs)?;
    let protocol = profile.map(config::profile).transpose()?.map(|p| p.protocol());
    let admission = agent::demos::Admission {
        world: protocol.map(|protocol| agent::demos::RunWorld {
            protocol: Some(protocol),
            ..agent::demos::RunWorld::default()
        }),
        include_withdrawn,
    };
    let admitted = read_in_thread(py, &path, move |p| agent::demos::read_admitted(p, &admission))?;
    let (episodes, note) = (admitted.read, admitted.note);
    let arrays = guard(|| {
        // The reader holds a file to one world, that of its first episode (which exists).
        let Some(first) = episodes.first() else {
            return Err(value_error(format!("{} holds no episode", path.display())));
        };
        let (grid, blocks) = (first.grid, first.goal.block_count());
        let steps: usize = episodes.iter().map(|e| e.steps.len()).sum();
        let bytes = array_bytes(steps, kind, grid, blocks);
        if let Some(max) = max_bytes.filter(|&max| bytes > u128::from(max)) {
            return Err(value_error(format!(
                "{}: its {steps} steps as obs={obs} make {:.1} GiB of arrays, more than this machine's {:.1} GiB of memory",
                path.display(),
                bytes as f64 / f64::from(1u32 << 30),
                max as f64 / f64::from(1u32 << 30)
            )));
        }
        let mut columns = Columns::default();
        for e in &episodes {
            let recorded = e.world.as_ref().map_or(sim::ActionProtocol::Free, |w| w.protocol);
            let mut obs = Observation {
                grid: e.grid,
                state: e.start.clone(),
                goal: e.goal.clone(),
                protocol: protocol.unwrap_or(recorded),
                view: e.view,
            };
            for (k, step) in e.steps.iter().enumerate() {
                let next = Observation {
                    state: step.state.clone(),
                    ..obs.clone()
                };
                columns.push(
                    e.episode,
                    obs,
                    step.action,
                    step.reward,
                    next.clone(),
                    step.terminated,
                    step.truncated,
                    k == 0,
                );
                obs = next;
            }
        }
        columns.into_dict(py, kind, grid, blocks)
    })?;
    Ok((arrays, note))
}

/// The episodes of a recording as the researcher's exports read them (Minari's
/// `to_minari`): `{"withdrawn": bool, "episodes": [...]}`, each episode a dict with its
/// `observations` (T + 1, encoded as `obs`), `actions`, `rewards`, `terminations`,
/// `truncations` (T each; an episode a crash or a mode switch cut short ends truncated),
/// `person` (the person chose the step), `t_ms` (milliseconds since the episode's first
/// view, -1 untimed) and `received_ms` (-1 untimed); and its `episode` number, `goal`
/// (text), `view`, `grid`, `blocks`, `started_ms`, `ended` (by its rules), `participant`
/// (a dict, or `None`) and `world` (`reward`, `protocol`, `start`, `horizon`, or `None`
/// before recording version 3; `start` is `uniform` in a version 3 recording). Every line is checked; a bad one (the last line a kill cut short)
/// is skipped, as the researcher's page does. Episodes without a step are left out. A
/// withdrawn participant's recording gives no episode (`withdrawn` says why) unless
/// `include_withdrawn`.
#[pyfunction]
#[pyo3(signature = (path, obs="planes", include_withdrawn=false))]
pub fn recording_episodes<'py>(
    py: Python<'py>,
    path: PathBuf,
    obs: &str,
    include_withdrawn: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = config::obs_kind(obs)?;
    let admission = agent::demos::Admission {
        world: None,
        include_withdrawn,
    };
    let mut read = read_in_thread(py, &path, |p| agent::demos::read_demonstrations(p, None))?;
    // The one rule of every reader: a withdrawn recording is left out unless an audit asks.
    let note = match admission.withdrawal(&path, read.withdrawn) {
        Ok(note) => note,
        Err(refused) => {
            read.episodes.clear();
            Some(refused.to_string())
        }
    };
    guard(|| {
        let out = PyDict::new(py);
        out.set_item("withdrawn", read.withdrawn)?;
        out.set_item("note", note)?;
        let episodes = pyo3::types::PyList::empty(py);
        for e in &read.episodes {
            if let Some(d) = episode_dict(py, kind, e)? {
                episodes.append(d)?;
            }
        }
        out.set_item("episodes", episodes)?;
        Ok(out)
    })
}

/// One episode of a recording as [`recording_episodes`] gives it, its observations encoded
/// as `kind`; `None` for an episode without a step.
fn episode_dict<'py>(
    py: Python<'py>,
    kind: ObsKind,
    e: &agent::demos::DemoEpisode,
) -> PyResult<Option<Bound<'py, PyDict>>> {
    let Some(last) = e.steps.last() else {
        return Ok(None);
    };
    let blocks = e.goal.block_count();
    let protocol = e.world.as_ref().map_or(sim::ActionProtocol::Free, |w| w.protocol);
    let first = Observation {
        grid: e.grid,
        state: e.start.clone(),
        goal: e.goal.clone(),
        protocol,
        view: e.view,
    };
    let observations: Vec<Observation> = std::iter::once(first.clone())
        .chain(e.steps.iter().map(|s| Observation {
            state: s.state.clone(),
            ..first.clone()
        }))
        .collect();
    let ended = last.terminated || last.truncated;
    let n = e.steps.len();
    let d = PyDict::new(py);
    d.set_item("observations", encode(py, kind, &observations, e.grid, blocks)?)?;
    d.set_item(
        "actions",
        PyArray1::from_vec(py, e.steps.iter().map(|s| s.action.index() as i64).collect()),
    )?;
    d.set_item(
        "rewards",
        PyArray1::from_vec(py, e.steps.iter().map(|s| s.reward).collect()),
    )?;
    d.set_item(
        "terminations",
        PyArray1::from_vec(py, e.steps.iter().map(|s| s.terminated).collect()),
    )?;
    // Cut short (a crash, the person switching modes): truncated at its last step.
    let truncations: Vec<bool> = e
        .steps
        .iter()
        .enumerate()
        .map(|(k, s)| s.truncated || (!ended && k + 1 == n))
        .collect();
    d.set_item("truncations", PyArray1::from_vec(py, truncations))?;
    d.set_item(
        "person",
        PyArray1::from_vec(py, e.steps.iter().map(|s| s.demonstrated).collect()),
    )?;
    let time = |f: fn(&agent::demos::DemoStep) -> Option<u64>| -> Vec<i64> {
        e.steps.iter().map(|s| f(s).map_or(-1, |t| t as i64)).collect()
    };
    d.set_item("t_ms", PyArray1::from_vec(py, time(|s| s.time.t_ms)))?;
    d.set_item("received_ms", PyArray1::from_vec(py, time(|s| s.time.received_ms)))?;
    d.set_item("episode", e.episode)?;
    d.set_item("goal", e.goal.to_string())?;
    d.set_item("view", e.view.to_string())?;
    d.set_item("grid", (e.grid.width(), e.grid.height()))?;
    d.set_item("blocks", blocks)?;
    d.set_item("started_ms", e.started_ms)?;
    d.set_item("ended", ended)?;
    match &e.participant {
        Some(p) => {
            let who = PyDict::new(py);
            who.set_item("number", p.number)?;
            who.set_item("condition", &p.condition)?;
            who.set_item("code", &p.code)?;
            who.set_item("ids", p.ids.clone())?;
            d.set_item("participant", who)?;
        }
        None => d.set_item("participant", py.None())?,
    }
    match &e.world {
        Some(w) => {
            let world = PyDict::new(py);
            world.set_item("reward", &w.reward)?;
            world.set_item("protocol", w.protocol.to_string())?;
            world.set_item("start", w.start.to_string())?;
            world.set_item("horizon", w.horizon)?;
            d.set_item("world", world)?;
        }
        None => d.set_item("world", py.None())?,
    }
    Ok(Some(d))
}

/// `read(path)` on a thread of its own, the caller checking for signals (Ctrl-C) every
/// 100 ms: opening a FIFO blocks until a writer comes, which no signal check inside the
/// reader could interrupt.
fn read_in_thread<T: Send + 'static>(
    py: Python<'_>,
    path: &std::path::Path,
    read: impl FnOnce(&std::path::Path) -> agent::Result<T> + Send + 'static,
) -> PyResult<T> {
    use std::sync::mpsc::{RecvTimeoutError, channel};
    let (sender, receiver) = channel();
    let owned = path.to_path_buf();
    std::thread::spawn(move || {
        let read = guard(|| read(&owned).or_value_error());
        // The caller may have gone (interrupted): nobody is left to tell.
        let _ = sender.send(read);
    });
    // Borrowed across the GIL's release, so it must be shareable.
    let receiver = std::sync::Mutex::new(receiver);
    loop {
        let wait = || {
            let receiver = receiver.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            receiver.recv_timeout(std::time::Duration::from_millis(100))
        };
        match py.detach(wait) {
            Ok(read) => return read,
            Err(RecvTimeoutError::Timeout) => py.check_signals()?,
            Err(RecvTimeoutError::Disconnected) => {
                return Err(value_error(format!(
                    "{}: the reader stopped without an answer",
                    path.display()
                )));
            }
        }
    }
}
