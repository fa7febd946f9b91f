//! The competition's plan format, and a replay of its actions over the problem's facts.
//!
//! A plan is one action per line, `(unstack b3 b5)`, `(putdown b3)`, `(pickup b4)`,
//! `(stack b4 b3)`, and `; cost = N (unit cost)` at the end, as the competition's plan
//! files are. Every block move is two actions, so a plan of `M` moves costs `2 M`. A plan
//! planned here ([`PddlPlan::text`]) adds `; lower bound = L`, the cost no plan can beat
//! ([`crate::towers::Certificate`]), and `; optimal` when the plan's cost meets it.
//!
//! [`Problem::replay`] checks a plan the way a plan validator does: it applies each
//! action's precondition and effects, as the domain file writes them, to the set of facts
//! the problem file states, and checks the goal's facts at the end. It shares nothing with
//! the planners' towers, so it checks them independently.

use std::collections::HashSet;
use std::fmt::Write as _;

use crate::error::Result;
use crate::towers::{BlockPlanner, Certificate, Place, TowerPlan, Towers};

use super::domain::{ActionNames, Operator};
use super::error::PddlError;
use super::problem::{Fact, Problem};

/// One action of the 4-operator domain; blocks by index into [`Problem::block_names`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Action {
    /// `(pickup x)`: take the clear block `x` from the table.
    Pickup(usize),
    /// `(putdown x)`: put the held block `x` on the table.
    Putdown(usize),
    /// `(stack x y)`: put the held block `x` on the clear block `y`.
    Stack(usize, usize),
    /// `(unstack x y)`: take the clear block `x` from `y`.
    Unstack(usize, usize),
}

/// An action's precondition and effects, as facts over its blocks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Conditions {
    /// What must hold before.
    pub pre: Vec<Fact>,
    /// What holds after.
    pub add: Vec<Fact>,
    /// What no longer holds after (deleted before the adds, as STRIPS does).
    pub del: Vec<Fact>,
}

impl Action {
    /// Which of the four it is.
    pub fn operator(self) -> Operator {
        match self {
            Action::Pickup(_) => Operator::Pickup,
            Action::Putdown(_) => Operator::Putdown,
            Action::Stack(..) => Operator::Stack,
            Action::Unstack(..) => Operator::Unstack,
        }
    }

    /// The action as PDDL, with the blocks' names and the domain's action names: `(stack
    /// b4 b3)`.
    pub fn to_pddl(self, blocks: &[String], actions: &ActionNames) -> String {
        let name = actions.of(self.operator());
        match self {
            Action::Pickup(x) | Action::Putdown(x) => format!("({name} {})", blocks[x]),
            Action::Stack(x, y) | Action::Unstack(x, y) => format!("({name} {} {})", blocks[x], blocks[y]),
        }
    }

    /// Its precondition and effects: the 4-operator domain's rules, which the replay
    /// applies and a domain file is checked against ([`super::Domain`]).
    pub fn conditions(self) -> Conditions {
        match self {
            Action::Pickup(x) => Conditions {
                pre: vec![Fact::Clear(x), Fact::OnTable(x), Fact::ArmEmpty],
                add: vec![Fact::Holding(x)],
                del: vec![Fact::Clear(x), Fact::OnTable(x), Fact::ArmEmpty],
            },
            Action::Putdown(x) => Conditions {
                pre: vec![Fact::Holding(x)],
                add: vec![Fact::Clear(x), Fact::ArmEmpty, Fact::OnTable(x)],
                del: vec![Fact::Holding(x)],
            },
            Action::Stack(x, y) => Conditions {
                pre: vec![Fact::Clear(y), Fact::Holding(x)],
                add: vec![Fact::ArmEmpty, Fact::Clear(x), Fact::On(x, y)],
                del: vec![Fact::Clear(y), Fact::Holding(x)],
            },
            Action::Unstack(x, y) => Conditions {
                pre: vec![Fact::On(x, y), Fact::Clear(x), Fact::ArmEmpty],
                add: vec![Fact::Holding(x), Fact::Clear(y)],
                del: vec![Fact::On(x, y), Fact::Clear(x), Fact::ArmEmpty],
            },
        }
    }
}

/// The actions that carry out `plan` from `start`: each move is `pickup` or `unstack` (from
/// where the block stands then) and `putdown` or `stack`. An error at the first move that
/// is not legal.
pub fn actions(start: &Towers, plan: &TowerPlan) -> Result<Vec<Action>> {
    let mut state = start.clone();
    let mut out = Vec::with_capacity(2 * plan.len());
    for &mv in &plan.moves {
        let take = match state.support(mv.block) {
            Place::Table => Action::Pickup(mv.block),
            Place::On(y) => Action::Unstack(mv.block, y),
        };
        state.apply(mv, crate::towers::Table::Unbounded)?;
        out.push(take);
        out.push(match mv.to {
            Place::Table => Action::Putdown(mv.block),
            Place::On(y) => Action::Stack(mv.block, y),
        });
    }
    Ok(out)
}

/// A plan for a [`Problem`], checked: its block moves and the actions that carry them out,
/// replayed over the file's facts before it is returned ([`Problem::solve`]), with the
/// lower bound it is measured against.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PddlPlan {
    /// The block moves, first to last.
    pub moves: TowerPlan,
    /// The actions, two per move: the competitions' cost is their number.
    pub actions: Vec<Action>,
    /// The bound's parts, in block moves.
    pub certificate: Certificate,
    /// The best proven lower bound on the fewest block moves
    /// ([`crate::towers::CertifiedPlan::lower_bound`]).
    pub lower_bound: usize,
}

