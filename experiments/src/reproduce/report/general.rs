//! E10's tables in the report: the general policy on uniform problems by size, on a few
//! blocks against the fewest moves, and on Neural Logic Machines' generator beside their
//! published figures.

use std::fmt::Write as _;

use super::{cells, markdown_table};
use crate::reproduce::text::num;
use crate::reproduce::{General, SizeFigures};

/// E10's tables: the uniform problems by size, those of a few blocks against the fewest
/// moves, and NLM's generator beside NLM's figures.
pub(super) fn tables(md: &mut String, g: &General) {
    let solved = |r: &SizeFigures| format!("{:.1}%", 100.0 * r.success);
    let _ = writeln!(md, "\n### Uniform problems, by number of blocks\n");
    let head = cells([
        "blocks",
        "problems",
        "solved",
        "policy: mean moves",
        "near-optimal: mean moves",
        "× near-optimal",
        "worst × near-optimal",
        "optimum proven",
        "policy × optimum",
        "near-optimal × optimum",
    ]);
    let rows = g.uniform.iter().map(|r| {
        vec![
            r.blocks.to_string(),
            r.problems.to_string(),
            solved(r),
            num(r.mean_moves, 2),
            num(r.near_optimal_moves, 2),
            num(r.near_optimal_ratio, 4),
            num(r.worst_ratio, 3),
            format!("{}%", num(Some(100.0 * r.proven), 1)),
            num(r.optimum_ratio, 4),
            num(r.near_optimal_optimum_ratio, 4),
        ]
    });
    markdown_table(md, &head, rows);
    let _ = writeln!(md, "\n### A few blocks, against the fewest moves\n");
    let head = cells([
        "blocks",
        "problems",
        "solved",
        "fewest moves",
        "policy × fewest",
        "near-optimal × fewest",
    ]);
    let rows = g.exact.iter().map(|r| {
        vec![
            r.blocks.to_string(),
            r.problems.to_string(),
            solved(r),
            num(r.fewest_moves, 2),
            num(r.fewest_ratio, 4),
            num(r.near_optimal_fewest_ratio, 4),
        ]
    });
    markdown_table(md, &head, rows);
    let _ = writeln!(md, "\n### Neural Logic Machines' generator\n");
    let head = cells([
        "blocks",
        "problems",
        "solved",
        "policy: mean moves",
        "near-optimal: mean moves",
        "NLM (published): solved",
        "NLM: mean moves",
    ]);
    let rows = g.nlm.iter().map(|r| {
        vec![
            r.blocks.to_string(),
            r.problems.to_string(),
            solved(r),
            num(r.mean_moves, 2),
            num(r.near_optimal_moves, 2),
            r.published.map_or("-".into(), |p| format!("{:.0}%", 100.0 * p.0)),
            num(r.published.map(|p| p.1), 1),
        ]
    });
    markdown_table(md, &head, rows);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reproduce::e10::TrainingFigures;

    fn size(blocks: usize, fewest: Option<f64>, published: Option<(f64, f64)>) -> SizeFigures {
        SizeFigures {
            blocks,
            problems: 4,
            success: 0.75,
            mean_moves: Some(12.0),
            near_optimal_moves: Some(13.5),
            near_optimal_ratio: Some(0.888_888),
            worst_ratio: None,
            fewest_moves: fewest,
            fewest_ratio: fewest.map(|f| 12.0 / f),
            near_optimal_fewest_ratio: fewest.map(|f| 13.5 / f),
            proven: 1.0,
            optimum_moves: fewest,
            optimum_ratio: fewest.map(|f| 12.0 / f),
            near_optimal_optimum_ratio: fewest.map(|f| 13.5 / f),
            published,
        }
    }

    #[test]
    fn e10s_tables_read_as_the_report_has_them() {
        let g = General {
            training: TrainingFigures {
                config: neural::relational::RelationalConfig::general(),
                examples: 0,
                last_success: 0.0,
                last_moves_ratio: 0.0,
            },
            uniform: vec![size(10, None, None)],
            exact: vec![size(4, Some(8.0), None)],
            nlm: vec![size(12, None, Some((1.0, 20.3))), size(50, None, None)],
        };
        let mut md = String::new();
        tables(&mut md, &g);
        assert_eq!(
            md,
            "\n### Uniform problems, by number of blocks\n\n\
             | blocks | problems | solved | policy: mean moves | near-optimal: mean moves | × near-optimal | worst × \
             near-optimal | optimum proven | policy × optimum | near-optimal × optimum |\n\
             |---|---|---|---|---|---|---|---|---|---|\n\
             | 10 | 4 | 75.0% | 12.00 | 13.50 | 0.8889 | - | 100.0% | - | - |\n\
             \n### A few blocks, against the fewest moves\n\n\
             | blocks | problems | solved | fewest moves | policy × fewest | near-optimal × fewest |\n\
             |---|---|---|---|---|---|\n\
             | 4 | 4 | 75.0% | 8.00 | 1.5000 | 1.6875 |\n\
             \n### Neural Logic Machines' generator\n\n\
             | blocks | problems | solved | policy: mean moves | near-optimal: mean moves | NLM (published): solved | \
             NLM: mean moves |\n|---|---|---|---|---|---|---|\n\
             | 12 | 4 | 75.0% | 12.00 | 13.50 | 100% | 20.3 |\n\
             | 50 | 4 | 75.0% | 12.00 | 13.50 | - | - |\n"
        );
    }
}
