"""``blockstack.train`` and ``blockstack.train_dqn``: the Rust tabular and network trainers,
their settings' names and whole numbers checked in Python first.

Why: pyo3 turns ``seed=-1`` into an ``OverflowError`` that names no argument, and the Ray
sweep must refuse a misspelt flag before Ray starts, not inside a task.
"""

from __future__ import annotations

import inspect
from typing import Any, Dict, Mapping

from blockstack import _native
from blockstack._checks import U32_MAX, U64_MAX, whole

#: The tabular trainer's whole-number settings and the largest value each takes (the Rust
#: side's widths).
WHOLE_SETTINGS = {
    "blocks": U64_MAX,
    "games": U64_MAX,
    "seed": U64_MAX,
    "horizon": U32_MAX,
    "eval_episodes": U64_MAX,
    "eval_seed": U64_MAX,
    "checkpoint_every": U64_MAX,
}

#: Every setting :func:`train` takes.
SETTINGS = tuple(inspect.signature(_native.train).parameters)

#: The network trainer's whole-number settings and the largest value each takes.
DQN_WHOLE_SETTINGS = {
    "blocks": U64_MAX,
    "steps": U64_MAX,
    "pretrain": U64_MAX,
    "buffer": U64_MAX,
    "batch": U64_MAX,
    "hidden": U64_MAX,
    "hindsight": U64_MAX,
    "horizon": U32_MAX,
    "seed": U64_MAX,
    "eval_episodes": U64_MAX,
    "eval_seed": U64_MAX,
    "checkpoint_every": U64_MAX,
}

#: Every setting :func:`train_dqn` takes.
DQN_SETTINGS = tuple(inspect.signature(_native.train_dqn).parameters)


def _checked(settings: Mapping[str, Any], names: tuple, wholes: Mapping[str, int]) -> Dict[str, Any]:
    unknown = sorted(k for k in settings if k not in names)
    if unknown:
        raise ValueError(f"unknown setting(s) {', '.join(unknown)}: the settings are {', '.join(names)}")
    checked = dict(settings)
    for name, high in wholes.items():
        if checked.get(name) is not None:
            checked[name] = whole(name, checked[name], 0, high)
    return checked


def check_settings(settings: Dict[str, Any]) -> Dict[str, Any]:
    """``settings`` of :func:`train` with their whole numbers as ints; a ``ValueError``
    naming an unknown setting or a whole number out of range."""
    return _checked(settings, SETTINGS, WHOLE_SETTINGS)


def check_dqn_settings(settings: Dict[str, Any]) -> Dict[str, Any]:
    """``settings`` of :func:`train_dqn` with their whole numbers as ints; a ``ValueError``
    naming an unknown setting or a whole number out of range."""
    return _checked(settings, DQN_SETTINGS, DQN_WHOLE_SETTINGS)


def train(**settings: Any) -> Dict[str, Any]:
    return _native.train(**check_settings(settings))


def train_dqn(**settings: Any) -> Dict[str, Any]:
    return _native.train_dqn(**check_dqn_settings(settings))


train.__doc__ = _native.train.__doc__
train_dqn.__doc__ = _native.train_dqn.__doc__
