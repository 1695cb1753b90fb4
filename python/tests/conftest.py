"""Shared fixtures: the repository's files and the release binary the CLI tests compare with."""

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SYSTEMS = ROOT / "systems"


def obsan_binary():
    """The `obsan` binary to compare with: $OBSAN_BIN, target/release/obsan, or PATH."""
    env = os.environ.get("OBSAN_BIN")
    if env:
        return env
    for d in (os.environ.get("CARGO_TARGET_DIR"), ROOT / "target"):
        if d:
            p = pathlib.Path(d) / "release" / "obsan"
            if p.exists():
                return str(p)
    return shutil.which("obsan")


@pytest.fixture(scope="session")
def cli():
    """Run the release binary; returns (exit code, stdout, stderr)."""
    import subprocess

    exe = obsan_binary()
    if exe is None:
        pytest.skip("no obsan binary to compare with (cargo build --release, or set OBSAN_BIN)")
    # Comparing with another release's binary (an old `obsan` on PATH) would test nothing.
    import obsan

    version = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.split()
    if version[-1:] != [obsan.__version__]:
        pytest.fail(f"{exe} is {' '.join(version)!r}, the package is obsan {obsan.__version__}")

    def run(*args):
        p = subprocess.run([exe, *map(str, args)], capture_output=True, text=True, cwd=ROOT)
        return p.returncode, p.stdout, p.stderr

    return run


@pytest.fixture(autouse=True, scope="session")
def _ctrl_c_raises_keyboard_interrupt():
    """A shell starts background jobs with SIGINT ignored, and Python then installs no
    KeyboardInterrupt handler: the Ctrl-C tests would see nothing (they failed so in a CI
    run started with `&`). Put Python's own handler back for the session."""
    import signal

    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
