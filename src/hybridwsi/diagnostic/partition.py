"""Component selection (docs/THEORY.md §5): which forces to model, which to leave to a surrogate.

Candidates (built from the history's matrices and/or the coefficients, restricted to the
history's DOFs; :func:`hybridwsi.forces.linear.known_from`):

==================== =========================================================================
``hydrostatic``       ``-C z`` (``hydrostatic_stiffness``)
``added_mass_inf``    ``-A∞ z̈`` (``added_mass_inf``)
``radiation_memory``  ``-∫K ż`` as state space (the history's ``radiation_ss`` attribute, or a
                      fit of the IRF of the coefficients)
``linear_damping``    ``-B ż`` with ``B = B(ω_p)`` at the motion's peak frequency (all DOFs)
``quadratic_damping`` ``-Bq |ż| ż`` (only when ``quadratic_drag`` is given)
``excitation``        the history's ``F_exc`` as a prescribed time series
==================== =========================================================================

Every subset is a partition (``linear_damping`` and ``radiation_memory`` both model radiation
damping, so they are not combined). For each partition the residual
``F_bb = F_tot − Σ known`` is regressed (:func:`~hybridwsi.diagnostic.regression.regress`),
the identified ``(α, β, γ)`` play the surrogate in the stability checks (a)–(c) of
:mod:`~hybridwsi.diagnostic.stability`, and the reference is reconstructed with the residual
prescribed (:func:`~hybridwsi.diagnostic.reconstruct.reconstruct`).

Score (lower is better)::

    score = ρ_c + nrms_recon + 0.1 · n_unknown_physics

``ρ_c`` is the spectral radius of the loosely coupled step map at the target Δt (the residual's
sensitivity as the integrator sees it), ``nrms_recon`` the reconstruction's RMS error over the
std of z, and the last term prefers partitions that model more of the physics when the first
two tie. Partitions failing (b) or (c) (``feasible = False``) rank after all feasible ones.
"""

from __future__ import annotations

import itertools
import json
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from hybridwsi.diagnostic.reconstruct import reconstruct
from hybridwsi.diagnostic.regression import regress
from hybridwsi.diagnostic.stability import CoupledStep, assess
from hybridwsi.errors import InputError
from hybridwsi.forces import (
    KnownComponent,
    LinearDamping,
    QuadraticDamping,
    RadiationMemory,
    as_matrix,
)
from hybridwsi.forces.external import PrescribedForce
from hybridwsi.forces.linear import has_known, known_from, mass_from
from hybridwsi.history import time_step, validate
from hybridwsi.hydro import coefficients

CANDIDATES = ("hydrostatic", "added_mass_inf", "radiation_memory", "linear_damping",
              "quadratic_damping", "excitation")
EXCLUSIVE = ({"radiation_memory", "linear_damping"},)
#: weight of each physics candidate left to the surrogate in the score
UNKNOWN_WEIGHT = 0.1


def peak_omega(hist: xr.Dataset) -> float:
    """Peak [rad/s] of the periodograms of z, each DOF normalised to unit total power and
    summed, so that every DOF counts alike whatever its unit (m or rad)."""
    z = np.asarray(hist["z"].values, float)
    spec = np.abs(np.fft.rfft(z - z.mean(axis=0), axis=0)) ** 2
    total = spec.sum(axis=0)
    spec = (spec[:, total > 0] / total[total > 0]).sum(axis=1)
    w = 2 * np.pi * np.fft.rfftfreq(z.shape[0], time_step(hist))
    return float(w[1:][np.argmax(spec[1:])])


def available_candidates(hist: xr.Dataset, coeffs: xr.Dataset | None = None, *,
                         quadratic_drag: float | None = None) -> list[str]:
    """Names of the candidates these inputs can supply, in :data:`CANDIDATES` order."""
    has_b = coefficients.has(coeffs, "radiation_damping")
    ok = {
        "hydrostatic": has_known(hist, coeffs, "hydrostatic"),
        "added_mass_inf": has_known(hist, coeffs, "added_mass_inf"),
        "radiation_memory": "radiation_ss" in hist.attrs or has_b,
        "linear_damping": has_b,
        "quadratic_damping": quadratic_drag is not None,
        "excitation": "F_exc" in hist,
    }
    return [name for name in CANDIDATES if ok[name]]


