"""Command line: ``hybridwsi <command> ...``, one sub-command per pipeline stage.

Each command lives in :mod:`hybridwsi.commands.<name>` and provides ``HELP`` (one line),
``add_arguments(parser)`` and ``run(args) -> int``. Commands are imported lazily so that
``hybridwsi diagnose`` does not pay for importing Capytaine or PyTorch.

Errors that come from bad input (:class:`hybridwsi.errors.InputError`) are printed as one line
``error: ...`` on stderr with exit status 2; never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys

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


def _available() -> dict[str, object]:
    mods = {}
    for name, modname in COMMANDS.items():
        spec = importlib.util.find_spec(f"hybridwsi.commands.{modname}")
        if spec is not None:
            mods[name] = modname
    return mods


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The top-level parser; with ``only``, import just that command's module."""
    from hybridwsi import __version__

    parser = argparse.ArgumentParser(
        prog="hybridwsi",
        description="Hybrid (physics + ML) solvers for floating bodies in waves: "
        "stability diagnostic, BEM/Cummins and SPH generators, paper reproduction.",
    )
    parser.add_argument("--version", action="version", version=f"hybridwsi {__version__}")
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


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    cmd = next((a for a in argv if not a.startswith("-")), None)
    parser = build_parser(only=cmd if cmd in COMMANDS else None)
    args = parser.parse_args(argv)
    if not getattr(args, "_run", None):
        parser.print_help()
        return 0 if cmd is None else 2
    try:
        return int(args._run(args) or 0)
    except HybridWSIError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted (partial results were not written; re-run to resume)",
              file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
