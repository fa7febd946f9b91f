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
//! # The side view: dynamics for a drop
//!
//! In the side view ([`View::Side`]) every block is a **dynamic** body under gravity, except
//! the held one, which is kinematic and moved by the same shape-cast controller. A Drop
//! makes the held block dynamic and runs rapier's pipeline until every body is at rest; the
//! resting cell of every block is then read back, checked to be within
//! [`SIDE_ALIGN_TOLERANCE`] of a cell centre (an error otherwise), and the bodies are put
//! exactly on their cells and to sleep, so that rounding never accumulates across drops.
//! The settings, and why:
//!
//! - Colliders are [`SIDE_HALF_WIDTH`] x [`SIDE_HALF_HEIGHT`] with a contact skin of
//!   [`SIDE_CONTACT_SKIN`]: a block resting on the table or on another block keeps its skin
//!   between them, so a stack's centres are exactly one cell apart (0.9 of height plus two
//!   skins of 0.05), while blocks side by side stay 0.2 apart, further than two skins, and
//!   never touch (no friction from a neighbouring tower slows a fall). The shape cast sees
//!   the shape without its skin, so moves are decided as in the top view.
//! - Rotations are locked: unit blocks land square on what is below (the fall is vertical),
//!   and a locked body cannot creep sideways by tipping, which keeps the read-back on cells.
//! - Gravity [`SIDE_GRAVITY`] (four times Earth's, in cells per second squared) shortens a
//!   fall of six rows to about 35 steps of 1/60 s. Stronger gravity was tried: at 150 a
//!   tower of four compressed under its own weight by more than the alignment tolerance.
//!   CCD is on, so that no fall (up to 15 rows, faster than half a block per step) can pass
//!   through a block.
//! - The contact solver ([`SideSolver`]) is chosen by the tallest tower the world can
//!   build, its block count. Up to [`SIDE_SMALL_WORLD_BLOCKS`] blocks it is rapier's default
//!   (60 steps a second, 4 iterations, contacts of 30 Hz): the cheapest, and a tower of nine
//!   comes to rest within the alignment tolerance. See "Tall towers" for more blocks.
//! - Rest is rapier's own sleep: a drop steps the pipeline until every block sleeps, and a
//!   block sleeps once it has moved less than 0.05 cells per second (rapier's threshold,
//!   which counts the solver's position corrections as motion too) for
//!   [`SIDE_TIME_UNTIL_SLEEP`] (three steps, not rapier's default half second, which would
//!   add 30 steps to every drop). Sleeping blocks cost the solver nothing, so only the
//!   falling block and the tower it lands on are solved. Bodies are never put to sleep by
//!   hand: one put to sleep before rapier had solved its contacts fell through the table
//!   once woken. [`SIDE_MAX_SETTLE_STEPS`] bounds a drop.
//! - `enhanced-determinism` (on in the workspace's Cargo.toml) makes rapier's arithmetic
//!   the same on every machine, so a drop comes to rest the same way everywhere; the
//!   snap to cell centres then makes the logical state exact.
//!
//! # Tall towers
//!
//! rapier's contacts are soft springs: under load they give a little, and a stack's
//! give adds up from the bottom, the block at height `k` carrying `N - k` blocks. Under
//! the default solver the eleventh block of a tower rests 0.052 below its cell, past the
//! tolerance, and the tenth can too: one picked off a tower of ten, dropped back, picked
//! again and dropped from a row higher rested 0.055 below its cell (36 times in E9's 10^6
//! random steps at ten blocks, in its long run at commit c1acf3e; a test replays the
//! first). Stiffer contacts give less (the give falls as the square of the contact's
//! frequency), but a contact stiff against the substep rings and never sleeps: at 60 steps
//! a second with 4 iterations, 120 Hz contacts kept a tower of ten oscillating. So a
//! world of ten blocks or more uses [`SideSolver::TALL`]: contacts of 300 Hz, 120 steps a second
//! of 24 iterations each (a substep of 1/2880 s), twelve times the default's solver work
//! per simulated second, which is why small worlds keep the default. How tall a tower
//! then stands, and whether random block moves of 20, 50 and 100 blocks end where the grid
//! model says, is measured by `cargo run --release -p sim --example side_physics` (its
//! output is docs/results/side-physics.md); the settings were chosen by it.
//!
//! # Why the side view casts against each collider
//!
//! In the top view the cast goes through the broad phase's tree, which only our own
//! updates change. In the side view rapier's pipeline steps update and reorganise that tree
//! too (its deferred optimisation pass), and a soak of random play found a cast through it
//! that missed a wall right beside the held block (the block left the grid) while a cast
//! against the wall itself hit. So the side view casts the held block's shape against
//! every other collider directly (at most 16 blocks and 4 walls, a fraction of a
//! microsecond each): the same shape cast, without the tree.
//!
//! # State read-back
//!
//! [`World::cell_of`] and [`World::state`] read the bodies' translations; nothing keeps a
//! second copy of where the blocks are. Only the held block (a property of the controller,
//! not of the bodies) is stored beside them.

