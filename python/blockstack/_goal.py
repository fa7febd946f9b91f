"""Goal arguments: the text the Rust crates read (``"1,0,2"``) from text or a sequence."""

from __future__ import annotations

from typing import Optional, Sequence, Union

Goal = Union[str, Sequence[int], None]


def goal_text(goal: Goal) -> Optional[str]:
    """``goal`` as text: ``None`` stays ``None``; a sequence of block ids is joined by commas."""
    if goal is None or isinstance(goal, str):
        return goal
    return ",".join(str(int(b)) for b in goal)
