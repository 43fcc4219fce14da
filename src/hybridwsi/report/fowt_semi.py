"""The OC4-DeepCwind semi-submersible in six DOFs: its linear system, natural frequencies, free
decays and RAOs at several wave headings (library functions for the report section).

Everything comes from the case (``load_case("oc4_semi")``):

- coefficients: the shipped Capytaine solution of the columns and heave plates
  (``bem_oc4_semi.nc``, taken without solving when the inputs match) plus the slender
  members' Morison inertia (:func:`hybridwsi.casemodel.case_coefficients`);
- mooring: MoorPy's linearised stiffness K = −∂F/∂q of the three catenary lines;
- viscous damping: the members' Morison drag (columns, heave plates axially, pontoons, braces)
  linearised by energy equivalence (Borgman) at the velocity amplitudes of ``[linear_drag]``,
  one DOF at a time and summed (:func:`linearised_drag`).

The linear 6-DOF system of the decays and RAOs:

    (M + A∞) z̈ + ∫K ż + (C_hs + K_moor) z + B_drag ż = F_exc(t, β)

(radiation state space; ``B_drag`` constant). The frequency domain solves the same system with
A(ω), B(ω) (:func:`hybridwsi.report.fowt.frequency_response`).
"""

from __future__ import annotations

import json
import math
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import scipy.integrate
import scipy.linalg
import xarray as xr
from scipy.interpolate import CubicSpline

from hybridwsi.casemodel import case_coefficients, linearised_member_drag, radiation_ss
from hybridwsi.cases import Case, load_case
from hybridwsi.cummins import simulate
from hybridwsi.diagnostic import stability
from hybridwsi.diagnostic.regression import regress
from hybridwsi.dofs import RIGID_DOFS, motion_unit
from hybridwsi.files import _jsonable, atomic_write
from hybridwsi.forces import Hydrostatic, KnownComponent, LinearDamping, MemberMorison, \
    MooringForce, MooringSystem
from hybridwsi.hydro import coefficients as co
from hybridwsi.hydro.modal import Mode, natural_frequencies
from hybridwsi.report.fowt import decay_figure, decay_frequency, decay_histories, rao_curve, \
    rao_point
from hybridwsi.report.fowt_semi_hybrid import run_semi_hybrid, semi_hybrid_markdown
from hybridwsi.report.plots import save
from hybridwsi.surrogate import fowt as fd
from hybridwsi.waves import JONSWAP

#: initial offsets of the free decays [m, m, m, rad, rad, rad]: small (linear mooring)
SEMI_DECAY_OFFSET = {"Surge": 5.0, "Sway": 5.0, "Heave": 1.0, "Roll": 0.02, "Pitch": 0.02,
                     "Yaw": 0.05}
#: the solver step the radiation model is fitted for [s] (unused by a [radiation] table)
RADIATION_DT = 0.25
#: decay durations [s]: about 8 periods of each mode
SEMI_DECAY_DURATION = {"Surge": 900.0, "Sway": 900.0, "Heave": 150.0, "Roll": 220.0,
                       "Pitch": 220.0, "Yaw": 650.0}


@dataclass(frozen=True)
class SemiSystem:
    """The linear 6-DOF model of the semi.

    Attributes
    ----------
    coeffs : xarray.Dataset
        BEM + slender-member coefficients (6 DOFs, wave headings of ``[bem]``).
    mooring : ndarray (6, 6)
        K = −∂F/∂q at q = 0 [N/m, N/rad, N m/m, N m/rad], rows = force DOF.
    drag : ndarray (6, 6)
        Linearised member drag [N s/m, N s/rad, N m s/m, N m s/rad].
    radiation_ss : RadiationSS
        The radiation state space of the time domain (:func:`radiation_state_space`).
    dofs : tuple of str
        The six DOFs.
    """
    coeffs: xr.Dataset
    mooring: np.ndarray
    drag: np.ndarray
    radiation_ss: Any = None
    dofs: tuple[str, ...] = RIGID_DOFS

    @property
    def max_dt(self) -> float | None:
        """Largest RK4 step [s] for the radiation state space: 2 / max|pole| (RK4 is stable
        to |λ dt| ≈ 2.8 on the imaginary axis)."""
        if self.radiation_ss is None or not self.radiation_ss.order:
            return None
        return 2.0 / float(np.abs(self.radiation_ss.poles).max())

    def forces(self) -> list[KnownComponent]:
        """The linear components of the Cummins run: mooring stiffness and drag damping."""
        return [Hydrostatic(self.mooring), LinearDamping(self.drag)]