use rapier2d::parry::query::{DefaultQueryDispatcher, ShapeCastOptions, cast_shapes};
use rapier2d::prelude::*;

use crate::error::{Result, SimError};
use crate::grid::{Cell, Direction, Grid};
use crate::state::{BlockId, Cells, State};
use crate::view::View;
use crate::world::World;

/// Half the side of a block's collider, in world units (a cell is 1.0): blocks are
/// 0.9 wide, leaving a 0.1 gap between neighbours.
pub const BLOCK_HALF_EXTENT: f32 = 0.45;

/// Moves between two broad-phase updates; bounds the list of changed leaves that
/// `set_aabb` grows.
const MOVES_PER_BROAD_PHASE_UPDATE: u32 = 1024;

/// Half the thickness of a wall collider.
const WALL_HALF_THICKNESS: f32 = 0.5;

/// Side view: half the width of a block's collider (module docs: blocks side by side stay
/// 0.2 apart).
pub const SIDE_HALF_WIDTH: f32 = 0.40;

/// Side view: half the height of a block's collider; with two contact skins a stack's
/// centres are one cell apart.
pub const SIDE_HALF_HEIGHT: f32 = 0.45;

/// Side view: the contact skin of a block's collider.
pub const SIDE_CONTACT_SKIN: f32 = 0.05;

/// Side view: gravity, in cells per second squared (downward).
pub const SIDE_GRAVITY: f32 = 4.0 * 9.81;

/// Side view: the most blocks a world may have for [`SideSolver::SMALL`] to settle its
/// tallest tower (module docs, "Tall towers"); larger worlds use [`SideSolver::TALL`].
pub const SIDE_SMALL_WORLD_BLOCKS: usize = 9;

/// Side view: the settings of rapier's contact solver, chosen by the tallest tower a world
/// can build, its block count (module docs, "Tall towers").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SideSolver {
    /// Pipeline steps per simulated second (`1 / IntegrationParameters::dt`).
    pub steps_per_second: f32,
    /// Solver iterations (substeps) per step.
    pub iterations: usize,
    /// The natural frequency (Hz) of a contact between two blocks; a contact with the table
    /// or a wall is twice as stiff, as in rapier's defaults.
    pub contact_hz: f32,
}

impl SideSolver {
    /// Up to [`SIDE_SMALL_WORLD_BLOCKS`] blocks: rapier's defaults (60 steps a second, 4
    /// iterations, contacts of 30 Hz), the cheapest settings under which a tower of nine
    /// stands (module docs, "Tall towers").
    pub const SMALL: SideSolver = SideSolver {
        steps_per_second: 60.0,
        iterations: 4,
        contact_hz: 30.0,
    };

    /// More blocks: contacts ten times as stiff, and as many substeps as keep them from
    /// ringing (`docs/results/side-physics.md` measures how tall a tower stands).
    pub const TALL: SideSolver = SideSolver {
        steps_per_second: 120.0,
        iterations: 24,
        contact_hz: 300.0,
    };

    /// The settings for a world of `blocks` blocks.
    pub fn for_blocks(blocks: usize) -> SideSolver {
        if blocks <= SIDE_SMALL_WORLD_BLOCKS {
            SideSolver::SMALL
        } else {
            SideSolver::TALL
        }
    }

    /// Writes these settings into `params`; rapier's damping ratio (10) is kept.
    fn apply(self, params: &mut IntegrationParameters) {
        params.dt = 1.0 / self.steps_per_second;
        params.num_solver_iterations = self.iterations;
        params.contact_softness.natural_frequency = self.contact_hz;
        params.static_contact_softness.natural_frequency = 2.0 * self.contact_hz;
    }
}

