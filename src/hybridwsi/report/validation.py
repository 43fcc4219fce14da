"""Validation of the linear (BEM/Cummins) model against the measured decay tests (paper Fig. 1).

Kramer et al. (2021) dropped a half-submerged sphere (D = 0.3 m) from H0 = 0.1D, 0.3D and 0.5D.
The error measure is the one of the blind comparison this data set comes from: the RMS of the
heave normalised by the drop height, ``sqrt(mean((z_model/H0 − z_exp/H0)²))`` over
``t ∈ [0, 5 Te0]``, evaluated on the experiment's time grid (the model is interpolated linearly).
Applied to the 11 published codes in ``numerical/`` it reproduces the value quoted for LPF2 at
0.1D (0.0107), so our model is scored exactly as they were.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from hybridwsi import bodies, cummins
from hybridwsi.cases import load_case
from hybridwsi.errors import InputError
from hybridwsi.history import fit_damped_oscillator
from hybridwsi.history.signal import crossing_period, rms_heave_error
from hybridwsi.importers.kramer import (
    KRAMER_DROPS,
    kramer_numerical_files,
    read_kramer_drop,
    read_kramer_numerical,
)
from hybridwsi.sph.decay import first_extrema, grid_convergence

DROPS = KRAMER_DROPS


@dataclass
class DecayValidation:
    """Results of :func:`run_decay_validation`.

    Attributes
    ----------
    rms : dict
        ``{drop: {"linear": rms, "nonlinear_hydrostatics": rms}}``.
    codes : dict
        ``{drop: {code: rms}}`` for the published codes, computed the same way.
    periods : dict
        ``{drop: {"experiment" | model | code: period / Te0}}``: mean zero-crossing period over
        the RMS window (:func:`crossing_period`), the quantity behind most of the RMS error.
    curves : xarray.Dataset
        Normalised heave of the experiment (mean, CI bounds) and of our models on the
        experiment's time grid, per drop; the data behind Fig. 1.
    """

    rms: dict[str, dict[str, float]]
    codes: dict[str, dict[str, float]]
    curves: xr.Dataset
    inputs: dict[str, Any] = field(default_factory=dict)
    periods: dict[str, dict[str, float]] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """``{"01D": {"rms": ..., "rms_nonlinear_hydrostatics": ..., "codes": {...}}, ...}``."""
        out: dict[str, Any] = {}
        for drop in self.rms:
            out[drop] = {
                "rms": self.rms[drop]["linear"],
                "rms_nonlinear_hydrostatics": self.rms[drop].get("nonlinear_hydrostatics"),
                "codes": self.codes.get(drop, {}),
                "period_over_Te0": self.periods.get(drop, {}),
            }
        return out

    def to_markdown(self) -> str:
        """Table of RMS(heave/H0) over [0, 5 Te0]: ours next to the published codes."""
        codes = sorted({c for d in self.codes.values() for c in d})
        head = "| drop | ours (linear) | ours (nonlinear hydrostatics) | " + " | ".join(codes) + " |"
        rule = "|" + "---|" * (3 + len(codes))
        rows = [head, rule]
        for drop in self.rms:
            r = self.rms[drop]
            cells = [
                f"{self.codes[drop][c]:.4f}" if c in self.codes.get(drop, {}) else "–" for c in codes
            ]
            nl = r.get("nonlinear_hydrostatics")
            rows.append(
                f"| {drop} | {r['linear']:.4f} | {nl:.4f} | " + " | ".join(cells) + " |"
                if nl is not None
                else f"| {drop} | {r['linear']:.4f} | – | " + " | ".join(cells) + " |"
            )
        if self.periods:
            names = list(next(iter(self.periods.values())))
            rows += ["", "Mean zero-crossing period / Te0 over the same window:", "",
                     "| drop | " + " | ".join(names) + " |", "|" + "---|" * (1 + len(names))]
            for drop, per in self.periods.items():
                rows.append(f"| {drop} | " + " | ".join(
                    f"{per[n]:.4f}" if n in per else "–" for n in names) + " |")
        return "\n".join(rows)


def score_published_codes(drop: str, te0: float, window=(0.0, 5.0),
                          measured: xr.Dataset | None = None,
                          periods: dict[str, float] | None = None) -> dict[str, float]:
    """RMS of each published code of the blind comparison for one drop.

    ``measured`` is the experiment's history of that drop when the caller already read it;
    ``periods``, when given, receives each code's :func:`crossing_period` / Te0.
    """
    exp = read_kramer_drop(drop, normalised=True) if measured is None else measured
    t_exp, zn_exp = exp["time"].values, exp["z"].values[:, 0]
    out = {}
    for code, path in kramer_numerical_files(drop).items():
        num = read_kramer_numerical(path, require_uniform=False)
        z = num["z"].values[:, 0]
        out[code] = rms_heave_error(num["time"].values, z / z[0], t_exp, zn_exp, te0, window)
        if periods is not None:
            periods[code] = crossing_period(num["time"].values / te0, z, window)
    return out


def decay_measures(t: np.ndarray, zn: np.ndarray, te0: float, measured: xr.Dataset,
                   fit_window: float = 2.5, rms_window: float = 5.0) -> dict[str, float]:
    """The measures of a decay record that issue 15 puts beside the 11 codes.

    Parameters
    ----------
    t, zn : ndarray
        Time [s] from the release and heave / H0 [-].
    te0 : float
        Normalisation period [s].
    measured : xr.Dataset
        The experiment's normalised history of the same drop (the RMS reference).
    fit_window, rms_window : float
        Ends of the damped-oscillator fit window and of the RMS window, in units of ``te0``.

    Returns
    -------
    dict
        ``period_d`` [s], ``zeta`` [-] and ``z_eq`` [-] of a damped oscillator with a free
        equilibrium fitted over [0, fit_window te0] (:func:`hybridwsi.history.fit_damped_oscillator`);
        the first ``trough`` [-] and its time ``trough_t`` [s]; ``rms`` over [0, rms_window te0]
        as :func:`rms_heave_error` (NaN when the record is shorter).
    """
    t, zn = np.asarray(t, float), np.asarray(zn, float)
    fit = fit_damped_oscillator(t, zn, te0, (0.0, fit_window * te0))
    after = t >= 0.0  # a measured record starts before the release
    t1, z1, _, _ = first_extrema(t[after], zn[after])
    try:
        rms = rms_heave_error(t, zn, measured["time"].values, measured["z"].values[:, 0], te0,
                              (0.0, rms_window))
    except InputError:  # record shorter than the RMS window
        rms = float("nan")
    return {"period_d": fit["period_d"], "zeta": fit["zeta"], "z_eq": fit["z_eq"],
            "trough": z1, "trough_t": t1, "rms": rms}


def decay_measures_published(drop: str, te0: float, measured: xr.Dataset | None = None
                             ) -> dict[str, dict[str, float]]:
    """:func:`decay_measures` of the experiment (``"experiment"``) and of each published code
    of one drop (each normalised by its own initial heave, as :func:`score_published_codes`);
    ``measured`` is the experiment's normalised history when the caller already read it."""
    exp = read_kramer_drop(drop, normalised=True) if measured is None else measured
    rows = {"experiment": decay_measures(exp["time"].values, exp["z"].values[:, 0], te0, exp)}
    for code, path in kramer_numerical_files(drop).items():
        num = read_kramer_numerical(path, require_uniform=False)
        z = num["z"].values[:, 0]
        rows[code] = decay_measures(num["time"].values, z / z[0], te0, exp)
    return rows


