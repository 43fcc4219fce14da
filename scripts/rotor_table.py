"""The NREL 5-MW rotor's steady operating curve and thrust derivatives, from CCBlade.

Writes ``src/hybridwsi/data/rotor_nrel5mw.nc``, the table that
:class:`hybridwsi.forces.rotor.OperatingRotor` reads (docs/OC3_HYWIND.md, "The rotor").
CCBlade ships inside WISDEM, which is too heavy for the core install, so this script runs in
the separate RAFT/WISDEM environment and the table it writes is shipped:

    PYTHONPATH=src nice -n 10 /work/venvs/raft/bin/python scripts/rotor_table.py

(``--quick``: coarse grids, for a look; ``--out PATH``: elsewhere.) About 6 minutes on a
shared 2-core machine.

The rotor (Jonkman, Butterfield, Musial & Scott 2009, "Definition of a 5-MW reference wind
turbine for offshore system development", NREL/TP-500-38060):

- blade: the 17 AeroDyn nodes of Table 2-1 (RNodes, AeroTwst, Chord, airfoil), hub radius
  1.5 m, tip radius 63 m, 3 blades, precone 2.5 deg, shaft tilt 5 deg (Table 1-1);
- airfoils: the DU/NACA64 polars of Appendix B (rotational augmentation and Viterna
  extrapolation already applied), as WISDEM ships them in
  ``examples/02_reference_turbines/nrel5mw.yaml`` (one Reynolds number);
- air: rho = 1.225 kg/m^3, kinematic viscosity 1.464e-5 m^2/s (AeroDyn input); uniform inflow
  (no shear: the hub-height wind is the rotor's wind), CCBlade with Prandtl tip and hub
  losses, wake rotation, drag in the induction (RAFT's settings), 4 azimuth sectors (the tilt
  makes them necessary; 8 or 16 change T and Q by < 3e-5).

The controller (Jonkman 2009 chapter 7, Table 7-2; the DISCON source of the same report):
generator torque on the high-speed shaft, gearbox ratio 97 (ideal gearbox, so the rotor
torque in steady state is 97 x the generator torque):

- region 1 (generator speed below 70.16224 rad/s = 6.9 rpm rotor): no torque;
- region 1 1/2 (up to 91.21091 rad/s): linear ramp to the region-2 law;
- region 2: K w^2, K = 2.332287 N m/(rad/s)^2 (optimal tip-speed ratio 7.55, zero pitch);
- region 2 1/2: the 10 %-slip induction-generator line up to 121.6805 rad/s;
- region 3: the blade-pitch PI control holds 122.9096 rad/s (12.1 rpm rotor) and the torque
  gives 5 296 610 W mechanical power (5 MW electric at 94.4 % generator efficiency).

So for each hub-height wind speed U the steady state is: pitch 0 and the rotor speed where the
aerodynamic torque equals 97 x the generator torque (regions 1-2 1/2), or, once that speed
would exceed 12.1 rpm, 12.1 rpm and the pitch where the aerodynamic power is 5 296 610 W
(region 3). Rated wind speed is where both hold at zero pitch. Outside 3-25 m/s (cut-in,
cut-out) the table continues the same laws (2-3 m/s: the rotor idles at its zero-torque
speed; 25-30 m/s: the pitch keeps rising), for turbulent excursions: shut-down is not modelled.

Derivatives: CCBlade's analytic dT/dU, dT/dOmega, dT/dpitch and the same for the torque Q at
every operating point. The slope along the operating curve (the controller moving rotor speed
or pitch with the wind, in steady state) follows from the torque balance by the implicit
function theorem:

- regions 1-2 1/2 (pitch fixed): dOmega/dU = -Q_U / (Q_Omega - 97^2 tau_g'(97 Omega));
- region 3 (speed fixed, torque 97 tau_rated): dpitch/dU = -Q_U / Q_pitch;
- dT/dU(operating) = T_U + T_Omega dOmega/dU + T_pitch dpitch/dU.

The script checks these against finite differences of the computed curve and prints the
comparison; nothing in the file is fitted or adjusted.

For the rotor-speed dynamics of the ``"pi"`` controller model the file also holds the thrust
and torque coefficients on a (tip-speed ratio, pitch) grid, 1-18 x -2-32 deg
(``thrust_coefficient_surface``, ``torque_coefficient_surface``; CCBlade at 10 m/s: with
uniform inflow and one Reynolds number per airfoil they do not depend on the wind speed), and
the DISCON torque-law constants as numeric attributes.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
import scipy.optimize
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from hybridwsi.files import to_netcdf  # noqa: E402
from hybridwsi.forces.controller import baseline_torque_law  # noqa: E402
from hybridwsi.cli import Parser  # noqa: E402

OUT = ROOT / "src" / "hybridwsi" / "data" / "rotor_nrel5mw.nc"

# Jonkman 2009 Table 2-1: AeroDyn blade nodes [m], twist [deg], chord [m], airfoil
R_NODES = [2.8667, 5.6000, 8.3333, 11.7500, 15.8500, 19.9500, 24.0500, 28.1500, 32.2500,
           36.3500, 40.4500, 44.5500, 48.6500, 52.7500, 56.1667, 58.9000, 61.6333]
TWIST = [13.308, 13.308, 13.308, 13.308, 11.480, 10.162, 9.011, 7.795, 6.544, 5.361, 4.188,
         3.125, 2.319, 1.526, 0.863, 0.370, 0.106]
CHORD = [3.542, 3.854, 4.167, 4.557, 4.652, 4.458, 4.249, 4.007, 3.748, 3.502, 3.256, 3.010,
         2.764, 2.518, 2.313, 2.086, 1.419]
AIRFOIL = ["Cylinder1", "Cylinder1", "Cylinder2", "DU40_A17", "DU35_A17", "DU35_A17",
           "DU30_A17", "DU25_A17", "DU25_A17", "DU21_A17", "DU21_A17"] + ["NACA64_A17"] * 6
ROTOR = dict(Rhub=1.5, Rtip=63.0, B=3, precone=2.5, tilt=5.0)   # m, m, -, deg, deg
RHO, KIN_VISC = 1.225, 1.464e-5                                  # kg/m^3, m^2/s
N_SECTOR = 4

# Jonkman 2009 Table 7-2 / DISCON: the torque law of hybridwsi.forces.controller (one code)
LAW = baseline_torque_law("constant_power")
GEARBOX = 97.0
VS_CTINSP, VS_RGN2SP, VS_RGN2K = LAW.cut_in_speed, LAW.region2_speed, LAW.k
VS_RTGNSP, PC_REFSPD, VS_RTPWR, VS_SLPC = (LAW.rated_speed, LAW.reference_speed,
                                           LAW.rated_power, LAW.slip_percent)
VS_TRGNSP = LAW.transition_speed
OMEGA_RATED = PC_REFSPD / GEARBOX                                # rad/s, rotor
RPM = 30.0 / math.pi                                             # rpm per rad/s
SOURCES = (
    "Blade and controller: J. Jonkman, S. Butterfield, W. Musial, G. Scott (2009), Definition "
    "of a 5-MW Reference Wind Turbine for Offshore System Development, NREL/TP-500-38060, "
    "Tables 1-1, 2-1, 7-2 and the DISCON controller source of the same report. Airfoil polars: "
    "its Appendix B, as shipped in WISDEM examples/02_reference_turbines/nrel5mw.yaml. "
    "Aerodynamics: CCBlade (S. A. Ning 2014, Wind Energy 17:1327-1345) inside WISDEM.")


def generator_torque(w_gen: float) -> float:
    """Steady generator torque [N m, high-speed shaft] at generator speed ``w_gen`` [rad/s]
    (the DISCON torque law at zero pitch; in steady region 3 the speed is at or above
    VS_RtGnSp)."""
    return float(LAW.torque(w_gen))


def generator_torque_slope(w_gen: float) -> float:
    """d(generator torque)/d(generator speed) [N m s/rad] of :func:`generator_torque`."""
    return float(LAW.slope(w_gen))


def region(w_gen: float, pitch: float) -> float:
    """Control region (1, 1.5, 2, 2.5 or 3) of a steady state."""
    if pitch > 0.0 or w_gen >= VS_RTGNSP:
        return 3.0
    if w_gen <= VS_CTINSP:
        return 1.0
    if w_gen < VS_RGN2SP:
        return 1.5
    return 2.0 if w_gen < VS_TRGNSP else 2.5


def build_rotor(derivatives: bool):
    """CCBlade of the NREL 5-MW rotor (module docstring)."""
    import wisdem
    from wisdem.ccblade.ccblade import CCAirfoil, CCBlade
    from wisdem.inputs.validation import load_geometry_yaml

    site = Path(wisdem.__file__).resolve().parents[1]
    yaml = site / "examples" / "02_reference_turbines" / "nrel5mw.yaml"
    polars = {}
    for foil in load_geometry_yaml(str(yaml))["airfoils"]:
        p = foil["polars"][0]["re_sets"][0]
        polars[foil["name"]] = CCAirfoil(p["cl"]["grid"], [p["re"]], p["cl"]["values"],
                                        p["cd"]["values"], p["cm"]["values"])
    af = [polars[name] for name in AIRFOIL]
    return CCBlade(R_NODES, CHORD, TWIST, af, ROTOR["Rhub"], ROTOR["Rtip"], ROTOR["B"], RHO,
                   RHO * KIN_VISC, ROTOR["precone"], ROTOR["tilt"], 0.0, 0.0, 90.0, N_SECTOR,
                   derivatives=derivatives), str(yaml)


class Rotor:
    """Thrust T [N] and torque Q [N m] of CCBlade at (U [m/s], Omega [rad/s], pitch [rad])."""

    def __init__(self) -> None:
        self.plain, self.yaml = build_rotor(False)
        self.full, _ = build_rotor(True)
        self.calls = 0

    def loads(self, u: float, omega: float, pitch: float) -> tuple[float, float]:
        self.calls += 1
        out, _ = self.plain.evaluate([u], [omega * RPM], [math.degrees(pitch)])
        return float(out["T"][0]), float(out["Q"][0])

    def derivatives(self, u: float, omega: float, pitch: float) -> dict[str, float]:
        """Loads and their partial derivatives per m/s, per rad/s, per rad."""
        out, der = self.full.evaluate([u], [omega * RPM], [math.degrees(pitch)])
        area = math.pi * (ROTOR["Rtip"] * math.cos(math.radians(ROTOR["precone"]))) ** 2
        d = {"T": float(out["T"][0]), "Q": float(out["Q"][0]), "P": float(out["P"][0])}
        d["CT"] = d["T"] / (0.5 * RHO * area * u ** 2)
        for q in ("T", "Q"):
            dq = der["d" + q]
            d[q + "_U"] = float(np.diag(dq["dUinf"])[0])
            d[q + "_Omega"] = float(np.diag(dq["dOmega"])[0]) * RPM
            d[q + "_pitch"] = float(np.diag(dq["dpitch"])[0]) * math.degrees(1.0)
        return d


def torque_balance(rotor: Rotor, u: float, omega: float) -> float:
    """Aerodynamic minus generator torque on the rotor [N m] at zero pitch."""
    return rotor.loads(u, omega, 0.0)[1] - GEARBOX * generator_torque(GEARBOX * omega)


def steady_state(rotor: Rotor, u: float) -> tuple[float, float]:
    """(rotor speed [rad/s], pitch [rad]) of the controller's steady state at wind speed u."""
    if torque_balance(rotor, u, OMEGA_RATED) < 0.0:  # below rated: speed balances the torque
        omega = scipy.optimize.brentq(lambda w: torque_balance(rotor, u, w), 0.05, OMEGA_RATED,
                                      xtol=1e-12, rtol=1e-13)
        return omega, 0.0
    q_rated = GEARBOX * generator_torque(PC_REFSPD)
    pitch = scipy.optimize.brentq(lambda p: rotor.loads(u, OMEGA_RATED, p)[1] - q_rated, 0.0,
                                  math.radians(40.0), xtol=1e-12, rtol=1e-13)
    return OMEGA_RATED, pitch


