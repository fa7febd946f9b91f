//! The state representations: keys in range, what each keeps and what it forgets.

use agent::repr::goal_rank;
use agent::{Repr, ReprKind, Representation};
use proptest::prelude::*;
use sim::{Action, BlockId, Cell, Goal, Grid, State};

/// A state of `n` blocks on distinct cells of `grid` from `picks` (indices into the
/// cells not yet taken), holding `held` (`n` = nothing).
fn state_from(grid: Grid, n: usize, picks: &[usize], held: usize) -> State {
    let mut free: Vec<Cell> = grid.cells().collect();
    let cells: Vec<Cell> = picks[..n].iter().map(|&p| free.remove(p % free.len())).collect();
    let held = (held % (n + 1) < n).then(|| BlockId::of(held % (n + 1)));
    State::new(&cells, held).unwrap()
}

fn goal_from(n: usize, index: usize) -> Goal {
    let all = Goal::all(n).unwrap();
    all[index % all.len()].clone()
}

/// The state with block ids renamed by `rename` (block b becomes rename[b]).
fn renamed(state: &State, rename: &[usize]) -> State {
    let mut cells = vec![Cell::default(); state.block_count()];
    for b in state.blocks() {
        cells[rename[b.index()]] = state.cell(b);
    }
    State::new(&cells, state.held_block().map(|h| BlockId::of(rename[h.index()]))).unwrap()
}

/// `action` with its block renamed by `rename` (a Pick of block b picks rename[b]).
fn renamed_action(action: Action, rename: &[usize]) -> Action {
    match action {
        Action::Pick(b) => Action::Pick(BlockId::of(rename[b.index()])),
        other => other,
    }
}

fn renamed_goal(goal: &Goal, rename: &[usize]) -> Goal {
    let order: Vec<usize> = goal.order().iter().map(|b| rename[b.index()]).collect();
    Goal::from_indices(&order).unwrap()
}

proptest! {
    #[test]
    fn keys_are_below_the_key_count(
        n in 2usize..5, w in 2usize..8, h in 4usize..8,
        picks in prop::collection::vec(0usize..1000, 4), held in 0usize..5, g in 0usize..24,
    ) {
        let grid = Grid::new(w, h).unwrap();
        let state = state_from(grid, n, &picks, held);
        let goal = goal_from(n, g);
        for kind in ReprKind::ALL {
            let repr = Repr::new(kind, grid, n).unwrap();
            prop_assert!(repr.key(&state, &goal) < repr.key_count(), "{kind}");
        }
    }

    #[test]
    fn role_names_blocks_by_their_place_in_the_goal(
        picks in prop::collection::vec(0usize..1000, 3), held in 0usize..4, g in 0usize..6, r in 0usize..6,
    ) {
        // Renaming the blocks in state and goal alike is the same problem: same key, and
        // every action maps to the column of the renamed action.
        let grid = Grid::default();
        let repr = Repr::new(ReprKind::Role, grid, 3).unwrap();
        let state = state_from(grid, 3, &picks, held);
        let goal = goal_from(3, g);
        let rename: Vec<usize> = goal_from(3, r).order().iter().map(|b| b.index()).collect();
        let (state2, goal2) = (renamed(&state, &rename), renamed_goal(&goal, &rename));
        prop_assert_eq!(repr.key(&state, &goal), repr.key(&state2, &goal2));
        for a in Action::all(3) {
            let a2 = renamed_action(a, &rename);
            prop_assert_eq!(repr.column(&goal, a), repr.column(&goal2, a2));
            prop_assert_eq!(repr.action(&goal, repr.column(&goal, a)), a);
        }
    }

    #[test]
    fn role_and_raw_keep_the_whole_state(
        p1 in prop::collection::vec(0usize..1000, 3), h1 in 0usize..4,
        p2 in prop::collection::vec(0usize..1000, 3), h2 in 0usize..4, g in 0usize..6,
    ) {
        let grid = Grid::default();
        let (s1, s2) = (state_from(grid, 3, &p1, h1), state_from(grid, 3, &p2, h2));
        let goal = goal_from(3, g);
        for kind in [ReprKind::Role, ReprKind::Raw] {
            let repr = Repr::new(kind, grid, 3).unwrap();
            prop_assert_eq!(repr.key(&s1, &goal) == repr.key(&s2, &goal), s1 == s2, "{}", kind);
        }
    }
}

