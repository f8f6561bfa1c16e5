"""Fixtures for the sgr.evogym tests: an Xvfb display for the tests that open windows (skipped
where Xvfb, Debian's xvfb package, is not installed; .ci/run installs it)."""

import os
import select
import shutil
import subprocess
import time

import pytest


@pytest.fixture(scope="module")
def xvfb_display():
    """Start Xvfb on a display number it chooses itself and point $DISPLAY at it for the module.

    Xvfb picks the number (`-displayfd`) and writes it once it is listening: two test workers that
    each looked for a free number could pick the same one, and one module's windows then opened on
    the other's server, which went away under them (a worker crashed, a window failed to open)."""
    if not shutil.which("Xvfb"):
        pytest.skip("needs Xvfb (Debian package xvfb)")
    read, write = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0", "1600x900x24"],
                            pass_fds=(write,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write)
    got = b""
    deadline = time.monotonic() + 20
    while not got.endswith(b"\n") and time.monotonic() < deadline:
        ready, _, _ = select.select([read], [], [], max(0.0, deadline - time.monotonic()))
        chunk = os.read(read, 16) if ready else b""
        if not chunk:
            break
        got += chunk
    os.close(read)
    if not got.strip().isdigit():
        proc.kill()
        proc.wait(timeout=10)
        pytest.fail(f"Xvfb did not report a display within 20 s (got {got!r})")
    display = f":{int(got)}"
    old = os.environ.get("DISPLAY")
    os.environ["DISPLAY"] = display
    yield display
    if old is None:
        os.environ.pop("DISPLAY", None)
    else:
        os.environ["DISPLAY"] = old
    proc.terminate()
    proc.wait(timeout=10)