def rated_wind_speed(rotor: Rotor) -> float:
    """Wind speed [m/s] at which 12.1 rpm balances the torque at zero pitch."""
    return scipy.optimize.brentq(lambda u: torque_balance(rotor, u, OMEGA_RATED), 10.0, 13.0,
                                 xtol=1e-10, rtol=1e-13)


def operating_slopes(d: dict[str, float], omega: float, pitch: float, above: bool
                     ) -> tuple[float, float, float]:
    """(dOmega/dU [rad/m], dpitch/dU [rad s/m], dT/dU [N s/m]) along the operating curve."""
    if above:
        d_omega, d_pitch = 0.0, -d["Q_U"] / d["Q_pitch"]
    else:
        slope_gen = GEARBOX ** 2 * generator_torque_slope(GEARBOX * omega)
        d_omega, d_pitch = -d["Q_U"] / (d["Q_Omega"] - slope_gen), 0.0
    return d_omega, d_pitch, d["T_U"] + d["T_Omega"] * d_omega + d["T_pitch"] * d_pitch


def operating_curve(rotor: Rotor, speeds: np.ndarray, u_rated: float) -> xr.Dataset:
    """The table over ``speeds`` [m/s] (module docstring for the variables)."""
    rows = []
    t0 = time.time()
    for k, u in enumerate(speeds):
        omega, pitch = steady_state(rotor, float(u))
        at_rated = abs(u - u_rated) < 1e-9
        if at_rated:  # the kink: 12.1 rpm, zero pitch, and the region-3 side's slopes
            omega, pitch = OMEGA_RATED, 0.0
        d = rotor.derivatives(float(u), omega, pitch)
        above = pitch > 0.0 or at_rated
        d_omega, d_pitch, slope = operating_slopes(d, omega, pitch, above)
        rows.append(dict(d, omega=omega, pitch=pitch, d_omega=d_omega, d_pitch=d_pitch,
                         slope=slope, region=region(GEARBOX * omega, pitch)))
        if k % 20 == 0:
            print(f"  U {u:5.2f} m/s: {omega * RPM:6.3f} rpm, pitch {math.degrees(pitch):6.3f} "
                  f"deg, T {d['T'] / 1e3:7.2f} kN, dT/dU {slope / 1e3:8.3f} kN/(m/s) "
                  f"[{time.time() - t0:.0f} s, {rotor.calls} CCBlade calls]", flush=True)
    col = {key: np.array([r[key] for r in rows]) for key in rows[0]}
    return _dataset(speeds, col, u_rated)


