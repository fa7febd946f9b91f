//! The physics backend: every block a rapier2d rigid body, moved by a discrete controller
//! that asks rapier's collision detection whether each move is free (docs/world.md section 4).
//!
//! # How a move is decided
//!
//! The held block's own collider shape is cast through the broad phase from where the body
//! stands, one cell's length in the move's direction, excluding the block's own body. Walls
//! and other blocks are ordinary colliders, so any hit before the neighbouring cell centre
//! means the move is blocked. Colliders are a little smaller than a cell
//! ([`BLOCK_HALF_EXTENT`]), so blocks on neighbouring cells, even diagonal ones, never touch,
//! and a block two cells away is first touched after the cast has gone further than one
//! cell.
//!
//! # Why no dynamics solve
//!
//! A move is a teleport to a cell centre computed from integer cell coordinates, so nothing
//! drifts. No `PhysicsPipeline::step` runs: nothing in the world has velocity between
//! moves, and a pipeline step costs about 15 times the shape cast (1.5-2 us against 0.2 us
//! here) while adding nothing the cast does not already decide. The broad phase is kept
//! current with `BroadPhaseBvh::set_aabb` after every move, and a periodic
//! `BroadPhaseBvh::update` clears the list of changed leaves that `set_aabb` grows.
//!
//! # State read-back
//!
//! [`World::cell_of`] and [`World::state`] read the bodies' translations; nothing keeps a
//! second copy of where the blocks are. Only the held block (a property of the controller,
//! not of the bodies) is stored beside them.

use rapier2d::parry::query::{DefaultQueryDispatcher, ShapeCastOptions};
use rapier2d::prelude::*;

use crate::error::Result;
use crate::grid::{Cell, Direction, Grid};
use crate::state::{BlockId, MAX_BLOCKS, State};
use crate::world::World;

/// Half the side of a block's collider, in world units (a cell is 1.0): blocks are
/// 0.9 wide, leaving a 0.1 gap between neighbours.
pub const BLOCK_HALF_EXTENT: f32 = 0.45;

/// Moves between two broad-phase updates; bounds the list of changed leaves that
/// `set_aabb` grows.
const MOVES_PER_BROAD_PHASE_UPDATE: u32 = 1024;

/// Half the thickness of a wall collider.
const WALL_HALF_THICKNESS: f32 = 0.5;

/// One block: its body and the collider attached to it.
#[derive(Clone, Copy, Debug)]
struct BlockBody {
    body: RigidBodyHandle,
    collider: ColliderHandle,
}

/// Blocks as rapier2d rigid bodies inside four static walls.
#[derive(Clone)]
pub struct PhysicsWorld {
    grid: Grid,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    broad_phase: BroadPhaseBvh,
    params: IntegrationParameters,
    blocks: Vec<BlockBody>,
    held: Option<BlockId>,
    moves_since_update: u32,
}

impl PhysicsWorld {
    /// A world on `grid` with its blocks placed as `state` says; an error if the state
    /// does not fit the grid.
    pub fn new(grid: Grid, state: State) -> Result<Self> {
        state.check_fits(grid)?;
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let blocks = state
            .cells()
            .iter()
            .map(|&cell| {
                // Kinematic: the controller, not a force, decides where a block goes.
                let body = bodies.insert(RigidBodyBuilder::kinematic_position_based().translation(centre(cell)));
                let collider = colliders.insert_with_parent(
                    ColliderBuilder::cuboid(BLOCK_HALF_EXTENT, BLOCK_HALF_EXTENT),
                    body,
                    &mut bodies,
                );
                BlockBody { body, collider }
            })
            .collect();
        let (w, h) = (grid.width() as f32, grid.height() as f32);
        let t = WALL_HALF_THICKNESS;
        // Left, right, bottom, top: each overlaps the corners so no gap is left.
        for (x, y, hx, hy) in [
            (-t, h / 2.0, t, h / 2.0 + 2.0 * t),
            (w + t, h / 2.0, t, h / 2.0 + 2.0 * t),
            (w / 2.0, -t, w / 2.0 + 2.0 * t, t),
            (w / 2.0, h + t, w / 2.0 + 2.0 * t, t),
        ] {
            colliders.insert(ColliderBuilder::cuboid(hx, hy).translation(Vector::new(x, y)));
        }
        let mut world = PhysicsWorld {
            grid,
            bodies,
            colliders,
            broad_phase: BroadPhaseBvh::new(),
            params: IntegrationParameters::default(),
            blocks,
            held: state.held_block(),
            moves_since_update: 0,
        };
        let all: Vec<ColliderHandle> = world.colliders.iter().map(|(h, _)| h).collect();
        world.update_broad_phase(&all);
        Ok(world)
    }

