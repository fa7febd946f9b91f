"""Plans from any state, by the Rust exact solver or oracle; PDDL problems, one or a
folder of them."""

from __future__ import annotations

import json
import os
from typing import Optional, Sequence, Tuple

from blockstack import _native
from blockstack._checks import cells_of, optional_whole
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

    ``solver`` names a planner as ``blockstack solve --solver`` does: ``"exact"`` gives a
    shortest plan (A* over the joint state) under ``protocol`` (``"free"`` or ``"paper"``,
    as ``blockstack solve --protocol``); ``"oracle"`` the centroid + A* oracle's. An empty list when the goal holds already; ``ValueError`` for a
    state or goal that does not fit the grid.

    ``view="side"`` plans in the classic Blocks World seen from the side (the goal may be
    several towers, ``"0,1/2"``), counting ``cost``. ``cost="moves"`` (the side view's
    default) gives block moves, a list of ``{"block": B, "onto": "table" | C}``: the fewest
    (``solver="exact"`` or ``"exact-moves"``) or the near-optimal planner's
    (``"near-optimal"``, or ``"oracle"``). ``cost="steps"`` gives action indices: the fewest
    gripper steps (``"exact"``; ``held`` may name a block held at the start), the fewest
    block moves carried out by the gripper (``"exact-moves"``) or the near-optimal
    block-move plan carried out (``"near-optimal"`` or ``"oracle"``). Both as ``blockstack
    solve --view side --cost ... --json`` prints them.
    """
    checked = cells_of(cells)
    held = optional_whole("held", held, 0, 255)
    for name, value in (("solver", solver), ("protocol", protocol), ("view", view)):
        if not isinstance(value, str):
            raise ValueError(f"{name} is a name (text), not {value!r}")
    if cost is not None and not isinstance(cost, str):
        raise ValueError(f"cost is a name (text), not {cost!r}")
    return _native.solve(checked, goal, held, _native.grid_size(grid), solver, protocol, view, cost)


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
    return _native.read_pddl(_path("path", path))


def _path(name: str, value) -> str:
    """``value`` as a file name: text or an ``os.PathLike`` of text; ``TypeError`` for
    anything else (``None``, a number, bytes), never turned into a name."""
    if isinstance(value, (str, os.PathLike)):
        path = os.fspath(value)
        if isinstance(path, str):
            return path
    raise TypeError(f"{name} is a file name (str or os.PathLike), not {value!r}")


def _name(name: str, value) -> Optional[str]:
    if value is not None and not isinstance(value, str):
        raise TypeError(f"{name} is a name (str), not {value!r}")
    return value


def solve_pddl(path, solver: Optional[str] = None, model=None, budget: Optional[int] = None,
               time_limit: Optional[float] = None, domain=None, plan_file=None) -> dict:
    """The plan of the PDDL problem ``path``, as ``blockstack solve --pddl`` makes it: by the
    planner ``solver`` names (``"near-optimal"``, the default, ``"optimal"`` or ``"exact"``)
    or by the relational policy in the model file ``model``, checked by replaying it over
    the file's facts. A dict of ``solver``, ``moves``, ``cost`` (actions), ``lower_bound``
    (no plan costs less), ``optimal`` (the cost meets the bound), ``certificate`` (the
    bound's parts in block moves: ``misplaced``, ``forced``, ``breakers``), ``plan`` (the
    actions) and ``text`` (the plan file). ``budget`` is the exact solver's states,
    ``time_limit`` the optimal solver's seconds.

    ``domain`` is the problem's domain file, as ``blockstack solve --domain`` reads it: the
    4-operator Blocks World in either spelling (``pickup``/``putdown`` or
    ``pick-up``/``put-down``), whose action names the plan takes. ``plan_file`` is a file
    the plan text is written to, as ``--plan-file`` writes it (atomically; only a regular
    file or a new path). A file or option refused is a ``ValueError``.
    """
    model = None if model is None else _path("model", model)
    domain = None if domain is None else _path("domain", domain)
    plan_file = None if plan_file is None else _path("plan_file", plan_file)
    return _native.solve_pddl(_path("path", path), _name("solver", solver), model, budget, time_limit,
                              domain, plan_file)


def solve_all(folder, solver: Optional[str] = None, model=None, bounds=None, budget: Optional[int] = None,
              time_limit: Optional[float] = None) -> dict:
    """Every PDDL problem below ``folder`` planned as :func:`solve_pddl` plans one, as
    ``blockstack solve-all --json`` reports it: a dict of ``solver``, ``tasks`` (a row per
    task: its cost, lower bound, gap, whether proven optimal, the best known cost and ratio
    where ``bounds``, a file of best known costs, gives one, or its error), ``groups`` (a
    summary per subfolder) and ``overall``. Links are followed, each folder once.
    """
    model = None if model is None else _path("model", model)
    bounds = None if bounds is None else _path("bounds", bounds)
    text = _native.solve_all(_path("folder", folder), _name("solver", solver), model, bounds, budget, time_limit)
    return json.loads(text)
