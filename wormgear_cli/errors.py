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

    def __reduce__(self):  # pickled with its problems (raised in a worker of --jobs, reported by the parent)
        return self.__class__, (self.problems,)


class SpecError(WormgearError):
    """A drive spec (TOML) that cannot be loaded or is invalid."""


class DataError(WormgearError):
    """A measurement file (CSV) that cannot be read."""


class UsageError(WormgearError):
    """A command-line option value that makes no sense."""


def did_you_mean(word: str, choices, *, show=str, otherwise: str = "", cutoff: float = 0.6) -> str:
    """The hint of every "unknown key" message: `` (did you mean X?)`` for the closest of
    ``choices`` to ``word`` (difflib ratio >= ``cutoff``), shown through ``show`` (a prefix,
    quotes), else ``otherwise`` (e.g. the list of valid names, or nothing)."""
    import difflib

    near = difflib.get_close_matches(word, list(choices), n=1, cutoff=cutoff)
    return f" (did you mean {show(near[0])}?)" if near else otherwise


def moved(old: str, new: str, stacklevel: int = 3) -> None:
    """Warn that ``old`` is now ``new`` (a DeprecationWarning, shown once per call site)."""
    import warnings

    warnings.warn(f"{old} moved to {new}; the old name will be removed in wormgear-cli 0.3",
                  DeprecationWarning, stacklevel=stacklevel)