impl PddlPlan {
    /// The plan's cost in the competitions' unit: its number of actions.
    pub fn cost(&self) -> usize {
        self.actions.len()
    }

    /// The lower bound in the competitions' unit: no plan costs less.
    pub fn lower_bound_cost(&self) -> usize {
        2 * self.lower_bound
    }

    /// Whether the plan is proven optimal: its cost meets the bound.
    pub fn is_optimal(&self) -> bool {
        self.moves.len() == self.lower_bound
    }

    /// The plan in the competition's format ([`Problem::plan_text`]), then `; lower bound =
    /// L` and, if proven, `; optimal`.
    pub fn text(&self, problem: &Problem) -> String {
        let mut out = problem.plan_text(&self.actions);
        let _ = writeln!(out, "; lower bound = {}", self.lower_bound_cost());
        if self.is_optimal() {
            out.push_str("; optimal\n");
        }
        out
    }
}

impl Problem {
    /// `planner`'s plan for this problem on the literature's unbounded table, its actions
    /// checked by replaying them over the file's facts ([`Problem::replay`]): a plan that
    /// breaks a precondition or misses a goal fact is an error, never returned.
    pub fn solve(&self, planner: &dyn BlockPlanner) -> Result<PddlPlan> {
        let certified = planner.plan_certified(self.start(), self.goal())?;
        let actions = actions(self.start(), &certified.plan)?;
        self.replay(&actions)?;
        Ok(PddlPlan {
            moves: certified.plan,
            actions,
            certificate: certified.certificate,
            lower_bound: certified.lower_bound,
        })
    }

    /// `action` as PDDL, with the problem's block names and its domain's action names.
    pub fn action_text(&self, action: Action) -> String {
        action.to_pddl(self.block_names(), self.action_names())
    }

    /// `actions` in the competition's plan format: one per line, then `; cost = N (unit
    /// cost)`; the actions named as the problem's domain names them.
    pub fn plan_text(&self, actions: &[Action]) -> String {
        let mut out = String::new();
        for &a in actions {
            out.push_str(&self.action_text(a));
            out.push('\n');
        }
        let _ = writeln!(out, "; cost = {} (unit cost)", actions.len());
        out
    }

    /// The actions of a plan in the competition's format (blank lines and `;` comments
    /// skipped, case ignored; either spelling of the actions' names).
    pub fn parse_plan(&self, text: &str) -> Result<Vec<Action>> {
        let index: std::collections::HashMap<String, usize> = self
            .block_names()
            .iter()
            .enumerate()
            .map(|(i, b)| (b.to_lowercase(), i))
            .collect();
        let mut out = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let err = |reason: String| PddlError::PlanSyntax { line: i + 1, reason };
            let line = raw.split(';').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let inner = line
                .strip_prefix('(')
                .and_then(|l| l.strip_suffix(')'))
                .ok_or_else(|| err(format!("{line:?} is not an action such as (pickup b1)")))?;
            let words: Vec<String> = inner.split_whitespace().map(str::to_lowercase).collect();
            let block = |w: &String| {
                index
                    .get(w)
                    .copied()
                    .ok_or_else(|| err(format!("{line} names {w}, which the problem does not declare")))
            };
            let op = words.first().and_then(|w| Operator::of_name(w));
            let action = match (op, words.as_slice()) {
                (Some(Operator::Pickup), [_, x]) => Action::Pickup(block(x)?),
                (Some(Operator::Putdown), [_, x]) => Action::Putdown(block(x)?),
                (Some(Operator::Stack), [_, x, y]) => Action::Stack(block(x)?, block(y)?),
                (Some(Operator::Unstack), [_, x, y]) => Action::Unstack(block(x)?, block(y)?),
                _ => {
                    return Err(err(format!(
                        "{line} is not an action of the 4-operator domain: (pickup x), (putdown x), (stack x y), (unstack x y)"
                    ))
                    .into());
                }
            };
            out.push(action);
        }
        Ok(out)
    }

    /// Checks that `actions` are applicable one after the other from the problem's initial
    /// facts and that the goal's facts hold after the last, by the domain's preconditions
    /// and effects over sets of facts (see the module docs).
    pub fn replay(&self, actions: &[Action]) -> Result<()> {
        let names = self.block_names();
        let mut facts: HashSet<Fact> = self.init_facts().iter().copied().collect();
        for (i, &a) in actions.iter().enumerate() {
            let Conditions { pre, add, del } = a.conditions();
            if let Some(missing) = pre.iter().find(|f| !facts.contains(f)) {
                return Err(PddlError::NotApplicable {
                    step: i + 1,
                    action: self.action_text(a),
                    reason: format!("{} does not hold", missing.to_pddl(names)),
                }
                .into());
            }
            // The domain's effects: deletes first, then adds (STRIPS).
            for f in &del {
                facts.remove(f);
            }
            facts.extend(add);
        }
        match self.goal_facts().iter().find(|f| !facts.contains(f)) {
            Some(f) => Err(PddlError::GoalNotReached {
                steps: actions.len(),
                fact: f.to_pddl(names),
            }
            .into()),
            None => Ok(()),
        }
    }
}
