"""Goal arguments: the text the Rust crates read (``"1,0,2"``) from text or a sequence."""

from __future__ import annotations

from typing import Optional, Sequence, Union

import numpy as np

Goal = Union[str, Sequence[int], None]

_FORM = 'a goal is text such as "1,0,2" or a sequence of block ids (whole numbers), bottom to top'


def goal_text(goal: Goal) -> Optional[str]:
    """``goal`` as text: ``None`` stays ``None``; a sequence of block ids is joined by commas.

    Only whole numbers are block ids: ``1.5`` or ``True`` are refused rather than rounded
    or read as 1, and bytes are refused rather than read as their character codes.
    """
    if goal is None or isinstance(goal, str):
        return goal
    if isinstance(goal, (bytes, bytearray, memoryview)):
        raise ValueError(f"{_FORM}, not bytes ({goal!r}): decode it to text first")
    try:
        ids = list(goal)
    except TypeError:
        raise ValueError(f"{_FORM}, not {goal!r}") from None
    for b in ids:
        if isinstance(b, (bool, np.bool_)) or not isinstance(b, (int, np.integer)):
            raise ValueError(f"{_FORM}: {b!r} in {goal!r} is not a block id")
    return ",".join(str(int(b)) for b in ids)
