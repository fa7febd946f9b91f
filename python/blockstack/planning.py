"""Plans from any state, by the Rust exact solver or oracle; PDDL problems."""

from __future__ import annotations

from typing import Optional, Sequence, Tuple

from blockstack import _native
from blockstack._goal import Goal


def solve(
    cells: Sequence[Tuple[int, int]],
    goal: Goal,
    held: Optional[int] = None,
    grid: Tuple[int, int] = (7, 7),
    solver: str = "exact",
    protocol: str = "free",
    view: str = "top",
    cost: Optional[str] = None,
) -> list:
    """A plan, as a list of action indices, from the state where block ``i`` stands on
    ``cells[i]`` (``(x, y)``, ``y`` upward) with ``held`` held, to ``goal`` (bottom to top,
    ``"1,0,2"`` or ``[1, 0, 2]``).

    ``solver="exact"`` gives a shortest plan (A* over the joint state) under ``protocol``
    (``"free"`` or ``"paper"``, as ``blockstack solve --protocol``); ``"oracle"`` the
    centroid + A* oracle's. An empty list when the goal holds already; ``ValueError`` for a
    state or goal that does not fit the grid.

    ``view="side"`` plans in the classic Blocks World seen from the side (the goal may be
    several towers, ``"0,1/2"``), counting ``cost``. ``cost="moves"`` (the side view's
    default) gives block moves, a list of ``{"block": B, "onto": "table" | C}``: the fewest
    (``solver="exact"``) or the near-optimal planner's (``"near-optimal"``, or
    ``"oracle"``). ``cost="steps"`` gives action indices: the fewest gripper steps
    (``"exact"``; ``held`` may name a block held at the start) or the near-optimal block-move
    plan carried out by the gripper (``"near-optimal"`` or ``"oracle"``). Both as
    ``blockstack solve --view side --cost ... --json`` prints them.
    """
    return _native.solve([tuple(c) for c in cells], goal, held, tuple(grid), solver, protocol, view, cost)


def read_pddl(path) -> dict:
    """The Blocks World problem in the PDDL file ``path`` (the planning competitions'
    4-operator domain: ``:objects``, ``:init`` with ``on`` / ``on-table`` / ``clear`` /
    ``arm-empty``, ``:goal``), as ``blockstack solve --pddl`` reads it: a dict of ``name``,
    ``domain``, ``blocks`` (the objects' names; block ``i`` is ``blocks[i]``), ``start`` and
    ``goal`` (lists of towers, each bottom to top, by block index; blocks the goal does not
    place are free) and ``plan``, the near-optimal planner's plan in the competitions'
    format (``["(unstack b3 b5)", "(putdown b3)", ...]``, two actions a block move).

    A file that is not such a problem (a block placed twice, a cycle of ``on``, an unknown
    predicate, a goal naming an undeclared block, a goal of bare ``on`` facts, a file over
    64 MiB) raises ``ValueError`` naming the file, the line and the problem.
    """
    return _native.read_pddl(str(path))