def decay_measures_table(rows: dict[str, dict[str, float]], drop: str) -> str:
    """Rows of :func:`decay_measures` as a Markdown table, one line per record."""
    lines = [f"| {drop} | T_d [s] | zeta | equilibrium / H0 | first trough / H0 | "
             "RMS(z/H0), [0, 5 Te0] |", "|---|---|---|---|---|---|"]
    for name, f in rows.items():
        lines.append(f"| {name} | {f['period_d']:.4f} | {f['zeta']:.4f} | {f['z_eq']:+.4f} | "
                     f"{f['trough']:+.3f} | {f['rms']:.4f} |")
    return "\n".join(lines)


#: the measures of :func:`decay_measures` whose grid convergence is reported
CONVERGENCE_MEASURES = ("period_d", "zeta", "trough", "rms")


def decay_convergence_table(rows: dict[float, dict[str, float]],
                            measures: tuple[str, ...] = CONVERGENCE_MEASURES) -> str:
    """Observed order, extrapolated value and GCI of the :func:`decay_measures` of runs at
    three or more particle spacings (the three finest; Celik et al. 2008 via
    :func:`hybridwsi.sph.decay.grid_convergence`), as a Markdown table.

    Parameters
    ----------
    rows : dict
        :func:`decay_measures` results keyed by particle spacing dp [m].
    measures : tuple of str
        The keys of ``rows`` to tabulate (default :data:`CONVERGENCE_MEASURES`; a caller that
        adds e.g. the hold force [N] to each row names it here).

    Returns
    -------
    str
        One line per measure: the values from the finest to the coarsest, the observed order,
        the extrapolated value, the GCI of the finest run [%] and whether the three are
        monotone (in the asymptotic range; otherwise the GCI is not to be trusted).
    """
    if len(rows) < 3:
        raise InputError(f"a grid convergence index needs runs at three spacings, got {len(rows)}")
    dps = sorted(rows)[:3]
    lines = [f"| measure (dp = {', '.join(f'{d:g}' for d in dps)} m) | values | observed order | "
             "extrapolated | GCI fine | monotone |", "|---|---|---|---|---|---|"]
    for q in measures:
        vals = tuple(rows[d][q] for d in dps)
        g = grid_convergence(vals, tuple(dps))
        lines.append(f"| {q} | {' / '.join(f'{v:.4f}' for v in vals)} | {g['order']:.2f} | "
                     f"{g['extrapolated']:.4f} | {100 * g['gci_fine']:.2f} % | "
                     f"{'yes' if g['monotone'] else 'no'} |")
    return "\n".join(lines)


