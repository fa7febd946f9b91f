"""Trains a network with ``blockstack dqn``, tests it with ``blockstack eval``, and records both.

    python python/benchmarks/dqn_runs.py run NAME -- --preset pixels --blocks 2 --seed 1
    python python/benchmarks/dqn_runs.py table

``run`` trains (the arguments after ``--`` are ``blockstack dqn``'s; ``--out`` is added),
times the training (wall clock, and user and system CPU of the child), then runs
``blockstack eval --model M --epsilon 0 --episodes 500 --json`` (``--episodes`` sets
another count), and writes ``docs/results/dqn/NAME.json``: the commands, the trainer's
summary lines, the times, the machine (cores, CPU model, load average before the run) and
the evaluation. ``table`` writes ``docs/results/dqn/README.md``, one row per recorded run,
from those files alone: docs/dqn.md cites its rows, so that no figure of a network run is
typed by hand.

The binary is ``target/release/blockstack`` unless ``--bin`` names another. The trained
network is kept under ``target/dqn-runs/NAME.safetensors``. Standard library only.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "docs" / "results" / "dqn"
FORMAT = 1


def busy_seconds() -> float:
    """CPU seconds every core has spent busy since boot (``/proc/stat``; 0 where it is absent)."""
    try:
        fields = [int(v) for v in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    except (OSError, ValueError):
        return 0.0
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return (sum(fields[:8]) - idle) / os.sysconf("SC_CLK_TCK")


def machine() -> dict:
    model = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    # The trainer's threads (rayon's pool): one thread or two train the same bits, at
    # different speeds.
    return {"cores": os.cpu_count(), "cpu": model, "rayon_threads": os.environ.get("RAYON_NUM_THREADS", "all cores")}


def child_cpu() -> tuple[float, float]:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime, usage.ru_stime


def write_atomically(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def run(args: argparse.Namespace) -> None:
    dqn = list(args.dqn)
    if dqn and dqn[0] == "--":
        dqn = dqn[1:]
    if "--out" in dqn:
        sys.exit("dqn_runs.py: leave out --out: the network goes to target/dqn-runs/NAME.safetensors")
    model = ROOT / "target" / "dqn-runs" / f"{args.name}.safetensors"
    model.parent.mkdir(parents=True, exist_ok=True)
    train = [args.bin, "dqn", *dqn, "--out", str(model)]
    record = {"format": FORMAT, "name": args.name, "machine": machine()}
    user0, sys0 = child_cpu()
    busy0 = busy_seconds()
    start = time.perf_counter()
    done = subprocess.run(train, capture_output=True, text=True)
    wall = time.perf_counter() - start
    user1, sys1 = child_cpu()
    # Cores kept busy by everything else while it trained: 0 on a quiet machine.
    others = max(0.0, busy_seconds() - busy0 - (user1 - user0) - (sys1 - sys0)) / wall
    if done.returncode != 0:
        sys.exit(f"dqn_runs.py: blockstack dqn failed ({done.returncode}): {done.stderr.strip()}")
    evaluate = [args.bin, "eval", "--model", str(model), "--epsilon", "0", "--episodes", str(args.episodes), "--json"]
    tested = subprocess.run(evaluate, capture_output=True, text=True)
    if tested.returncode != 0:
        sys.exit(f"dqn_runs.py: blockstack eval failed ({tested.returncode}): {tested.stderr.strip()}")
    record.update(
        train={
            "command": "blockstack dqn " + " ".join(dqn) + " --out M",
            "summary": done.stdout.strip().splitlines(),
            "wall_seconds": round(wall, 1),
            "user_seconds": round(user1 - user0, 1),
            "system_seconds": round(sys1 - sys0, 1),
            "other_cores_busy": round(others, 2),
        },
        eval={"command": f"blockstack eval --model M --epsilon 0 --episodes {args.episodes} --json", "result": json.loads(tested.stdout)},
    )
    path = RESULTS / f"{args.name}.json"
    write_atomically(path, json.dumps(record, indent=1) + "\n")
    print(f"wrote {path.relative_to(ROOT)}")
    table(args)


def minutes(seconds: float) -> str:
    m, s = divmod(round(seconds), 60)
    return f"{m} min {s:02d} s"


def table(_args: argparse.Namespace) -> None:
    write_atomically(RESULTS / "README.md", render_table())
    print(f"wrote {(RESULTS / 'README.md').relative_to(ROOT)}")


#: Presets renamed since records were made, by their old names: a record keeps the command
#: it ran; the table shows it with today's name (the same preset, the same network).
RENAMED_PRESETS = {"pixels": "dqfd-screen", "dqfd-pixels": "dqfd-paper-screen"}


def current_command(command: str) -> str:
    """``command`` with each renamed preset (:data:`RENAMED_PRESETS`) under today's name."""
    words = command.split(" ")
    for k in range(1, len(words)):
        if words[k - 1] == "--preset" and words[k] in RENAMED_PRESETS:
            words[k] = RENAMED_PRESETS[words[k]]
    return " ".join(words)


def render_table() -> str:
    """docs/results/dqn/README.md as the records beside it make it."""
    rows = []
    for path in sorted(RESULTS.glob("*.json")):
        r = json.loads(path.read_text())
        if r.get("format") != FORMAT:
            sys.exit(f"dqn_runs.py: {path} is not a record of format {FORMAT}")
        e, t = r["eval"]["result"], r["train"]
        games = e["episodes"]
        reached = games - e["failures"]
        worst = min(g["episodes"] - g["failures"] for g in e["per_goal"]) / min(g["episodes"] for g in e["per_goal"])
        rows.append(
            f"| `{r['name']}` | `{current_command(t['command'])}` | {100 * reached / games:.1f} % ({reached:,} of {games:,}) "
            f"| {100 * worst:.1f} % | {e['mean_ratio_to_optimum']:.3f}x | {minutes(t['wall_seconds'])} "
            f"| {t['user_seconds']:,.0f} s | {t['other_cores_busy']:.2f} |"
        )
    return "\n".join(
        [
            "# Network runs",
            "",
            "Written by `python python/benchmarks/dqn_runs.py table` from the records beside it, each made",
            "by `python python/benchmarks/dqn_runs.py run NAME -- <dqn flags>`: the network trained by the",
            "command shown, then played greedily (`eval --epsilon 0`, physics, seed 2) on every goal.",
            "Reached: games that reached the goal; worst goal: the lowest per-goal share; ratio: steps",
            "over the shortest plan, over the games that reached the goal; wall and user CPU: the",
            "training alone; others: cores kept busy by other processes while it trained, on average",
            "(0 on a quiet machine; the machine's cores are in each record). A record made before a",
            "preset was renamed keeps its command; the table shows it with today's name ("
            + ", ".join(f"`{old}` is `{new}`" for old, new in RENAMED_PRESETS.items())
            + ").",
            "",
            "| run | training | reached | worst goal | ratio | wall | user CPU | others |",
            "|---|---|---|---|---|---|---|---|",
            *rows,
            "",
        ]
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", default=str(ROOT / "target" / "release" / "blockstack"))
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="train, test and record one run")
    r.add_argument("name")
    r.add_argument("--episodes", type=int, default=500)
    r.add_argument("dqn", nargs=argparse.REMAINDER)
    r.set_defaults(func=run)
    t = sub.add_parser("table", help="write docs/results/dqn/README.md from the records")
    t.set_defaults(func=table)
    args = parser.parse_args()
    args.func(args)


if __name__ == "__main__":
    main()
