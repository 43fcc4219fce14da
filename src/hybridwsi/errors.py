"""Exceptions raised on bad input.

Every user-facing failure (unreadable file, NaN, unsorted time, missing column, ...) raises
:class:`InputError` with a one-line message that says what is wrong and how to fix it. The CLI
turns it into ``error: <message>`` on stderr and a non-zero exit status, never a traceback.
"""

from __future__ import annotations


class HybridWSIError(Exception):
    """Base class of the package's own exceptions."""


class InputError(HybridWSIError, ValueError):
    """Bad user input: data, file or parameter. The message is meant for the end user."""


class SolverError(HybridWSIError, RuntimeError):
    """A numerical solver failed (integration diverged, BEM produced NaN, ...)."""


class Note(UserWarning):
    """Information worth a line at the end of a run, not a problem: the CLI prints it as
    ``note: ...`` (a warning as ``warning: ...``)."""