def _dataset(speeds: np.ndarray, col: dict[str, np.ndarray], u_rated: float) -> xr.Dataset:
    """Variables with units and meanings (the file's schema)."""
    dim = ("wind_speed",)
    var = {
        "rotor_speed": (col["omega"], "rad/s", "steady rotor speed"),
        "blade_pitch": (col["pitch"], "rad", "steady collective blade pitch"),
        "thrust": (col["T"], "N", "aerodynamic rotor thrust along the shaft (no rotor weight)"),
        "torque": (col["Q"], "N m", "aerodynamic rotor torque about the shaft"),
        "power": (col["P"], "W", "aerodynamic rotor power"),
        "thrust_coefficient": (col["CT"], "1", "T / (0.5 rho pi R^2 U^2), R = Rtip cos(precone)"),
        "dT_dU_frozen": (col["T_U"], "N s/m", "dT/dU at fixed rotor speed and pitch"),
        "dT_dOmega": (col["T_Omega"], "N s/rad", "dT/d(rotor speed) at fixed U and pitch"),
        "dT_dpitch": (col["T_pitch"], "N/rad", "dT/d(pitch) at fixed U and rotor speed"),
        "dQ_dU": (col["Q_U"], "N s", "dQ/dU at fixed rotor speed and pitch"),
        "dQ_dOmega": (col["Q_Omega"], "N m s/rad", "dQ/d(rotor speed) at fixed U and pitch"),
        "dQ_dpitch": (col["Q_pitch"], "N m/rad", "dQ/d(pitch) at fixed U and rotor speed"),
        "dOmega_dU": (col["d_omega"], "rad/m", "rotor speed slope of the operating curve"),
        "dpitch_dU": (col["d_pitch"], "rad s/m", "pitch slope of the operating curve"),
        "dT_dU": (col["slope"], "N s/m",
                  "dT/dU along the operating curve (the controller in steady state)"),
        "region": (col["region"], "1", "control region 1, 1.5, 2, 2.5 or 3"),
    }
    ds = xr.Dataset({k: (dim, v, {"units": u, "long_name": n}) for k, (v, u, n) in var.items()},
                    coords={"wind_speed": ("wind_speed", speeds,
                                           {"units": "m/s", "long_name": "hub-height wind speed"})})
    ds.attrs.update(rated_wind_speed=u_rated, cut_in_wind_speed=3.0, cut_out_wind_speed=25.0,
                    rated_rotor_speed=OMEGA_RATED, rated_mechanical_power=VS_RTPWR,
                    gearbox_ratio=GEARBOX, rotor_radius=ROTOR["Rtip"],
                    rotor_area_radius=ROTOR["Rtip"] * math.cos(math.radians(ROTOR["precone"])),
                    shaft_tilt_deg=ROTOR["tilt"], precone_deg=ROTOR["precone"], air_density=RHO)
    return ds


