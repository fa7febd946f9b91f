"""The network runs docs/dqn.md cites are records, and their table is what the records make."""

import importlib.util
import re

from conftest import ROOT


def dqn_runs():
    spec = importlib.util.spec_from_file_location("dqn_runs", ROOT / "python" / "benchmarks" / "dqn_runs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_table_is_what_the_records_make():
    runs = dqn_runs()
    assert (runs.RESULTS / "README.md").read_text() == runs.render_table(), (
        "docs/results/dqn/README.md differs from its records: run `python python/benchmarks/dqn_runs.py table`"
    )


def test_docs_dqn_cites_every_record_and_only_records():
    runs = dqn_runs()
    text = (ROOT / "docs" / "dqn.md").read_text()
    recorded = {p.stem for p in runs.RESULTS.glob("*.json")}
    cited = set(re.findall(r"the record\s+`([a-z0-9-]+)`", text))
    assert cited, "docs/dqn.md cites no record as `the record `NAME``: the test's pattern is stale"
    assert cited <= recorded, f"docs/dqn.md cites records that do not exist: {sorted(cited - recorded)}"
    named = set(re.findall(r"`([a-z0-9-]+)`", text))
    assert recorded <= named, f"records docs/dqn.md does not name: {sorted(recorded - named)}"
