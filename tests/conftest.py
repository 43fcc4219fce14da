"""Shared set-up of the test suite: end-to-end runs built once per session, a private BEM
cache, and the grouping that keeps ``pytest -n 2`` (pytest-xdist, ``make test``) fast.

Writing a fast test:

- A claim about what ``hybridwsi reproduce --quick`` writes is checked on the one run of the
  session: the fixture :func:`quick_results` (a read-only folder; copy it with
  ``shutil.copytree`` before changing anything). A module that uses it is listed in
  :data:`SHARED_RUN_MODULES`, so that it runs on the worker that made the run (a module that is
  not listed still works, but may make the other worker wait for the run: a warning says so).
- BEM coefficients are cached in a folder of this session (``$HYBRIDWSI_CACHE``), shared by the
  xdist workers; the user's ``~/.cache/hybridwsi`` is neither read nor written. Set
  ``HYBRIDWSI_TEST_CACHE=DIR`` to keep the cache between sessions (faster repeated runs).
- Under ``make test`` (``-n 2 --dist loadscope --no-loadscope-reorder``) every module is one
  unit of work (its module-scoped fixtures are built once, so build what several tests of a
  module need in a module-scoped fixture); the units listed in :data:`HEAVY_FIRST` start first.
- A test takes seconds; a run that only checks its claim at full size is ``@pytest.mark.slow``
  (``make test-slow``, it must still pass). ``make test`` prints the 15 slowest tests.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import warnings
from pathlib import Path

import pytest

#: the xdist unit of work of every module that reads the shared ``reproduce --quick`` run
REPRODUCE_GROUP = "reproduce_quick"
SHARED_RUN_MODULES = ("tests/test_reproduce.py", "tests/test_fowt.py",
                      "tests/test_fowt_hybrid.py", "tests/test_kramer_hybrid.py")

#: units of work started first under xdist, largest first (so that the last units to finish
#: are small ones): the largest CPU times of the suite (--durations)
HEAVY_FIRST = (REPRODUCE_GROUP, "tests/test_corpus.py", "tests/test_tutorial.py",
               "tests/test_sph_tank.py", "tests/test_surrogate_fast.py",
               "tests/test_sph_waves.py", "tests/test_sph_static.py", "tests/test_bem.py",
               "tests/test_sweep.py", "tests/test_surrogate_rollout.py",
               "tests/test_sweep_case.py", "tests/test_sph_3d.py", "tests/test_sph_packing.py")


def work_unit(nodeid: str) -> str:
    """The xdist unit of work of a test: its module, or the shared run's group."""
    module = nodeid.split("::", 1)[0]
    return REPRODUCE_GROUP if module in SHARED_RUN_MODULES else module


def pytest_configure(config: pytest.Config) -> None:
    """One BEM cache for the whole session (the xdist workers inherit the variable)."""
    if hasattr(config, "workerinput"):  # an xdist worker: the controller set it up
        return
    keep = os.environ.get("HYBRIDWSI_TEST_CACHE")
    if keep:
        root = Path(keep)
        root.mkdir(parents=True, exist_ok=True)
    else:
        root = Path(tempfile.mkdtemp(prefix="hybridwsi-test-cache-"))
        config.add_cleanup(lambda: shutil.rmtree(root, ignore_errors=True))
    os.environ["HYBRIDWSI_CACHE"] = str(root)


@pytest.hookimpl(tryfirst=True, optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log):
    """``--dist loadscope``: a module per unit of work, the shared run's modules as one."""
    if config.getvalue("dist") != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class SharedRunScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return work_unit(nodeid)

    return SharedRunScheduling(config, log)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """In an xdist worker: the units of :data:`HEAVY_FIRST` first (the controller hands the
    units out in collection order under ``--no-loadscope-reorder``); and a warning for a
    module that uses the shared run without being listed."""
    if not hasattr(config, "workerinput"):
        return
    rank = {name: i for i, name in enumerate(HEAVY_FIRST)}
    items.sort(key=lambda it: rank.get(work_unit(it.nodeid), len(rank)))
    if config.workerinput.get("workerid") != "gw0":
        return
    stray = sorted({it.nodeid.split("::", 1)[0] for it in items
                    if "quick_results" in getattr(it, "fixturenames", ())
                    and work_unit(it.nodeid) != REPRODUCE_GROUP})
    if stray:
        warnings.warn(f"{', '.join(stray)} use quick_results: add them to SHARED_RUN_MODULES in "
                      "tests/conftest.py (else a worker may wait for the shared run)",
                      pytest.PytestWarning, stacklevel=1)


def _shared_dir(tmp_path_factory: pytest.TempPathFactory, worker_id: str) -> Path:
    """A folder all workers of this session see (the xdist base temp), else this session's."""
    base = tmp_path_factory.getbasetemp()
    return base if worker_id == "master" else base.parent


@pytest.fixture(scope="session")
def worker_id(request: pytest.FixtureRequest) -> str:
    """xdist's worker id ("gw0", ...), "master" without xdist (as xdist's own fixture)."""
    inp = getattr(request.config, "workerinput", None)
    return inp["workerid"] if inp else "master"


@pytest.fixture(scope="session")
def quick_results(tmp_path_factory: pytest.TempPathFactory, worker_id: str) -> Path:
    """The folder of one ``hybridwsi reproduce --quick --quiet`` run (through the CLI's
    ``main``), made once per session; under xdist the first worker that needs it makes it
    (file lock) and the others read it. Read-only: copy it to change it."""
    from filelock import FileLock

    from hybridwsi.cli import main

    root = _shared_dir(tmp_path_factory, worker_id)
    out = root / "reproduce_quick"
    with FileLock(str(root / "reproduce_quick.lock")):
        if not (out / "summary.json").is_file():
            status = main(["reproduce", "--quick", "--quiet", "--out", str(out)])
            assert status == 0, f"reproduce --quick exited with {status}"
    return out


