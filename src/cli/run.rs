//! `blockstack run`: play episodes with an agent.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;
use files::OutputPath;
use oracle::pddl::{Problem, SideTask};
use sim::trajectory::TrajectoryWriter;
use sim::{Env, EnvConfig, GoalSpec, View};

use super::profile::{PlayRulesArgs, ProfileArg, played};
use super::solver_budget::SolverBudgetArg;
use super::stdout::line;
use super::world::{GoalArg, WorldArgs};
use agent::eval::RunReport;
use agent::{EpisodeStart, OracleKind, PlayingModel, PolicyKind, PolicyOptions};
use neural::AnyModel;

/// Arguments of `blockstack run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The agent: random, oracle (the view's: ours or the paper's from above, --oracle; the
    /// near-optimal planner from the side), exact (the fewest gripper steps, in either view),
    /// exact-moves (the fewest block moves carried out by the gripper; side view),
    /// near-optimal (the near-optimal block-move planner carried out; side view), q (a
    /// tabular model, --model), dqn (a network, --model) or relational (a relational policy,
    /// `dqn --preset general`, --model; `dqn` plays one too, as earlier releases named it).
    #[arg(long, default_value = "random")]
    pub agent: PolicyKind,
    #[command(flatten)]
    pub world: WorldArgs,
    #[command(flatten)]
    pub goal: GoalArg,
    #[command(flatten)]
    pub profile: ProfileArg,
    #[command(flatten)]
    pub play: PlayRulesArgs,
    /// The oracle `--agent oracle` plays: astar (ours) or paper (the authors' greedy walker)
    /// [default: the profile's: astar under spec, paper under original]
    #[arg(long)]
    pub oracle: Option<OracleKind>,
    /// Episodes to play.
    #[arg(long, default_value_t = 100)]
    pub episodes: u64,
    /// Base seed: episode k starts from seed episode_seed(seed, k).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write every episode, step by step, to this file as JSON Lines (`-`: standard
    /// output).
    #[arg(long)]
    pub trajectory: Option<PathBuf>,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// The model file the `q`, `dqn` or `relational` agent plays (see `blockstack train`,
    /// `blockstack dqn`).
    #[arg(long, required_if_eq_any([("agent", "q"), ("agent", "dqn"), ("agent", "relational")]))]
    pub model: Option<PathBuf>,
    /// A trained agent's probability of a random legal action [default: the model's own:
    /// its profile's test policy, 0.1, for a tabular model or a network; 0 for a relational
    /// policy]
    #[arg(long)]
    pub epsilon: Option<f64>,
    #[command(flatten)]
    pub budget: SolverBudgetArg,
    /// Play a Blocks World problem in PDDL (the planning competitions' 4-operator domain)
    /// in the side view: every episode starts from its start state towards its goal, on the
    /// side view's default grid for its blocks. A task whose start already meets its goal
    /// has no episode to play and is refused.
    #[arg(long, value_name = "PROBLEM.pddl", conflicts_with_all = ["goal", "blocks", "grid", "start"])]
    pub pddl: Option<PathBuf>,
}

/// The agents that play a model file.
const MODEL_AGENTS: [PolicyKind; 3] = [PolicyKind::Q, PolicyKind::Dqn, PolicyKind::Relational];

/// Refuses, naming the flag, a flag given for an agent that does not use it (it would be
/// ignored, and the run would not be what was asked).
fn check_agent_flags(args: &RunArgs) -> Result<()> {
    let agent_flags: [(&str, bool, &[PolicyKind]); 4] = [
        ("--model", args.model.is_some(), &MODEL_AGENTS),
        ("--epsilon", args.epsilon.is_some(), &MODEL_AGENTS),
        ("--oracle", args.oracle.is_some(), &[PolicyKind::Oracle]),
        (
            "--solver-budget",
            args.budget.solver_budget.is_some(),
            &[PolicyKind::Exact],
        ),
    ];
    for (flag, given, owners) in agent_flags {
        let names: Vec<&str> = owners.iter().map(|o| o.name()).collect();
        let owners = match names.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => names.concat(),
        };
        anyhow::ensure!(
            !given || names.contains(&args.agent.name()),
            "{flag} does not apply to --agent {}: it is for --agent {owners} only",
            args.agent.name()
        );
    }
    Ok(())
}

