"""The numbers and the figure of docs/OC3_HYWIND.md "The rotor" (hybridwsi's own environment).

    PYTHONPATH=src nice -n 10 python scripts/rotor_docs.py

Writes ``docs/figures/rotor_nrel5mw.png`` and ``.nc`` (the shipped operating curve against the
published one) and prints the Markdown tables: mean thrust against the published values, the
mean offsets (linearised and with the tabulated MoorPy mooring) beside RAFT's
(``docs/figures/raft_oc3_rotor.json``, ``scripts/raft_oc3.py``), and the damping ratios of
the surge and pitch free decays, parked and operating, predicted (complex modes of the linear
model with dT/dU j jᵀ added) and observed (the decays, fitted). About a minute.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import scipy.optimize  # noqa: E402
import xarray as xr  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from hybridwsi.cases import load_case  # noqa: E402
from hybridwsi.cummins import simulate  # noqa: E402
from hybridwsi.cummins.system import build_system  # noqa: E402
from hybridwsi.dofs import index  # noqa: E402
from hybridwsi.files import to_netcdf  # noqa: E402
from hybridwsi.forces import (  # noqa: E402
    Hydrostatic,
    MooringForce,
    OperatingRotor,
    PIControlledRotor,
    RotorTable,
    additional_damping,
)
from hybridwsi.forces.controller import PI_GAINS, PitchPI, baseline_torque_law  # noqa: E402
from hybridwsi.hydro import coefficients as co  # noqa: E402
from hybridwsi.hydro.modal import damped_modes, decay_modes  # noqa: E402
from hybridwsi.report.fowt import oc3_coefficients  # noqa: E402
from hybridwsi.wind import SteadyWind  # noqa: E402

FIG = ROOT / "docs" / "figures" / "rotor_nrel5mw"
RAFT = ROOT / "docs" / "figures" / "raft_oc3_rotor.json"
TILT = math.radians(5.0)
HUB = (-5.0, 0.0, 90.0)
WEIGHT = 110000.0 * 9.80665 * math.sin(TILT)  # N: rotor weight along the tilted shaft
# NREL turbine-models Offshore/NREL_5MW_126_RWT.csv (FAST steady states of Jonkman 2009)
PUBLISHED = {3.0: 171.7, 4.0: 215.9, 5.0: 268.9, 6.0: 330.3, 7.0: 398.6, 8.0: 478.0, 9.0: 579.2,
             10.0: 691.496, 11.0: 790.615, 11.3: 819.271, 11.4: 805.112, 12.0: 689.957,
             13.0: 608.4, 14.0: 557.9, 15.0: 520.5, 16.0: 491.2, 17.0: 467.7, 18.0: 448.4,
             19.0: 432.3, 20.0: 418.8, 21.0: 406.7, 22.0: 395.3, 23.0: 385.1, 24.0: 376.7,
             25.0: 369.3}
PITCH_T71 = {11.4: 0.0, 12: 3.83, 13: 6.60, 14: 8.70, 15: 10.45, 16: 12.06, 17: 13.54,
             18: 14.92, 19: 16.23, 20: 17.47, 21: 18.70, 22: 19.94, 23: 21.18, 24: 22.35,
             25: 23.47}  # Jonkman 2009 Table 7-1 [deg]
DOFS3 = ["Surge", "Heave", "Pitch"]
OMEGA_SURGE, OMEGA_PITCH = 0.0507, 0.212  # rad/s, OC3 natural frequencies


def figure(table: RotorTable) -> None:
    ds = table.data.sel(wind_speed=slice(3.0, 25.0))
    u = ds["wind_speed"].values
    fig, ax = plt.subplots(3, 1, figsize=(7.5, 9), sharex=True)
    ax[0].plot(u, ds["thrust"] / 1e3, label="CCBlade thrust (shipped table)")
    ax[0].plot(u, (ds["thrust"] + WEIGHT) / 1e3, "--", label="+ rotor weight along shaft (94 kN)")
    ax[0].plot(list(PUBLISHED), list(PUBLISHED.values()), "ko", ms=4,
               label="published (FAST, NREL turbine-models)")
    ax[0].set_ylabel("thrust [kN]")
    ax[1].plot(u, ds["dT_dU"] / 1e3, label="dT/dU along the operating curve")
    ax[1].plot(u, ds["dT_dU_frozen"] / 1e3, label="∂T/∂U at fixed speed and pitch")
    ax[1].axhline(0.0, color="k", lw=0.5)
    ax[1].set_ylim(-300, 200)
    ax[1].set_ylabel("thrust slope [kN s/m]")
    ax[2].plot(u, np.degrees(ds["blade_pitch"]), label="pitch (table)")
    ax[2].plot(list(PITCH_T71), list(PITCH_T71.values()), "ko", ms=4,
               label="pitch, Jonkman 2009 Table 7-1")
    ax2 = ax[2].twinx()
    ax2.plot(u, ds["rotor_speed"] * 30 / math.pi, "C1", label="rotor speed")
    ax2.set_ylabel("rotor speed [rpm]", color="C1")
    ax[2].set_ylabel("blade pitch [deg]")
    ax[2].set_xlabel("hub-height wind speed U [m/s]")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=8, loc="best")
    fig.suptitle("NREL 5-MW steady operating curve (CCBlade + baseline controller)")
    fig.tight_layout()
    fig.savefig(FIG.with_suffix(".png"), dpi=110)
    data = ds[["thrust", "dT_dU", "dT_dU_frozen", "blade_pitch", "rotor_speed"]].copy()
    data["published_thrust"] = xr.DataArray(
        np.array(list(PUBLISHED.values())) * 1e3, dims="published_wind_speed",
        coords={"published_wind_speed": list(PUBLISHED)},
        attrs={"units": "N", "source": "NREL turbine-models Offshore/NREL_5MW_126_RWT.csv"})
    data.attrs.update(rotor_weight_along_shaft_N=WEIGHT, command="python scripts/rotor_docs.py")
    to_netcdf(data, FIG.with_suffix(".nc"))


def thrust_rows(table: RotorTable) -> None:
    print("| U [m/s] | CCBlade T [kN] | + weight [kN] | published [kN] | difference |")
    print("|---|---|---|---|---|")
    for u in (8.0, 11.4, 18.0, 3.0):
        t = float(table.thrust(u)) / 1e3
        print(f"| {u:g} | {t:.1f} | {t + WEIGHT / 1e3:.1f} | {PUBLISHED[u]:.1f} | "
              f"{(t + WEIGHT / 1e3) / PUBLISHED[u] - 1:+.1%} |")


def offsets(case, coeffs, table) -> dict[float, tuple]:
    """Mean (surge, heave, pitch): linearised mooring (Eq. 5-3 K) and tabulated MoorPy."""
    idx = index(DOFS3)
    k = np.asarray(case["mooring"]["reference"]["K"])[np.ix_(idx, idx)]
    c = co.matrix(coeffs, "hydrostatic_stiffness", DOFS3)
    mooring = MooringForce.from_case(case, DOFS3)
    out = {}
    for u in (8.0, 11.4, 18.0):
        f = OperatingRotor(table, SteadyWind(u), HUB, DOFS3, shaft_tilt=TILT).mean_force()
        lin = np.linalg.solve(c + k, f)
        nonlin = scipy.optimize.fsolve(
            lambda q: mooring.ode_force(0.0, q, np.zeros(3), None) - c @ q + f, lin, xtol=1e-12)
        out[u] = (lin, nonlin)
    return out


def offset_rows(off: dict, raft: dict) -> None:
    print("| U [m/s] | surge lin. / MoorPy table / RAFT [m] | pitch lin. / MoorPy table / RAFT "
          "[deg] |")
    print("|---|---|---|")
    for u, (lin, non) in off.items():
        r = raft["results"]["no_control"][f"{u:g}"]
        print(f"| {u:g} | {lin[0]:.2f} / {non[0]:.2f} / {r['surge_m']:.2f} | "
              f"{math.degrees(lin[2]):.2f} / {math.degrees(non[2]):.2f} / "
              f"{math.degrees(r['pitch_rad']):.2f} |")


def pi_rotor(table: RotorTable, u: float, gains: str, filter_hz: float = 0.25,
             dofs: list[str] = DOFS3) -> PIControlledRotor:
    return PIControlledRotor(table, SteadyWind(u), HUB, dofs,
                             pitch_control=PitchPI(*PI_GAINS[gains]),
                             torque_law=baseline_torque_law("constant_torque"),
                             drivetrain_inertia=40469564.0, filter_hz=filter_hz,
                             shaft_tilt=TILT)


def pi_damping_rows(table: RotorTable, raft: dict) -> None:
    """dT/dU(ω) of our PI model (Re of the transfer) beside RAFT's aeroServoMod 2."""
    print("| U [m/s] | gains | ours, filter 0.25 Hz: ω_surge / ω_pitch | ours, no filter | "
          "RAFT |")
    print("|---|---|---|---|---|")
    for u in (8.0, 11.4, 18.0):
        for gains in ("baseline", "oc3_detuned"):
            vals = []
            for f in (0.25, 1e3):
                h = pi_rotor(table, u, gains, f).transfer([OMEGA_SURGE, OMEGA_PITCH])[:, 0].real
                vals.append(f"{h[0] / 1e3:.1f} / {h[1] / 1e3:.1f}")
            r = raft["results"][f"pi_{gains}"][f"{u:g}"]
            print(f"| {u:g} | {gains} | {vals[0]} | {vals[1]} | {r['B11_at_surge'] / 1e3:.1f} / "
                  f"{r['B11_at_pitch'] / 1e3:.1f} |")


