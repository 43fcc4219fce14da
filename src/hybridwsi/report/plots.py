"""Figures of the report (PNG, with the data behind them saved by the caller as NetCDF).

Every figure labels its axes with units and draws the reference on the same axes as the model.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless: figures are files, never windows
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from hybridwsi.dofs import is_rotation  # noqa: E402
from hybridwsi.history import atomic_write  # noqa: E402
from hybridwsi.importers.kramer import KRAMER_TE0  # noqa: E402

DROP_LABEL = {"01D": "H0 = 0.1D", "03D": "H0 = 0.3D", "05D": "H0 = 0.5D"}


def save(fig: plt.Figure, path: str | Path, dpi: int = 150) -> Path:
    """Save a figure as PNG atomically and close it."""
    out = atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi, format="png"))
    plt.close(fig)
    return out


def decay_validation_figure(curves: xr.Dataset) -> plt.Figure:
    """Paper Fig. 1: normalised heave decay, experiment (mean and 95 % band) vs our models.

    Parameters
    ----------
    curves : xarray.Dataset
        ``DecayValidation.curves``: ``exp_mean``, ``exp_ci95_lower/upper`` (drop_test, t_exp) and
        ``heave_over_H0`` (drop_test, model, t_exp), with ``t_exp`` in units of Te0.
    """
    drops = list(curves["drop_test"].values)
    fig, axes = plt.subplots(len(drops), 1, figsize=(8, 2.6 * len(drops)), sharex=True)
    axes = np.atleast_1d(axes)
    styles = {"linear": ("C0", "-"), "nonlinear_hydrostatics": ("C3", "--")}
    for ax, drop in zip(axes, drops):
        c = curves.sel(drop_test=drop)
        t = c["t_exp"].values
        ax.fill_between(t, c["exp_ci95_lower"].values, c["exp_ci95_upper"].values, color="0.75",
                        label="experiment 95 % CI")
        ax.plot(t, c["exp_mean"].values, color="k", lw=1.0, label="experiment mean")
        for model in c["model"].values:
            color, ls = styles.get(str(model), ("C2", ":"))
            ax.plot(t, c["heave_over_H0"].sel(model=model).values, color=color, ls=ls, lw=1.2,
                    label=f"BEM/Cummins ({str(model).replace('_', ' ')})")
        ax.set_xlim(-0.2, 5.0)
        ax.set_ylabel("heave / H0 [-]")
        ax.set_title(f"Heave decay, {DROP_LABEL.get(str(drop), drop)}", fontsize=10)
        ax.axhline(0.0, color="0.5", lw=0.5)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel(f"t / Te0 [-]  (Te0 = {KRAMER_TE0} s)")
    fig.tight_layout()
    return fig


def reconstruction_figure(
    reference: xr.Dataset,
    reconstructions: dict[str, xr.Dataset],
    verdicts: dict[str, str],
    moved: dict[str, xr.Dataset] | None = None,
    title: str = "BEM",
    bias: float = 0.0,
) -> plt.Figure:
    """Paper Fig. 2: the first DOF reconstructed with several partitions against the reference.

    Top: z(t) of the reference and of each reconstruction. Middle: |error| on a log scale (so
    drift and neutral error growth are visible). Bottom (when ``moved`` is given): error after
    moving the identified α, β, γ into the ODE (docs/THEORY.md §4a). Axes in mm for a
    translation, mrad for a rotation, and δF in N or N m (:mod:`hybridwsi.dofs`).
    """
    dof = str(reference["dof"].values[0])
    unit, force_unit = ("mrad", "N m") if is_rotation(dof) else ("mm", "N")
    n_rows = 3 if moved else 2
    fig, axes = plt.subplots(n_rows, 1, figsize=(9, 2.8 * n_rows), sharex=True)
    t = reference["time"].values
    zr = reference["z"].values[:, 0]
    ax = axes[0]
    ax.plot(t, zr * 1e3, color="k", lw=2.0, label="reference")
    for i, (name, rec) in enumerate(reconstructions.items()):
        ax.plot(rec["time"], rec["z"].values[:, 0] * 1e3, color=f"C{i}", lw=1.0, ls="--",
                label=f"case {name} ({verdicts.get(name, '?')})")
    ax.set_ylabel(f"{dof.lower()} z [{unit}]")
    ax.set_title(f"{title}: reconstruction m z̈ = F_known + F_bb(t)", fontsize=10)
    ax.legend(fontsize=8, ncol=2, loc="upper left")
    ax.grid(alpha=0.3)

    def _errors(ax, recs, label):
        for i, (name, rec) in enumerate(recs.items()):
            err = np.abs(np.interp(t, rec["time"].values, rec["z"].values[:, 0]) - zr)
            ax.semilogy(t, np.maximum(err, 1e-15) * 1e3, color=f"C{i}", lw=1.0,
                        label=f"case {name}")
        # a diverging reconstruction leaves the axis instead of hiding the others
        ax.set_ylim(1e-9, 1e3)
        ax.set_ylabel(f"|z − z_ref| [{unit}]\n{label}")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, ncol=3, loc="lower right")

    extra = " + δF" if bias else ""
    _errors(axes[1], reconstructions, f"prescribed F_bb{extra}")
    if moved:
        _errors(axes[2], moved, f"memory α, β, γ in ODE{extra}")
    if bias:
        axes[1].set_title(f"constant force error δF = {bias:.3g} {force_unit} added to F_bb",
                          fontsize=9)
    axes[-1].set_xlabel("time t [s]")
    fig.tight_layout()
    return fig


def sph_decay_figure(curves: xr.Dataset) -> plt.Figure:
    """SPH heave decay runs against the Kramer et al. (2021) experiment on the same axes.

    Parameters
    ----------
    curves : xarray.Dataset
        ``exp_mean``, ``exp_ci95_lower/upper`` (t) and ``heave_over_H0`` (run, t), with ``t``
        in units of Te0 (see ``scripts/sph_compare_kramer.py``).
    """
    fig, ax = plt.subplots(figsize=(8, 3.4))
    t = curves["t"].values
    ax.fill_between(t, curves["exp_ci95_lower"].values, curves["exp_ci95_upper"].values,
                    color="0.75", label="experiment 95 % CI")
    ax.plot(t, curves["exp_mean"].values, color="k", lw=1.0, label="experiment mean")
    for i, run in enumerate(curves["run"].values):
        ax.plot(t, curves["heave_over_H0"].sel(run=run).values, color=f"C{i}", lw=1.1,
                label=str(run))
    ax.set_xlim(-0.2, 5.0)
    ax.set_xlabel(f"t / Te0 [-]  (Te0 = {KRAMER_TE0} s)")
    ax.set_ylabel("heave / H0 [-]")
    ax.set_title("SPH heave decay of the Kramer sphere, H0 = 0.1D", fontsize=10)
    ax.axhline(0.0, color="0.5", lw=0.5)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    return fig
