//! The field's files: Blocks World problems in PDDL, as the planning competitions write
//! them, and plans in the competitions' format.
//!
//! # What is read
//!
//! A problem of the 4-operator domain (`pickup`, `putdown`, `stack`, `unstack`; the
//! predicates `on`, `on-table`, `clear`, `arm-empty`, `holding`), such as the 2023
//! competition's learning track writes (`ipc2023-learning/benchmarks`, folder
//! `blocksworld`):
//!
//! ```text
//! (define (problem blocksworld-01)
//!  (:domain blocksworld)
//!  (:objects b1 b2 b3 - object)
//!  (:init (arm-empty) (clear b3) (on b3 b1) (on-table b1) (clear b2) (on-table b2))
//!  (:goal (and (on b1 b2) (on-table b2))))
//! ```
//!
//! Case is ignored, `;` starts a comment, `(:requirements ...)` and object types (`-
//! block`, `- (either block thing)`) are skipped, and so are `(:metric minimize
//! (total-cost))` and an init's `(= (total-cost) 0)`: every action costs 1. The 2000
//! competition's `ontable` and `handempty` are read as `on-table` and `arm-empty`. Block `i`
//! is the `i`-th object of `:objects`, and the names are kept for the plans written back
//! ([`Problem::block_names`]).
//!
//! The problem's `(:domain NAME)` must be a Blocks World's: the domain file's name when one
//! is given ([`Problem::read_in`] with a [`Domain`], checked to be the 4-operator domain
//! in either spelling, `pickup`/`putdown` or `pick-up`/`put-down`; its action names are the
//! plan's), else a name holding `block`. A problem of another domain is refused, never
//! planned as blocks.
//!
//! The initial state must be one state of the world: every block placed once (on the table
//! or on one block), no cycle of `on`, `clear` exactly where nothing stands, the arm empty.
//! The goal states exactly what the file says: a block placed by `on` or `on-table`
//! must stand there, a block the goal does not place is free, and a tower's bottom stands
//! on the table only where `on-table` says so. A goal that puts a block on one it does not
//! place (bare `on` facts, as PDDLGym writes goals) cannot be read as towers from the table
//! up, so it is refused, naming the fact, never read as something else; so is a goal
//! `clear` that its towers do not imply (it is implied when the goal places every block,
//! as the competition's goals do).
//!
//! Each refusal is one line naming the file, the line and the problem: a block placed
//! twice, a cycle of `on`, an unknown predicate, a fact naming an undeclared block, a file
//! larger than [`MAX_PROBLEM_BYTES`] (refused before it is read).
//!
//! # Why a reader of our own
//!
//! The `pddl` crate (0.2, a typed PDDL 3.1 parser) reads the competition's files, but it
//! refuses legal PDDL that other tools write: facts with no space between them
//! (`(on b2 b1)(on-table b1)`) and upper-case keywords (`(DEFINE (PROBLEM ...`, as the
//! 2000 competition's files are); its errors are parser positions, not one line naming the
//! problem; and it is licensed under the EUPL-1.2, a copyleft licence, where blockstack is
//! MIT or Apache-2.0. The fragment read here is five predicates in four sections; the
//! checks that matter (a block placed twice, a cycle) are the domain's, which no general
//! parser makes.
//!
//! # Where it lives
//!
//! A problem file is a block-move problem: towers of blocks, a goal of towers, and plans
//! of block moves, which are [`crate::towers`]' vocabulary; a file says nothing of a grid,
//! so the side view's world (`sim`) is built from the towers on its default grid
//! ([`Problem::side_task`]) by whoever plays them.
//!
//! # Example
//!
//! ```
//! use oracle::pddl::{self, Problem};
//! use oracle::towers::NearOptimal;
//!
//! let problem = Problem::parse(
//!     "(define (problem p) (:domain blocksworld) (:objects b1 b2 b3)
//!       (:init (arm-empty) (clear b3) (on b3 b1) (on-table b1) (clear b2) (on-table b2))
//!       (:goal (and (on b1 b2) (on-table b2))))",
//! )?;
//! let plan = NearOptimal::new().plan(problem.start(), problem.goal())?;
//! let actions = pddl::actions(problem.start(), &plan)?;
//! assert_eq!(actions.len(), 2 * plan.len());
//! assert_eq!(
//!     problem.plan_text(&actions),
//!     "(unstack b3 b1)\n(putdown b3)\n(pickup b1)\n(stack b1 b2)\n; cost = 4 (unit cost)\n"
//! );
//! problem.replay(&actions)?;
//! // What is written reads back as the same problem.
//! assert_eq!(Problem::parse(&problem.to_string())?, problem);
//! # Ok::<(), oracle::OracleError>(())
//! ```

pub mod domain;
pub mod error;
pub mod plan;
pub mod problem;
mod sexpr;
pub mod suite;
pub mod world;

pub use domain::{ActionNames, Domain, Operator};
pub use error::PddlError;
pub use plan::{Action, Conditions, PddlPlan, actions};
pub use problem::{Fact, MAX_PROBLEM_BYTES, Problem};
pub use suite::{BestKnown, SuiteReport, Summary, TaskRow};
pub use world::SideTask;
