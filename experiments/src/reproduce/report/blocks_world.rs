//! E9's tables in the report: the problems grouped by stacking steps, blocks and goal
//! towers, each agent's figures beside the planners', and the physics against the grid
//! model.

use std::fmt::Write as _;

use super::{cells, markdown_table};
use crate::reproduce::text::num;
use crate::reproduce::{BlocksWorld, Group};

/// E9's tables: the problems grouped three ways, and physics against the grid model.
pub(super) fn tables(md: &mut String, w: &BlocksWorld) {
    let grid = |blocks: usize| {
        let g = crate::reproduce::e9::grid_for(blocks);
        format!("{} x {}", g.width(), g.height())
    };
    groups(
        md,
        "By stacking steps (the fewest block moves)",
        "stacking steps",
        &w.by_stacking_steps,
        None,
    );
    groups(md, "By number of blocks", "blocks", &w.by_blocks, Some(&grid));
    groups(md, "By number of goal towers", "towers", &w.by_towers, None);
    let _ = writeln!(md, "\n### Physics against the grid model\n");
    let head = cells([
        "blocks",
        "grid",
        "episodes",
        "same starts",
        "random steps",
        "same outcome",
        "drops",
        "landed on the same cell",
        "physics errors",
    ]);
    let rows = w.agreement.iter().map(|a| {
        vec![
            a.blocks.to_string(),
            a.grid.clone(),
            a.episodes.to_string(),
            a.same_starts.to_string(),
            a.steps.to_string(),
            a.same_steps.to_string(),
            a.drops.to_string(),
            a.same_landings.to_string(),
            a.physics_errors.to_string(),
        ]
    });
    markdown_table(md, &head, rows);
    for e in w.agreement.iter().filter_map(|a| a.first_error.as_ref()) {
        let _ = writeln!(md, "\nThe first physics error: {e}.");
    }
}

/// A table of E9's groups, keyed by `key`, with a grid column when `grid` is given. Block
/// moves and gripper steps are over the games that reached the goal.
fn groups(md: &mut String, title: &str, key: &str, groups: &[Group], grid: Option<&dyn Fn(usize) -> String>) {
    let _ = writeln!(md, "\n### {title}\n");
    let mut agents: Vec<&str> = Vec::new();
    for a in groups.iter().flat_map(|g| &g.agents) {
        if !agents.contains(&a.agent.as_str()) {
            agents.push(&a.agent);
        }
    }
    let mut head = vec![key.to_string()];
    if grid.is_some() {
        head.push("grid".into());
    }
    head.extend(
        [
            "problems",
            "fewest moves",
            "near-optimal plan",
            "× fewest (worst)",
            "fewest gripper steps",
        ]
        .map(String::from),
    );
    for a in &agents {
        head.extend(
            ["reached", "moves × fewest", "gripper steps", "steps × fewest"].map(|figure| format!("{a}: {figure}")),
        );
    }
    let rows = groups.iter().map(|g| {
        let mut cells = vec![g.key.to_string()];
        if let Some(grid) = grid {
            cells.push(grid(g.key));
        }
        cells.extend([
            g.problems.to_string(),
            num(Some(g.fewest_moves), 2),
            num(Some(g.near_optimal_moves), 2),
            format!(
                "{} ({})",
                num(Some(g.near_optimal_ratio), 3),
                num(Some(g.near_optimal_worst), 2)
            ),
            num(g.fewest_steps, 1),
        ]);
        for a in &agents {
            match g.agents.iter().find(|f| f.agent == *a) {
                Some(f) => cells.extend([
                    format!("{:.1}%", 100.0 * f.success),
                    num(f.moves_ratio, 3),
                    num(f.mean_steps, 1),
                    num(f.steps_ratio, 3),
                ]),
                None => cells.extend(["-".to_string(), "-".into(), "-".into(), "-".into()]),
            }
        }
        cells
    });
    markdown_table(md, &head, rows);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reproduce::e9::{AgentFigures, Agreement};

    #[test]
    fn e9s_tables_read_as_the_report_has_them() {
        let agent = |name: &str| AgentFigures {
            agent: name.into(),
            games: 2,
            success: 0.5,
            mean_moves: Some(3.0),
            moves_ratio: Some(1.25),
            mean_steps: Some(14.0),
            steps_ratio: None,
            physics_errors: 0,
        };
        let group = |key: usize, agents: Vec<AgentFigures>| Group {
            key,
            problems: 2,
            fewest_moves: 2.5,
            near_optimal_moves: 3.0,
            near_optimal_ratio: 1.2,
            near_optimal_worst: 1.5,
            fewest_steps: None,
            agents,
        };
        let w = BlocksWorld {
            problems_per_cell: 2,
            backend: sim::Backend::Physics,
            by_blocks: vec![
                group(3, vec![agent("exact"), agent("learner")]),
                group(4, vec![agent("exact")]),
            ],
            by_towers: vec![group(1, vec![agent("exact")])],
            by_stacking_steps: vec![group(2, vec![agent("exact")])],
            agreement: vec![Agreement {
                blocks: 3,
                grid: "3 x 4".into(),
                episodes: 5,
                same_starts: 5,
                steps: 100,
                same_steps: 99,
                drops: 20,
                same_landings: 19,
                physics_errors: 1,
                first_error: Some("episode 7, step 3: not at rest".into()),
            }],
            problems: Vec::new(),
        };
        let mut md = String::new();
        tables(&mut md, &w);
        let exact = "| exact: reached | exact: moves × fewest | exact: gripper steps | exact: steps × fewest";
        let figures = "| problems | fewest moves | near-optimal plan | × fewest (worst) | fewest gripper steps ";
        let played = "| 50.0% | 1.250 | 14.0 | - |";
        let grid = |n: usize| {
            let g = crate::reproduce::e9::grid_for(n);
            format!("{} x {}", g.width(), g.height())
        };
        let expected = format!(
            "\n### By stacking steps (the fewest block moves)\n\n\
             | stacking steps {figures}{exact} |\n|---|---|---|---|---|---|---|---|---|---|\n\
             | 2 | 2 | 2.50 | 3.00 | 1.200 (1.50) | - {played}\n\
             \n### By number of blocks\n\n\
             | blocks | grid {figures}{exact} | learner: reached | learner: moves × fewest | learner: gripper steps | \
             learner: steps × fewest |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n\
             | 3 | {} | 2 | 2.50 | 3.00 | 1.200 (1.50) | - {played} 50.0% | 1.250 | 14.0 | - |\n\
             | 4 | {} | 2 | 2.50 | 3.00 | 1.200 (1.50) | - {played} - | - | - | - |\n\
             \n### By number of goal towers\n\n\
             | towers {figures}{exact} |\n|---|---|---|---|---|---|---|---|---|---|\n\
             | 1 | 2 | 2.50 | 3.00 | 1.200 (1.50) | - {played}\n\
             \n### Physics against the grid model\n\n\
             | blocks | grid | episodes | same starts | random steps | same outcome | drops | landed on the same cell | \
             physics errors |\n|---|---|---|---|---|---|---|---|---|\n\
             | 3 | 3 x 4 | 5 | 5 | 100 | 99 | 20 | 19 | 1 |\n\
             \nThe first physics error: episode 7, step 3: not at rest.\n",
            grid(3),
            grid(4)
        );
        assert_eq!(md, expected);
    }
}
