"""``blockstack.train``: the Rust tabular trainer, its settings' names and whole numbers
checked in Python first.

Why: pyo3 turns ``seed=-1`` into an ``OverflowError`` that names no argument, and the Ray
sweep must refuse a misspelt flag before Ray starts, not inside a task.
"""

from __future__ import annotations

import inspect
from typing import Any, Dict

from blockstack import _native
from blockstack._checks import U32_MAX, U64_MAX, whole

#: The whole-number settings and the largest value each takes (the Rust side's widths).
WHOLE_SETTINGS = {
    "blocks": U64_MAX,
    "games": U64_MAX,
    "seed": U64_MAX,
    "horizon": U32_MAX,
    "eval_episodes": U64_MAX,
    "eval_seed": U64_MAX,
}

#: Every setting :func:`train` takes.
SETTINGS = tuple(inspect.signature(_native.train).parameters)


def check_settings(settings: Dict[str, Any]) -> Dict[str, Any]:
    """``settings`` with their whole numbers as ints; a ``ValueError`` naming an unknown
    setting or a whole number out of range."""
    unknown = sorted(k for k in settings if k not in SETTINGS)
    if unknown:
        raise ValueError(f"unknown setting(s) {', '.join(unknown)}: the settings are {', '.join(SETTINGS)}")
    checked = dict(settings)
    for name, high in WHOLE_SETTINGS.items():
        if checked.get(name) is not None:
            checked[name] = whole(name, checked[name], 0, high)
    return checked


def train(**settings: Any) -> Dict[str, Any]:
    return _native.train(**check_settings(settings))


train.__doc__ = _native.train.__doc__
