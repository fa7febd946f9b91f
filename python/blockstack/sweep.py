"""Grids of training runs on Ray, tabular or network, each checkpointed to a shared folder so
that a run lost with its node goes on from its last checkpoint.

    python -m blockstack.sweep CONFIG [--address auto] [--num-cpus N] [--out results.csv]
                                      [--storage DIR] [--retries N]

``CONFIG`` (TOML or JSON) has two tables of flags (``-`` or ``_`` in names; the same
defaults): ``train``, shared by every run, and ``sweep``, whose every flag is a list; each
combination of their values is one run. ``command`` in ``train`` says which trainer:
``"train"`` (the default: :func:`blockstack.train`, ``blockstack train``'s flags) or
``"dqn"`` (:func:`blockstack.train_dqn`, ``blockstack dqn``'s flags: any preset and
flag). Every run's flags and files are checked before Ray starts, by its trainer itself
(``check=True``: the resolver and readers the run uses), in one line naming the config file. Both take ``checkpoint_every`` and evaluate each run with ``eval_episodes``,
``eval_goals``, ``eval_seed`` and ``eval_epsilon``::

    [train]
    command = "dqn"
    preset = "dqn-planes"
    blocks = 2
    eval_episodes = 100

    [sweep]
    lr = [0.001, 0.0003]
    seed = [1, 2, 3, 4]

Every run is a Ray task of one CPU that calls the trainer in the worker process (the Rust
trainer, in-process) with a folder of its own under ``--storage`` (default: ``--out``'s name
with ``-runs``), named by a hash of its flags: ``checkpoint.safetensors``, written every
``checkpoint_every`` games or steps; ``model.safetensors``; and ``result.json``, its row of
the table, once it has ended. A file a run reads (``demos_file``) is part of its key by its
contents (SHA-256), not only its path: a run whose file changed is a new run, never an old
run's result. A task lost with its node (or its worker) is run again by Ray
(``--retries`` times); the trainer then finds the run's checkpoint and goes on from it, and
ends with the model a run that never stopped ends with, byte for byte. A run whose
``result.json`` exists is not run again: running the same command again after the driver,
the head or the whole cluster stopped takes every run up where its files left it.

Why Ray tasks and not Tune trials: a run's checkpoint is the trainer's own file, written
atomically where every node reads it, and resuming is the trainer's (``train --resume``
and ``dqn --resume`` from the command line), so Tune's checkpoint copies and its experiment
state would only hold the same thing twice; a task is retried on another node by Ray core
alone; and a sweep stopped for any reason resumes by running its command again, with no
experiment state of Tune's to restore. ``ray`` alone (no ``ray[tune]``) is needed.

Without ``--address`` a local Ray starts with ``--num-cpus`` CPUs (all by default);
``--address auto`` joins the cluster ``ray start`` made (docs/cluster.md). The results: a
line as each run ends; one table, printed and written as CSV to ``--out`` (one row per run,
in the config's order: the swept flags, the run's folder, then the trainer's totals and
evaluation figures; ``resumed_at`` is the games or steps a run had done when it was last
taken up from its checkpoint, 0 for a run that never stopped); and one chart beside it
(``.png`` and ``.svg``): each setting's share of games that reached the goal (the
evaluation's, else training's), its mean over the seeds with their range. A run that fails
is named on stderr and the exit status is 1; the finished runs are still printed and
written.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import io
import itertools
import json
import os
import sys
import tempfile
import time
from typing import Any, Dict, List, Optional, Tuple

from blockstack import _native, _ray
from blockstack.training import DQN_SETTINGS, SETTINGS, check_dqn_settings, check_settings

#: The most runs one sweep may have: combinations are counted before any is built.
MAX_RUNS = 100_000

#: The trainers a sweep runs, by ``command``.
COMMANDS = ("train", "dqn")

#: Flags the sweep sets for each run itself.
OWN_FLAGS = ("out", "checkpoint", "resume")

#: The trainers' keyword that checks a run without training it (:func:`check_runs`).
CHECK_FLAG = "check"

#: Flags that name a file a run reads: its contents are part of the run's key.
FILE_FLAGS = ("demos_file",)

#: The evaluation's flags, taken by both trainers.
EVAL_FLAGS = ("eval_episodes", "eval_goals", "eval_seed", "eval_epsilon")


def read_config(path: str) -> Dict[str, Dict[str, Any]]:
    """The ``train`` and ``sweep`` tables of a TOML or JSON file, flag names with ``_``.

    Every way a file can be wrong is a ``ValueError`` (or ``OSError``) of one line naming
    the file: a pipe, a device or a file over 2 MiB (refused before it is read), syntax
    errors, a file or table that is not a table, a swept flag that is not a non-empty list,
    more than :data:`MAX_RUNS` combinations.
    """
    data = _native.read_config_file(path)
    try:
        if path.endswith(".json"):
            config = json.loads(data)
        else:
            try:
                import tomllib
            except ImportError:  # Python < 3.11
                try:
                    import tomli as tomllib
                except ImportError:
                    raise SystemExit(f"{path}: reading TOML needs Python >= 3.11 or `pip install tomli`; or write JSON")
            config = tomllib.loads(data.decode())
    except (ValueError, UnicodeDecodeError) as e:  # JSONDecodeError and TOMLDecodeError are ValueErrors
        raise ValueError(f"{path}: {str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
    if not isinstance(config, dict):
        raise ValueError(f"{path}: a sweep config is a table with [train] and [sweep], not {type(config).__name__}")
    unknown = set(config) - {"train", "sweep"}
    if unknown:
        raise ValueError(f"{path}: unknown tables {sorted(unknown)}: use [train] and [sweep]")
    tables = {}
    for table in ("train", "sweep"):
        value = config.get(table, {})
        if not isinstance(value, dict):
            raise ValueError(f"{path}: {table} must be a table of flags, not {type(value).__name__}")
        tables[table] = {str(k).replace("-", "_"): v for k, v in value.items()}
    if "command" in tables["sweep"]:
        raise ValueError(f"{path}: command is not swept: a sweep runs one trainer (a sweep each)")
    command = tables["train"].get("command", "train")
    if command not in COMMANDS:
        raise ValueError(f"{path}: command = {command!r}: choose \"train\" or \"dqn\"")
    count = 1
    for flag, values in tables["sweep"].items():
        if not isinstance(values, list) or not values:
            raise ValueError(f"{path}: sweep.{flag} must be a non-empty list of values")
        count *= len(values)
    if count > MAX_RUNS:
        raise ValueError(f"{path}: the sweep has {count:,} combinations, more than {MAX_RUNS:,}: sweep fewer values")
    return tables


def command_of(config: Dict[str, Dict[str, Any]]) -> str:
    """The trainer the config's runs use: ``"train"`` or ``"dqn"``."""
    return config["train"].get("command", "train")