def _candidate(name: str, hist: xr.Dataset, coeffs: xr.Dataset | None,
               quadratic_drag: float | None) -> KnownComponent:
    dofs = [str(d) for d in hist["dof"].values]
    if name in ("hydrostatic", "added_mass_inf"):
        return known_from(hist, coeffs, [name])[0]
    if name == "radiation_memory":
        return RadiationMemory.from_history(hist) or RadiationMemory.from_coefficients(coeffs, dofs)
    if name == "linear_damping":
        return LinearDamping.from_coefficients(coeffs, dofs, peak_omega(hist))
    if name == "quadratic_damping":
        return QuadraticDamping(quadratic_drag).linearise_on(hist)
    return PrescribedForce("F_exc")


def build_candidates(
    hist: xr.Dataset,
    coeffs: xr.Dataset | None = None,
    names: Sequence[str] | None = None,
    *,
    quadratic_drag: float | None = None,
) -> dict[str, KnownComponent]:
    """The candidate known components ``names`` (default: every available one).

    Raises
    ------
    InputError
        A requested candidate these inputs cannot supply.
    """
    avail = available_candidates(hist, coeffs, quadratic_drag=quadratic_drag)
    names = avail if names is None else list(names)
    missing = [c for c in names if c not in avail]
    if missing:
        raise InputError(f"candidate(s) {missing} not available (need coefficients, history "
                         f"matrices or F_exc); available: {', '.join(avail) or 'none'}")
    return {name: _candidate(name, hist, coeffs, quadratic_drag) for name in names}


def enumerate_partitions(names: Sequence[str]) -> list[tuple[str, ...]]:
    """All subsets of ``names`` (in candidate order) without mutually exclusive pairs."""
    names = [n for n in CANDIDATES if n in names] + [n for n in names if n not in CANDIDATES]
    out = []
    for r in range(len(names) + 1):
        for combo in itertools.combinations(names, r):
            if any(ex <= set(combo) for ex in EXCLUSIVE):
                continue
            out.append(combo)
    return out


def _verdicts(m, known, reg, dt, scheme) -> dict[str, Any]:
    """The partition's stability (:func:`~hybridwsi.diagnostic.stability.assess`) as table
    columns; feasible: stable in the continuous loop and strictly stable lagged at ``dt``."""
    rep = assess(CoupledStep.from_components(m, known, reg, dt=dt, scheme=scheme))
    return {
        "prescribed_verdict": rep.prescribed.verdict,
        "surrogate_verdict": rep.continuous.verdict,
        "loosely_coupled_verdict": rep.loosely_coupled.verdict,
        "spectral_radius": rep.spectral_radius,
        "max_stable_dt": rep.max_stable_dt,
        "added_mass_ratio": rep.added_mass_ratio,
        "feasible": bool(rep.continuous_stable and rep.loosely_coupled.verdict == "stable"),
    }