proptest! {
    #[test]
    fn role_towers_is_one_problem_per_shape_and_keeps_the_whole_state(
        p1 in prop::collection::vec(0usize..1000, 4), h1 in 0usize..5,
        p2 in prop::collection::vec(0usize..1000, 4), h2 in 0usize..5,
        g in 0usize..73, r in 0usize..24,
    ) {
        let grid = Grid::default();
        let repr = Repr::new(ReprKind::RoleTowers, grid, 4).unwrap();
        let goals = Goal::all_towers(4).unwrap();
        let goal = goals[g].clone();
        let (s1, s2) = (state_from(grid, 4, &p1, h1), state_from(grid, 4, &p2, h2));
        prop_assert!(repr.key(&s1, &goal) < repr.key_count());
        prop_assert_eq!(repr.key(&s1, &goal) == repr.key(&s2, &goal), s1 == s2);
        // Renaming blocks in state and goal alike is the same problem.
        let rename: Vec<usize> = goal_from(4, r).order().iter().map(|b| b.index()).collect();
        let towers: Vec<Vec<usize>> =
            goal.tower_lists().iter().map(|t| t.iter().map(|&b| rename[b]).collect()).collect();
        let goal2 = Goal::of_towers(&towers, 4).unwrap();
        let s1_renamed = renamed(&s1, &rename);
        prop_assert_eq!(repr.key(&s1, &goal), repr.key(&s1_renamed, &goal2));
        for a in Action::all(4) {
            let a2 = renamed_action(a, &rename);
            prop_assert_eq!(repr.column(&goal, a), repr.column(&goal2, a2));
            prop_assert_eq!(repr.action(&goal, repr.column(&goal, a)), a);
        }
    }
}

#[test]
fn role_towers_tells_goals_of_different_shapes_apart() {
    let grid = Grid::default();
    let repr = Repr::new(ReprKind::RoleTowers, grid, 3).unwrap();
    let state = State::new(&[Cell::new(0, 0), Cell::new(0, 1), Cell::new(4, 0)], None).unwrap();
    let keys: std::collections::BTreeSet<u64> = ["0,1,2", "0,1/2", "0/1/2", "0,1/", "0/"]
        .iter()
        .map(|g| repr.key(&state, &Goal::parse(g, Some(3)).unwrap()))
        .collect();
    assert_eq!(keys.len(), 5);
    // Towers are read longest first, so the order they are written in does not matter.
    let key = |g: &str| repr.key(&state, &Goal::parse(g, Some(3)).unwrap());
    assert_eq!(key("0,1/2"), key("2/0,1"));
    assert_eq!(repr.key_count(), 49 * 49 * 49 * 4 * 12);
}

#[test]
fn raw_ignores_the_goal_and_pairwise_does_not() {
    let grid = Grid::default();
    let state = State::new(&[Cell::new(0, 0), Cell::new(3, 4), Cell::new(6, 6)], Some(BlockId(1))).unwrap();
    let (a, b) = (
        Goal::from_indices(&[0, 1, 2]).unwrap(),
        Goal::from_indices(&[2, 1, 0]).unwrap(),
    );
    let raw = Repr::new(ReprKind::Raw, grid, 3).unwrap();
    assert_eq!(raw.key(&state, &a), raw.key(&state, &b));
    let pairwise = Repr::new(ReprKind::Pairwise, grid, 3).unwrap();
    assert_ne!(pairwise.key(&state, &a), pairwise.key(&state, &b));
}

#[test]
fn pairwise_sees_distances_and_directions_only() {
    // Shifting every block by the same amount keeps the pairwise key.
    let grid = Grid::default();
    let goal = Goal::from_indices(&[0, 1, 2]).unwrap();
    let pairwise = Repr::new(ReprKind::Pairwise, grid, 3).unwrap();
    let s = State::new(&[Cell::new(0, 0), Cell::new(2, 1), Cell::new(4, 4)], Some(BlockId(0))).unwrap();
    let shifted = State::new(&[Cell::new(1, 2), Cell::new(3, 3), Cell::new(5, 6)], Some(BlockId(0))).unwrap();
    assert_eq!(pairwise.key(&s, &goal), pairwise.key(&shifted, &goal));
    // Moving the closest block to the other side of the held block changes it.
    let flipped = State::new(&[Cell::new(2, 0), Cell::new(0, 1), Cell::new(4, 4)], Some(BlockId(0))).unwrap();
    assert_ne!(pairwise.key(&s, &goal), pairwise.key(&flipped, &goal));
}