def _experiment_curves(measured: dict[str, xr.Dataset], drops: tuple[str, ...], te0: float
                       ) -> xr.Dataset:
    """The measured heave / H0 (mean and 95 % band) of each drop on its own t / Te0 grid."""
    return xr.concat(
        [
            xr.Dataset(
                {
                    "exp_mean": ("t_exp", measured[d]["z"].values[:, 0]),
                    "exp_ci95_lower": ("t_exp", measured[d]["ci95_lower"].values.ravel()),
                    "exp_ci95_upper": ("t_exp", measured[d]["ci95_upper"].values.ravel()),
                },
                coords={"t_exp": measured[d]["time"].values / te0},
            )
            for d in drops
        ],
        dim=pd.Index(list(drops), name="drop_test"),
    )


def run_decay_validation(
    coeffs: xr.Dataset,
    *,
    drops: tuple[str, ...] = DROPS,
    nonlinear: bool = True,
    dt: float | None = None,
    progress: bool = True,
) -> DecayValidation:
    """Simulate the three drops with the Cummins model and score them against the experiment.

    Parameters
    ----------
    coeffs : xarray.Dataset
        BEM coefficients of the Kramer sphere (``hydro.bem.compute``), including A∞ and C.
    drops : tuple of str
        Which drops to run (``"01D"``, ``"03D"``, ``"05D"``).
    nonlinear : bool
        Also run with exact spherical-cap hydrostatics.
    dt : float, optional
        Time step [s] (default from the case file).
    progress : bool
        Show a progress bar over the runs.
    """
    from tqdm.auto import tqdm

    case = load_case("kramer2021_decay")
    te0 = case["experiment"]["Te0"]
    window = tuple(case["experiment"]["rms_window"])
    sim = case["simulation"]
    dt = float(dt or sim["dt"])
    body = bodies.FloatingSphere.kramer2021()
    variants = {"linear": False, **({"nonlinear_hydrostatics": True} if nonlinear else {})}

    rms: dict[str, dict[str, float]] = {}
    codes: dict[str, dict[str, float]] = {}
    periods: dict[str, dict[str, float]] = {}
    curves = []
    jobs = [(d, v) for d in drops for v in variants]
    bar = tqdm(jobs, desc="decay runs", disable=not progress)
    exp_cache: dict[str, xr.Dataset] = {}
    for drop, variant in bar:
        h0 = case["drops"][drop]
        if drop not in exp_cache:
            exp_cache[drop] = read_kramer_drop(drop, normalised=True)
        exp = exp_cache[drop]
        hist = cummins.simulate(
            coeffs,
            mass=case["body"]["mass"],
            duration=sim["duration"],
            dt=dt,
            z0=h0,
            nonlinear_hydrostatics=variants[variant],
            body=body,
        )
        t_exp, zn_exp = exp["time"].values, exp["z"].values[:, 0]
        zn = hist["z"].values[:, 0] / h0
        rms.setdefault(drop, {})[variant] = rms_heave_error(
            hist["time"].values, zn, t_exp, zn_exp, te0, window
        )
        per = periods.setdefault(drop, {})
        per.setdefault("experiment", crossing_period(t_exp / te0, zn_exp, window))
        per[variant] = crossing_period(hist["time"].values / te0, zn, window)
        on_grid = np.interp(t_exp, hist["time"].values, zn, left=np.nan)
        curves.append(
            xr.DataArray(on_grid, dims="t_exp", coords={"t_exp": t_exp / te0}).expand_dims(
                drop_test=[drop], model=[variant]
            )
        )
    for drop in drops:
        codes[drop] = score_published_codes(drop, te0, window, measured=exp_cache[drop],
                                            periods=periods[drop])
    model = xr.combine_by_coords([c.to_dataset(name="heave_over_H0") for c in curves])[
        "heave_over_H0"
    ]
    exp_ds = _experiment_curves(exp_cache, drops, te0)
    ds = xr.merge([exp_ds, model])
    ds["t_exp"].attrs.update(units="1", long_name="t / Te0")
    ds.attrs.update(te0=te0, rms_window=str(window), dt=dt)
    return DecayValidation(rms=rms, codes=codes, curves=ds, inputs={"dt": dt, "te0": te0},
                           periods=periods)
