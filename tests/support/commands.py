"""The Typer app as its click group, built once per test process, as the program builds it once per
process (typer.main.get_command reads every command's signature and annotations again: about 0.05 s of
CPU a call).  The CLI runners of tests/conftest.py and the tests that read the commands' options and
help share it."""

from __future__ import annotations

import functools

from typer.main import get_command


@functools.cache
def click_group(app):
    """``typer.main.get_command(app)``, once per app."""
    return get_command(app)