def linearised_drag(case: Mapping[str, Any], amplitudes: Mapping[str, float] | None = None
                    ) -> np.ndarray:
    """Σ over DOFs of the Borgman-linearised member drag, (6, 6)
    (:func:`hybridwsi.casemodel.linearised_member_drag`)."""
    return linearised_member_drag(case, amplitudes)


def radiation_state_space(case: Mapping[str, Any], coeffs: xr.Dataset):
    """The case's radiation state space (``[radiation]``, :func:`hybridwsi.casemodel.
    radiation_ss`) on the six DOFs.

    The default fit (a 30 s kernel, up to 20 states, the 6×6 kernel weighed by its largest
    entries) loses the semi's heave radiation and makes the coupled system unstable; the
    case's (40 s, up to 60 states, balanced) keeps B(ω) within 1.8 % RMS of the BEM's and the
    system stable (docs/OC4_SEMI.md)."""
    return radiation_ss(coeffs, RIGID_DOFS, None, RADIATION_DT, case.get("radiation"))


def semi_system(case: Case | None = None, table: str = "bem",
                cache_dir: Any = None) -> SemiSystem:
    """Coefficients (``[table]``: ``"bem"`` shipped, ``"bem_quick"`` coarse), MoorPy stiffness,
    linearised drag and radiation state space of the case (default ``oc4_semi``)."""
    case = load_case("oc4_semi") if case is None else case
    coeffs = case_coefficients(case, quick=table == "bem_quick", cache_dir=cache_dir)
    return SemiSystem(coeffs=coeffs, mooring=MooringSystem.from_case(case).stiffness(),
                      drag=linearised_drag(case),
                      radiation_ss=radiation_state_space(case, coeffs))


def semi_modes(system: SemiSystem) -> list[Mode]:
    """Undamped natural modes, A(ω) at each mode's frequency, C_hs + K_moor."""
    return natural_frequencies(system.coeffs, system.mooring, list(system.dofs))


def semi_decays(system: SemiSystem, *, dt: float = 0.2,
                offsets: Mapping[str, float] = SEMI_DECAY_OFFSET,
                durations: Mapping[str, float] = SEMI_DECAY_DURATION
                ) -> dict[str, dict[str, Any]]:
    """Free decay released in each DOF of ``offsets``: ``{dof: {"history", "hz"}}`` with the
    frequency [Hz] from the mean zero-crossing period of the released DOF."""
    hists = decay_histories(system.coeffs, system.forces(), dofs=system.dofs, dt=dt,
                            offsets=offsets, durations=durations,
                            radiation_ss=system.radiation_ss)
    return {d: {"history": h, "hz": decay_frequency(h, d)} for d, h in hists.items()}


def semi_raos(system: SemiSystem, periods: Sequence[float], headings_deg: Sequence[float], *,
              quick: bool = False) -> list[dict[str, Any]]:
    """Time-domain vs frequency-domain RAOs per heading and period
    (:func:`hybridwsi.report.fowt.rao_point`, all six DOFs)."""
    out = []
    for beta in headings_deg:
        for period in periods:
            point = rao_point(system.coeffs, system.forces(), float(period),
                              stiffness=system.mooring, damping=system.drag,
                              dofs=system.dofs, quick=quick, direction=math.radians(beta),
                              radiation_ss=system.radiation_ss, max_dt=system.max_dt)
            out.append({**point, "heading_deg": float(beta)})
    return out


def semi_rao_curves(system: SemiSystem, omegas: np.ndarray, headings_deg: Sequence[float]
                    ) -> np.ndarray:
    """|X(ω)|/a (n_heading, n_ω, 6) of the frequency-domain model."""
    return np.array([rao_curve(system.coeffs, system.mooring, system.drag, omegas,
                               system.dofs, direction=math.radians(b)) for b in headings_deg])


#: what each partition of :func:`semi_diagnostic` leaves to the network
SEMI_RESIDUAL = {
    "1": "everything (inertia, hydrostatics, mooring, radiation, drag, excitation)",
    "2": "A∞, radiation memory, drag, mooring nonlinearity, excitation",
    "3": "radiation memory, drag, mooring nonlinearity, excitation",
    "A_inf_to_network": "A∞ (6×6), drag, mooring nonlinearity",
    "A_inf_coupling_to_network": "A∞ off-diagonal couplings, drag, mooring nonlinearity",
    "recommended": "member drag + (tabulated mooring − K q)",
}


