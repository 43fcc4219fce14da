"""Run many ``python -m hybridwsi.cli ...`` invocations fast: import once, fork per case.

Reads one JSON request per stdin line ``{"argv": [...], "cwd": DIR, "stdout": FILE,
"stderr": FILE, "timeout": S}``; for each, forks a child that changes to ``cwd``, redirects
its stdout/stderr to the files and runs the module ``hybridwsi.cli`` as ``__main__`` (exactly
what ``python -m hybridwsi.cli`` does, with the heavy libraries already imported), then writes
``{"rc": status}`` back. A child that runs longer than ``timeout`` is killed by SIGALRM
(status -14). Used by ``tests/test_corpus.py`` to run hundreds of cases in seconds each.
"""

from __future__ import annotations

import importlib
import json
import os
import runpy
import signal
import sys
import traceback
import warnings

#: imported once in the server so that each forked case starts warm (never hybridwsi.cli:
#: runpy must execute it fresh as __main__)
PRELOAD = (
    "numpy", "scipy.signal", "scipy.interpolate", "pandas", "xarray", "netCDF4", "h5py",
    "matplotlib", "torch", "distributed", "dask.array", "zarr", "capytaine",
    "hybridwsi.commands._options", "hybridwsi.importers", "hybridwsi.hydro.formats",
    "hybridwsi.hydro.bem", "hybridwsi.cummins", "hybridwsi.diagnostic.regression",
    "hybridwsi.diagnostic.stability", "hybridwsi.diagnostic.partition", "hybridwsi.sweep",
    "hybridwsi.surrogate.network", "hybridwsi.surrogate.rollout", "hybridwsi.surrogate.demo",
    "hybridwsi.report.reproduce",
    *(f"hybridwsi.commands.{m}" for m in ("diagnose", "import_", "bem", "simulate",
                                          "reproduce", "sph", "select", "sweep", "hybrid",
                                          "coeffs")),
)


def _preload() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in PRELOAD:
            try:
                importlib.import_module(name)
            except ImportError:
                pass  # an optional extra: the case itself reports it
    sys.modules.pop("hybridwsi.cli", None)


def _child(req: dict) -> None:
    os.chdir(req["cwd"])
    for fd, name in ((1, req["stdout"]), (2, req["stderr"])):
        f = os.open(name, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(f, fd)
        os.close(f)
    signal.alarm(int(req.get("timeout", 120)))
    sys.argv = ["hybridwsi", *req["argv"]]
    code = 0
    try:
        runpy.run_module("hybridwsi.cli", run_name="__main__", alter_sys=True)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except BaseException:  # what the interpreter would do: print the traceback, status 1
        traceback.print_exc()
        code = 1
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(code)


def main() -> None:
    _preload()
    import gc
    gc.freeze()
    for line in sys.stdin:
        req = json.loads(line)
        pid = os.fork()
        if pid == 0:
            _child(req)
        _, status = os.waitpid(pid, 0)
        sys.stdout.write(json.dumps({"rc": os.waitstatus_to_exitcode(status)}) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
