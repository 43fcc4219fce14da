"""Layout contracts of issue 12: no import cycle between the data layers, one version source,
one Kramer loader."""

from __future__ import annotations

import ast
from importlib.metadata import version as dist_version
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import hybridwsi

SRC = Path(hybridwsi.__file__).parent


def _imported_modules(package: Path) -> set[str]:
    """Every module named by an import statement in a package (also inside functions)."""
    out: set[str] = set()
    for path in package.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                out |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module:
                out |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
    return out


@pytest.mark.parametrize("upper", ["hybridwsi.importers", "hybridwsi.report",
                                   "hybridwsi.diagnostic", "hybridwsi.surrogate"])
def test_history_imports_nothing_above_it(upper):
    # history is the data model every layer above reads; an import of a layer above is a cycle
    assert not any(m == upper or m.startswith(upper + ".")
                   for m in _imported_modules(SRC / "history"))


@pytest.mark.parametrize("lower", ["surrogate", "diagnostic"])
@pytest.mark.parametrize("upper", ["hybridwsi.report", "hybridwsi.commands"])
def test_library_imports_neither_report_nor_commands(lower, upper):
    # the studies (surrogate/kramer.py, surrogate/fowt.py) are library code: the report and
    # the command line call them, never the other way round (issue 28 item 3)
    imported = _imported_modules(SRC / lower)
    assert any(m.startswith("hybridwsi.") for m in imported)  # the scan sees the imports
    assert not [m for m in imported if m == upper or m.startswith(upper + ".")]


def test_importers_and_report_packages_keep_their_public_names():
    from hybridwsi import importers
    from hybridwsi.report import reproduce, validation

    for name in importers.__all__:
        assert hasattr(importers, name), name
    assert callable(reproduce.run) and callable(validation.run_decay_validation)


def test_provenance_reads_the_installed_versions():
    from hybridwsi._meta import package_version, provenance, version

    assert version() == hybridwsi.__version__
    prov = provenance("numpy", "surely-not-a-package-xyz")
    assert list(prov) == ["hybridwsi", "numpy", "surely-not-a-package-xyz"]
    assert prov["numpy"] == dist_version("numpy") == np.__version__
    assert prov["surely-not-a-package-xyz"] == package_version("surely-not-a-package-xyz") \
        == "unknown"


def test_sph_decay_reads_the_shipped_experiment_through_the_importer():
    # the experiment table the SPH comparison uses equals the shipped CSV read independently
    from hybridwsi.importers.kramer import KRAMER_TE0, kramer_decay_file
    from hybridwsi.sph.decay import TE0, load_experiment

    assert TE0 == KRAMER_TE0 == 0.7561
    raw = pd.read_csv(kramer_decay_file("03D"), float_precision="round_trip")
    exp = load_experiment("03D")
    for col in ("t_over_Te0", "x3_over_H0m_mean", "ci95_lower", "ci95_upper"):
        np.testing.assert_allclose(exp[col].to_numpy(), raw[col].to_numpy(), rtol=1e-14,
                                   atol=1e-15)


def test_decay_validation_periods_use_the_equilibrium_crossing_routine():
    # the measured 0.1D record's mean crossing period over [0, 5 Te0] is close to Te0 (the
    # data are normalised by it; damping lengthens the period only by ~1/(1 - zeta^2)^0.5)
    from hybridwsi.importers.kramer import read_kramer_drop
    from hybridwsi.report.validation import crossing_period

    exp = read_kramer_drop("01D", normalised=True)
    p = crossing_period(exp["time"].values / 0.7561, exp["z"].values[:, 0], (0.0, 5.0))
    assert p == pytest.approx(1.0, abs=0.02)
