//! The rules of docs/world.md section 2 on hand-built states, for both backends.

use sim::{Action, BlockId, Cell, Effect, Grid, GridWorld, PhysicsWorld, SimError, State, World};

fn state(cells: &[(u16, u16)], held: Option<u16>) -> State {
    let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
    State::new(&cells, held.map(BlockId)).unwrap()
}

/// Runs `check` on a grid world and a physics world built from the same state.
fn both(grid: Grid, start: State, check: impl Fn(&mut dyn World)) {
    check(&mut GridWorld::new(grid, start.clone()).unwrap());
    check(&mut PhysicsWorld::new(grid, start).unwrap());
}

fn cells(w: &dyn World) -> Vec<(u16, u16)> {
    w.state().cells().iter().map(|c| (c.x, c.y)).collect()
}

#[test]
fn held_block_moves_in_each_direction() {
    let start = state(&[(3, 3), (0, 0)], Some(0));
    for (action, to) in [
        (Action::Up, (3, 4)),
        (Action::Down, (3, 2)),
        (Action::Left, (2, 3)),
        (Action::Right, (4, 3)),
    ] {
        both(Grid::default(), start.clone(), |w| {
            assert_eq!(w.act(action).unwrap(), Effect::Moved);
            assert_eq!(cells(w), vec![to, (0, 0)], "{action}");
            assert_eq!(w.held_block(), Some(BlockId(0)));
        });
    }
}

#[test]
fn walls_block_moves_out_of_the_grid() {
    // Block 0 in the bottom-left corner, block 1 in the top-right corner of a 5x4 grid.
    let grid = Grid::new(5, 4).unwrap();
    for (held, action) in [
        (0, Action::Left),
        (0, Action::Down),
        (1, Action::Right),
        (1, Action::Up),
    ] {
        both(grid, state(&[(0, 0), (4, 3)], Some(held)), |w| {
            assert_eq!(w.act(action).unwrap(), Effect::Blocked, "block {held} {action}");
            assert_eq!(cells(w), vec![(0, 0), (4, 3)]);
        });
    }
}

#[test]
fn blocks_block_moves_into_them() {
    // Block 0 at the centre, surrounded on all four sides.
    let start = state(&[(3, 3), (3, 4), (3, 2), (2, 3), (4, 3)], Some(0));
    for action in [Action::Up, Action::Down, Action::Left, Action::Right] {
        both(Grid::default(), start.clone(), |w| {
            assert_eq!(w.act(action).unwrap(), Effect::Blocked, "{action}");
            assert_eq!(w.state(), start);
        });
    }
}

#[test]
fn diagonal_and_distant_blocks_do_not_block() {
    // Diagonal neighbours and a block two cells away leave every move free.
    let start = state(&[(3, 3), (2, 4), (4, 2), (5, 3), (3, 5)], Some(0));
    for action in [Action::Up, Action::Down, Action::Left, Action::Right] {
        both(Grid::default(), start.clone(), |w| {
            assert_eq!(w.act(action).unwrap(), Effect::Moved, "{action}")
        });
    }
}

#[test]
fn moves_with_nothing_held_change_nothing() {
    let start = state(&[(3, 3), (5, 5)], None);
    for action in [Action::Up, Action::Down, Action::Left, Action::Right] {
        both(Grid::default(), start.clone(), |w| {
            assert_eq!(w.act(action).unwrap(), Effect::NothingHeld);
            assert_eq!(w.state(), start);
        });
    }
}

#[test]
fn pick_switches_and_releases_in_place() {
    both(Grid::default(), state(&[(1, 1), (5, 5)], Some(0)), |w| {
        assert_eq!(w.act(Action::Pick(BlockId(1))).unwrap(), Effect::Picked);
        assert_eq!(w.held_block(), Some(BlockId(1)));
        assert_eq!(w.act(Action::Right).unwrap(), Effect::Moved);
        // Block 0 stayed where it was released; block 1 moved.
        assert_eq!(cells(w), vec![(1, 1), (6, 5)]);
        assert_eq!(w.act(Action::Pick(BlockId(1))).unwrap(), Effect::Unchanged);
    });
}

#[test]
fn drop_releases_and_a_second_drop_does_nothing() {
    both(Grid::default(), state(&[(1, 1), (5, 5)], Some(1)), |w| {
        assert_eq!(w.act(Action::Drop).unwrap(), Effect::Dropped);
        assert_eq!(w.held_block(), None);
        assert_eq!(w.act(Action::Drop).unwrap(), Effect::Unchanged);
        assert_eq!(w.act(Action::Up).unwrap(), Effect::NothingHeld);
        assert_eq!(cells(w), vec![(1, 1), (5, 5)]);
    });
}

#[test]
fn picking_a_missing_block_is_an_error() {
    both(Grid::default(), state(&[(1, 1), (5, 5)], None), |w| {
        assert_eq!(
            w.act(Action::Pick(BlockId(2))),
            Err(SimError::NoSuchBlock { block: 2, blocks: 2 })
        );
    });
}

#[test]
fn action_indices_follow_the_table() {
    let names: Vec<String> = Action::all(3).map(|a| a.to_string()).collect();
    assert_eq!(
        names,
        ["up", "down", "left", "right", "drop", "pick 0", "pick 1", "pick 2"]
    );
    for a in Action::all(3) {
        assert_eq!(Action::from_index(a.index(), 3), Ok(a));
        assert_eq!(Action::parse(&a.to_string(), 3), Ok(a));
    }
    assert_eq!(
        Action::from_index(8, 3),
        Err(SimError::ActionOutOfRange { index: 8, blocks: 3 })
    );
}

#[test]
fn a_state_rejects_overlaps_and_missing_held_blocks() {
    let c = Cell::new(2, 2);
    assert!(matches!(State::new(&[c, c], None), Err(SimError::CellsOverlap { .. })));
    assert!(matches!(
        State::new(&[c, Cell::new(0, 0)], Some(BlockId(2))),
        Err(SimError::NoSuchBlock { .. })
    ));
    let outside = State::new(&[Cell::new(7, 0), c], None).unwrap();
    assert!(matches!(
        GridWorld::new(Grid::default(), outside.clone()),
        Err(SimError::CellOutsideGrid { .. })
    ));
    assert!(matches!(
        PhysicsWorld::new(Grid::default(), outside),
        Err(SimError::CellOutsideGrid { .. })
    ));
}

#[test]
fn placing_a_state_that_does_not_fit_is_an_error_and_changes_nothing() {
    let start = state(&[(1, 1), (5, 5)], None);
    let three = state(&[(0, 0), (1, 0), (2, 0)], None);
    let outside = State::new(&[Cell::new(0, 0), Cell::new(0, 7)], None).unwrap();
    both(Grid::default(), start.clone(), |w| {
        assert!(matches!(
            w.place(&three),
            Err(SimError::BlockCountMismatch {
                expected: 2,
                found: 3,
                ..
            })
        ));
        assert!(matches!(
            w.place(&outside),
            Err(SimError::CellOutsideGrid { x: 0, y: 7, .. })
        ));
        assert_eq!(w.state(), start);
        let moved = state(&[(6, 6), (0, 0)], Some(1));
        w.place(&moved).unwrap();
        assert_eq!(w.state(), moved);
    });
}