/// Plays the episodes and prints the summary.
pub fn run(args: RunArgs) -> Result<()> {
    check_agent_flags(&args)?;
    // No episodes, no figures: a mean over nothing would print as -0.00.
    anyhow::ensure!(args.episodes > 0, "--episodes 0: play at least 1 episode");
    let trajectory_out = args.trajectory.as_deref().map(OutputPath::check).transpose()?;
    super::stdout::claim_for_data(&[trajectory_out.as_ref()])?;
    if let (Some(out), Some(model)) = (&args.trajectory, &args.model) {
        files::refuse_same_file(out, model).context("--trajectory and --model")?;
    }
    let model = match &args.model {
        Some(path) => {
            let model = super::eval::load_model(path)?;
            anyhow::ensure!(
                args.agent.plays(model.kind()),
                "{} holds a {} model, not what --agent {} plays",
                path.display(),
                model.name(),
                args.agent
            );
            Some(model)
        }
        None => None,
    };
    // A model's own world unless the command line says otherwise.
    let base = model
        .as_ref()
        .map_or(sim::ProfileParts::of(sim::Profile::Spec), neural::AnyModel::parts);
    let rules = played(base, args.profile, args.play, args.world.reward);
    let trained_in = model.as_ref().map(AnyModel::world);
    // A model's size and view unless the flags say otherwise (and then it is refused); the
    // backend and horizon are the command's own defaults.
    let base = trained_in.map_or_else(EnvConfig::default, |w| EnvConfig {
        grid: w.grid,
        blocks: w.blocks,
        view: w.view,
        ..EnvConfig::default()
    });
    let task = args
        .pddl
        .as_deref()
        .map(|path| pddl_task(path, &args.world))
        .transpose()?;
    let config = match &task {
        Some(task) => task_config(task, &args.world, base, &rules)?,
        None => args.world.config(base, &rules, args.goal.goal.as_deref())?,
    };
    if let Some(m) = &model {
        m.check_world(config.grid, config.blocks)?;
        // A model plays the world it learnt.
        m.check_view(config.view)
            .map_err(|e| anyhow::anyhow!("{e} (leave --view out to play its own)"))?;
    }
    let options = PolicyOptions {
        // The model's own unless asked (the default-play rule, `neural::any`).
        epsilon: args.epsilon.unwrap_or(
            model
                .as_ref()
                .map_or(agent::profile::TEST_EPSILON, AnyModel::default_epsilon),
        ),
        oracle: args.oracle.unwrap_or(PolicyOptions::of_profile(rules.profile).oracle),
        node_budget: args.budget.budget(),
    };
    let model: Option<&dyn PlayingModel> = model.as_ref().map(|m| m as &dyn PlayingModel);
    let mut policy = args
        .agent
        .policy(&config, model, &options)
        .with_context(|| format!("--agent {}", args.agent))?;
    let mut env = Env::new(config.clone())?;
    let mut trajectory = trajectory_out.as_ref().map(TrajectoryWriter::create).transpose()?;
    let bar = super::progress::bar(args.episodes, "episodes");
    if let Some(task) = &task {
        warn_short_horizon(task, &config)?;
    }
    let start = task
        .as_ref()
        .map_or(EpisodeStart::Drawn, |t| EpisodeStart::Given(&t.start, &t.goal));
    let results = agent::rollout::play_observed(
        &mut env,
        policy.as_mut(),
        start,
        args.episodes,
        args.seed,
        &mut trajectory,
        &mut |_| bar.inc(1),
    )
    .map_err(|e| args.budget.explain(e))?;
    bar.finish_and_clear();
    if let Some(t) = trajectory {
        t.finish()?;
    }
    let goal = match &config.goal {
        GoalSpec::Fixed(g) => Some(g.to_string()),
        GoalSpec::Random => None,
    };
    // No timings, so two runs compare equal; `eval --json` holds the same fields and more.
    let mut report = RunReport::new(policy.name(), &config, rules.profile, goal, args.seed, &results);
    if let Some(path) = &args.pddl {
        // Not the start rule's draw: every episode began at the task's start.
        report.start = "pddl".into();
        // The task's goal, not its towers: a 2,000-block goal is a line of 8 KB.
        report.goal = Some(format!("the task's ({})", path.display()));
    }
    if args.json {
        line(serde_json::to_string(&report)?)?;
    } else {
        print_report(&report)?;
    }
    if args.agent == PolicyKind::Exact && config.view == sim::View::Side {
        // Before this release `exact` played the fewest block moves here: say where that went.
        let _ = writeln!(
            std::io::stderr(),
            "blockstack: note: --agent exact plays the fewest gripper steps in the side view too; \
             --agent exact-moves plays the fewest block moves (what --agent exact played here before)"
        );
    }
    Ok(())
}