def semi_sea_history(system: SemiSystem, case: Mapping[str, Any] | None = None, *,
                     hs: float = 4.0, tp: float = 11.0, heading_deg: float = 30.0,
                     seed: int = 1, n_components: int = 100, duration: float = 600.0,
                     dt: float = 0.2, ramp: float = 20.0) -> xr.Dataset:
    """A nonlinear six-DOF Cummins run in a long-crested JONSWAP sea at ``heading_deg`` [deg]:
    the radiation state space, MoorPy's tabulated mooring (F(q) − F0) and every member's
    Morison drag on the relative velocity with the Airy kinematics (``F_ext`` their sum)."""
    case = load_case("oc4_semi") if case is None else case
    wave = JONSWAP(hs=hs, tp=tp, seed=seed, n_components=n_components,
                   direction=math.radians(heading_deg))
    dofs = list(system.dofs)
    drag = MemberMorison.from_case(case, dofs, wave=wave, ramp=ramp, inertia=False)
    return simulate(system.coeffs, dofs=dofs, duration=duration, dt=dt, wave=wave, ramp=ramp,
                    forces=[MooringForce.from_case(case, dofs), drag],
                    radiation_ss=system.radiation_ss)


def semi_diagnostic(system: SemiSystem, hist: xr.Dataset, *,
                    accuracies: Sequence[float] = (1e-4, 1e-2), perturbation: float = 1e-3
                    ) -> dict[str, Any]:
    """The 6×6 diagnostic of every partition on a six-DOF history (JSON-ready): α, β, γ,
    identifiability per DOF and per coupling (every pair i < j: entries (i, j), (j, i) of α
    and γ move by 10 % only under a force error above the stated accuracy, and both DOFs
    identifiable, i.e. also the random error small), the lagged
    verdict (spectral radius of the Newmark lagged step at the history's Δt) and, for the
    linear known parts 1–3, the observed lagged run of the regressed surrogate
    (:mod:`hybridwsi.surrogate.fowt`, the OC3 analysis in six DOFs)."""
    dofs = [str(d) for d in hist["dof"].values]
    dt = float(hist["time"].values[1] - hist["time"].values[0])
    parts = fd.partitions(hist, Hydrostatic(system.mooring), LinearDamping(np.zeros((6, 6))))
    rows = []
    for name, known in parts.items():
        entry = fd.partition_entry(name, hist, known, accuracies, dt=dt,
                                   perturbation=perturbation)
        entry["left_to_network"] = SEMI_RESIDUAL[name]
        regs = [_quiet_regress(hist, known, acc) for acc in accuracies]
        entry["couplings_identifiable"] = {
            f"{acc:g}": [f"{dofs[i]}-{dofs[j]}" for i in range(6) for j in range(i + 1, 6)
                         if fd.coupling_identifiable(r, acc, i, j)
                         and r.identifiable_dof[i] and r.identifiable_dof[j]]
            for acc, r in zip(accuracies, regs)}
        entry["where"], entry["reason"] = fd.verdict_line(entry)
        rows.append(entry)
    mass = fd.rigid_mass(hist)
    added_mass_inf = np.asarray(hist["added_mass_inf"].values)
    return {"history": {"duration_s": float(hist["time"].values[-1]), "dt": dt, "dofs": dofs,
                        "wave": hist.attrs.get("wave")},
            "std_z": dict(zip(dofs, np.asarray(hist["z"].values).std(axis=0).tolist())),
            "mass": mass.tolist(), "added_mass_inf": added_mass_inf.tolist(),
            "rho_M_inv_A_inf": stability.added_mass_ratio(mass, np.zeros_like(mass),
                                                             added_mass_inf),
            "partitions": rows}


def _quiet_regress(hist: xr.Dataset, known: Sequence[KnownComponent], accuracy: float) -> Any:


    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return regress(hist, "F_tot", list(known), force_accuracy=accuracy)


