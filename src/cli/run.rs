//! `blockstack run`: play episodes with an agent.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use files::OutputPath;
use sim::trajectory::TrajectoryWriter;
use sim::{Env, GoalSpec};

use super::profile::{PlayRulesArgs, ProfileArg, played};
use super::solver_budget::SolverBudgetArg;
use super::stdout::line;
use super::world::WorldArgs;
use agent::eval::RunReport;
use agent::{
    ExactPolicy, LearnerProfile, OracleKind, OraclePolicy, PaperOraclePolicy, Policy, RandomPolicy, TowersPolicy,
};
use neural::AnyModel;

/// Which agent plays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AgentKind {
    /// Uniformly random legal actions.
    Random,
    /// An oracle: ours (centroid + A*) or the paper's (--oracle).
    Oracle,
    /// The exact solver: shortest plans.
    Exact,
    /// A trained tabular Q-learner, read from --model.
    Q,
    /// A trained network, read from --model (see `blockstack dqn`).
    Dqn,
}

/// Arguments of `blockstack run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The agent.
    #[arg(long, value_enum, default_value_t = AgentKind::Random)]
    pub agent: AgentKind,
    #[command(flatten)]
    pub world: WorldArgs,
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
    /// The model file the `q` or `dqn` agent plays (see `blockstack train`, `blockstack dqn`).
    #[arg(long, required_if_eq_any([("agent", "q"), ("agent", "dqn")]))]
    pub model: Option<PathBuf>,
    /// The `q` or `dqn` agent's probability of a random legal action [default: the paper's
    /// test policy: 0.1; 0 for a relational policy (`dqn --preset general`)]
    #[arg(long)]
    pub epsilon: Option<f64>,
    #[command(flatten)]
    pub budget: SolverBudgetArg,
}

/// Refuses, naming the flag, a flag given for an agent that does not use it (it would be
/// ignored, and the run would not be what was asked).
fn check_agent_flags(args: &RunArgs) -> Result<()> {
    let agent_flags: [(&str, bool, &[AgentKind]); 4] = [
        ("--model", args.model.is_some(), &[AgentKind::Q, AgentKind::Dqn]),
        ("--epsilon", args.epsilon.is_some(), &[AgentKind::Q, AgentKind::Dqn]),
        ("--oracle", args.oracle.is_some(), &[AgentKind::Oracle]),
        (
            "--solver-budget",
            args.budget.solver_budget.is_some(),
            &[AgentKind::Exact],
        ),
    ];
    for (flag, given, owners) in agent_flags {
        anyhow::ensure!(
            !given || owners.contains(&args.agent),
            "{flag} does not apply to --agent {}: it is for --agent {} only",
            args.agent.name(),
            owners.iter().map(|o| o.name()).collect::<Vec<_>>().join(" or ")
        );
    }
    Ok(())
}

impl AgentKind {
    /// The name `--agent` takes.
    fn name(self) -> String {
        self.to_possible_value()
            .expect("no variant is skipped")
            .get_name()
            .to_string()
    }
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
    let model = match (args.agent, &args.model) {
        (AgentKind::Q | AgentKind::Dqn, Some(path)) => {
            let model = super::eval::load_model(path)?;
            match (args.agent, &model) {
                (AgentKind::Q, AnyModel::Q(_))
                | (AgentKind::Dqn, AnyModel::Dqn(_))
                | (AgentKind::Dqn, AnyModel::Relational(_)) => {}
                _ => anyhow::bail!(
                    "{} holds a {} model, not what --agent {} plays",
                    path.display(),
                    model.name(),
                    if args.agent == AgentKind::Q { "q" } else { "dqn" }
                ),
            }
            Some(model)
        }
        _ => None,
    };
    // A model's own world unless the command line says otherwise.
    let base = model
        .as_ref()
        .map_or(sim::ProfileParts::of(sim::Profile::Spec), neural::AnyModel::parts);
    let rules = played(base, args.profile, args.play, args.world.reward.as_deref())?;
    let trained_in = model.as_ref().map(|m| m.world().view);
    let config = args.world.config(&rules, trained_in.unwrap_or_default())?;
    if let Some(m) = &model {
        m.check_world(config.grid, config.blocks)?;
    }
    // A model plays the world it learnt.
    if let Some(view) = trained_in.filter(|&v| v != config.view) {
        anyhow::bail!(
            "the model learnt the {view} view; it cannot play the {} view (leave --view out to play its own)",
            config.view
        );
    }
    let oracle = args.oracle.unwrap_or(LearnerProfile::of(rules.profile).oracle);
    let side = config.view == sim::View::Side;
    let mut policy: Box<dyn Policy + '_> = match (args.agent, &model) {
        (AgentKind::Random, _) => Box::new(RandomPolicy),
        (AgentKind::Exact, _) if side => Box::new(TowersPolicy::new(oracle::towers::MovePlanner::Exact)),
        (AgentKind::Oracle, _) if side => Box::new(TowersPolicy::new(oracle::towers::MovePlanner::NearOptimal)),
        (AgentKind::Oracle, _) => match oracle {
            OracleKind::Astar => Box::new(OraclePolicy::new(config.grid)),
            OracleKind::Paper => Box::new(PaperOraclePolicy::new(config.grid)),
        },
        (AgentKind::Exact, _) => Box::new(ExactPolicy::with_planner(args.budget.solver(config.grid))),
        (AgentKind::Q | AgentKind::Dqn, Some(m)) => {
            // A relational policy plays greedily unless asked: it is measured greedy.
            let default = match m {
                AnyModel::Relational(_) => 0.0,
                _ => agent::profile::TEST_EPSILON,
            };
            m.policy(args.epsilon.unwrap_or(default))?
        }
        (AgentKind::Q | AgentKind::Dqn, None) => anyhow::bail!("--agent q and --agent dqn need --model FILE"),
    };
    let mut env = Env::new(config)?;
    let mut trajectory = trajectory_out.as_ref().map(TrajectoryWriter::create).transpose()?;
    let bar = super::progress::bar(args.episodes, "episodes");
    let results = agent::rollout::play_observed(
        &mut env,
        policy.as_mut(),
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
    let goal = match config.goal {
        GoalSpec::Fixed(g) => Some(g.to_string()),
        GoalSpec::Random => None,
    };
    // No timings, so two runs compare equal; `eval --json` holds the same fields and more.
    let report = RunReport::new(policy.name(), &config, rules.profile, goal, args.seed, &results);
    if args.json {
        line(serde_json::to_string(&report)?)
    } else {
        print_report(&report)
    }
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