def damping_rows(table: RotorTable, raft: dict) -> None:
    print("| U [m/s] | ours dT/dU (quasi-steady) | RAFT no control | RAFT PI ω→0 | RAFT PI "
          "(baseline) at ω_surge / ω_pitch | RAFT PI (OC3 detuned) at ω_surge / ω_pitch |")
    print("|---|---|---|---|---|---|")
    res = raft["results"]
    for u in (8.0, 11.4, 18.0):
        k = f"{u:g}"
        b, d, n = res["pi_baseline"][k], res["pi_oc3_detuned"][k], res["no_control"][k]
        print(f"| {u:g} | {float(table.thrust_slope(u)) / 1e3:.1f} "
              f"(frozen {float(table.value('dT_dU_frozen', u)) / 1e3:.1f}) | "
              f"{n['B11_at_surge'] / 1e3:.1f} | {b['B11_low_frequency'] / 1e3:.1f} | "
              f"{b['B11_at_surge'] / 1e3:.1f} / {b['B11_at_pitch'] / 1e3:.1f} | "
              f"{d['B11_at_surge'] / 1e3:.1f} / {d['B11_at_pitch'] / 1e3:.1f} |")


def _predicted(coeffs, k, b_add, rotor) -> dict[str, float]:
    """ζ per mode of the linear model: dT/dU j jᵀ added (quasi-steady), or the PI rotor's
    linearised states joined to the platform's (complex modes, A and B at each mode)."""
    if isinstance(rotor, PIControlledRotor):
        modes = damped_modes(coeffs, k, b_add, DOFS3, state_force=rotor.state_space(3))
    else:
        b = rotor.linear_coefficients(3)[1] if rotor is not None else 0.0 * b_add
        modes = damped_modes(coeffs, k, b_add + b, DOFS3)
    return {m.dominant_dof: m.zeta for m in modes}