def semi_mode_variants(system: SemiSystem) -> dict[str, float]:
    """Surge and pitch frequencies [Hz] of the variants behind the natural-frequency table of
    docs/OC4_SEMI.md: the coupled surge–pitch pair with A(ω) at the mode's own frequency or
    with A∞, and pitch alone (surge held) with either; rigid mass, C_hs + K_moor."""
    c = system.coeffs
    m = co.matrix(c, "mass")
    k = co.matrix(c, "hydrostatic_stiffness") + system.mooring

    def freqs(a: np.ndarray, idx: list[int]) -> np.ndarray:
        w2 = scipy.linalg.eigh(k[np.ix_(idx, idx)], (m + a)[np.ix_(idx, idx)], eigvals_only=True)
        return np.sqrt(w2) / (2 * math.pi)

    def own(idx: list[int], which: int, f: float) -> float:  # A at the mode's own frequency
        for _ in range(50):
            f = float(freqs(co.at_frequency(c, "added_mass", 2 * math.pi * f), idx)[which])
        return f

    added_mass_inf = co.matrix(c, "added_mass_inf")
    return {"surge_coupled": own([0, 4], 0, 0.009), "pitch_coupled": own([0, 4], 1, 0.04),
            "surge_coupled_A_inf": float(freqs(added_mass_inf, [0, 4])[0]),
            "pitch_coupled_A_inf": float(freqs(added_mass_inf, [0, 4])[1]),
            "pitch_alone": own([4], 0, 0.04),
            "pitch_alone_A_inf": float(freqs(added_mass_inf, [4])[0])}


def mooring_amplitude_ratio(case: Mapping[str, Any], dof: str, amplitudes: Sequence[float]
                            ) -> list[float]:
    """Frequency of an undamped one-DOF oscillator on MoorPy's nonlinear mooring force along
    ``dof`` at each amplitude [m or rad], over its small-amplitude frequency (same mass): the
    period is ∮ dx / v with ½ m v² = V(X) − V(x), taken on each side of rest (the catenaries
    are not symmetric in surge)."""
    system = MooringSystem.from_case(case)
    i = RIGID_DOFS.index(dof)
    top = 1.2 * max(amplitudes)
    x = np.linspace(-top, top, 97)
    f0 = system.force6(np.zeros(6))[i]
    restoring = CubicSpline(x, [f0 - system.force6(np.eye(6)[i] * v)[i] for v in x])
    energy = restoring.antiderivative()
    k0 = float(restoring.derivative()(0.0))
    out = []
    for amp in amplitudes:
        half = 0.0
        for side in (1.0, -1.0):
            e_max = energy(side * amp)
            half += scipy.integrate.quad(  # x = X sin u removes the turning-point singularity
                lambda u: amp * math.cos(u) / math.sqrt(
                    max(2 * (e_max - energy(side * amp * math.sin(u))), 1e-300)),
                0, math.pi / 2, limit=200)[0]
        out.append(float(2 * math.pi / math.sqrt(k0) / (2 * half)))
    return out


# ----------------------------------------------------------------------------- report section
#: regular-wave periods [s] and headings [deg] of the report's RAO table (quick: every other)
SEMI_RAO_PERIODS = (5.0, 7.0, 9.0, 11.0, 13.0, 17.0, 22.0, 30.0)
SEMI_RAO_HEADINGS = (0.0, 30.0, 60.0)


def semi_decay_figure(decays: Mapping[str, Mapping[str, Any]]) -> tuple[Any, xr.Dataset]:
    """The six free decays, each in its released DOF [m or rad] against time [s]."""
    return decay_figure({d: v["history"] for d, v in decays.items()},
                        {d: f"{d}: {v['hz']:.5f} Hz (zero crossings)" for d, v in decays.items()},
                        columns=2, title="OC4-DeepCwind semi free decays (6-DOF linear Cummins, "
                                         "linearised member drag)")


def semi_rao_figure(points: Sequence[Mapping[str, Any]], omegas: np.ndarray,
                    curves: np.ndarray, headings: Sequence[float]) -> tuple[Any, xr.Dataset]:
    """|X|/a [m/m, rad/m] per DOF: frequency-domain curves per heading (BEM A(ω), B(ω)) with
    the time-domain steady-state points on them."""
    fig, axes = plt.subplots(3, 2, figsize=(10, 8), sharex=True)
    td = np.full((len(headings), len(SEMI_RAO_PERIODS), 6), np.nan)
    w_td = 2 * math.pi / np.asarray(SEMI_RAO_PERIODS)
    for p in points:
        h = list(headings).index(p["heading_deg"])
        k = int(np.argmin(np.abs(w_td - p["omega"])))
        td[h, k] = [p["time_domain"][d] for d in RIGID_DOFS]
    for i, (ax, dof) in enumerate(zip(axes.T.ravel(), RIGID_DOFS)):
        for h, beta in enumerate(headings):
            line, = ax.plot(omegas, curves[h, :, i], "-", lw=1, label=f"{beta:g}° frequency domain")
            ax.plot(w_td, td[h, :, i], "o", ms=4, color=line.get_color(),
                    label=f"{beta:g}° time domain")
        ax.set_ylabel(f"|{dof}| / a [{motion_unit(dof)}/m]")
        ax.set_yscale("log")
        ax.set_ylim(bottom=max(1e-6, np.nanmax(curves[:, :, i]) * 1e-4))
        ax.grid(alpha=0.3, which="both")
    axes[0, 0].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("ω [rad/s]")
    fig.tight_layout()
    ds = xr.Dataset({"rao_fd": (("heading", "omega", "dof"), curves),
                     "rao_td": (("heading", "omega_td", "dof"), td)},
                    coords={"heading": list(headings), "omega": omegas, "omega_td": w_td,
                            "dof": list(RIGID_DOFS)},
                    attrs={"units": "m/m (Surge, Sway, Heave), rad/m (Roll, Pitch, Yaw)",
                           "omega_units": "rad/s", "heading_units": "deg"})
    return fig, ds