/// The side-view task of the problem file at `path`; `--view top` is refused (a problem
/// is a side-view task; `--blocks`, `--grid` and `--goal` are refused by clap).
fn pddl_task(path: &Path, world: &WorldArgs) -> Result<SideTask> {
    anyhow::ensure!(
        world.view.is_none_or(|v| v == View::Side),
        "--pddl plays its task in the side view: leave out --view top"
    );
    let problem = Problem::read(path)?;
    problem.side_task().with_context(|| format!("{}", path.display()))
}

/// Says on standard error when the horizon is shorter than the near-optimal planner's plan
/// of `task` in gripper steps (what `--agent near-optimal` plays): its episodes would be
/// cut off before the goal, and every one counted a failure.
fn warn_short_horizon(task: &SideTask, config: &EnvConfig) -> Result<()> {
    let solver = oracle::ExactSolver::new(config.grid).with_view(View::Side);
    let steps = oracle::PlannerKind::NearOptimal
        .plan_steps(&solver, &task.start, &task.goal)?
        .len();
    if (config.horizon as usize) < steps {
        let _ = writeln!(
            std::io::stderr(),
            "blockstack: note: the horizon of {} steps is shorter than the near-optimal plan of this task ({steps} steps), \
             so episodes end before the goal: give --horizon {steps} or more",
            config.horizon
        );
    }
    Ok(())
}

/// The world of `task` (its blocks, grid and goal, the side view), the other flags over
/// `base` as for any run, checked.
fn task_config(task: &SideTask, world: &WorldArgs, base: EnvConfig, rules: &sim::ProfileParts) -> Result<EnvConfig> {
    let world = WorldArgs {
        blocks: Some(task.start.block_count()),
        grid: Some(task.grid),
        view: Some(View::Side),
        ..*world
    };
    let mut config = world.config(base, rules, None)?;
    config.goal = GoalSpec::Fixed(task.goal.clone());
    config.validate()?;
    Ok(config)
}

fn print_report(r: &RunReport) -> Result<()> {
    let s = &r.summary;
    line(format_args!(
        "agent {}, {} blocks, goal {}, grid {}, horizon {}, {} backend, seed {}; profile {} (protocol {}, start {})",
        r.agent,
        r.blocks,
        r.goal.as_deref().unwrap_or("random"),
        r.grid,
        r.horizon,
        r.backend,
        r.seed,
        r.profile,
        r.protocol,
        r.start
    ))?;
    line(format_args!("episodes      {}", s.episodes))?;
    line(format_args!("failures      {}", s.failures))?;
    let fmt = |v: Option<f64>| v.map_or("- (no episode reached the goal)".to_string(), |v| format!("{v:.2}"));
    line(format_args!("mean steps    {}", fmt(s.mean_steps)))?;
    line(format_args!("median steps  {}", fmt(s.median_steps)))?;
    line(format_args!(
        "mean steps, a failure counted as the horizon  {:.2}",
        r.mean_steps_failures_as_horizon
    ))
}