def settings_of(command: str) -> List[str]:
    """The settings a sweep's config may give ``command``'s runs: the trainer's, but the
    files the sweep sets itself and the check it makes."""
    names = SETTINGS if command == "train" else DQN_SETTINGS
    return [n for n in names if n not in OWN_FLAGS and n != CHECK_FLAG]


def runs(config: Dict[str, Dict[str, Any]], path: Optional[str] = None) -> List[Dict[str, Any]]:
    """The flags of every run: each combination of the sweep's values over the shared flags,
    each checked as its trainer checks its settings before training. A ``ValueError`` names
    the config file ``path`` (when given) and the flag."""
    where = f"{path}: " if path else ""
    command = command_of(config)
    check = check_settings if command == "train" else check_dqn_settings
    shared = {k: v for k, v in config["train"].items() if k != "command"}
    swept = config["sweep"]
    own = sorted(set(OWN_FLAGS) & (set(shared) | set(swept)))
    if own:
        raise ValueError(f"{where}{', '.join(own)}: the sweep sets each run's files itself (see --storage)")
    allowed = settings_of(command)
    unknown = sorted((set(shared) | set(swept)) - set(allowed))
    if unknown:
        raise ValueError(
            f"{where}unknown flag(s) {', '.join(unknown)} for command {command!r}: the flags are {', '.join(allowed)}"
        )
    names = list(swept)
    try:
        return [check(dict(shared, **dict(zip(names, values)))) for values in itertools.product(*swept.values())]
    except ValueError as e:
        raise ValueError(f"{where}{e}") from None


