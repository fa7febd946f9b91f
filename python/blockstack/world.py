"""The world keywords: one set, taken the same way by every environment and by
:func:`blockstack.demonstrations`.

:class:`blockstack.StackEnv`, :class:`blockstack.BlocksWorldEnv`,
:class:`blockstack.vector.StackVectorEnv`, :class:`blockstack.StackGoalEnv` and
:func:`blockstack.demonstrations` describe the world they play with these keywords and no
others (each adds its own keywords about what it does with the world: ``obs``,
``render_mode``, ``actions``, ``threads``...). :func:`world_of` reads them into a
:class:`World`, checking every type and range first, so that a bad value is one
``ValueError`` naming the keyword, never a ``TypeError`` or ``OverflowError``; the Rust side
(``sim::EnvConfig``) then checks that the values make a world.

- ``blocks``: number of blocks ``N`` (2 to 16; default 3).
- ``goal``: the stack bottom to top (``"1,0,2"`` or ``[1, 0, 2]``), or towers (``"0,1/2"``);
  ``None`` (the default) draws one stack each episode.
- ``grid``: ``(width, height)`` or text such as ``"7x7"``; ``None`` (the default) is
  ``(7, 7)``, and in the side view ``(7, 7)`` up to 7 blocks and ``(N, N + 1)`` beyond
  (docs/world.md, "The side view at any size").
- ``reward``: ``sparse``, ``dense``, ``paper``, ``step-cost`` or ``paper-code``; ``None``
  (the default) takes the profile's.
- ``backend``: ``physics`` (rapier2d, the default) or ``grid`` (the occupancy model).
- ``horizon`` (or Gymnasium's name for it, ``max_episode_steps``): steps before an episode
  is truncated, default 1000; ``horizon`` wins when both are given.
- ``profile``: ``spec`` (the default) or ``original`` (the paper's world as its authors
  coded it).
- ``protocol`` (``free`` or ``paper``) and ``start`` (``uniform`` or ``paper``): one rule of
  the profile each; ``None`` (the default) keeps the profile's.
- ``view``: ``top`` (the default, the paper's world) or ``side`` (the classic Blocks World).
"""

from __future__ import annotations

import dataclasses
from typing import Any, Optional, Sequence, Union

from blockstack import _native
from blockstack._checks import U32_MAX, whole
from blockstack._goal import Goal, goal_text

Grid = Union[str, Sequence[int]]


@dataclasses.dataclass(frozen=True)
class World:
    """The world keywords, checked (module docs). The Rust side reads it by attribute."""

    blocks: int = 3
    goal: Goal = None
    grid: Optional[Grid] = None
    reward: Optional[str] = None
    backend: str = "physics"
    horizon: int = 1000
    profile: str = "spec"
    protocol: Optional[str] = None
    start: Optional[str] = None
    view: str = "top"

    def __post_init__(self):
        def put(name: str, value: Any) -> None:
            object.__setattr__(self, name, value)

        put("blocks", whole("blocks", self.blocks))
        for name in ("backend", "profile", "view"):
            _text(name, getattr(self, name))
        put("grid", _native.grid_size(self.grid, self.view, self.blocks))
        put("horizon", whole("horizon", self.horizon, 0, U32_MAX))
        put("goal", goal_text(self.goal))
        for name in ("reward", "protocol", "start"):
            value = getattr(self, name)
            if value is not None:
                _text(name, value)


#: Every world keyword, in :class:`World`'s order, then ``max_episode_steps``.
KEYWORDS = tuple(f.name for f in dataclasses.fields(World)) + ("max_episode_steps",)


def _text(name: str, value: Any) -> None:
    if not isinstance(value, str):
        raise ValueError(f"{name} is a name (text), not {value!r}")


def world_of(keywords: dict) -> World:
    """The :class:`World` of ``keywords`` (world keywords only); a ``ValueError`` naming any
    keyword that is not one, or a value of the wrong type or range."""
    unknown = sorted(str(k) for k in keywords if k not in KEYWORDS)
    if unknown:
        raise ValueError(
            f"unknown keyword(s) {', '.join(unknown)}: the world keywords are {', '.join(KEYWORDS)}"
        )
    given = dict(keywords)
    steps = given.pop("max_episode_steps", 1000)
    horizon = given.pop("horizon", None)
    steps = whole("max_episode_steps", steps, 0, U32_MAX)
    return World(horizon=steps if horizon is None else horizon, **given)
