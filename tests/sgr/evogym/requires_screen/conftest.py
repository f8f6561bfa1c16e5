"""evogym's tests that need a screen get one: every test here runs with the Xvfb display of
tests/sgr/evogym/conftest.py (skipped where Xvfb is not installed)."""

import pytest


@pytest.fixture(autouse=True)
def _screen(xvfb_display):
    return xvfb_display