def check_runs(command: str, all_runs: List[Dict[str, Any]], swept: List[str], path: str) -> None:
    """Every run's settings resolved and its files read by the trainer itself
    (``check=True``: the same resolver and readers the run uses, training nothing), so that
    a run that would fail on its flags or files fails here, before Ray starts: a
    ``ValueError`` naming the config file ``path`` and the run."""
    import blockstack

    trainer = blockstack.train if command == "train" else blockstack.train_dqn
    # With the files the sweep gives every run (in a scratch folder: nothing is written), so
    # that a setting that needs them (checkpoint_every) is checked as the run will use it.
    with tempfile.TemporaryDirectory() as scratch:
        for flags in all_runs:
            try:
                trainer(**flags, **_files(scratch), **{CHECK_FLAG: True})
            except ValueError as e:
                raise ValueError(f"{path}: run {_describe(flags, swept)}: {e}") from None


def run_name(command: str, flags: Dict[str, Any]) -> str:
    """The name of a run's folder: a hash of its trainer, its flags and the contents of the
    files they name (:data:`FILE_FLAGS`), so that the same run finds its files again and
    another run, or the same flags over a changed file, never does. A file that cannot be
    read is a ``ValueError`` naming it."""
    key: Dict[str, Any] = {"command": command, "flags": flags}
    contents = {flag: _native.file_digest(str(flags[flag])) for flag in FILE_FLAGS if flags.get(flag) is not None}
    if contents:
        key["contents"] = contents
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:12]


def _files(folder: str) -> Dict[str, str]:
    """The files the sweep gives a run whose folder is ``folder`` (:data:`OWN_FLAGS`)."""
    return dict(out=os.path.join(folder, "model.safetensors"), checkpoint=os.path.join(folder, "checkpoint.safetensors"))


def _run(command: str, flags: Dict[str, Any], folder: str) -> Dict[str, Any]:
    """One run, in a Ray worker: its row from ``result.json`` if it ended before, else
    trained (from its checkpoint, if it has one), with the row written there."""
    import blockstack

    result = os.path.join(folder, "result.json")
    if os.path.exists(result):
        with open(result) as f:
            return json.load(f)
    os.makedirs(folder, exist_ok=True)
    trainer = blockstack.train if command == "train" else blockstack.train_dqn
    row = trainer(**flags, **_files(folder))
    row["run"] = os.path.basename(folder)
    _native.write_output(result, json.dumps(row).encode())
    return row


def table(rows: List[Dict[str, Any]], swept: List[str]) -> List[str]:
    """The columns: the swept flags first, the run's folder, then every result field in the
    order given."""
    columns = list(swept) + ["run"]
    for row in rows:
        for key in row:
            if key not in columns:
                columns.append(key)
    return columns