/// Side view: how long (simulated seconds) a block must stay still (rapier's sleep
/// threshold, 0.05 cells per second) before it sleeps; a drop ends when every block sleeps.
pub const SIDE_TIME_UNTIL_SLEEP: f32 = 3.0 / 60.0;

/// Side view: the most pipeline steps a drop may take before it is an error.
pub const SIDE_MAX_SETTLE_STEPS: u32 = 2000;

/// Side view: how far from a cell centre a resting block may be read back (module docs).
pub const SIDE_ALIGN_TOLERANCE: f32 = 0.05;

/// rapier's dynamics state, side view only: what `PhysicsPipeline::step` needs beside the
/// bodies, colliders and broad phase. The pipeline and the CCD solver are workspaces, so a
/// clone starts fresh ones (and no joints are ever made).
struct Dynamics {
    pipeline: PhysicsPipeline,
    islands: IslandManager,
    narrow_phase: NarrowPhase,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    soft_bodies: SoftBodySet,
    ccd_solver: CCDSolver,
}

impl Dynamics {
    fn new() -> Self {
        Dynamics {
            pipeline: PhysicsPipeline::new(),
            islands: IslandManager::new(),
            narrow_phase: NarrowPhase::new(),
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: MultibodyJointSet::new(),
            soft_bodies: SoftBodySet::new(),
            ccd_solver: CCDSolver::new(),
        }
    }
}

impl Clone for Dynamics {
    fn clone(&self) -> Self {
        Dynamics {
            pipeline: PhysicsPipeline::new(),
            islands: self.islands.clone(),
            narrow_phase: self.narrow_phase.clone(),
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: self.multibody_joints.clone(),
            soft_bodies: self.soft_bodies.clone(),
            ccd_solver: CCDSolver::new(),
        }
    }
}

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
    /// The side view's dynamics; `None` in the top view, where nothing ever moves by force.
    dynamics: Option<Box<Dynamics>>,
    /// Pipeline steps the last drop took to come to rest (side view).
    settle_steps: u32,
}

impl PhysicsWorld {
    /// A top-view world on `grid` with its blocks placed as `state` says; an error if the
    /// state does not fit the grid.
    pub fn new(grid: Grid, state: State) -> Result<Self> {
        Self::new_in(View::Top, grid, state)
    }