#[test]
fn chasing_keeps_the_pair_not_the_goal() {
    // Block 1 held, chasing the cell below 2 in both goals, with equal chain distances:
    // the two goals share the key, the paper's partial extension to unseen goals.
    let grid = Grid::default();
    let chasing = Repr::new(ReprKind::Chasing, grid, 3).unwrap();
    let state = State::new(&[Cell::new(0, 3), Cell::new(3, 1), Cell::new(3, 5)], Some(BlockId(1))).unwrap();
    let (a, b) = (
        Goal::from_indices(&[0, 1, 2]).unwrap(),
        Goal::from_indices(&[1, 2, 0]).unwrap(),
    );
    assert_eq!(a.chain_distance(&state), b.chain_distance(&state));
    assert_eq!(chasing.key(&state, &a), chasing.key(&state, &b));
    // Holding another block, or moving the chased cell, changes the key.
    let other = state.with_held(Some(BlockId(0))).unwrap();
    assert_ne!(chasing.key(&state, &a), chasing.key(&other, &a));
    let moved = State::new(&[Cell::new(0, 3), Cell::new(3, 1), Cell::new(4, 5)], Some(BlockId(1))).unwrap();
    assert_ne!(chasing.key(&state, &a), chasing.key(&moved, &a));
}

#[test]
fn chasing_sees_whether_the_chased_cell_is_taken() {
    // Goal 0,1,2: block 0 chases the cell below 1. With 2 on that cell the key differs
    // from the same distances with the cell free.
    let grid = Grid::default();
    let chasing = Repr::new(ReprKind::Chasing, grid, 3).unwrap();
    let goal = Goal::from_indices(&[0, 1, 2]).unwrap();
    let taken = State::new(&[Cell::new(0, 3), Cell::new(3, 4), Cell::new(3, 3)], Some(BlockId(0))).unwrap();
    let free = State::new(&[Cell::new(0, 3), Cell::new(3, 4), Cell::new(2, 4)], Some(BlockId(0))).unwrap();
    assert_eq!(goal.chain_distance(&taken), goal.chain_distance(&free));
    assert_eq!(
        goal.chased_distance(BlockId(0), &taken),
        goal.chased_distance(BlockId(0), &free)
    );
    assert_ne!(chasing.key(&taken, &goal), chasing.key(&free, &goal));
}

#[test]
fn goal_rank_numbers_the_goals_in_order() {
    for n in 2..6 {
        for (i, g) in Goal::all(n).unwrap().iter().enumerate() {
            assert_eq!(goal_rank(g), i as u64);
        }
    }
}

#[test]
fn key_counts_for_three_blocks_on_seven_by_seven() {
    let grid = Grid::default();
    let count = |k| Repr::new(k, grid, 3).unwrap().key_count();
    assert_eq!(count(ReprKind::Raw), 49 * 49 * 49 * 4);
    assert_eq!(count(ReprKind::Role), 49 * 49 * 49 * 4);
    assert_eq!(count(ReprKind::Pairwise), 37 * 9 * 4 * 6);
    assert_eq!(count(ReprKind::Chasing), 4 * 3 * 14 * 25 * 18);
}

#[test]
fn a_representation_too_large_to_number_is_an_error() {
    let grid = Grid::new(16, 16).unwrap();
    let err = Repr::new(ReprKind::Raw, grid, 16).unwrap_err();
    assert!(err.to_string().contains("more states than a table can number"), "{err}");
    assert!(Repr::new(ReprKind::Chasing, grid, 16).is_ok());
}

#[test]
fn representation_names_parse() {
    for k in ReprKind::ALL {
        assert_eq!(k.name().parse::<ReprKind>().unwrap(), k);
    }
    let err = "roles".parse::<ReprKind>().unwrap_err();
    assert!(
        err.to_string()
            .contains("choose raw, pairwise, chasing, chasing-code, role or role-towers")
    );
}

/// The `chasing-code` key of a tuple, by the layout the representation documents, for 3
/// blocks on 7 x 7: `R = 4 * 6^2 + 13^2 + 1 = 314` values of `d / 625`, `2 * 313 + 1 = 627`
/// of `D / 625`, the `314^2` nothing-held keys first.
fn held_key(held: u64, partner_slot: u64, held_is_lower: bool, d: u64, total: u64, heading: u64) -> u64 {
    314 * 314 + (((((held * 2 + partner_slot) * 2 + u64::from(held_is_lower)) * 314 + d) * 627 + total) * 9 + heading)
}

