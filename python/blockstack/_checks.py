"""Arguments checked before they reach Rust: whole numbers in the range the native side
takes, and sizes within what the machine can hold.

Why here: pyo3 turns an int that does not fit into ``OverflowError`` without naming the
argument, and an allocation that fails in Rust aborts the interpreter. Checking first
gives one ``ValueError`` that names the argument, and never an abort.
"""

from __future__ import annotations

import os
from typing import Any, Optional

import numpy as np

#: The largest unsigned 32-bit and 64-bit integers (``u32``/``u64`` on the Rust side).
U32_MAX = 2**32 - 1
U64_MAX = 2**64 - 1

#: A lower bound on the memory one Rust environment holds beyond its observation buffers
#: (its world, generator and physics state: about 8 KiB measured with ``physics``).
ENV_BYTES = 4096


def whole(name: str, value: Any, low: int = 0, high: int = U64_MAX) -> int:
    """``value`` as an int in ``[low, high]``; a ``ValueError`` naming ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be a whole number in [{low}, {high}], not {value!r}")
    number = int(value)
    if not low <= number <= high:
        raise ValueError(f"{name}={number} is out of range: it must be in [{low}, {high}]")
    return number


def optional_whole(name: str, value: Any, low: int = 0, high: int = U64_MAX) -> Optional[int]:
    """As :func:`whole`, with ``None`` kept as ``None``."""
    return None if value is None else whole(name, value, low, high)


def whole_numbers(name: str, value: Any) -> np.ndarray:
    """``value`` as an array of whole numbers (int64): integers as they are, floats only when
    every one is a whole number (a replay buffer may store block ids as floats); a
    ``ValueError`` naming ``name`` for a fraction, a boolean, text or anything else, rather
    than a value rounded or compared as something it is not."""
    array = np.asarray(value)
    if array.dtype.kind in "iu":
        return array.astype(np.int64, copy=False)
    if array.dtype.kind == "f" and np.all(np.isfinite(array)) and np.all(array == np.round(array)):
        return array.astype(np.int64)
    raise ValueError(f"{name} holds whole numbers (block ids, cells), not {array.dtype} values: {value!r}")


def cells_of(cells: Any) -> list:
    """Every block's ``(x, y)``, each a pair of whole numbers in ``[0, 255]``; a
    ``ValueError`` naming ``cells[i]`` otherwise (the native side would raise
    ``OverflowError`` or ``TypeError`` naming nothing)."""
    checked = []
    for i, cell in enumerate(cells):
        try:
            x, y = cell
        except (TypeError, ValueError):
            raise ValueError(f"cells[{i}] must be an (x, y) pair, not {cell!r}") from None
        checked.append((whole(f"cells[{i}] x", x, 0, 255), whole(f"cells[{i}] y", y, 0, 255)))
    return checked


def memory_bytes() -> Optional[int]:
    """This machine's physical memory in bytes, or ``None`` where the system does not say."""
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def fits_in_memory(what: str, needed: int) -> None:
    """A ``ValueError`` naming ``what`` (``"num_envs=10000000"``) when ``needed`` bytes are
    more than the machine's physical memory: refused up front rather than aborting later."""
    total = memory_bytes()
    if total is not None and needed > total:
        raise ValueError(
            f"{what} needs at least {needed / 2**30:,.1f} GiB, more than this machine's "
            f"{total / 2**30:,.1f} GiB of memory: use fewer"
        )


def observation_bytes(obs: str, blocks: int, grid) -> int:
    """Bytes of one observation of kind ``obs`` (``state``: its three int64 arrays)."""
    from blockstack._native import observation_shape

    shape = observation_shape(obs, blocks, tuple(grid))
    if shape is None:
        return 8 * (2 * blocks + 1 + blocks)
    return int(np.prod(shape, dtype=np.uint64))
