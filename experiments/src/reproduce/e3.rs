//! E3: unseen goals. The paper's learner trains on four goals and is tested on the other
//! two, against the random agent, with a two-sample Kolmogorov-Smirnov test (paper section
//! VI-B1). Our learner, trained on one goal only, is tested on the same games.

use agent::{QAgent, RandomPolicy};

use super::arms::{ArmResult, Goals, Row, Suite, Table, TestOutcome, mean_of, play_replicates};
use super::text::{num, p_value, significance};
use super::{Context, Experiment, HORIZON, Result, Scale, Setting, goals, paper, paper_learner};

/// Jobs reported: the trainings and their suites, the random agent's and ours (twice).
pub(super) fn jobs(scale: &Scale) -> u64 {
    2 * scale.replicates as u64 + 3
}

/// Runs E3 with our trained learner `ours`.
pub(super) fn run(ctx: &Context, ours: &QAgent) -> Result<Experiment> {
    let train_goals = goals(&paper::E3_TRAIN_GOALS);
    let trained = ctx.train_replicates("E3", |r| ctx.paper_config(&train_goals, r))?;
    let suite = Suite {
        blocks: 3,
        goals: Goals::Each(goals(&paper::E3_TEST_GOALS)),
        episodes: ctx.scale.e3_games_per_goal,
        seed: ctx.seeds.test,
        horizon: HORIZON,
    };
    let optimum = suite.optimum()?;
    let eps = ctx.test_epsilon();
    let q = play_replicates(
        &suite,
        &trained,
        |t| Ok(Box::new(t.agent.policy(eps)?)),
        ctx.progress,
        "E3",
    )?;
    let q = ArmResult::of(
        "Q-learning (paper's)",
        "the paper's learner trained on 0,1,2 1,0,2 2,0,1 0,2,1",
        Some(eps),
        &q,
        &optimum,
        HORIZON,
    );
    let random = suite.play(&mut RandomPolicy)?;
    ctx.progress.advance("E3");
    let random = ArmResult::of("random", "uniformly random actions", None, &[random], &optimum, HORIZON);
    let mut ours_arms = Vec::new();
    for epsilon in [eps, 0.0] {
        let results = suite.play(&mut ours.policy(epsilon)?)?;
        ctx.progress.advance("E3");
        ours_arms.push(ArmResult::of(
            if epsilon > 0.0 {
                "ours (role + step-cost)".to_string()
            } else {
                "ours (role + step-cost), greedy".to_string()
            },
            "our learner trained on 0,1,2 only",
            Some(epsilon),
            &[results],
            &optimum,
            HORIZON,
        ));
    }
    let ks_q = TestOutcome::ks(&q, &random)?;
    let ks_ours = TestOutcome::ks(&ours_arms[0], &random)?;
    let theirs = paper::E3.rows;
    let reading = format!(
        "On the unseen goals the paper's learner failed {} of {} games against the random agent's {} (paper: {} \
         and {} of {}); the Kolmogorov-Smirnov test finds the difference {} (paper: p = {}). Ours, trained on one \
         goal, failed {} with mean {} steps ({}x the shortest plan).",
        num(Some(q.failures), 1),
        q.games,
        num(Some(random.failures), 0),
        theirs[0].failures.unwrap_or_default(),
        theirs[1].failures.unwrap_or_default(),
        theirs[1].games.unwrap_or_default(),
        significance(ks_q.p_value),
        p_value(theirs[0].p_value.unwrap_or_default()),
        num(Some(ours_arms[0].failures), 0),
        num(ours_arms[0].mean_steps, 1),
        num(ours_arms[0].mean_ratio_to_optimum, 2),
    );
    let config = ctx.paper_config(&train_goals, 0);
    let mut rows = vec![
        Row {
            ours: q,
            paper: Some(theirs[0]),
            tests: vec![Some(ks_q)],
        },
        Row {
            ours: random,
            paper: Some(theirs[1]),
            tests: vec![None],
        },
    ];
    let mut ours_arms = ours_arms.into_iter();
    rows.push(Row {
        ours: ours_arms.next().expect("two arms"),
        paper: None,
        tests: vec![Some(ks_ours)],
    });
    rows.push(Row {
        ours: ours_arms.next().expect("two arms"),
        paper: None,
        tests: vec![None],
    });
    Ok(Experiment {
        id: "E3".into(),
        title: "Unseen goals".into(),
        setup: vec![
            Setting {
                name: "paper's learner".into(),
                value: format!(
                    "{}, {} training games on \
                     0,1,2 1,0,2 2,0,1 0,2,1 in turn, physics backend; {} agents, training seeds {:?}",
                    paper_learner(&config),
                    config.games,
                    ctx.scale.replicates,
                    ctx.seeds.training
                ),
            },
            Setting {
                name: "our learner".into(),
                value: ours_description(ours),
            },
            Setting {
                name: "games".into(),
                value: format!("{} (the paper's 100), per agent", suite.describe()),
            },
            Setting {
                name: "test policy".into(),
                value: format!("random action with probability {eps} (the paper's); ours also greedy"),
            },
            Setting {
                name: "mean optimum".into(),
                value: format!("{} steps from these starts", num(mean_of(&optimum), 2)),
            },
            Setting {
                name: "test".into(),
                value: "two-sample Kolmogorov-Smirnov against the random agent, on steps with a failure counted as \
                        1000 (the paper's)"
                    .into(),
            },
        ],
        tables: vec![Table {
            title: "Unseen goals 2,1,0 and 1,2,0".into(),
            suite: suite.describe(),
            paper: Some(paper::E3),
            tests: vec!["KS vs random".into()],
            rows,
        }],
        curves: Vec::new(),
        reading,
        figures: Vec::new(),
    })
}

/// What our learner is, from its recorded training.
pub(super) fn ours_description(ours: &QAgent) -> String {
    match ours.training() {
        Some(t) => {
            let replays: Vec<&str> = [(t.backward_replay, "backward replay"), (t.final_replay, "final replay")]
                .iter()
                .filter(|(on, _)| *on)
                .map(|&(_, name)| name)
                .collect();
            format!(
                "{} representation, {} reward, alpha {}, gamma {}, epsilon {}{}, {} training games on {} (seed {}), \
                 {} backend",
                t.repr,
                t.reward,
                t.params.alpha,
                t.params.gamma,
                t.params.epsilon,
                replays.iter().map(|r| format!(", {r}")).collect::<String>(),
                t.games,
                t.goals.iter().map(ToString::to_string).collect::<Vec<_>>().join(" "),
                t.seed,
                t.backend
            )
        }
        None => ours.name(),
    }
}
