"""The reproduction (``blockstack reproduce``), E8's arms on a Ray cluster.

    python -m blockstack.reproduce [--quick | --long] [--only E8,...] [--seed N] [--out DIR]
                                   [--jobs N] [--ray [ADDRESS]] [--num-cpus N] [--storage DIR]

The same experiments, settings and report as ``blockstack reproduce`` (docs/cli.md), run by
the same Rust code in this process. With ``--ray``, E8's arms (each a network trained for up
to an hour: most of ``--long``'s two CPU-hours) are sent to Ray as tasks of one CPU as soon as
the run starts, one task an arm, the costliest first (Ray starts them in that order as CPUs
free up), and the other experiments run here meanwhile; the report
waits for the arms and is written here. Every arm is fixed by its seed, so the report's
figures are the ones a run on one machine gives.

``--ray`` alone starts a local Ray of ``--num-cpus`` CPUs; ``--ray auto`` joins the cluster
``ray start`` made on this machine, ``--ray HOST:PORT`` another. Every node needs
``pip install blockstack[ray]`` of the same build. Each arm writes a checkpoint into
``--storage`` (default: ``--out``'s name with ``-e8-arms``; on a cluster, a folder every node
reaches) at every point of its learning curve: an arm whose node dies is run again by Ray on
another node and goes on from there, and running the command again after the driver or the
cluster stopped takes every arm up where its checkpoint left it.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import List, Optional

from blockstack import _native, _ray


def _run_arm(index: int, seed: int, quick: bool, long: bool, checkpoint: str) -> str:
    return _native.run_e8_arm(index, seed=seed, quick=quick, long=long, checkpoint=checkpoint)


def _parse(argv: Optional[List[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m blockstack.reproduce", description=__doc__.splitlines()[0])
    budget = parser.add_mutually_exclusive_group()
    budget.add_argument("--quick", action="store_true", help="small counts, to check the pipeline")
    budget.add_argument("--long", action="store_true", help="E8 at its long budget (every arm at full budget)")
    parser.add_argument("--only", default="", help="run only these experiments, e.g. E8 or E1,E5")
    parser.add_argument("--seed", type=int, default=1, help="the seed everything derives from")
    parser.add_argument("--out", default="report", help="the report's folder")
    parser.add_argument("--jobs", type=int, help="threads for the experiments run here (default: one per core)")
    parser.add_argument("--ray", nargs="?", const="", metavar="ADDRESS",
                        help="run E8's arms on Ray: a cluster's address (auto, HOST:PORT), or none for a local Ray")
    parser.add_argument("--num-cpus", type=int, help="CPUs of the local Ray (default: all)")
    parser.add_argument("--storage", help="E8's arms' checkpoints, where every node reaches (default: OUT's name + -e8-arms)")
    parser.add_argument("--retries", type=int, default=3, help="times an arm lost with its node is run again (default 3)")
    return parser.parse_args(argv)


def main(argv: Optional[List[str]] = None) -> int:
    args = _parse(argv)
    only = [o.strip() for o in args.only.split(",") if o.strip()]
    try:
        if args.seed < 0:
            raise ValueError(f"--seed must be a whole number of 0 or more, not {args.seed}")
        for name in ("jobs", "num_cpus"):
            value = getattr(args, name)
            if value is not None and value < 1:
                raise ValueError(f"--{name.replace('_', '-')} must be at least 1, not {value}")
        if args.retries < 0:
            raise ValueError(f"--retries must be 0 or more, not {args.retries}")
        names = _native.e8_arms(seed=args.seed, quick=args.quick, long=args.long, only=only)
        start = _native.e8_start_order(seed=args.seed, quick=args.quick, long=args.long, only=only)
        _native.check_folder(args.out)
        storage = os.path.abspath(args.storage or args.out.rstrip(os.sep) + "-e8-arms")
        on_ray = args.ray is not None and (not only or "E8" in (o.upper() for o in only))
        if on_ray:
            _native.check_folder(storage)
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    settings = dict(seed=args.seed, quick=args.quick, long=args.long, only=only, jobs=args.jobs)
    if not on_ray:
        return _report(lambda: _native.reproduce(args.out, **settings), args)
    ray = _ray.import_ray()
    if ray is None:
        return 2
    _ray.start(ray, args.ray, args.num_cpus)
    try:
        task = ray.remote(max_retries=args.retries, **_ray.TASK_OPTIONS)(_run_arm)
        budget = "quick" if args.quick else "long" if args.long else "default"
        checkpoints = [os.path.join(storage, f"{budget}-seed{args.seed}-arm{i:02d}.safetensors") for i in range(len(names))]
        # Submitted costliest first: Ray starts tasks as CPUs free up, in the order sent.
        refs = [None] * len(names)
        for i in start:
            refs[i] = task.remote(i, args.seed, args.quick, args.long, checkpoints[i])
        print(f"E8: {len(names)} arms sent to Ray ({_ray.cpus(ray)} CPUs), checkpoints in {storage}", flush=True)
        started = time.monotonic()

        def e8_runs(count: int) -> List[str]:
            if count != len(refs):
                raise ValueError(f"E8 asks for {count} arms, and {len(refs)} were sent")
            index = {ref: i for i, ref in enumerate(refs)}
            pending, done = list(refs), 0
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                ray.get(ready[0])  # an arm that failed stops the run here, naming it
                done += 1
                elapsed = _ray.clock(time.monotonic() - started)
                print(f"E8: {done}/{len(refs)} arms done ({elapsed}): {names[index[ready[0]]]}", flush=True)
            return ray.get(refs)

        return _report(lambda: _native.reproduce(args.out, e8_runs=e8_runs, **settings), args)
    finally:
        ray.shutdown()


def _report(run, args: argparse.Namespace) -> int:
    """Runs the reproduction and prints what ``blockstack reproduce`` prints after it."""
    try:
        r = run()
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except Exception as e:  # a task's error, from Ray
        print(f"error: {str(e).strip().splitlines()[-1]}", file=sys.stderr)
        return 1
    budget = "quick" if args.quick else "long" if args.long else "full"
    threads = r["threads"]
    ids = ", ".join(i for i, _ in r["experiments"])
    print(f"reproduced {ids} ({budget} run, seed {args.seed}, {threads} thread{'' if threads == 1 else 's'}) "
          f"in {r['seconds']:.0f} s")
    for i, reading in r["experiments"]:
        print(f"{i}: {reading}")
    print(f"report: {r['readme']} (results: {r['results']}, summary: {r['summary']}, {len(r['pictures'])} pictures)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
