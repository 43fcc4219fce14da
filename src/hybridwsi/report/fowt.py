"""The floating-wind section of the report: OC3-Hywind mooring, natural frequencies, decays, RAOs.

Everything is computed from the case (``load_case("oc3_hywind")``) and the shipped Capytaine
coefficients (``bem_oc3_hywind.nc``, taken without solving when the inputs match):

- ``fowt/mooring.json``: MoorPy's linearised 6×6 stiffness K = −∂F/∂q at q = 0 (lines plus the
  yaw spring) and the preload F0 beside the published Eq. 5-3 / Eq. 5-2 values;
- ``fowt/natural_frequencies.json``: surge, heave and pitch from the eigen-analysis (A at the
  mode's frequency, hydrostatics with the weight term plus K) and from simulated free decays;
- ``fowt/decay.png`` / ``.nc``: the three free decays (3-DOF surge–heave–pitch Cummins with the
  radiation state space, the mooring as its linearised stiffness, the additional linear damping);
- ``fowt/rao.png`` / ``.nc`` / ``.json``: steady-state amplitudes in regular waves from the time
  domain against the frequency-domain solution of the same linear system.
- ``fowt/diagnostic.json``, ``fowt/hybrid.json``, ``fowt/hybrid_rollout.png`` / ``.nc``: the
  stability diagnostic in surge, heave and pitch and the 3-DOF hybrid in irregular seas
  (:mod:`hybridwsi.report.fowt_hybrid`, issue 13 items 7–8).

The linear system of decays and RAOs (no Morison drag, no mooring nonlinearity):

    (M + A∞) z̈ + ∫K ż + (C_hs + K_moor) z + B_add ż = F_exc(t)
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from hybridwsi.casemodel import case_coefficients, linear_components, mooring_component
from hybridwsi.cases import load_case
from hybridwsi.cummins import simulate
from hybridwsi.dofs import RIGID_DOFS, index, motion_unit
from hybridwsi.files import atomic_write
from hybridwsi.forces import KnownComponent, MooringSystem
from hybridwsi.history import mean_crossing_period
from hybridwsi.hydro import coefficients as co
from hybridwsi.hydro.modal import natural_frequencies
from hybridwsi.report.fowt_hybrid import run_fowt_hybrid
from hybridwsi.report.fowt_moordyn_hybrid import report_section as design_hybrid_section
from hybridwsi.report.plots import save
from hybridwsi.waves import Regular, excitation_force

#: DOFs of the head-sea analysis and the keys of natural_frequencies.json
DOFS = ("Surge", "Heave", "Pitch")
#: initial offsets of the free decays [m, m, rad]: small, so the linearised mooring is exact
DECAY_OFFSET = {"Surge": 5.0, "Heave": 1.0, "Pitch": 0.02}
#: regular-wave periods of the RAOs [s]: the definition's sea states 2-8 (Table 4-1) plus
#: three longer ones towards the heave/pitch resonance (~30 s)
RAO_PERIODS = (4.8, 6.5, 8.1, 9.7, 11.3, 13.6, 17.0, 20.0, 25.0)
RAO_HEIGHT = 1.0  # m: linear system, the height only scales the response


#: rad/s: the frequency-domain RAO curve, from the shipped coefficients' lowest frequency (0.025)
#: to 2: the surge (0.0505), heave (0.201) and pitch (0.213) resonances are in it (issue 29)
RAO_OMEGA_RANGE = (0.025, 2.0)


def oc3_coefficients(case: dict[str, Any] | None = None, cache_dir: Path | None = None
                     ) -> xr.Dataset:
    """The OC3-Hywind coefficients (:func:`hybridwsi.casemodel.case_coefficients`: the shipped
    file when the inputs match)."""
    return case_coefficients(load_case("oc3_hywind") if case is None else case,
                             cache_dir=cache_dir)


def mooring_summary(case: dict[str, Any], system: MooringSystem | None = None
                    ) -> dict[str, Any]:
    """``mooring.json``: K (6×6, −∂F/∂q at q = 0, lines + yaw spring), F0 (6) and Eq. 5-3."""
    system = MooringSystem.from_case(case) if system is None else system
    k, f0 = system.stiffness(), system.preload()
    ref = case["mooring"]["reference"]
    return {
        "K": [[float(v) for v in row] for row in k],
        "F0": [float(v) for v in f0],
        "dofs": list(RIGID_DOFS),
        "units": {"K": "N/m (force/translation), N/rad (force/rotation), N m/m "
                       "(moment/translation), N m/rad (moment/rotation); rows = force DOF",
                  "F0": "N (Surge, Sway, Heave), N m (Roll, Pitch, Yaw)"},
        "sign_convention": "K = -dF/dq about the undisplaced position (Jonkman 2010 Eq. 5-1); "
                           "includes the yaw spring",
        "reference": {"K": ref["K"], "F0": ref["preload"],
                      "source": "Jonkman 2010 (NREL/TP-500-47535) Eq. 5-3 and Eq. 5-2; lines "
                                "only (add the yaw spring 9.834e7 N m/rad to K66)"},
    }


def modal_summary(coeffs: xr.Dataset, stiffness: np.ndarray, dofs: Sequence[str] = DOFS
                  ) -> dict[str, float]:
    """Natural frequency [Hz] per dominant DOF from :func:`natural_frequencies`."""
    idx = index(dofs)
    modes = natural_frequencies(coeffs, np.asarray(stiffness)[np.ix_(idx, idx)], dofs)
    return {m.dominant_dof: m.frequency for m in modes}


def decay_histories(coeffs: xr.Dataset, forces: Sequence[KnownComponent], *,
                    dofs: Sequence[str] = DOFS, quick: bool = False, dt: float = 0.25,
                    offsets: Mapping[str, float] | None = None,
                    durations: Mapping[str, float] | None = None,
                    radiation_ss: Any = None) -> dict[str, xr.Dataset]:
    """Free decays released from ``offsets`` [m or rad] (default :data:`DECAY_OFFSET`) in each
    DOF of ``offsets`` (the others at rest), all ``dofs`` free.

    Durations [s] per released DOF from ``durations``; default 10 surge periods (1240 s; 6
    when ``quick``), 10 heave/pitch periods (300 s). ``radiation_ss``: a fitted radiation
    state space (:func:`hybridwsi.hydro.statespace.fit_radiation_ss`) instead of the default
    fit in every run.
    """
    offsets = DECAY_OFFSET if offsets is None else offsets
    out = {}
    for dof in offsets:
        z0 = np.zeros(len(dofs))
        z0[list(dofs).index(dof)] = offsets[dof]
        if durations is not None:
            duration = float(durations[dof])
        else:
            duration = (750.0 if quick else 1250.0) if dof == "Surge" else 300.0
        out[dof] = simulate(coeffs, dofs=dofs, duration=duration, dt=dt, z0=z0,
                            forces=list(forces), radiation_ss=radiation_ss)
    return out


def decay_frequency(hist: xr.Dataset, dof: str) -> float:
    """Frequency [Hz] from the mean zero-crossing period of ``dof`` (first crossing skipped)."""
    return 1.0 / mean_crossing_period(hist["time"].values, hist["z"].sel(dof=dof).values)


def harmonic_amplitude(t: np.ndarray, y: np.ndarray, omega: float) -> np.ndarray:
    """Complex amplitude Ŷ of ``y(t) ≈ Re(Ŷ e^{iωt}) + c`` by least squares (per column).

    ``y`` shape (nt,) or (nt, n); the fit window should hold whole periods.
    """
    basis = np.column_stack([np.cos(omega * t), -np.sin(omega * t), np.ones_like(t)])
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return coef[0] + 1j * coef[1]


def frequency_response(coeffs: xr.Dataset, omega: float, force: np.ndarray,
                       stiffness: np.ndarray, damping: np.ndarray,
                       dofs: Sequence[str] = DOFS, radiation_ss: Any = None) -> np.ndarray:
    """Steady-state complex amplitude X = [−ω²(M + A(ω)) + iω(B(ω) + B_add) + C + K]⁻¹ F̂.

    Convention z = Re(X e^{iωt}); A and B interpolated linearly in ω (the coefficients'
    :func:`~hybridwsi.hydro.coefficients.at_frequency`), C the hydrostatics with the weight
    term, ``stiffness`` K and ``damping`` B_add on ``dofs`` [SI per DOF]. With
    ``radiation_ss`` (a :class:`~hybridwsi.hydro.statespace.RadiationSS` on ``dofs``), A and
    B are the time-domain radiation model's own, ``A∞ + Im K̂(ω)/ω`` and ``Re K̂(ω)``.
    """
    m = co.matrix(coeffs, "mass", dofs)
    if radiation_ss is None:
        a = co.at_frequency(coeffs, "added_mass", omega, dofs)
        b = co.at_frequency(coeffs, "radiation_damping", omega, dofs)
    else:
        a = co.matrix(coeffs, "added_mass_inf", dofs) + radiation_ss.equivalent_added_mass(omega)
        b = radiation_ss.equivalent_damping(omega)
    c = co.matrix(coeffs, "hydrostatic_stiffness", dofs)
    z = -omega**2 * (m + a) + 1j * omega * (b + damping) + c + stiffness
    return np.linalg.solve(z, np.asarray(force, dtype=complex))


def rao_point(coeffs: xr.Dataset, forces: Sequence[KnownComponent], period: float, *,
              stiffness: np.ndarray, damping: np.ndarray, dofs: Sequence[str] = DOFS,
              quick: bool = False, direction: float = 0.0, radiation_ss: Any = None,
              max_dt: float | None = None) -> dict[str, Any]:
    """One regular wave travelling towards ``direction`` [rad]: time-domain steady-state
    amplitude per DOF against the frequency domain, both per unit wave amplitude (m/m, rad/m).

    The run ramps the excitation over 300 s (so the slow surge mode is hardly excited) and
    fits the last whole wave periods; F̂_exc is fitted from the same run's ``F_exc`` so that
    both sides see the identical excitation (BEM F_e interpolated at ω). The relative error
    is NaN for a DOF the wave does not move (frequency-domain amplitude exactly 0).
    The step is T/40, at most ``max_dt`` [s] (a radiation state space with fast poles
    needs it for the RK4 stability). ``radiation_ss`` as in :func:`decay_histories`; with
    it the result also holds the
    frequency domain of that radiation model (``frequency_domain_ss``, ``relative_error_ss``:
    the time integration alone, without the state-space fit's and the coefficients' own
    Kramers-Kronig differences).
    """
    omega = 2.0 * math.pi / period
    amp = RAO_HEIGHT / 2.0
    dt = period / 40.0 if max_dt is None else min(period / 40.0, float(max_dt))
    duration = 1500.0 if quick else 2500.0
    hist = simulate(coeffs, dofs=dofs, duration=duration, dt=dt,
                    wave=Regular(period=period, height=RAO_HEIGHT, direction=direction),
                    ramp=300.0, forces=list(forces), radiation_ss=radiation_ss)
    t = hist["time"].values
    n_per = int(math.floor(600.0 / period))
    sel = t >= t[-1] - n_per * period - 1e-9
    td = harmonic_amplitude(t[sel], hist["z"].values[sel], omega) / amp
    f_hat = harmonic_amplitude(t[sel], hist["F_exc"].values[sel], omega) / amp
    out = {"period": period, "omega": omega, "direction": direction,
           "time_domain": {d: float(abs(td[i])) for i, d in enumerate(dofs)}}
    models = {"": None} if radiation_ss is None else {"": None, "_ss": radiation_ss}
    for suffix, model in models.items():
        fd = frequency_response(coeffs, omega, f_hat, stiffness, damping, dofs, model)
        ref = np.where(np.abs(fd) > 0, np.abs(fd), np.nan)
        out[f"frequency_domain{suffix}"] = {d: float(abs(fd[i])) for i, d in enumerate(dofs)}
        out[f"relative_error{suffix}"] = {d: float(abs(abs(td[i]) - abs(fd[i])) / ref[i])
                                          for i, d in enumerate(dofs)}
    return out


def rao_curve(coeffs: xr.Dataset, stiffness: np.ndarray, damping: np.ndarray,
              omegas: np.ndarray, dofs: Sequence[str] = DOFS, direction: float = 0.0
              ) -> np.ndarray:
    """|X(ω)|/a on ``omegas`` (n_ω, n_dof) with F̂ = F_e(ω) interpolated like the time domain,
    waves towards ``direction`` [rad]."""
    out = np.empty((omegas.size, len(dofs)))
    t = np.array([0.0])
    for k, w in enumerate(omegas):
        # F_exc(0) and F_exc(T/4) of a unit-amplitude wave give Re and -Im of F̂ (e^{iωt})
        wave = Regular(period=2 * math.pi / w, height=2.0, direction=direction)
        f0 = excitation_force(wave, coeffs, t, list(dofs))[0]
        f1 = excitation_force(wave, coeffs, t + 0.5 * math.pi / w, list(dofs))[0]
        out[k] = np.abs(frequency_response(coeffs, w, f0 - 1j * f1, stiffness, damping, dofs))
    return out


def _write_json(path: Path, data: Any) -> None:
    atomic_write(path, lambda tmp: Path(tmp).write_text(json.dumps(data, indent=2) + "\n"))


def _unit_per_wave(dof: str) -> str:
    return f"{motion_unit(dof)}/m"


def decay_figure(decays: Mapping[str, xr.Dataset], titles: Mapping[str, str] | None = None,
                 *, columns: int = 1, title: str = "OC3-Hywind free decays (3-DOF linear "
                 "Cummins)") -> tuple[plt.Figure, xr.Dataset]:
    """Free decays, each released in its own DOF [m or rad] against time [s]; ``titles``
    per DOF (default: the OC3 offsets), panels in ``columns`` columns (filled down)."""
    rows = -(-len(decays) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(7 + 2 * (columns - 1), 7), squeeze=False)
    data = {}
    for ax, (dof, hist) in zip(axes.T.ravel(), decays.items()):
        t, z = hist["time"].values, hist["z"].sel(dof=dof).values
        ax.plot(t, z, lw=1)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(f"{dof} [{motion_unit(dof)}]")
        ax.set_title(titles[dof] if titles else
                     f"{dof} decay from {DECAY_OFFSET[dof]:g} {motion_unit(dof)}", fontsize=9)
        ax.grid(alpha=0.3)
        data[dof] = xr.DataArray(z, coords={f"time_{dof}": t}, dims=(f"time_{dof}",),
                                 attrs={"units": motion_unit(dof)})
    fig.tight_layout()
    return fig, xr.Dataset(data, attrs={"title": title})


def rao_figure(points: Sequence[dict[str, Any]], omegas: np.ndarray, curve: np.ndarray,
               dofs: Sequence[str] = DOFS) -> tuple[plt.Figure, xr.Dataset]:
    """|RAO| against ω: frequency-domain curves with the time-domain points on them."""
    fig, axes = plt.subplots(len(dofs), 1, figsize=(7, 8), sharex=True)
    w_td = np.array([p["omega"] for p in points])
    td = np.array([[p["time_domain"][d] for d in dofs] for p in points])
    for i, (ax, dof) in enumerate(zip(axes, dofs)):
        ax.plot(omegas, curve[:, i], "-", lw=1, label="frequency domain")
        ax.plot(w_td, td[:, i], "o", ms=5, label="time domain (steady state)")
        ax.set_ylabel(f"|{dof}| / a [{_unit_per_wave(dof)}]")
        ax.set_yscale("log")
        ax.set_xscale("log")
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("ω [rad/s]")
    fig.tight_layout()
    ds = xr.Dataset(
        {"rao_fd": (("omega", "dof"), curve), "rao_td": (("omega_td", "dof"), td)},
        coords={"omega": omegas, "omega_td": w_td, "dof": list(dofs)},
        attrs={"units": ", ".join(f"{d}: {_unit_per_wave(d)}" for d in dofs),
               "omega_units": "rad/s"})
    return fig, ds


def run_fowt(out: Path, *, quick: bool = False, progress: bool = False,
             hybrid: bool = True) -> str:
    """Write ``out/fowt/`` (mooring, natural frequencies, decays, RAOs and, with ``hybrid``,
    the multi-DOF diagnostic and the hybrid of :mod:`hybridwsi.report.fowt_hybrid`) and
    return Markdown.

    ``quick`` shortens the surge decay and the regular-wave runs and uses 5 wave periods, and
    the irregular seas of the hybrid (``[hybrid] quick_duration``, ``quick_long_duration``).
    """
    start = time.time()

    def log(msg: str) -> None:
        if progress:
            print(f"[fowt {time.time() - start:6.1f} s] {msg}", flush=True)

    folder = Path(out) / "fowt"
    folder.mkdir(parents=True, exist_ok=True)
    case = load_case("oc3_hywind")
    coeffs = oc3_coefficients(case)
    system = MooringSystem.from_case(case)
    mooring = mooring_summary(case, system)
    _write_json(folder / "mooring.json", mooring)
    k6 = np.asarray(mooring["K"])
    idx = index(DOFS)
    k3 = k6[np.ix_(idx, idx)]
    log("mooring.json")

    forces = linear_components(case, DOFS, stiffness=k6)  # [-K z, additional damping]
    modal = modal_summary(coeffs, k6)
    decays = decay_histories(coeffs, forces, quick=quick)
    # the same decays with the tabulated nonlinear mooring: the offsets are small enough
    # that it gives the linearised frequencies (a check on "small offsets keep it linear")
    tabulated = decay_histories(coeffs, [mooring_component(case, DOFS, "table"), forces[1]],
                                quick=quick)
    refs = case["reference_natural_frequencies"]
    nat = {d.lower(): {"hz": modal[d], "reference_hz": float(refs[d.lower()]),
                       "from_decay_hz": decay_frequency(decays[d], d),
                       "decay_offset": DECAY_OFFSET[d], "decay_offset_unit": motion_unit(d),
                       "mooring": "linearised stiffness K (MoorPy, Eq. 5-1 convention)",
                       "from_decay_tabulated_mooring_hz": decay_frequency(tabulated[d], d)}
           for d in DOFS}
    _write_json(folder / "natural_frequencies.json", nat)
    fig, ds = decay_figure(decays)
    save(fig, folder / "decay.png")
    ds.to_netcdf(folder / "decay.nc")
    log("natural frequencies and decays")

    damping = np.asarray(forces[1].linear_coefficients(len(DOFS))[1])
    periods = RAO_PERIODS[::2] if quick else RAO_PERIODS
    points = [rao_point(coeffs, forces, p, stiffness=k3, damping=damping, quick=quick)
              for p in periods]
    omegas = np.geomspace(*RAO_OMEGA_RANGE, 400)
    curve = rao_curve(coeffs, k3, damping, omegas)
    _write_json(folder / "rao.json", {"dofs": list(DOFS), "wave_height": RAO_HEIGHT,
                                      "units": {d: _unit_per_wave(d) for d in DOFS},
                                      "points": points})
    fig, ds = rao_figure(points, omegas, curve)
    save(fig, folder / "rao.png")
    ds.to_netcdf(folder / "rao.nc")
    log("RAOs")
    design_md = design_hybrid_section(folder)  # the shipped MoorDyn-coupled runs: no MoorDyn
    log("the hybrid on the MoorDyn-coupled reference")
    hybrid_md = run_fowt_hybrid(folder, case, coeffs,
                                *linear_components(case, case["hybrid"]["dofs"], stiffness=k6),
                                write_json=_write_json, quick=quick, log=log) if hybrid else ""
    return fowt_markdown(mooring, nat, points, time.time() - start, design_md + hybrid_md)


def fowt_markdown(mooring: dict[str, Any], nat: dict[str, Any],
                  points: Sequence[dict[str, Any]], wall: float, hybrid_md: str = "") -> str:
    """The report section."""
    k = np.asarray(mooring["K"])
    ref = mooring["reference"]
    lines = ["## Floating offshore wind: OC3-Hywind", "",
             "NREL 5-MW turbine on the OC3-Hywind spar (Jonkman 2010), shipped Capytaine "
             "coefficients (320 m), MoorPy mooring. Files in `fowt/`.", "",
             "| mooring term | MoorPy | Eq. 5-3 |", "|---|---|---|"]
    for name, (i, j) in {"K11": (0, 0), "K33": (2, 2), "K55": (4, 4), "K15": (0, 4)}.items():
        lines.append(f"| {name} | {k[i, j]:.5g} | {ref['K'][i][j]:.5g} |")
    lines.append(f"| F0 heave [N] (Eq. 5-2) | {mooring['F0'][2]:.6g} | {ref['F0'][2]:.6g} |")
    lines += ["", "| mode | eigen-analysis [Hz] | free decay [Hz] | reference [Hz] |",
              "|---|---|---|---|"]
    for d, v in nat.items():
        lines.append(f"| {d} | {v['hz']:.5f} | {v['from_decay_hz']:.5f} | "
                     f"{v['reference_hz']:.4f} |")
    worst = max(max(p["relative_error"].values()) for p in points)
    lines += ["", f"RAOs (surge, heave, pitch) at {len(points)} regular waves: time-domain "
              f"steady state vs the frequency-domain solution of the same linear system, "
              f"largest difference {100 * worst:.3f} %.", "",
              "![decays](fowt/decay.png)", "", "![RAOs](fowt/rao.png)", "",
              hybrid_md, f"Section wall time {wall:.0f} s.", ""]
    return "\n".join(lines)
