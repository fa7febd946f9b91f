//! The optimal block-move solver for the classic Blocks World at any size, with its
//! certificate: a lower bound that the plan's length meets.
//!
//! # The bound
//!
//! Every misplaced block (one not standing for good where the goal wants it, see
//! [`TowerGoal`]) moves at least once. Some move twice: call a block's first move `f` and
//! its last `l` (the same move if it moves once). Every plan keeps these orders:
//!
//! 1. a block standing on a misplaced block `s` leaves before `s` first moves;
//! 2. a block's misplaced goal support is placed for good before the block is;
//! 3. a block standing on a well-placed block `s` leaves before the block the goal puts on
//!    `s` arrives for good.
//!
//! Each order runs from an `f` to an `f` (1), an `l` to an `l` (2) or an `f` to an `l`
//! (3): following them, one only passes from the goal's towers back to the start's
//! through a block moved once, whose `f` is its `l`. So the blocks moved once cannot close
//! a cycle of these orders; in the deadlock graph (an edge `x -> y` when `f(x)` must come
//! before `l(y)` through the orders), the blocks moved twice break every cycle. A block
//! with a loop (it stands above a block that must end below it, for instance) moves twice
//! in every plan. So every plan has at least
//!
//! > misplaced blocks + blocks forced to move twice + the smallest set of the other blocks
//! > that breaks every remaining cycle
//!
//! moves: the [`Certificate`]'s three parts (Slaney & Thiébaux, "Blocks World revisited",
//! Artificial Intelligence 125, 2001, after Gupta & Nau's deadlocks).
//!
//! # The plan
//!
//! Conversely, given a set that breaks every cycle, moving its blocks to the table first and
//! to their goal places later, and every other misplaced block once, straight to where it
//! ends, in an order that keeps 1-3 (a topological order), is a plan of exactly as many
//! moves as the misplaced blocks and the set's together. So a smallest set gives an optimal
//! plan, which meets the bound: the proof closes. The plan is replayed before it is returned.
//!
//! The smallest set is a minimum feedback vertex set, NP-hard in general (as optimal Blocks
//! World planning is); `fvs` says how it is found and why that way. Past the time limit the
//! solver returns its best plan (the better of its set's and the near-optimal planner's)
//! and the bound proven so far, and claims optimality only where the two meet.
//!
//! # Reach
//!
//! On the 2023 planning competition's 90 Blocks World test tasks (5 to 488 blocks)
//! `blockstack solve-all --solver optimal` reports how many close and how long each took
//! (docs/results/ipc). Problems whose deadlock graph has a strongly connected part larger
//! than [`MAX_COMPONENT`] blocks (uniform problems of thousands of blocks) get a packing of
//! disjoint cycles as that part's bound and the near-optimal planner's plan.

use std::time::{Duration, Instant};

use crate::error::Result;

use super::TowersError;
use super::deadlock::DeadlockGraph;
pub use super::fvs::MAX_COMPONENT;
use super::fvs::minimum_fvs;
use super::goal::TowerGoal;
use super::near_optimal::NearOptimal;
use super::plan::TowerPlan;
use super::state::{Move, NONE, Place, Table, Towers};

/// The time limit of [`OptimalMoves::new`].
pub const DEFAULT_TIME_LIMIT: Duration = Duration::from_secs(10);

/// A lower bound on the block moves of every plan, in its parts (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Certificate {
    /// Blocks not in their final position: each moves at least once.
    pub misplaced: usize,
    /// Blocks forced to move twice in every plan (a deadlock with themselves).
    pub forced: usize,
    /// A lower bound on the smallest set of the other blocks that breaks every deadlock
    /// (each of its blocks moves twice); the set's size when the proof closes.
    pub breakers: usize,
}

impl Certificate {
    /// The bound: the sum of the parts.
    pub fn lower_bound(&self) -> usize {
        self.misplaced + self.forced + self.breakers
    }