def _observed(case, coeffs, k, ss, rotor, dof: str) -> float:
    """ζ of the released mode fitted to a free decay (a real exponential more for the PI
    rotor: its speed and filter modes)."""
    c = co.matrix(coeffs, "hydrostatic_stiffness", DOFS3) + k
    z_eq = np.linalg.solve(c, rotor.mean_force()) if rotor is not None else np.zeros(3)
    kick, dur, om = {"Surge": ([5.0, 0, 0], 900.0, [OMEGA_SURGE, OMEGA_PITCH]),
                     "Pitch": ([0, 0, 0.02], 300.0, [OMEGA_PITCH, OMEGA_SURGE])}[dof]
    comps = [Hydrostatic(k), additional_damping(case, DOFS3)] + ([rotor] if rotor else [])
    try:
        h = simulate(coeffs, dofs=DOFS3, duration=dur, dt=0.25, z0=z_eq + kick, forces=comps,
                     radiation_ss=ss)
        y = h["z"].sel(dof=dof).values - z_eq[DOFS3.index(dof)]
        return decay_modes(h["time"].values, y, om,
                           aperiodic=2 * int(isinstance(rotor, PIControlledRotor)))[0][0]
    except Exception as exc:  # grew out of the table, or no longer a damped oscillation
        print(f"<!-- {dof}: {exc} -->")
        return float("nan")


def decay_rows(case, coeffs, table) -> None:
    idx = index(DOFS3)
    k = np.asarray(case["mooring"]["reference"]["K"])[np.ix_(idx, idx)]
    ss = build_system(coeffs, dofs=DOFS3, radiation="statespace", dt=0.25).ss
    b_add = additional_damping(case, DOFS3).linear_coefficients(3)[1]
    parked = {d: (_predicted(coeffs, k, b_add, None)[d], _observed(case, coeffs, k, ss, None, d))
              for d in ("Surge", "Pitch")}
    print("| U [m/s] | rotor | mode | ζ pred. / obs. | Δζ vs parked pred. / obs. |")
    print("|---|---|---|---|---|")
    for d in ("Surge", "Pitch"):
        print(f"| – | parked | {d.lower()} | {parked[d][0]:.4f} / {parked[d][1]:.4f} | |")
    for u in (8.0, 11.4, 18.0):
        for label, rotor in (("quasi-steady", OperatingRotor(table, SteadyWind(u), HUB, DOFS3,
                                                             shaft_tilt=TILT)),
                             ("PI OC3 detuned", pi_rotor(table, u, "oc3_detuned"))):
            pred = _predicted(coeffs, k, b_add, rotor)
            for d in ("Surge", "Pitch"):
                obs = _observed(case, coeffs, k, ss, rotor, d)
                print(f"| {u:g} | {label} | {d.lower()} | {pred[d]:.4f} / {obs:.4f} | "
                      f"{pred[d] - parked[d][0]:+.4f} / {obs - parked[d][1]:+.4f} |")


def main() -> int:
    case = load_case("oc3_hywind")
    coeffs = oc3_coefficients(case)
    table = RotorTable.nrel_5mw()
    raft = json.loads(RAFT.read_text())
    figure(table)
    thrust_rows(table)
    print()
    offset_rows(offsets(case, coeffs, table), raft)
    print()
    damping_rows(table, raft)
    print()
    pi_damping_rows(table, raft)
    print()
    decay_rows(case, coeffs, table)
    return 0


if __name__ == "__main__":
    from hybridwsi.cli import run_script

    run_script(main)