def write_csv(path: str, rows: List[Dict[str, Any]], columns: List[str]) -> None:
    """Writes the rows through the Rust ``files`` crate: atomically, complete or not at all."""
    out = io.StringIO()
    w = csv.DictWriter(out, fieldnames=columns, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    _native.write_output(path, out.getvalue().encode())


def success(row: Dict[str, Any]) -> Tuple[float, str]:
    """The share of a run's games that reached the goal, in percent, and which games: the
    evaluation's if it has one, else training's."""
    if row.get("eval_episodes"):
        return 100.0 * (1 - row["eval_failures"] / row["eval_episodes"]), "evaluation"
    return 100.0 * row["successes"] / max(row["games"], 1), "training"


def chart_bars(rows: List[Dict[str, Any]], swept: List[str]) -> Tuple[List[Tuple[str, float, Optional[Tuple[float, float]]]], str]:
    """One bar per setting (the swept flags but ``seed``): the mean success over its runs,
    with their range when there are several; and which games the bars count."""
    key = [f for f in swept if f != "seed"]
    groups: Dict[str, List[float]] = {}
    which = "evaluation"
    for row in rows:
        name = ", ".join(f"{f}={_cell(row.get(f))}" for f in key) or "every run"
        value, which = success(row)
        groups.setdefault(name, []).append(value)
    bars = [
        (name, sum(v) / len(v), (min(v), max(v)) if len(v) > 1 else None)
        for name, v in groups.items()
    ]
    return bars, which


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m blockstack.sweep", description=__doc__.splitlines()[0])
    parser.add_argument("config", help="a TOML or JSON file with [train] and [sweep] tables")
    parser.add_argument("--address", help="a Ray cluster to join (e.g. auto); default: start a local Ray")
    parser.add_argument("--num-cpus", type=int, help="CPUs of the local Ray (default: all)")
    parser.add_argument("--out", default="sweep-results.csv", help="the CSV table to write (the chart goes beside it)")
    parser.add_argument("--storage", help="the runs' folders, on storage every node reaches (default: OUT's name + -runs)")
    parser.add_argument("--retries", type=int, default=3, help="times a run lost with its node is run again (default 3)")
    args = parser.parse_args(argv)
    stem = os.path.splitext(args.out)[0]
    storage = os.path.abspath(args.storage or stem + "-runs")
    # Everything that can be checked is checked here, before Ray starts.
    try:
        if args.num_cpus is not None and args.num_cpus < 1:
            raise ValueError(f"--num-cpus must be at least 1, not {args.num_cpus}")
        if args.retries < 0:
            raise ValueError(f"--retries must be 0 or more, not {args.retries}")
        config = read_config(args.config)
        command = command_of(config)
        all_runs = runs(config, args.config)
        check_runs(command, all_runs, list(config["sweep"]), args.config)
        names = [run_name(command, flags) for flags in all_runs]
        _native.check_output(args.out)  # before any run, not after all of them
        _native.check_folder(storage)
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    ray = _ray.import_ray()
    if ray is None:
        return 2
    _ray.start(ray, args.address, args.num_cpus)
    swept = list(config["sweep"])
    results: Dict[int, Dict[str, Any]] = {}
    failed = []
    started = time.monotonic()
    try:
        task = ray.remote(max_retries=args.retries, **_ray.TASK_OPTIONS)(_run)
        print(f"{len(all_runs)} {command} runs on {_ray.cpus(ray)} CPUs, checkpoints in {storage}", flush=True)
        pending = {
            task.remote(command, flags, os.path.join(storage, name)): i
            for i, (flags, name) in enumerate(zip(all_runs, names))
        }
        # Each run is reported once, as its task ends; one run's failure keeps every other's.
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            i = pending.pop(ready[0])
            which = _describe(all_runs[i], swept)
            elapsed = _ray.clock(time.monotonic() - started)
            done = f"[{len(results) + len(failed) + 1}/{len(all_runs)}, {elapsed}]"
            try:
                row = ray.get(ready[0])
            except ray.exceptions.RayError as e:
                cause = e.cause if getattr(e, "cause", None) is not None else e
                failed.append((i, cause))
                print(f"{done} run {which} failed", flush=True)
                continue
            results[i] = row
            value, games = success(row)
            resumed = f", resumed at {row['resumed_at']}" if row.get("resumed_at") else ""
            print(f"{done} run {which}: {value:.1f}% of {games} games reached the goal{resumed}", flush=True)
    finally:
        ray.shutdown()
    rows = [results[i] for i in sorted(results)]
    status = 0
    if rows:
        columns = table(rows, swept)
        # On screen, flags every run shares go on one line; the CSV keeps every column.
        shared = [c for c in columns if c not in swept and c not in ("run", "train_seconds", "resumed_at")
                  and len({_cell(r.get(c)) for r in rows}) == 1]
        print("every run: " + ", ".join(f"{c}={_cell(rows[0].get(c))}" for c in shared))
        shown = [c for c in columns if c not in shared]
        out = io.StringIO()
        w = csv.writer(out, delimiter="\t", lineterminator="\n")
        w.writerow(shown)
        for row in rows:
            w.writerow([_cell(row.get(c)) for c in shown])
        print(out.getvalue(), end="", flush=True)
        try:
            write_csv(args.out, rows, columns)
            bars, games = chart_bars(rows, swept)
            pictures = _native.bar_chart(
                stem,
                title=f"{command} sweep: {len(rows)} runs",
                y_label=f"reached the goal, {games} (%)",
                bars=bars,
                value_label="mean over seeds" if "seed" in swept else "run",
                interval_label="range over seeds",
                note=f"Each bar: the runs of one setting ({', '.join(f for f in swept if f != 'seed') or 'all'}); "
                     f"the share of their {games} games that reached the goal.",
            )
            print(f"wrote {args.out} and {', '.join(map(str, pictures))}")
        except (OSError, ValueError) as e:
            print(f"error: the results were not all written: {e}", file=sys.stderr)
            status = 1
    for i, error in sorted(failed, key=lambda f: f[0]):
        which = _describe(all_runs[i], swept)
        print(f"error: run {which} failed: {str(error).strip().splitlines()[-1]}", file=sys.stderr)
        status = 1
    return status


def _describe(flags: Dict[str, Any], swept: List[str]) -> str:
    return ", ".join(f"{name}={_cell(flags.get(name))}" for name in swept) or "the only run"


def _cell(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


if __name__ == "__main__":
    sys.exit(main())
