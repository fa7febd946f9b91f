"""Grids of training runs as Ray tasks, each calling the Rust trainer in this process's kind.

    python -m blockstack.sweep CONFIG [--address auto] [--num-cpus N] [--out results.csv]

``CONFIG`` (TOML or JSON) has two tables of ``blockstack train`` flags (``-`` or ``_`` in
names; the same defaults, i.e. the paper's learner): ``train``, shared by every run, and
``sweep``, whose every flag is a list; each combination of their values is one run. The
flags of :func:`blockstack.train` also evaluate each run (``eval_episodes``,
``eval_goals``, ``eval_seed``, ``eval_epsilon``)::

    [train]
    repr = "chasing"
    reward = "paper"
    goals = "0,1,2:1,0,2:2,0,1:0,2,1"
    games = 100
    eval_episodes = 100
    eval_goals = "2,1,0:1,2,0"

    [sweep]
    gamma = [0.1, 0.5, 0.9]
    seed = [1, 2, 3, 4, 5]

Every run is a Ray task (one CPU) that calls :func:`blockstack.train` in the worker
process: the Rust trainer, in-process, no subprocess and no files. Without ``--address``
a local Ray starts with ``--num-cpus`` CPUs (all by default); ``--address auto`` joins a
running cluster (``ray start --head`` on one machine, ``ray start --address ...`` on the
others), and every machine needs ``pip install blockstack[ray]``.

The results are one table: printed, and written as CSV to ``--out`` (one row per run: the
swept flags, then the training totals and evaluation figures). A run that fails is named
on stderr and the exit status is 1; the finished runs are still printed and written.
"""

from __future__ import annotations

import argparse
import csv
import io
import itertools
import json
import sys
from typing import Any, Dict, List

from blockstack import _native
from blockstack.training import check_settings


#: The most runs one sweep may have: combinations are counted before any is built.
MAX_RUNS = 100_000


def read_config(path: str) -> Dict[str, Dict[str, Any]]:
    """The ``train`` and ``sweep`` tables of a TOML or JSON file, flag names with ``_``.

    Every way a file can be wrong is a ``ValueError`` (or ``OSError``) of one line naming
    the file: syntax errors, a file or table that is not a table, a swept flag that is not
    a non-empty list, more than :data:`MAX_RUNS` combinations.
    """
    with open(path, "rb") as f:
        data = f.read()
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
    count = 1
    for flag, values in tables["sweep"].items():
        if not isinstance(values, list) or not values:
            raise ValueError(f"{path}: sweep.{flag} must be a non-empty list of values")
        count *= len(values)
    if count > MAX_RUNS:
        raise ValueError(f"{path}: the sweep has {count:,} combinations, more than {MAX_RUNS:,}: sweep fewer values")
    return tables


def runs(config: Dict[str, Dict[str, Any]]) -> List[Dict[str, Any]]:
    """The flags of every run: each combination of the sweep's values over the shared flags,
    each checked as :func:`blockstack.train` checks its settings before training."""
    swept = config["sweep"]
    names = list(swept)
    return [
        check_settings(dict(config["train"], **dict(zip(names, values))))
        for values in itertools.product(*swept.values())
    ]


def _train(flags: Dict[str, Any]) -> Dict[str, Any]:
    import blockstack

    return blockstack.train(**flags)


def table(rows: List[Dict[str, Any]], swept: List[str]) -> List[str]:
    """The columns: the swept flags first, then every result field in the order given."""
    columns = list(swept)
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


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m blockstack.sweep", description=__doc__.splitlines()[0])
    parser.add_argument("config", help="a TOML or JSON file with [train] and [sweep] tables")
    parser.add_argument("--address", help="a Ray cluster to join (e.g. auto); default: start a local Ray")
    parser.add_argument("--num-cpus", type=int, help="CPUs of the local Ray (default: all)")
    parser.add_argument("--out", default="sweep-results.csv", help="the CSV table to write")
    args = parser.parse_args(argv)
    # Everything that can be checked is checked here, before Ray starts.
    try:
        if args.num_cpus is not None and args.num_cpus < 1:
            raise ValueError(f"--num-cpus must be at least 1, not {args.num_cpus}")
        config = read_config(args.config)
        all_runs = runs(config)
        _native.check_output(args.out)  # before any run, not after all of them
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    try:
        import ray
    except ImportError:
        print("the sweep runs on Ray: pip install 'blockstack[ray]'", file=sys.stderr)
        return 2
    if args.address:
        ray.init(address=args.address, logging_level="ERROR")
    else:
        ray.init(num_cpus=args.num_cpus, include_dashboard=False, logging_level="ERROR")
    swept = list(config["sweep"])
    rows, failed = [], []
    try:
        task = ray.remote(num_cpus=1)(_train)
        print(f"{len(all_runs)} runs on {int(ray.cluster_resources().get('CPU', 0))} CPUs", flush=True)
        pending = [task.remote(flags) for flags in all_runs]
        # One run's failure keeps every other run's result.
        for flags, ref in zip(all_runs, pending):
            try:
                rows.append(ray.get(ref))
            except ray.exceptions.RayTaskError as e:
                failed.append((flags, e.cause if getattr(e, "cause", None) is not None else e))
    finally:
        ray.shutdown()
    status = 0
    if rows:
        columns = table(rows, swept)
        # On screen, flags every run shares go on one line; the CSV keeps every column.
        shared = [c for c in columns if c not in swept and c != "train_seconds" and len({_cell(r.get(c)) for r in rows}) == 1]
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
            print(f"wrote {args.out}")
        except (OSError, ValueError) as e:
            print(f"error: the table was not written: {e}", file=sys.stderr)
            status = 1
    for flags, error in failed:
        which = ", ".join(f"{name}={_cell(flags.get(name))}" for name in swept) or "the only run"
        print(f"error: run {which} failed: {str(error).strip().splitlines()[-1]}", file=sys.stderr)
        status = 1
    return status


def _cell(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


if __name__ == "__main__":
    sys.exit(main())
