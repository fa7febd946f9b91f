"""What the sweep and the reproduction share about Ray: joining a cluster or starting a local
Ray, and the tasks' settings.

Every task takes one CPU and its native code one thread (``RAYON_NUM_THREADS=1``): a node of
``N`` CPUs runs ``N`` tasks side by side, never more threads than cores. A network's results
do not depend on its threads (``neural``'s products split batches the same way on one or
two), so where and beside what a task runs changes none of its bits.
"""

from __future__ import annotations

import sys
from typing import Optional

#: What every task of the package asks of Ray.
TASK_OPTIONS = {
    "num_cpus": 1,
    "runtime_env": {"env_vars": {"RAYON_NUM_THREADS": "1"}},
}


def import_ray():
    """The ``ray`` module, or ``None`` after saying on stderr how to install it."""
    try:
        import ray
    except ImportError:
        print("this runs on Ray: pip install 'blockstack[ray]'", file=sys.stderr)
        return None
    return ray


def start(ray, address: Optional[str], num_cpus: Optional[int]) -> None:
    """Joins the cluster at ``address`` (``auto``: the one ``ray start`` made on this
    machine), or starts a local Ray of ``num_cpus`` CPUs (all by default) without its
    dashboard."""
    if address:
        ray.init(address=address, logging_level="ERROR")
    else:
        ray.init(num_cpus=num_cpus, include_dashboard=False, logging_level="ERROR")


def cpus(ray) -> int:
    """The CPUs of the cluster, as Ray counts them now."""
    return int(ray.cluster_resources().get("CPU", 0))


def clock(seconds: float) -> str:
    """``seconds`` as ``1 h 02 min``, ``3 min 05 s`` or ``12.3 s``."""
    if seconds >= 3600:
        return f"{int(seconds // 3600)} h {int(seconds % 3600 // 60):02d} min"
    if seconds >= 60:
        return f"{int(seconds // 60)} min {int(seconds % 60):02d} s"
    return f"{seconds:.1f} s"
