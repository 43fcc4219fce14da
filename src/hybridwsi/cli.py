"""Command line: ``hybridwsi <command> ...``, one sub-command per pipeline stage.

Each command lives in :mod:`hybridwsi.commands.<name>` and provides ``HELP`` (one line),
``add_arguments(parser)`` and ``run(args) -> int``. Commands are imported lazily so that
``hybridwsi diagnose`` does not pay for importing Capytaine or PyTorch. Options shared by
several commands come from :mod:`hybridwsi.commands._options` (one name, one meaning; the
table is in docs/CLI.md).

Every failure the user can fix is printed as ONE line ``error: ...`` on stderr with exit
status 2, never a traceback (warnings are printed as ``warning: ...`` lines after a successful
run only): usage errors of argparse (:class:`Parser`), bad input
(:class:`hybridwsi.errors.InputError`), solver failures, operating-system errors on the files,
and a missing optional dependency (the message names the extra to install).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import importlib.util
import signal
import sys
import warnings
from collections.abc import Callable, Iterator
from typing import NoReturn

from hybridwsi import __version__
from hybridwsi.commands._options import missing_dependency, one_line
from hybridwsi.errors import HybridWSIError

#: command name -> module under hybridwsi.commands (module names are Python identifiers)
COMMANDS: dict[str, str] = {
    "diagnose": "diagnose",
    "import": "import_",
    "bem": "bem",
    "simulate": "simulate",
    "reproduce": "reproduce",
    "sph": "sph",
    "select": "select",
    "sweep": "sweep",
    "hybrid": "hybrid",
    "coeffs": "coeffs",
}

#: exit status of every error the user can fix (bad input, bad option, missing extra)
EXIT_ERROR = 2
#: exit statuses of a run stopped by Ctrl-C (SIGINT) and by SIGTERM (kill, batch schedulers)
EXIT_INTERRUPTED, EXIT_TERMINATED = 130, 143


class Terminated(KeyboardInterrupt):
    """SIGTERM received: stop as for Ctrl-C (long runs write their checkpoint first)."""


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated


@contextlib.contextmanager
def _stop_on_sigterm() -> Iterator[None]:
    """While the command runs, turn SIGTERM into :class:`Terminated` (then restore it).

    A job started in the background by a non-interactive shell (``nohup ... &``) ignores
    Ctrl-C's SIGINT, and ``kill`` and batch schedulers send SIGTERM, whose default is to die
    on the spot, losing the progress since the last checkpoint. Left alone when someone else
    already handles SIGTERM, or off the main thread (where no handler can be set).
    """
    try:
        previous = signal.getsignal(signal.SIGTERM)
        if previous == signal.SIG_DFL:
            signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:
        previous = None
    try:
        yield
    finally:
        if previous == signal.SIG_DFL:
            signal.signal(signal.SIGTERM, previous)


def print_error(message: str) -> None:
    """The CLI's one error format: ``error: <message>`` on one stderr line."""
    print(f"error: {one_line(message)}", file=sys.stderr)


class Parser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are one ``error: ...`` line and exit status 2.

    argparse prints the usage and then the message; sub-parsers made by ``add_subparsers``
    are of the parent's class, so one override covers the root parser and every command.
    """

    def error(self, message: str) -> NoReturn:
        print_error(f"{self.prog}: {message} (see: {self.prog} --help)")
        sys.exit(EXIT_ERROR)


def _available() -> dict[str, str]:
    return {name: modname for name, modname in COMMANDS.items()
            if importlib.util.find_spec(f"hybridwsi.commands.{modname}") is not None}


def build_parser(only: str | None = None) -> Parser:
    """The top-level parser; with ``only``, import just that command's module."""
    parser = Parser(
        prog="hybridwsi",
        description="Hybrid (physics + ML) solvers for floating bodies in waves: "
        "stability diagnostic, BEM/Cummins and SPH generators, paper reproduction.",
    )
    parser.add_argument("--version", action="version", version=f"hybridwsi {__version__}",
                        help="print the version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, modname in _available().items():
        if only is not None and name != only:
            sub.add_parser(name, help=f"(see: hybridwsi {name} --help)")
            continue
        mod = importlib.import_module(f"hybridwsi.commands.{modname}")
        p = sub.add_parser(name, help=mod.HELP, description=getattr(mod, "DESCRIPTION", mod.HELP))
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run)
    return parser


def _run(args: argparse.Namespace) -> int:
    """Run a parsed command; every user-fixable failure becomes one ``error:`` line.

    Warnings raised while the command runs are printed after it, one ``warning: ...`` line
    each; when the command fails, only its error line is printed.
    """
    try:
        with _stop_on_sigterm(), warnings.catch_warnings(record=True) as caught:
            status = int(args._run(args) or 0)
        for w in caught:  # re-issued, so that callers of main() still see them as warnings
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        return status
    except HybridWSIError as exc:
        print_error(str(exc))
    except ModuleNotFoundError as exc:
        message = missing_dependency(exc.name)
        if message is None:  # not an optional extra: a broken installation, keep the trace
            raise
        print_error(message)
    except OSError as exc:  # disk full, permission denied... while writing or reading files
        where = f" ({exc.filename})" if exc.filename else ""
        print_error(f"{exc.strerror or exc}{where}")
    except MemoryError:
        print_error("out of memory: reduce the problem size (time steps, panels, cases)")
    except KeyboardInterrupt as exc:
        what = "terminated" if isinstance(exc, Terminated) else "interrupted"
        print_error(f"{what} (partial results were not written; re-run to resume)")
        return EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED
    return EXIT_ERROR


def run_script(script_main: Callable[[], int | None]) -> NoReturn:
    """Run the ``main()`` of a script in ``scripts/`` with the CLI's error handling (bad input,
    a missing optional extra, an OS error: one ``error:`` line and exit status 2) and exit
    with its status. Scripts build their parser with :class:`Parser` for usage errors."""
    sys.exit(_run(argparse.Namespace(_run=lambda _args: script_main())))


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``hybridwsi`` console script; returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    cmd = next((a for a in argv if not a.startswith("-")), None)
    parser = build_parser(only=cmd if cmd in COMMANDS else None)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version (0) or a usage error (2, already printed)
        return int(exc.code or 0)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 0 if cmd is None else EXIT_ERROR
    saved = warnings.formatwarning
    warnings.formatwarning = _format_warning
    try:
        return _run(args)
    finally:
        warnings.formatwarning = saved


def _format_warning(message, category, filename, lineno, line=None) -> str:
    """A warning printed by the CLI: one ``warning: ...`` line, no source excerpt."""
    return f"warning: {one_line(str(message))}\n"


if __name__ == "__main__":  # python -m hybridwsi.cli
    sys.exit(main())