    /// A world of `view` on `grid` with its blocks placed as `state` says; an error if the
    /// state does not fit the grid (or, in the side view, has a block standing on nothing).
    pub fn new_in(view: View, grid: Grid, state: State) -> Result<Self> {
        view.check_world(grid, state.block_count())?;
        state.check_fits(grid)?;
        view.check_state(&state)?;
        let side = view == View::Side;
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let blocks = state
            .cells()
            .iter()
            .map(|&cell| {
                let body = if side {
                    // Dynamic under gravity (module docs); `put` makes the held one kinematic.
                    RigidBodyBuilder::dynamic().lock_rotations().ccd_enabled(true)
                } else {
                    // Kinematic: the controller, not a force, decides where a block goes.
                    RigidBodyBuilder::kinematic_position_based()
                };
                let body = bodies.insert(body.translation(centre(cell)));
                // Side view: rapier's own sleep decides rest (module docs), sooner than its
                // default half second.
                bodies[body].activation_mut().time_until_sleep = SIDE_TIME_UNTIL_SLEEP;
                let shape = if side {
                    ColliderBuilder::cuboid(SIDE_HALF_WIDTH, SIDE_HALF_HEIGHT).contact_skin(SIDE_CONTACT_SKIN)
                } else {
                    ColliderBuilder::cuboid(BLOCK_HALF_EXTENT, BLOCK_HALF_EXTENT)
                };
                let collider = colliders.insert_with_parent(shape, body, &mut bodies);
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
        let mut params = IntegrationParameters::default();
        if side {
            SideSolver::for_blocks(state.block_count()).apply(&mut params);
        }
        let mut world = PhysicsWorld {
            grid,
            bodies,
            colliders,
            broad_phase: BroadPhaseBvh::new(),
            params,
            blocks,
            held: None,
            moves_since_update: 0,
            dynamics: side.then(|| Box::new(Dynamics::new())),
            settle_steps: 0,
        };
        let all: Vec<ColliderHandle> = world.colliders.iter().map(|(h, _)| h).collect();
        world.update_broad_phase(&all);
        world.set_held(state.held_block());
        world.rest_all();
        Ok(world)
    }

    /// Side view: how many rapier pipeline steps the last drop took to bring every block to
    /// rest (0 before any drop, and in the top view).
    pub fn settle_steps(&self) -> u32 {
        self.settle_steps
    }

    /// Side view: zeroes every block's velocity (they stand exactly on their cells, at
    /// rest). They are not put to sleep by hand: a body put to sleep before rapier had solved
    /// its contacts fell through the table once woken, so rapier's own sleep timer decides.
    fn rest_all(&mut self) {
        if self.dynamics.is_none() {
            return;
        }
        for b in &self.blocks {
            self.bodies[b.body].set_linvel(Vector::ZERO, false);
        }
    }

    /// Side view: runs the pipeline until every block is at rest (module docs); the number
    /// of steps it took, or an error if they do not come to rest in
    /// [`SIDE_MAX_SETTLE_STEPS`].
    fn run_to_rest(&mut self, dropped: BlockId) -> Result<u32> {
        let gravity = Vector::new(0.0, -SIDE_GRAVITY);
        let params = self.params;
        for step in 1..=SIDE_MAX_SETTLE_STEPS {
            self.step_pipeline(&params, gravity);
            if self.blocks.iter().all(|b| self.bodies[b.body].is_sleeping()) {
                return Ok(step);
            }
        }
        let _ = dropped;
        let (block, speed, at) = self
            .blocks
            .iter()
            .enumerate()
            .map(|(i, b)| (i, self.bodies[b.body].linvel(), self.bodies[b.body].translation()))
            .max_by(|x, y| x.1.length().total_cmp(&y.1.length()))
            .expect("a world has blocks");
        Err(SimError::NotAtRest {
            block,
            reason: format!(
                "still moving at ({:.5}, {:.5}) cells/s at ({:.4}, {:.4}) after {SIDE_MAX_SETTLE_STEPS} steps",
                speed.x, speed.y, at.x, at.y
            ),
        })
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
        self.set_position(block, cell);
        self.count_move();
    }

    /// Puts `block`'s body and collider on `cell`, without the periodic broad-phase update
    /// ([`PhysicsWorld::count_move`] runs it).
    fn set_position(&mut self, block: BlockId, cell: Cell) {
        let b = self.blocks[block.index()];
        let target = centre(cell);
        self.bodies[b.body].set_translation(target, false);
        // The attached collider follows its body only on a pipeline step; set it here.
        let collider = &mut self.colliders[b.collider];
        collider.set_position(Pose::from_translation(target));
        let aabb = collider.compute_aabb();
        self.broad_phase.set_aabb(&self.params, b.collider, aabb);
    }

    /// Counts one move towards the next broad-phase update, and runs it when due.
    fn count_move(&mut self) {
        self.moves_since_update += 1;
        if self.moves_since_update >= MOVES_PER_BROAD_PHASE_UPDATE {
            self.update_broad_phase(&[]);
        }
    }

    /// Puts every block on its cell of `cells`, then counts the moves: in the side view the
    /// update is a pipeline step, which must not see a world half rearranged (two blocks on
    /// one cell for a moment: the narrow phase kept that overlap as a deep contact, and the
    /// next drop's solver pushed both blocks off their cells).
    fn set_positions(&mut self, cells: &[Cell]) {
        for (i, &cell) in cells.iter().enumerate() {
            self.set_position(BlockId::of(i), cell);
        }
        for _ in cells {
            self.count_move();
        }
    }

    /// Runs a broad-phase update: inserts `modified` colliders' leaves and clears the
    /// changed-leaf list. In the top view the pair events it reports are not needed. In the
    /// side view the narrow phase needs them (a pair reported once and dropped would never
    /// collide), so the update is a pipeline step of zero length, which only runs the
    /// collision detection (rapier's `IntegrationParameters::dt` docs) and moves nothing.
    fn update_broad_phase(&mut self, modified: &[ColliderHandle]) {
        self.moves_since_update = 0;
        if self.dynamics.is_some() {
            let mut params = self.params;
            params.dt = 0.0;
            self.step_pipeline(&params, Vector::ZERO);
            return;
        }
        let mut events = Vec::new();
        self.broad_phase
            .update(&self.params, &self.colliders, &self.bodies, modified, &[], &mut events);
    }

    /// Side view: one step of rapier's pipeline with `params` under `gravity`.
    fn step_pipeline(&mut self, params: &IntegrationParameters, gravity: Vector) {
        let Some(dynamics) = self.dynamics.as_deref_mut() else {
            return;
        };
        dynamics.pipeline.step(
            gravity,
            params,
            &mut dynamics.islands,
            &mut self.broad_phase,
            &mut dynamics.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut dynamics.impulse_joints,
            &mut dynamics.multibody_joints,
            &mut dynamics.soft_bodies,
            &mut dynamics.ccd_solver,
            &(),
            &(),
        );
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
    Cell::new((p.x - 0.5).round() as u16, (p.y - 0.5).round() as u16)
}

impl World for PhysicsWorld {
    fn grid(&self) -> Grid {
        self.grid
    }

    fn view(&self) -> View {
        if self.dynamics.is_some() { View::Side } else { View::Top }
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
        if self.dynamics.is_some() && self.held != held {
            // Side view: the held block is carried (kinematic); every other one falls.
            for (b, kind) in [
                (self.held, RigidBodyType::Dynamic),
                (held, RigidBodyType::KinematicPositionBased),
            ] {
                if let Some(b) = b {
                    let body = &mut self.bodies[self.blocks[b.index()].body];
                    body.set_body_type(kind, false);
                    body.set_linvel(Vector::ZERO, false);
                }
            }
        }
        self.held = held;
    }

    fn settle(&mut self, block: BlockId) -> Result<()> {
        self.bodies[self.blocks[block.index()].body].wake_up(true);
        self.settle_steps = self.run_to_rest(block)?;
        // Read back every block's resting cell, check it, and put the block exactly on it.
        let mut cells = Cells::from_elem(Cell::default(), self.blocks.len());
        for (i, (b, slot)) in self.blocks.iter().zip(cells.iter_mut()).enumerate() {
            let at = self.bodies[b.body].translation();
            let cell = cell_at(at);
            let error = (at - centre(cell)).length();
            if error > SIDE_ALIGN_TOLERANCE {
                return Err(SimError::NotAtRest {
                    block: i,
                    reason: format!(
                        "it rests at ({:.3}, {:.3}), {error:.3} from the centre of {cell}",
                        at.x, at.y
                    ),
                });
            }
            *slot = cell;
        }
        self.set_positions(&cells);
        self.rest_all();
        Ok(())
    }

    fn try_move(&mut self, block: BlockId, dir: Direction) -> bool {
        let b = self.blocks[block.index()];
        let (dx, dy) = dir.delta();
        let collider = &self.colliders[b.collider];
        let options = ShapeCastOptions {
            max_time_of_impact: 1.0,
            target_distance: 0.0,
            stop_at_penetration: true,
            compute_impact_geometry_on_penetration: false,
        };
        let travel = Vector::new(dx as f32, dy as f32);
        if self.dynamics.is_some() {
            // Side view: the cast goes against every other collider (module docs, "Why the
            // side view casts against each collider").
            let blocked = self.colliders.iter().any(|(h, other)| {
                h != b.collider
                    && cast_shapes(
                        collider.position(),
                        travel,
                        collider.shape(),
                        other.position(),
                        Vector::ZERO,
                        other.shape(),
                        options,
                    )
                    .is_ok_and(|hit| hit.is_some())
            });
            if blocked {
                return false;
            }
            let from = self.cell_of(block);
            let to = Cell::new((i32::from(from.x) + dx) as u16, (i32::from(from.y) + dy) as u16);
            self.teleport(block, to);
            return true;
        }
        let query = self.broad_phase.as_query_pipeline(
            &DefaultQueryDispatcher,
            &self.bodies,
            &self.colliders,
            QueryFilter::default().exclude_rigid_body(b.body),
        );
        // One cell's travel: anything hit before the neighbouring centre blocks the move.
        let hit = query.cast_shape(collider.position(), travel, collider.shape(), options);
        if hit.is_some() {
            return false;
        }
        let from = self.cell_of(block);
        // The walls kept the block inside the grid, so the neighbour exists.
        let to = Cell::new((i32::from(from.x) + dx) as u16, (i32::from(from.y) + dy) as u16);
        self.teleport(block, to);
        true
    }

    fn put(&mut self, state: &State) {
        self.set_positions(state.cells());
        self.set_held(state.held_block());
        self.rest_all();
    }

    fn state(&self) -> State {
        let cells: Cells = (0..self.blocks.len()).map(|i| self.cell_of(BlockId::of(i))).collect();
        State::new(&cells, self.held).expect("the walls and casts keep blocks on distinct cells")
    }
}