#[test]
fn chasing_code_keys_of_hand_computed_states() {
    use sim::coded_state::pair_distance;
    let grid = Grid::default();
    let repr = Repr::new(ReprKind::ChasingCode, grid, 3).unwrap();
    assert_eq!(repr.key_count(), 314 * 314 + 3 * 2 * 2 * 314 * 627 * 9);
    let goal = Goal::from_indices(&[0, 1, 2]).unwrap();
    let at = |x, y| Cell::new(x, y);
    // Block 0 held at (3, 2), its pair (0, 1); block 2 far at (0, 6): d(1, 2) from block 1's
    // cell to (0, 6).
    let key = |one: Cell| {
        let s = State::new(&[at(3, 2), one, at(0, 6)], Some(BlockId(0))).unwrap();
        (
            pair_distance(grid, at(3, 2), one),
            pair_distance(grid, one, at(0, 6)),
            repr.key(&s, &goal),
        )
    };
    // Block 1 stacked on block 0: d = 625 (1 unit), straight above (heading '-', 'u': 2 * 3 + 0).
    let (d, d12, k) = key(at(3, 3));
    assert_eq!(d, 625);
    assert_eq!(k, held_key(0, 0, true, 1, u64::from((d + d12) / 625), 2 * 3));
    // Beside it: 3125 (5 units), to the right ('r', '-': 1 * 3 + 2).
    let (d, d12, k) = key(at(4, 2));
    assert_eq!(d, 3125);
    assert_eq!(k, held_key(0, 0, true, 5, u64::from((d + d12) / 625), 3 + 2));
    // Directly below it: 5625 (9 units), below ('-', 'd': 2 * 3 + 1).
    let (d, d12, k) = key(at(3, 1));
    assert_eq!(d, 5625);
    assert_eq!(k, held_key(0, 0, true, 9, u64::from((d + d12) / 625), 2 * 3 + 1));
    // Nothing held: each goal pair's d, bottom pair first, as base-314 digits.
    let s = State::new(&[at(3, 2), at(3, 3), at(4, 3)], None).unwrap();
    assert_eq!(repr.key(&s, &goal), 314 + 5);
    // The top block held pairs with the block below it: block 2 held, pair (1, 2), block 2
    // the upper one; partner 1 is the second of the other blocks (0, 1), to its left ('l',
    // '-': 0 * 3 + 2).
    let s = State::new(&[at(3, 2), at(3, 3), at(4, 3)], Some(BlockId(2))).unwrap();
    assert_eq!(repr.key(&s, &goal), held_key(2, 1, false, 5, 1 + 5, 2));
}

#[test]
fn chasing_code_shares_a_row_between_equal_tuples_and_names_no_goal() {
    let grid = Grid::default();
    let repr = Repr::new(ReprKind::ChasingCode, grid, 3).unwrap();
    // The same configuration one column to the right: the same tuple, the same row.
    let s = State::new(&[Cell::new(1, 1), Cell::new(2, 3), Cell::new(4, 0)], Some(BlockId(1))).unwrap();
    let moved = State::new(&[Cell::new(2, 1), Cell::new(3, 3), Cell::new(5, 0)], Some(BlockId(1))).unwrap();
    let goal = Goal::from_indices(&[2, 1, 0]).unwrap();
    assert_eq!(repr.key(&s, &goal), repr.key(&moved, &goal));
    // Another goal under which the tuple is the same: the same row. Goals 0,1,2 and 1,2,0
    // both pair block 1 with block 2 above it; with the column 2, 0, 1 bottom to top,
    // d(0, 1) = d(2, 0) = 625, so D is equal too.
    let a = Goal::from_indices(&[0, 1, 2]).unwrap();
    let b = Goal::from_indices(&[1, 2, 0]).unwrap();
    let s = State::new(&[Cell::new(2, 2), Cell::new(2, 3), Cell::new(2, 1)], Some(BlockId(1))).unwrap();
    let (ca, cb) = (sim::CodedState::of(grid, &a, &s), sim::CodedState::of(grid, &b, &s));
    assert_eq!(ca, cb);
    assert_eq!(repr.key(&s, &a), repr.key(&s, &b));
    assert_ne!(a, b);
}

proptest! {
    #[test]
    fn chasing_code_keys_are_equal_exactly_when_the_tuples_are(
        n in 2usize..5, w in 2usize..8, h in 4usize..8,
        pa in prop::collection::vec(0usize..1000, 4), ha in 0usize..5, ga in 0usize..24,
        pb in prop::collection::vec(0usize..1000, 4), hb in 0usize..5, gb in 0usize..24,
    ) {
        let grid = Grid::new(w, h).unwrap();
        let repr = Repr::new(ReprKind::ChasingCode, grid, n).unwrap();
        let (sa, goal_a) = (state_from(grid, n, &pa, ha), goal_from(n, ga));
        let (sb, goal_b) = (state_from(grid, n, &pb, hb), goal_from(n, gb));
        let (ta, tb) = (sim::CodedState::of(grid, &goal_a, &sa), sim::CodedState::of(grid, &goal_b, &sb));
        prop_assert_eq!(ta == tb, repr.key(&sa, &goal_a) == repr.key(&sb, &goal_b), "{} / {}", ta, tb);
    }
}