#: grids of the coefficient surfaces: tip-speed ratio Omega Rtip / U [-] and pitch [deg]
TSR_GRID = np.round(np.arange(1.0, 18.0 + 1e-9, 0.25), 10)
PITCH_GRID = np.round(np.arange(-2.0, 32.0 + 1e-9, 0.5), 10)
U_REF = 10.0  # m/s: the coefficients do not depend on it (uniform inflow, one Reynolds number)


def coefficient_surfaces(rotor: Rotor, quick: bool) -> xr.Dataset:
    """CT(tsr, pitch) = T/(0.5 rho A U^2) and CQ = Q/(0.5 rho A R U^2) (A = pi R^2,
    R = Rtip cos(precone)) on a grid, for the rotor-speed dynamics of the "pi" controller."""
    tsr, pitch = (TSR_GRID[::4], PITCH_GRID[::4]) if quick else (TSR_GRID, PITCH_GRID)
    r_area = ROTOR["Rtip"] * math.cos(math.radians(ROTOR["precone"]))
    q = 0.5 * RHO * math.pi * r_area**2 * U_REF**2
    ct = np.empty((tsr.size, pitch.size))
    cq = np.empty_like(ct)
    t0 = time.time()
    for i, lam in enumerate(tsr):
        omega = lam * U_REF / ROTOR["Rtip"]
        for j, p in enumerate(pitch):
            t, qq = rotor.loads(U_REF, omega, math.radians(p))
            ct[i, j], cq[i, j] = t / q, qq / (q * r_area)
        if i % 10 == 0:
            print(f"  surfaces: tsr {lam:5.2f} [{time.time() - t0:.0f} s]", flush=True)
    if not (np.all(np.isfinite(ct)) and np.all(np.isfinite(cq))):
        raise RuntimeError("CCBlade returned non-finite coefficients on the surface grid")
    dims = ("tsr", "pitch")
    return xr.Dataset(
        {"thrust_coefficient_surface": (dims, ct, {"units": "1", "long_name":
                                                   "T / (0.5 rho pi R^2 U^2), R = Rtip cos(precone)"}),
         "torque_coefficient_surface": (dims, cq, {"units": "1", "long_name":
                                                   "Q / (0.5 rho pi R^3 U^2)"})},
        coords={"tsr": ("tsr", tsr, {"units": "1", "long_name": "Omega Rtip / U"}),
                "pitch": ("pitch", np.radians(pitch), {"units": "rad",
                                                       "long_name": "collective blade pitch"})})


