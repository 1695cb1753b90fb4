"""System.modes(out=...), montecarlo (one cell, shards and their merge),
diagnose(report=...), and Ctrl-C during long estimation."""

import json
import os
import signal
import threading
import time

import pytest

import obsan
from obsan import _native
from conftest import SYSTEMS


def test_modes_out_writes_a_full_rank_system_and_a_verified_decomposition(tmp_path):
    prefix = tmp_path / "loc"
    m = obsan.load(SYSTEMS / "localization.sys").modes(out=prefix)
    assert m["certificate"]["verified"] is True
    # The reduced system's state is the observable modes (D, thetaR - phiR,
    # section II), and it is observable: full rank.
    reduced = obsan.load(f"{prefix}.sys")
    r = reduced.rank()
    assert r["n"] == len(m["modes"]) == 2
    assert r["rank"] == r["n"] and r["exact"] is True
    v = obsan.verify(f"{prefix}.dec")
    assert v["checks"] and all(c["pass"] for c in v["checks"]), v["checks"]


CELL = dict(table=5, cell=1)


def test_montecarlo_one_cell_is_the_clis(cli, monkeypatch):
    code, out, err = cli("montecarlo", "--table", "5", "--cell", "1", "--runs", "3", "--json")
    assert code == 0, err
    monkeypatch.setattr(obsan, "NUMPY", False)
    tables = obsan.montecarlo(runs=3, **CELL)
    assert tables == json.loads(out)
    (t,) = tables
    assert t["table"] == 5 and t["runs"] == 3 and len(t["cells"]) == 1
    for m in t["cells"][0]["methods"]:
        assert len(m["rms_error"]) == len(t["columns"])


def test_three_shards_merged_are_one_run_bit_for_bit(monkeypatch):
    monkeypatch.setattr(obsan, "NUMPY", False)
    one = obsan.montecarlo(runs=5, **CELL)
    # In any order, as dicts or as the files the CLI writes.
    parts = {k: obsan.montecarlo(runs=5, shard=(k, 3), **CELL) for k in (3, 1, 2)}
    assert [parts[k]["shard"] for k in (1, 2, 3)] == [[1, 3], [2, 3], [3, 3]]
    assert obsan.montecarlo_merge([parts[2], parts[3], parts[1]]) == one
    with pytest.raises(obsan.ObsanError, match="missing shard 1/3"):
        obsan.montecarlo_merge([parts[2], parts[3]])


def test_montecarlo_merge_reads_part_files(tmp_path, monkeypatch):
    monkeypatch.setattr(obsan, "NUMPY", False)
    files = []
    for k in (1, 2):
        files.append(tmp_path / f"part{k}.json")
        files[-1].write_text(json.dumps(obsan.montecarlo(runs=2, shard=f"{k}/2", **CELL)))
    assert obsan.montecarlo_merge(files) == obsan.montecarlo(runs=2, **CELL)


def test_diagnose_writes_its_report_folder_and_nothing_partial_on_error(tmp_path):
    data = obsan.simulate(tmp_path / "sim", bearings=40, seed=5)
    report = tmp_path / "report"
    d = obsan.diagnose(SYSTEMS / "calib.sys", data, report=report)
    names = sorted(os.listdir(report))
    for f in ("report.md", "extended.sys", "diagnosis.json"):
        assert f in names, names
    assert any(n.endswith(".svg") for n in names), names
    assert json.loads((report / "diagnosis.json").read_text())["model"] == d["model"]
    obsan.load(report / "extended.sys")  # the extended model parses
    # Into an existing folder without force=True: refused, the folder unchanged.
    before = {n: (report / n).read_bytes() for n in names}
    with pytest.raises(obsan.ObsanError, match="exists"):
        obsan.diagnose(SYSTEMS / "calib.sys", data, report=report)
    assert {n: (report / n).read_bytes() for n in os.listdir(report)} == before
    # An error in the diagnosis itself (a dataset folder without a dataset) leaves no
    # folder at all.
    (tmp_path / "empty").mkdir()
    with pytest.raises(obsan.ObsanError):
        obsan.diagnose(SYSTEMS / "calib.sys", tmp_path / "empty", report=tmp_path / "r2")
    assert not (tmp_path / "r2").exists()


def _idle(limit=30.0):
    """Wait (up to `limit` s) until no obsan command runs on its thread."""
    end = time.monotonic() + limit
    while _native.running_commands() and time.monotonic() < end:
        time.sleep(0.05)
    return _native.running_commands() == 0


@pytest.fixture(scope="module")
def long_dataset(tmp_path_factory):
    # Nine circles with many bearings: the ML fit takes seconds (2.3 s wall on an
    # idle 2-core machine; with 3000 bearings it took 0.31 s there, finished before
    # the 0.5 s Ctrl-C, and the test failed without any fault in the cancel path).
    out = tmp_path_factory.mktemp("long") / "sim"
    return obsan.simulate(out, q=[0.9, 0.6, 0.3, 0.0, -0.3, -0.6, -0.9, -1.0, 0.8], bearings=30000, seed=4)


@pytest.mark.parametrize("what", ["montecarlo", "calibrate"])
def test_ctrl_c_stops_long_estimation_on_every_thread(what, long_dataset):
    # A command an earlier test timed out may still be reaching its next poll.
    assert _idle()
    calls = {
        # 400 runs of five estimators: minutes unless stopped.
        "montecarlo": lambda: obsan.montecarlo(runs=400, threads=2, **CELL),
        "calibrate": lambda: obsan.calibrate(long_dataset, method="ml"),
    }
    # SIGINT, as Ctrl-C sends it.
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            calls[what]()
    finally:
        timer.cancel()
    # The command's threads stopped (they do not run to the end, their result dropped).
    assert _idle(), f"{what} still runs after Ctrl-C"
    assert obsan.simplify("x + x")["canonical"] == "2*x"
