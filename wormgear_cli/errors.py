"""The one error family of the core.

Core code raises :class:`WormgearError` (or a subclass) for anything the
*user* got wrong: a bad file, a bad key, a bad option value.  Only the CLI
layer turns it into messages on stderr and exit code 2.  Anything else that
escapes is a bug and may raise normally.
"""

from __future__ import annotations


class WormgearError(Exception):
    """A user mistake.  ``problems`` holds one line per problem."""

    exit_code = 2

    def __init__(self, problems: str | list[str]):
        if isinstance(problems, str):
            problems = [problems]
        self.problems = list(problems)
        super().__init__("\n".join(self.problems))


class SpecError(WormgearError):
    """A drive spec (TOML) that cannot be loaded or is invalid."""


class DataError(WormgearError):
    """A measurement file (CSV) that cannot be read."""


class UsageError(WormgearError):
    """A command-line option value that makes no sense."""
