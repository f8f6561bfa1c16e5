"""Fixtures for the sgr.evogym tests: an Xvfb display for the tests that open windows (skipped
where Xvfb, Debian's xvfb package, is not installed; .ci/run installs it)."""

import os
import shutil
import subprocess
import time

import pytest


@pytest.fixture(scope="module")
def xvfb_display():
    """Start Xvfb on a free display number and point $DISPLAY at it for the module."""
    if not shutil.which("Xvfb"):
        pytest.skip("needs Xvfb (Debian package xvfb)")
    n = next(n for n in range(80, 200)
             if not os.path.exists(f"/tmp/.X11-unix/X{n}") and not os.path.exists(f"/tmp/.X{n}-lock"))
    proc = subprocess.Popen(["Xvfb", f":{n}", "-screen", "0", "1600x900x24"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(50):  # up when its socket exists
        if os.path.exists(f"/tmp/.X11-unix/X{n}"):
            break
        time.sleep(0.1)
    old = os.environ.get("DISPLAY")
    os.environ["DISPLAY"] = f":{n}"
    yield f":{n}"
    if old is None:
        os.environ.pop("DISPLAY", None)
    else:
        os.environ["DISPLAY"] = old
    proc.terminate()
    proc.wait(timeout=10)