def check_slopes(ds: xr.Dataset) -> float:
    """Largest relative difference between the analytic operating-curve slope and central
    finite differences of the computed thrust, away from the rated kink (printed)."""
    u, t = ds["wind_speed"].values, ds["thrust"].values
    fd = (t[2:] - t[:-2]) / (u[2:] - u[:-2])
    mid = u[1:-1]
    keep = np.abs(mid - ds.attrs["rated_wind_speed"]) > 0.25
    reg = ds["region"].values
    same = (reg[2:] == reg[:-2]) & (reg[2:] == reg[1:-1])
    keep &= same
    an = ds["dT_dU"].values[1:-1]
    err = np.abs(fd - an)[keep] / np.abs(ds["dT_dU_frozen"].values[1:-1][keep])
    print(f"operating-curve slope vs central differences of T (same region, >0.25 m/s from "
          f"rated): largest difference {err.max():.2e} of dT/dU(frozen)")
    return float(err.max())


def provenance(ds: xr.Dataset, rotor: Rotor, args: argparse.Namespace, seconds: float) -> None:
    """Inputs, versions, sources and the command as attributes (files carry their inputs)."""
    import tomllib
    from importlib.metadata import version

    hyb = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    ds.attrs.update(
        title="NREL 5-MW steady operating curve and thrust derivatives (CCBlade)",
        sources=SOURCES, hybridwsi_version=hyb, wisdem_version=version("wisdem"),
        numpy_version=np.__version__, scipy_version=scipy.__version__,
        command="PYTHONPATH=src python scripts/rotor_table.py"
                + (" --quick" if args.quick else ""),
        airfoil_file=os.path.relpath(rotor.yaml, Path(rotor.yaml).parents[3]),
        blade_r_m=R_NODES, blade_twist_deg=TWIST, blade_chord_m=CHORD,
        blade_airfoil=",".join(AIRFOIL), hub_radius=ROTOR["Rhub"], n_blades=ROTOR["B"],
        kinematic_viscosity=KIN_VISC, shear_exponent=0.0, n_sector=N_SECTOR,
        ccblade_options="tiploss, hubloss, wakerotation, usecd",
        controller=("DISCON torque law (regions 1, 1.5, 2, 2.5, 3 constant power) and PI "
                    "pitch to 12.1 rpm, steady state; gains do not enter the steady curve"),
        VS_CtInSp=VS_CTINSP, VS_Rgn2Sp=VS_RGN2SP, VS_Rgn2K=VS_RGN2K, VS_RtGnSp=VS_RTGNSP,
        PC_RefSpd=PC_REFSPD, VS_RtPwr=VS_RTPWR, VS_SlPc=VS_SLPC, VS_Rgn3MP=LAW.region3_pitch,
        generator_torque_units="rad/s, N m/(rad/s)^2, W, % (generator side, DISCON names)",
        wall_time_s=round(seconds, 1))