def rao_worst(points: Sequence[Mapping[str, Any]], heading: float, key: str
              ) -> dict[str, tuple[float, float] | None]:
    """Per DOF the largest ``key`` error (``relative_error_ss`` or ``relative_error``) and its
    period [s] at one heading, over the points where the DOF moves (> 1e-3 of the largest
    response of its unit); None where it does not."""
    out: dict[str, tuple[float, float] | None] = {}
    for d in RIGID_DOFS:
        group = ("Surge", "Sway", "Heave") if d in ("Surge", "Sway", "Heave") else (
            "Roll", "Pitch", "Yaw")
        errs = [(p[key][d], p["period"]) for p in points if p["heading_deg"] == heading
                and p["frequency_domain"][d] > 1e-3 * max(p["frequency_domain"][g]
                                                          for g in group)]
        out[d] = max(errs) if errs else None
    return out


def run_fowt_semi(out: Any, *, quick: bool = False, progress: bool = False,
                  hybrid: bool = True) -> str:
    """Write ``out/fowt_semi/`` (natural frequencies, decays, RAOs at three headings, the 6×6
    diagnostic in a 30° sea, the hybrid: ``hybrid.json``, ``hybrid_rollout.png/.nc`` and the
    model folder ``hybrid_model/``; JSON, PNG and the NetCDF behind each figure) and return
    the report section (Markdown). ``quick``: every other RAO period, 300 s seas;
    ``hybrid`` off: no hybrid (as :func:`hybridwsi.report.fowt.run_fowt`)."""
    start = time.time()

    def log(msg: str) -> None:
        if progress:
            print(f"[fowt_semi {time.time() - start:6.1f} s] {msg}", flush=True)

    def write_json(name: str, data: Any) -> None:
        atomic_write(folder / name, lambda tmp: Path(tmp).write_text(
            json.dumps(data, indent=2, default=float) + "\n"))

    folder = Path(out) / "fowt_semi"
    folder.mkdir(parents=True, exist_ok=True)
    case = load_case("oc4_semi")
    system = semi_system(case)
    refs = case.get("reference_natural_frequencies", {})
    decays = semi_decays(system)
    nat = {m.dominant_dof: {"hz": m.frequency, "from_decay_hz": decays[m.dominant_dof]["hz"],
                            "reference_hz": refs.get(m.dominant_dof.lower())}
           for m in semi_modes(system)}
    nat["variants"] = semi_mode_variants(system)
    write_json("natural_frequencies.json", nat)
    fig, ds = semi_decay_figure(decays)
    save(fig, folder / "decay.png")
    ds.to_netcdf(folder / "decay.nc")
    log("natural frequencies and decays")

    periods = SEMI_RAO_PERIODS[::2] if quick else SEMI_RAO_PERIODS
    points = semi_raos(system, periods, SEMI_RAO_HEADINGS, quick=quick)
    omegas = np.linspace(2 * math.pi / 32.0, 2 * math.pi / 4.5, 200)
    curves = semi_rao_curves(system, omegas, SEMI_RAO_HEADINGS)
    write_json("rao.json", {"dofs": list(RIGID_DOFS), "headings_deg": SEMI_RAO_HEADINGS,
                            "points": points})
    fig, ds = semi_rao_figure(points, omegas, curves, SEMI_RAO_HEADINGS)
    save(fig, folder / "rao.png")
    ds.to_netcdf(folder / "rao.nc")
    log("RAOs")

    hist = semi_sea_history(system, case, duration=300.0 if quick else 600.0)
    diag = semi_diagnostic(system, hist)
    write_json("diagnostic.json", diag)
    log("diagnostic")

    hybrid_md = ""
    if hybrid:
        hyb, (fig, ds) = run_semi_hybrid(system, case, folder, quick=quick, log=log)
        write_json("hybrid.json", _jsonable(hyb))
        save(fig, folder / "hybrid_rollout.png")
        ds.to_netcdf(folder / "hybrid_rollout.nc")
        hybrid_md = "\n" + semi_hybrid_markdown(hyb)
        log("hybrid")
    return semi_markdown(nat, points, diag, time.time() - start) + hybrid_md


