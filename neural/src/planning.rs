//! The planner of a block-move task chosen by name or by model file, in one place for every
//! front end (`blockstack solve --pddl`, `solve-all`, Python's `solve_pddl` and
//! `solve_all`): a planner of `oracle` named as [`oracle::PlannerKind`] names it, with the
//! options that apply to it, or a learned relational policy read from its file, played
//! greedily. It lives here because only this crate can read a model file and sees `oracle`.

use std::path::Path;

use oracle::towers::BlockPlanner;
use oracle::{PlanOptions, PlannerKind};

use crate::any::AnyModel;
use crate::error::{NeuralError, Result};

/// The planner a task is planned with when none is named: the near-optimal one (fast at any
/// size; the optimal solver proves, and may take its time limit).
pub const DEFAULT_PLANNER: PlannerKind = PlannerKind::NearOptimal;

/// What plans a task: a planner named `solver` (the default, [`DEFAULT_PLANNER`], if
/// `None`) with `options`, or the relational policy in the model file `model` (which takes
/// no planner option). An error for a model and a planner both named, an option that does
/// not apply, or a model file that is not a relational policy.
pub fn block_planner(
    solver: Option<PlannerKind>,
    model: Option<&Path>,
    options: &PlanOptions,
) -> Result<Box<dyn BlockPlanner>> {
    let Some(path) = model else {
        return Ok(solver.unwrap_or(DEFAULT_PLANNER).block_planner(options)?);
    };
    if let Some(solver) = solver {
        return Err(NeuralError::Mismatch(format!(
            "a task is planned by a planner or by a model, not both: {solver} and {}",
            path.display()
        )));
    }
    if *options != PlanOptions::default() {
        return Err(NeuralError::Mismatch(
            "a search budget or a time limit is a planner's: a learned policy takes neither".into(),
        ));
    }
    match AnyModel::load(path)? {
        AnyModel::Relational(policy) => Ok(policy as Box<dyn BlockPlanner>),
        other => Err(NeuralError::Mismatch(format!(
            "{} holds a {} model: a task of block moves is played by a relational policy \
             (blockstack dqn --preset general)",
            path.display(),
            other.name()
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_planner_is_named_or_a_model_given_never_both() {
        let planner = block_planner(None, None, &PlanOptions::default()).unwrap();
        assert_eq!(planner.name(), "near-optimal");
        let optimal = block_planner(Some(PlannerKind::Optimal), None, &PlanOptions::default()).unwrap();
        assert_eq!(optimal.name(), "optimal");
        let both = block_planner(
            Some(PlannerKind::Exact),
            Some(Path::new("m.net")),
            &PlanOptions::default(),
        );
        assert!(both.err().unwrap().to_string().contains("not both"));
        let budget = PlanOptions {
            budget: Some(5),
            ..PlanOptions::default()
        };
        let err = block_planner(None, Some(Path::new("m.net")), &budget)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("takes neither"), "{err}");
        let missing = block_planner(None, Some(Path::new("/nonexistent/m.net")), &PlanOptions::default());
        assert!(missing.is_err());
    }
}