    /// The largest distance, over all blocks, between a body's translation (or its
    /// collider's) and the centre of the cell it stands on. Zero up to rounding when the
    /// controller keeps its invariant.
    pub fn max_centre_error(&self) -> f32 {
        self.blocks
            .iter()
            .flat_map(|b| {
                let body = self.bodies[b.body].translation();
                let collider = self.colliders[b.collider].position().translation;
                let c = centre(cell_at(body));
                [(body - c).length(), (collider - c).length()]
            })
            .fold(0.0, f32::max)
    }

    /// Puts `block`'s body and collider on the centre of `cell` and tells the broad phase.
    fn teleport(&mut self, block: BlockId, cell: Cell) {
        let b = self.blocks[block.index()];
        let target = centre(cell);
        self.bodies[b.body].set_translation(target, false);
        // The attached collider follows its body only on a pipeline step; set it here.
        let collider = &mut self.colliders[b.collider];
        collider.set_position(Pose::from_translation(target));
        let aabb = collider.compute_aabb();
        self.broad_phase.set_aabb(&self.params, b.collider, aabb);
        self.moves_since_update += 1;
        if self.moves_since_update >= MOVES_PER_BROAD_PHASE_UPDATE {
            self.update_broad_phase(&[]);
        }
    }

    /// Runs a broad-phase update: inserts `modified` colliders' leaves and clears the
    /// changed-leaf list. The pair events it reports are not needed.
    fn update_broad_phase(&mut self, modified: &[ColliderHandle]) {
        let mut events = Vec::new();
        self.broad_phase
            .update(&self.params, &self.colliders, &self.bodies, modified, &[], &mut events);
        self.moves_since_update = 0;
    }
}

/// The world-space centre of `cell`, computed from its integer coordinates.
#[inline]
fn centre(cell: Cell) -> Vector {
    Vector::new(f32::from(cell.x) + 0.5, f32::from(cell.y) + 0.5)
}

/// The cell whose centre is nearest to `p`.
#[inline]
fn cell_at(p: Vector) -> Cell {
    Cell::new((p.x - 0.5).round() as u8, (p.y - 0.5).round() as u8)
}

impl World for PhysicsWorld {
    fn grid(&self) -> Grid {
        self.grid
    }

    fn block_count(&self) -> usize {
        self.blocks.len()
    }

    #[inline]
    fn cell_of(&self, block: BlockId) -> Cell {
        cell_at(self.bodies[self.blocks[block.index()].body].translation())
    }

    fn held_block(&self) -> Option<BlockId> {
        self.held
    }

    fn set_held(&mut self, held: Option<BlockId>) {
        self.held = held;
    }

    fn try_move(&mut self, block: BlockId, dir: Direction) -> bool {
        let b = self.blocks[block.index()];
        let (dx, dy) = dir.delta();
        let collider = &self.colliders[b.collider];
        let query = self.broad_phase.as_query_pipeline(
            &DefaultQueryDispatcher,
            &self.bodies,
            &self.colliders,
            QueryFilter::default().exclude_rigid_body(b.body),
        );
        // One cell's travel: anything hit before the neighbouring centre blocks the move.
        let hit = query.cast_shape(
            collider.position(),
            Vector::new(dx as f32, dy as f32),
            collider.shape(),
            ShapeCastOptions {
                max_time_of_impact: 1.0,
                target_distance: 0.0,
                stop_at_penetration: true,
                compute_impact_geometry_on_penetration: false,
            },
        );
        if hit.is_some() {
            return false;
        }
        let from = self.cell_of(block);
        // The walls kept the block inside the grid, so the neighbour exists.
        let to = Cell::new((i32::from(from.x) + dx) as u8, (i32::from(from.y) + dy) as u8);
        self.teleport(block, to);
        true
    }

    fn put(&mut self, state: &State) {
        for (i, &cell) in state.cells().iter().enumerate() {
            self.teleport(BlockId(i as u8), cell);
        }
        self.held = state.held_block();
    }

    fn state(&self) -> State {
        let mut cells = [Cell::default(); MAX_BLOCKS];
        for (i, c) in cells.iter_mut().take(self.blocks.len()).enumerate() {
            *c = self.cell_of(BlockId(i as u8));
        }
        State::new(&cells[..self.blocks.len()], self.held).expect("the walls and casts keep blocks on distinct cells")
    }
}
