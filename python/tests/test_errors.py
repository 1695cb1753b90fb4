"""Errors carry the CLI's text, with file, line and column."""

import os
import signal
import threading
import time

import pytest

import obsan
from conftest import SYSTEMS

BAD = "system t\nstate x\noutput y = x\n"


def test_loads_error_names_string_line_and_column():
    with pytest.raises(obsan.ObsanError) as e:
        obsan.loads(BAD)
    assert str(e.value).startswith("<string>:2:7: state 'x' has no equation")
    assert isinstance(e.value, ValueError)


def test_load_error_names_the_file(tmp_path, cli):
    p = tmp_path / "bad.sys"
    p.write_text(BAD)
    with pytest.raises(obsan.ObsanError) as e:
        obsan.load(p)
    assert str(e.value).startswith(f"{p}:2:7: ")
    # The same text as the CLI's stderr (after its "error: ").
    code, _, err = cli("show", p, "--json")
    assert code == 2
    assert err.strip() == "error: " + str(e.value).strip()


def test_missing_file_and_bad_expression():
    # A missing input is what open() raises, naming the path; a misspelt keyword is
    # Python's own TypeError, not the CLI's "Usage:" text.
    with pytest.raises(FileNotFoundError) as e:
        obsan.load(SYSTEMS / "no-such.sys")
    assert e.value.filename == str(SYSTEMS / "no-such.sys")
    with pytest.raises(obsan.ObsanError, match=r"<expression>:1:\d+"):
        obsan.simplify("x + * y")
    with pytest.raises(TypeError, match="no_such_option"):
        obsan.load(SYSTEMS / "calib.sys").rank(no_such_option=1)  # type: ignore[call-arg]
    with pytest.raises(FileNotFoundError):
        obsan.calibrate(SYSTEMS / "no-such-dataset")
    with pytest.raises(FileNotFoundError):
        obsan.diagnose(SYSTEMS / "calib.sys", SYSTEMS / "no-such-dataset")


def test_unknown_restriction():
    with pytest.raises(obsan.ObsanError, match="nope"):
        obsan.load(SYSTEMS / "calib.sys").rank(input="nope")


def test_ctrl_c_interrupts_long_work():
    # 2^20 terms: many seconds of exact expansion unless stopped.
    product = "*".join(f"(a{i} + b{i})" for i in range(20))
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        obsan.simplify(product, max_terms=100_000_000)
    assert time.monotonic() - start < 5
    # The engine stopped and the next call works.
    assert obsan.simplify("x + x")["canonical"] == "2*x"


def test_other_threads_run_while_obsan_works():
    # The GIL is released: a Python thread counts while a command runs.
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(1)
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    try:
        obsan.load(SYSTEMS / "calib.sys").symmetries(input="q")
    finally:
        done.set()
        t.join()
    assert len(ticks) > 5


def test_timeout_is_the_cli_error():
    product = "*".join(f"(a{i} + b{i})" for i in range(20))
    with pytest.raises(obsan.ObsanError, match=r"timed out after 0.2 s \(--timeout\)"):
        obsan.simplify(product, max_terms=100_000_000, timeout=0.2)


def test_wrong_types_are_type_errors_before_anything_runs(tmp_path, monkeypatch):
    # simulate(None) wrote ./None, diff('x^2', None) returned 0,
    # simplify(float('inf')) returned the symbol inf.
    monkeypatch.chdir(tmp_path)
    with pytest.raises(TypeError):
        obsan.simulate(None)
    with pytest.raises(TypeError):
        obsan.diff("x^2", None)
    with pytest.raises(TypeError):
        obsan.simplify(float("inf"))
    with pytest.raises(TypeError):
        obsan.load(3)
    with pytest.raises(TypeError):
        obsan.calibrate(None)
    with pytest.raises(TypeError):
        obsan.diagnose(SYSTEMS / "calib.sys", None)
    with pytest.raises(TypeError):
        obsan.run("simulate", "--out", None)
    assert list(tmp_path.iterdir()) == []


def test_sizes_past_the_limit_are_refused_before_allocating():
    # crlb(bearings=2**63) grew to 11 GB.
    with pytest.raises(obsan.ObsanError) as e:
        obsan.crlb(bearings=2**63)
    assert "at most 1000000" in str(e.value)
