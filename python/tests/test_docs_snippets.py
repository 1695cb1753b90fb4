"""Docs snippets that are files: each is run here, and the docs quote the file itself."""

import os
import pathlib
import re
import subprocess
import sys

import pytest

import obsan

ROOT = pathlib.Path(__file__).resolve().parents[2]
DASK_EXAMPLE = ROOT / "examples" / "python" / "montecarlo_dask.py"


def test_the_montecarlo_doc_quotes_the_dask_example_verbatim():
    doc = (ROOT / "docs" / "montecarlo.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", doc, flags=re.S)
    assert DASK_EXAMPLE.read_text() in blocks


def test_the_dask_example_runs_as_a_script_and_merges_to_the_one_run_table():
    try:
        import distributed  # noqa: F401
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("CI installs dask[distributed]: the Dask example must run there")
        pytest.skip("dask.distributed is not installed (pip install 'dask[distributed]')")
    # 3 shards of 6 runs on a 2-process LocalCluster: the script's own __main__ guard is what
    # lets the worker processes start (docs/montecarlo.md's earlier snippet had none).
    p = subprocess.run(
        [sys.executable, str(DASK_EXAMPLE), "--shards", "3", "--runs", "6", "--workers", "2"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=600,
    )
    assert p.returncode == 0, p.stderr
    # The same table computed in one piece: the merge of shards is bit for bit the one run.
    one = obsan.montecarlo(table=5, runs=6, seed=1, threads=1)
    want = []
    for cell in one[0]["cells"]:
        ls = next(m for m in cell["methods"] if m["method"] == "LS")
        want.append(f"{cell['label']} {ls['mean_abs_error']}")
    assert p.stdout.splitlines() == want


def test_the_readme_python_snippet_runs(monkeypatch):
    # The README's Python lines are what a newcomer pastes first: each block runs as written.
    monkeypatch.chdir(ROOT)
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)
    assert blocks
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})