def semi_markdown(nat: Mapping[str, Any], points: Sequence[Mapping[str, Any]],
                  diag: Mapping[str, Any], wall: float) -> str:
    """The report section of :func:`run_fowt_semi`."""
    lines = ["## Floating offshore wind: OC4-DeepCwind semi-submersible", "",
             "NREL 5-MW turbine on the OC4-DeepCwind semi (Robertson et al. 2014), six DOFs: "
             "shipped Capytaine coefficients of the columns and heave plates (0°, 30°, 60°), "
             "strip theory for pontoons and braces, MoorPy mooring, Borgman-linearised member "
             "drag (docs/OC4_SEMI.md). Files in `fowt_semi/`.", "",
             "| mode | eigen-analysis [Hz] | free decay [Hz] | reference [Hz] |",
             "|---|---|---|---|"]
    for d in ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"):
        v = nat[d]
        ref = f"{v['reference_hz']:.4f}" if v.get("reference_hz") else "–"
        lines.append(f"| {d} | {v['hz']:.5f} | {v['from_decay_hz']:.5f} | {ref} |")
    var = nat["variants"]
    lines += ["", f"Surge with A∞ instead of A(ω_n): {var['surge_coupled_A_inf']:.5f} Hz; pitch "
              f"with surge held: {var['pitch_alone']:.5f} Hz (docs/OC4_SEMI.md: why the coupled "
              "modes differ from the quoted references).", "",
              "RAOs, time-domain steady state against the frequency domain, worst over the "
              "periods per heading and DOF (DOFs the wave moves): of the same linear system "
              "(its radiation state space) / with the BEM's A(ω), B(ω):", "",
              "| heading | " + " | ".join(RIGID_DOFS) + " |", "|---" * 7 + "|"]
    for h in SEMI_RAO_HEADINGS:
        same, bem = rao_worst(points, h, "relative_error_ss"), rao_worst(points, h,
                                                                          "relative_error")
        cells = [("–" if same[d] is None else
                  f"{100 * same[d][0]:.3f} / {100 * bem[d][0]:.2f} %") for d in RIGID_DOFS]
        lines.append(f"| {h:g}° | " + " | ".join(cells) + " |")
    lines += ["", "![decays](fowt_semi/decay.png)", "", "![RAOs](fowt_semi/rao.png)", "",
              f"6×6 diagnostic in a 30° JONSWAP sea (Hs 4 m, Tp 11 s, "
              f"{diag['history']['duration_s']:.0f} s, Δt {diag['history']['dt']:g} s, nonlinear "
              f"mooring and member drag; ρ(M⁻¹A∞) = {diag['rho_M_inv_A_inf']:.3f}):", "",
              "| partition | left to the network | ρ((M+A_k)⁻¹α) | step-map ρ | verdict | "
              "identifiable DOFs at 1e-4 / 1e-2 | couplings at 1e-4 / 1e-2 | observed |",
              "|---|---|---|---|---|---|---|---|"]
    for r in diag["partitions"]:
        ident = [sum(v["per_dof"].values()) for v in r["identifiable"].values()]
        coup = [len(v) for v in r["couplings_identifiable"].values()]
        obs = r.get("observed")
        seen = "–" if obs is None else ("stable" if obs["observed_stable"] else "unstable")
        lines.append(f"| {r['partition']} | {r['left_to_network']} | "
                     f"{r['added_mass_ratio']:.4f} | {r['spectral_radius']:.5f} | "
                     f"{r['lagged_verdict']} | {ident[0]} / {ident[-1]} | "
                     f"{coup[0]} / {coup[-1]} of 15 | {seen} |")
    lines += ["", f"Section wall time {wall:.0f} s.", ""]
    return "\n".join(lines)