    /// The parts of the bound from `start` to `goal` that take no search: the misplaced
    /// blocks and those forced to move twice (no breakers counted); an error if the goal
    /// names a block the state lacks.
    pub fn quick(start: &Towers, goal: &TowerGoal) -> Result<Certificate> {
        goal.check_blocks(start.blocks())?;
        let graph = DeadlockGraph::of(start.below(), start.above(), goal);
        let forced = graph.loops();
        Ok(Certificate {
            misplaced: graph.misplaced,
            forced,
            breakers: 0,
        })
    }
}

/// A plan with the lower bound it is measured against.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CertifiedPlan {
    /// The plan.
    pub plan: TowerPlan,
    /// The bound's parts.
    pub certificate: Certificate,
    /// The best proven lower bound on the fewest moves: the certificate's, or the plan's
    /// length when a search proved it shortest otherwise (the exact A* solver).
    pub lower_bound: usize,
}

impl CertifiedPlan {
    /// `plan` with `certificate` as its bound.
    pub fn new(plan: TowerPlan, certificate: Certificate) -> CertifiedPlan {
        debug_assert!(certificate.lower_bound() <= plan.len(), "a bound above a plan");
        CertifiedPlan {
            lower_bound: certificate.lower_bound().min(plan.len()),
            plan,
            certificate,
        }
    }

    /// `plan`, proven shortest by a search of its own (the exact A* solver), with
    /// `certificate` as the bound's parts.
    pub fn proven(plan: TowerPlan, certificate: Certificate) -> CertifiedPlan {
        CertifiedPlan {
            lower_bound: plan.len(),
            plan,
            certificate,
        }
    }

    /// Whether the plan is proven shortest: its length meets the bound.
    pub fn is_optimal(&self) -> bool {
        self.plan.len() == self.lower_bound
    }

    /// How many moves the plan may be above the optimum: its length minus the bound.
    pub fn gap(&self) -> usize {
        self.plan.len() - self.lower_bound
    }
}

/// The optimal block-move solver on the literature's unbounded table (module docs): a
/// shortest plan with its certificate, or, past its time limit, its best plan and bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OptimalMoves {
    time_limit: Duration,
}

impl Default for OptimalMoves {
    fn default() -> Self {
        OptimalMoves {
            time_limit: DEFAULT_TIME_LIMIT,
        }
    }
}

impl OptimalMoves {
    /// The solver with the default time limit ([`DEFAULT_TIME_LIMIT`]).
    pub fn new() -> Self {
        Self::default()
    }

    /// This solver, searching for at most `limit` before it returns its best plan.
    pub fn with_time_limit(self, limit: Duration) -> Self {
        OptimalMoves { time_limit: limit }
    }

    /// Its time limit.
    pub fn time_limit(&self) -> Duration {
        self.time_limit
    }

    /// A plan from `start` to `goal` with its certificate; optimal when
    /// [`CertifiedPlan::is_optimal`]. An error if the goal names a block the state lacks.
    pub fn solve(&self, start: &Towers, goal: &TowerGoal) -> Result<CertifiedPlan> {
        let deadline = Instant::now() + self.time_limit;
        goal.check_blocks(start.blocks())?;
        let graph = DeadlockGraph::of(start.below(), start.above(), goal);
        let forced = graph.loops();
        let fvs = minimum_fvs(graph.succ.clone(), deadline);
        let certificate = Certificate {
            misplaced: graph.misplaced,
            forced,
            breakers: fvs.lower_bound - forced,
        };
        let ours = match &fvs.set {
            Some(set) => {
                let mut twice = vec![false; start.blocks()];
                set.iter().for_each(|&v| twice[graph.blocks[v]] = true);
                Some(plan_with(start, goal, &graph.well_placed, &twice)?)
            }
            None => None,
        };
        let plan = match ours {
            Some(plan) if plan.len() <= graph.misplaced + fvs.lower_bound => plan,
            ours => {
                let near = NearOptimal::new().plan(start, goal)?;
                match ours {
                    Some(plan) if plan.len() <= near.len() => plan,
                    _ => near,
                }
            }
        };
        if !goal.holds(&plan.replay(start, Table::Unbounded)?) {
            return Err(TowersError::NoPlan {
                planner: "optimal solver".into(),
                reason: "its plan does not reach the goal".into(),
            }
            .into());
        }
        Ok(CertifiedPlan::new(plan, certificate))
    }
}