def _reconstruction_error(hist, known, m) -> float:
    """Largest normalised RMS error of the reconstruction; inf when it fails (its result
    says so) or when this partition's ODE cannot be set up (singular m + A_k)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = reconstruct(hist, "F_tot", known, mass=m)
    except InputError:
        return float("inf")
    return float(np.max(res.metrics["nrms_error"])) if res.success else float("inf")


def select_partition(
    hist: xr.Dataset,
    coeffs: xr.Dataset | None = None,
    candidates: Sequence[str] | None = None,
    *,
    dt: float | None = None,
    mass: float | np.ndarray | None = None,
    force: str = "F_tot",
    quadratic_drag: float | None = None,
    scheme: str = "newmark",
    reconstruct_each: bool = True,
    force_accuracy: float = 0.01,
) -> pd.DataFrame:
    """Rank force partitions by the stability of their residual and reconstruction error.

    Parameters
    ----------
    hist : TimeHistory
        Reference with ``z, zdot, zddot`` and ``force`` (``F_exc`` enables ``excitation``).
    coeffs : Dataset, optional
        BEM coefficients (``hydrostatic_stiffness``, ``added_mass_inf``, ``radiation_damping``)
        of these DOFs or more (the history's DOFs are selected, in its order).
    candidates : sequence of str, optional
        Candidate names to combine (default: every one available, see module doc).
    dt : float, optional
        Target hybrid time step [s] for check (c); default the history's.
    mass : float or array, optional
        Rigid-body mass [kg, kg m, kg m²]; default the history's ``mass``, else the
        coefficients' restricted to the history's DOFs.
    force : str
        Total force variable [N].
    quadratic_drag : float, optional
        Bq [N s²/m²] of the ``quadratic_damping`` candidate.
    scheme : str
        Loosely coupled integrator (:mod:`hybridwsi.diagnostic.integrators`).
    reconstruct_each : bool
        Run the reconstruction per partition (the slow part).
    force_accuracy : float
        Relative accuracy of ``force`` (docs/THEORY.md §3b): the α/γ split of a residual is
        identifiable only when a larger force error is needed to move α or γ by 10 %.

    Returns
    -------
    pandas.DataFrame
        One row per partition, sorted by ``rank`` (1 = recommended); columns ``partition``,
        ``known``, ``alpha``, ``beta``, ``gamma`` (1-DOF: scalars; else lists),
        ``condition_number``, ``identifiable``, verdicts of (a)-(c), ``spectral_radius``,
        ``max_stable_dt``, ``added_mass_ratio``, ``recon_nrms``, ``feasible``, ``score``.
    """
    validate(hist)
    n = hist.sizes["dof"]
    m = mass if mass is not None else mass_from(hist, coeffs)
    if m is None:
        raise InputError("no mass: pass --mass, or use a history/coefficients carrying 'mass'")
    m = as_matrix(m, n, "mass")
    dt = float(dt if dt is not None else time_step(hist))
    if not dt > 0:
        raise InputError(f"dt must be positive, got {dt}")
    avail = available_candidates(hist, coeffs, quadratic_drag=quadratic_drag)
    built = build_candidates(hist, coeffs, candidates, quadratic_drag=quadratic_drag)
    rows = [_partition_row(hist, combo, [built[c] for c in combo], avail, m, dt, force=force,
                           scheme=scheme, reconstruct_each=reconstruct_each,
                           force_accuracy=force_accuracy)
            for combo in enumerate_partitions(list(built))]
    table = pd.DataFrame(rows)
    table = table.sort_values(["feasible", "score"], ascending=[False, True], kind="stable")
    table.insert(0, "rank", np.arange(1, len(table) + 1))
    table.attrs = {"dt": dt, "scheme": scheme, "mass": m.tolist(),
                   "score": "spectral_radius + recon_nrms + 0.1 * n_unknown (feasible first)"}
    return table.reset_index(drop=True)


def _partition_row(hist: xr.Dataset, combo: tuple[str, ...], known: list[KnownComponent],
                   avail: list[str], m: np.ndarray, dt: float, *, force: str, scheme: str,
                   reconstruct_each: bool, force_accuracy: float) -> dict[str, Any]:
    """One row of the ranking: the residual's regression, its stability, the reconstruction
    error and the score (module doc)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reg = regress(hist, force=force, known=known, force_accuracy=force_accuracy)
    row: dict[str, Any] = {
        "partition": "+".join(combo) or "(none)",
        "known": list(combo),
        "alpha": _squeeze(reg.alpha), "beta": _squeeze(reg.beta), "gamma": _squeeze(reg.gamma),
        "condition_number": float(reg.condition_number),
        "identifiable": bool(reg.identifiable),
    }
    row.update(_verdicts(m, known, reg, dt, scheme))
    row["recon_nrms"] = _reconstruction_error(hist, known, m) if reconstruct_each else np.nan
    n_unknown = len([c for c in CANDIDATES if c in avail and c not in combo
                     and not (c == "linear_damping" and "radiation_memory" in combo)
                     and not (c == "radiation_memory" and "linear_damping" in combo)])
    recon = row["recon_nrms"] if np.isfinite(row["recon_nrms"]) else 1e3
    row["score"] = float(row["spectral_radius"] + (0 if np.isnan(recon) else recon)
                         + UNKNOWN_WEIGHT * n_unknown)
    return row


def _squeeze(a: np.ndarray) -> float | list:
    a = np.asarray(a, dtype=float)
    return float(a[0, 0]) if a.size == 1 else a.tolist()


def table_to_json(table: pd.DataFrame) -> dict[str, Any]:
    """JSON-ready form of a :func:`select_partition` table."""
    recs = json.loads(table.to_json(orient="records"))
    return {"attrs": table.attrs, "partitions": recs}
