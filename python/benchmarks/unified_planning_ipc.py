"""blockstack as a Unified Planning Framework engine on a folder of competition tasks.

    python BLOCKSTACK/python/benchmarks/unified_planning_ipc.py --tasks blocksworld/testing \\
        --domain blocksworld/domain.pddl [--time-limit 60] [--out unified-planning.json]

Run from the root of a checkout of the planning competition's repository (the tasks are not
shipped here); ``BLOCKSTACK`` is this repository's checkout. Every ``*.pddl`` task under
``--tasks`` (sorted by path) is read by UPF's own ``PDDLReader`` with ``--domain``, planned
through UPF by the engine the package registers (``OneshotPlanner(name="blockstack")``, the
optimal solver with ``--time-limit`` seconds), and
its plan checked by UPF's own ``PlanValidator``. Prints one line per task and a summary, and
writes the same as JSON to ``--out``: for each task its status, plan length, lower bound,
whether UPF found the plan valid, and the seconds of the engine's ``solve`` call (wall time,
on the machine of the run); then how many tasks are solved optimally, solved otherwise, and
valid. Needs ``pip install "blockstack[up]"``.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", required=True, type=pathlib.Path, help="folder of PDDL tasks, searched recursively")
    parser.add_argument("--domain", required=True, type=pathlib.Path, help="the tasks' domain file")
    parser.add_argument("--time-limit", type=float, default=60.0, help="the optimal solver's seconds per task")
    parser.add_argument("--out", type=pathlib.Path, help="where to write the JSON (default: print only)")
    args = parser.parse_args()

    from unified_planning.engines import PlanGenerationResultStatus as Status
    from unified_planning.io import PDDLReader
    from unified_planning.shortcuts import OneshotPlanner, PlanValidator, get_environment

    get_environment().factory.add_engine("blockstack", "blockstack.unified_planning", "BlockstackPlanner")
    get_environment().credits_stream = None

    tasks = sorted(p for p in args.tasks.rglob("*.pddl") if p.resolve() != args.domain.resolve())
    if not tasks:
        print(f"--tasks {args.tasks}: no .pddl task there", file=sys.stderr)
        return 2
    rows = []
    with OneshotPlanner(name="blockstack", params={"time_limit": args.time_limit}) as planner:
        for path in tasks:
            problem = PDDLReader().parse_problem(str(args.domain), str(path))
            started = time.perf_counter()
            result = planner.solve(problem)
            seconds = time.perf_counter() - started
            plan = result.plan
            with PlanValidator(problem_kind=problem.kind) as validator:
                valid = plan is not None and validator.validate(problem, plan).status.name == "VALID"
            row = {
                "task": str(path.relative_to(args.tasks)),
                "status": result.status.name,
                "actions": len(plan.actions) if plan is not None else None,
                "lower_bound": int(result.metrics["lower_bound"]) if "lower_bound" in result.metrics else None,
                "valid": valid,
                "seconds": round(seconds, 3),
            }
            rows.append(row)
            print(f"{row['task']:24} {row['status']:20} {row['actions']!s:>6} {row['lower_bound']!s:>6} "
                  f"{'valid' if valid else 'INVALID':8} {seconds:8.2f} s", flush=True)
    summary = {
        "tasks": len(rows),
        "solved_optimally": sum(r["status"] == Status.SOLVED_OPTIMALLY.name for r in rows),
        "solved_satisficing": sum(r["status"] == Status.SOLVED_SATISFICING.name for r in rows),
        "valid": sum(r["valid"] for r in rows),
    }
    print(f"{summary['tasks']} tasks: {summary['solved_optimally']} solved optimally, "
          f"{summary['solved_satisficing']} satisficing, {summary['valid']} plans valid by UPF's PlanValidator")
    if args.out is not None:
        args.out.write_text(json.dumps({"time_limit": args.time_limit, "tasks": rows, "summary": summary}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