/// The plan that moves the blocks of `twice` to the table and later to their goal places,
/// and every other misplaced block once (module docs), in a topological order of the
/// orders 1-3; an error if `twice` leaves a cycle.
fn plan_with(start: &Towers, goal: &TowerGoal, wp: &[bool], twice: &[bool]) -> Result<TowerPlan> {
    let n = start.blocks();
    let below = start.below();
    // Events: 2b is b's first move, 2b + 1 its last (the same event for a block moved once).
    let first = |b: usize| 2 * b;
    let last = |b: usize| if twice[b] { 2 * b + 1 } else { 2 * b };
    let mut succ: Vec<Vec<usize>> = vec![Vec::new(); 2 * n];
    let mut indeg = vec![0usize; 2 * n];
    let mut edge = |a: usize, b: usize, succ: &mut Vec<Vec<usize>>| {
        succ[a].push(b);
        indeg[b] += 1;
    };
    for b in (0..n).filter(|&b| !wp[b]) {
        let s = below[b];
        if s != NONE && !wp[s] {
            edge(first(b), first(s), &mut succ);
        }
        if s != NONE && wp[s] && goal.above_of(s) != NONE {
            edge(first(b), last(goal.above_of(s)), &mut succ);
        }
        let g = goal.below_of(b);
        if goal.is_named(b) && g != NONE && !wp[g] {
            edge(last(g), last(b), &mut succ);
        }
        if twice[b] {
            edge(first(b), last(b), &mut succ);
        }
    }
    let events = |b: usize| if twice[b] { vec![2 * b, 2 * b + 1] } else { vec![2 * b] };
    let mut ready: std::collections::BinaryHeap<std::cmp::Reverse<usize>> = (0..n)
        .filter(|&b| !wp[b])
        .flat_map(events)
        .filter(|&e| indeg[e] == 0)
        .map(std::cmp::Reverse)
        .collect();
    let mut moves = Vec::new();
    while let Some(std::cmp::Reverse(e)) = ready.pop() {
        let b = e / 2;
        let to = if twice[b] && e % 2 == 0 {
            Place::Table
        } else {
            match goal.support(b) {
                Some(place) => place,
                None => Place::Table,
            }
        };
        moves.push(Move { block: b, to });
        for &w in &succ[e] {
            indeg[w] -= 1;
            if indeg[w] == 0 {
                ready.push(std::cmp::Reverse(w));
            }
        }
    }
    let expected = (0..n)
        .filter(|&b| !wp[b])
        .map(|b| 1 + usize::from(twice[b]))
        .sum::<usize>();
    if moves.len() != expected {
        return Err(TowersError::NoPlan {
            planner: "optimal solver".into(),
            reason: "its set of blocks moved twice leaves a deadlock".into(),
        }
        .into());
    }
    Ok(TowerPlan { moves })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::towers::{ExactMoves, random_goal, random_state};
    use proptest::prelude::*;

    #[test]
    fn a_deadlock_is_broken_by_one_block_and_the_bound_says_so() {
        // 1 on 0, 2 on 1; 3 alone. The goal: 1 on the table, 3 on 1, 2 on 3 (0 is free).
        let start = Towers::new(&[vec![0, 1, 2], vec![3]]).unwrap();
        let goal = TowerGoal::new(&[vec![1, 3, 2]]).unwrap();
        let solved = OptimalMoves::new().solve(&start, &goal).unwrap();
        assert_eq!(solved.plan.len(), 4);
        assert!(solved.is_optimal());
        assert_eq!(solved.gap(), 0);
        // 0, 1, 2 are misplaced (3 stands on the table, where the goal's tower needs 1);
        // 2 stands above 1 and must end above it: it moves twice.
        assert_eq!(
            solved.certificate,
            Certificate {
                misplaced: 3,
                forced: 1,
                breakers: 0
            }
        );
        assert_eq!(Certificate::quick(&start, &goal).unwrap().lower_bound(), 4);
    }

    #[test]
    fn without_time_it_returns_a_plan_and_claims_no_more_than_it_proved() {
        let start = random_state(60, 3);
        let goal = random_goal(60, 3, 60, 4).unwrap();
        let solved = OptimalMoves::new()
            .with_time_limit(Duration::ZERO)
            .solve(&start, &goal)
            .unwrap();
        assert!(goal.holds(&solved.plan.replay(&start, Table::Unbounded).unwrap()));
        assert!(solved.lower_bound <= solved.plan.len());
        let proven = OptimalMoves::new().solve(&start, &goal).unwrap();
        assert!(proven.is_optimal());
        assert!(solved.lower_bound <= proven.plan.len());
        assert_eq!(solved.is_optimal(), solved.plan.len() == proven.plan.len());
    }

    #[test]
    fn a_goal_naming_a_missing_block_is_refused() {
        let start = Towers::new(&[vec![0, 1]]).unwrap();
        let goal = TowerGoal::new(&[vec![1, 2]]).unwrap();
        assert!(OptimalMoves::new().solve(&start, &goal).is_err());
        assert!(Certificate::quick(&start, &goal).is_err());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// On small problems (goals naming some or all blocks) the optimal solver's plan
        /// is as short as the exact A* solver's, its proof closes, and its bound never
        /// exceeds the optimum.
        #[test]
        fn the_optimum_is_the_exact_solvers(
            blocks in 1usize..=9,
            stacks in 1usize..=3,
            named in 1usize..=9,
            seed in any::<u64>(),
        ) {
            let named = named.min(blocks);
            let stacks = stacks.min(named);
            let start = random_state(blocks, seed);
            let goal = random_goal(blocks, stacks, named, seed ^ 0x5eed).unwrap();
            let exact = ExactMoves::new().solve(&start, &goal).unwrap().len();
            let solved = OptimalMoves::new().solve(&start, &goal).unwrap();
            prop_assert!(goal.holds(&solved.plan.replay(&start, Table::Unbounded).unwrap()));
            prop_assert_eq!(solved.plan.len(), exact);
            prop_assert!(solved.is_optimal());
            let quick = Certificate::quick(&start, &goal).unwrap().lower_bound();
            prop_assert!(quick <= exact);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(120))]

        /// On every size the whole state space holds (up to 8 blocks), the optimal solver's
        /// plan is as long as the fewest moves a breadth-first search over every state finds,
        /// and its certificate's bound, with no search's help, is that number too.
        #[test]
        fn the_optimum_and_its_bound_are_the_breadth_first_searchs(
            blocks in 1usize..=8,
            stacks in 1usize..=3,
            named in 1usize..=8,
            seed in any::<u64>(),
        ) {
            let named = named.min(blocks);
            let stacks = stacks.min(named);
            let start = random_state(blocks, seed);
            let goal = random_goal(blocks, stacks, named, seed ^ 0xbf5).unwrap();
            let space = crate::towers::space::shared_space(blocks);
            let fewest = space.distances(&goal).unwrap().of(space, &start).unwrap() as usize;
            let solved = OptimalMoves::new().solve(&start, &goal).unwrap();
            prop_assert!(goal.holds(&solved.plan.replay(&start, Table::Unbounded).unwrap()));
            prop_assert_eq!(solved.plan.len(), fewest);
            prop_assert_eq!(solved.certificate.lower_bound(), fewest);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]

        /// The same on problems large enough for the search to branch: every block named,
        /// in the competition's shape of a few tall towers.
        #[test]
        fn the_optimum_is_the_exact_solvers_when_the_search_branches(
            blocks in 10usize..=12,
            seed in any::<u64>(),
        ) {
            let start = crate::towers::ipc_state(blocks, seed);
            let goal = TowerGoal::new(&crate::towers::ipc_state(blocks, seed ^ 1).towers()).unwrap();
            // A* may spend its budget on the hardest of these; they prove nothing here.
            let Ok(exact) = ExactMoves::new().solve(&start, &goal) else {
                return Ok(());
            };
            let exact = exact.len();
            let solved = OptimalMoves::new().solve(&start, &goal).unwrap();
            prop_assert_eq!(solved.plan.len(), exact);
            prop_assert!(solved.is_optimal());
        }
    }
}
