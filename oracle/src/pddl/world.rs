//! A problem file as the side view plays it: the world's size, the start state and the
//! goal, for whoever plays episodes from the task (`blockstack run --pddl`, Python's
//! `BlocksWorld-v0` built from a task).
//!
//! A file says nothing of a grid, so the task is laid on the side view's default grid for
//! its block count ([`Grid::side_default`]), which holds every state of that many blocks:
//! the start's towers stand on columns `0, 1, ...` ([`sim::view::state_of_towers`]).

use sim::{Goal, Grid, State, View};

use crate::error::Result;

use super::{PddlError, Problem};

/// A problem as a side-view world: the grid, the start and the goal.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SideTask {
    /// The side view's default grid for the problem's blocks.
    pub grid: Grid,
    /// The start state, its towers on columns `0, 1, ...`, nothing held.
    pub start: State,
    /// The goal's towers; the blocks it does not place are free.
    pub goal: Goal,
}

impl Problem {
    /// The side-view world of this problem. An error naming the limit for a task of more
    /// blocks than the side view holds, and one for a task whose start already meets its
    /// goal (an empty goal too): its plan is empty, but an episode cannot begin over.
    pub fn side_task(&self) -> Result<SideTask> {
        if self.goal().holds(self.start()) {
            return Err(PddlError::NothingToPlay {
                empty_goal: self.goal().towers().is_empty(),
            }
            .into());
        }
        let blocks = self.start().blocks();
        let grid = Grid::side_default(blocks);
        View::Side.check_world(grid, blocks)?;
        Ok(SideTask {
            grid,
            start: sim::view::state_of_towers(grid, &self.start().towers())?,
            goal: Goal::of_towers(self.goal().towers(), blocks)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_task_becomes_its_start_and_goal_on_the_default_grid() {
        let problem = Problem::parse(
            "(define (problem p) (:domain blocksworld) (:objects b1 b2 b3)
              (:init (arm-empty) (clear b3) (on b3 b1) (on-table b1) (clear b2) (on-table b2))
              (:goal (and (on b1 b2) (on-table b2))))",
        )
        .unwrap();
        let task = problem.side_task().unwrap();
        assert_eq!(task.grid, Grid::side_default(3));
        assert_eq!(sim::view::towers(&task.start).unwrap(), vec![vec![0, 2], vec![1]]);
        // One tower that leaves a block free is written with a `/`.
        assert_eq!(task.goal.to_string(), "1,0/");
        assert!(!task.goal.holds_in(View::Side, &task.start));
    }

    #[test]
    fn a_task_with_nothing_to_play_is_refused_with_one_message() {
        let head = "(define (problem p) (:domain blocksworld) (:objects b1 b2)
              (:init (arm-empty) (clear b2) (on b2 b1) (on-table b1))";
        let met = Problem::parse(&format!("{head} (:goal (and (on b2 b1) (on-table b1))))")).unwrap();
        let empty = Problem::parse(&format!("{head} (:goal (and)))")).unwrap();
        for (problem, says) in [(met, "its goal, so"), (empty, "its goal (which places no block), so")] {
            let err = problem.side_task().unwrap_err().to_string();
            assert!(err.contains(says), "{err}");
            assert!(err.contains("there is no episode to play"), "{err}");
        }
    }
}