def main(argv: list[str] | None = None) -> int:
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--quick", action="store_true", help="1 m/s steps (a look, not shipped)")
    args = ap.parse_args(argv)
    t0 = time.time()
    rotor = Rotor()
    u_rated = rated_wind_speed(rotor)
    print(f"rated wind speed {u_rated:.4f} m/s (Jonkman 2009: 11.4 m/s)")
    step = 1.0 if args.quick else 0.1
    speeds = np.round(np.arange(2.0, 30.0 + step / 2, step), 10)
    speeds = np.unique(np.append(speeds, u_rated))
    ds = operating_curve(rotor, speeds, u_rated)
    check_slopes(ds)
    ds = xr.merge([ds, coefficient_surfaces(rotor, args.quick)], combine_attrs="override")
    provenance(ds, rotor, args, time.time() - t0)
    to_netcdf(ds, args.out)
    for u in (8.0, u_rated, 18.0):
        row = ds.interp(wind_speed=u)
        print(f"U {u:7.4f}: T {float(row.thrust) / 1e3:8.2f} kN, {float(row.rotor_speed) * RPM:.3f}"
              f" rpm, pitch {math.degrees(float(row.blade_pitch)):.3f} deg, dT/dU "
              f"{float(row.dT_dU) / 1e3:.2f} (frozen {float(row.dT_dU_frozen) / 1e3:.2f}) kN s/m")
    print(f"wrote {args.out} ({len(speeds)} wind speeds, {time.time() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    from hybridwsi.cli import run_script

    run_script(main)
