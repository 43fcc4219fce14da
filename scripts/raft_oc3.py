"""RAFT (openraft 2.0.4) on OC3-Hywind with the NREL 5-MW rotor: mean offsets and aerodynamic
damping, for the side-by-side comparison in docs/OC3_HYWIND.md ("The rotor").

RAFT is a frequency-domain code with its own CCBlade rotor model, so it runs in the separate
RAFT/WISDEM environment and this script ships its numbers as a small JSON:

    PYTHONPATH=src nice -n 10 /work/venvs/raft/bin/python scripts/raft_oc3.py

(writes ``docs/figures/raft_oc3_rotor.json``; about a minute). The design is built from the
same sources as hybridwsi's case, not copied from RAFT's example:

- the rotor: the blade of ``scripts/rotor_table.py`` (Jonkman 2009 Table 2-1, the airfoils of
  WISDEM's nrel5mw.yaml), plus a point at the 63 m tip with the last node's chord and twist
  (AeroDyn's outermost element ends at the tip; RAFT's elements end at the last point); the
  operating schedule (rotor speed, pitch) of the shipped table ``rotor_nrel5mw.nc``; uniform
  inflow, 1.225 kg/m^3; tilt 5 deg, precone 2.5 deg, overhang 5 m, hub 90 m;
- the controller for ``aeroServoMod = 2``: the collective-pitch PI gains of Jonkman 2009
  Table 7-2 (baseline) or of the OC3-Hywind DISCON (detuned: KP 0.006275604 s,
  KI 0.0008965149; Jonkman 2010 NREL/TP-500-47535 section 7.2), both on generator speed,
  converted to rotor speed (x 97) and gain-scheduled 1/(1 + pitch/6.302336 deg); drivetrain
  inertia 35 444 067 + 97^2 x 534.116 kg m^2 (Jonkman 2009 Tables 1-1, 5-1). Below rated
  RAFT takes the generator torque as a PI law; the baseline's K w^2 is its proportional gain
  dQ_gen/dOmega = 2 K 97^3 Omega at each wind speed's rotor speed (one RAFT model per wind
  speed). Above rated RAFT zeroes the torque gains: a constant-torque region 3, the
  OC3-Hywind choice;
- the platform: the OC3 spar profile of ``cases/oc3_hywind.toml`` (9.4 m below 12 m depth,
  taper, 6.5 m above; draft 120 m), shell 0.027 m of 8500 kg/m^3 as RAFT's OC3 example, and a
  ballast (length and density) solved so that the platform's mass and CM are the case's
  (7 466 330 kg at -89.9155 m); the tower 10-87.6 m, 6.5 -> 3.87 m diameter, 0.027 -> 0.019 m
  wall, 8500 kg/m^3 (the OC3 definition's tower); RNA 350 000 kg;
- the mooring: the case's three lines (MoorPy in RAFT) and the 9.834e7 N m/rad yaw spring;
- still water, strip-theory hydrodynamics (no BEM: the offsets need only the statics, the
  damping is the rotor's own).

For each wind speed RAFT's ``solveStatics`` gives the mean offsets; its rotor's ``calcAero``
the mean aerodynamic load and the aerodynamic damping matrix B(omega) (about the platform
reference point), read at the OC3 surge (0.0507 rad/s) and pitch (0.212 rad/s) natural
frequencies. aeroServoMod 1 is RAFT without control (the frozen slope dT/dU at fixed rotor
speed and pitch); 2 with the PI controller.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import sys
import time
import tomllib
from importlib.metadata import version
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
sys.path.insert(0, str(ROOT / "src"))

import rotor_table as rt  # noqa: E402  (the blade and controller constants)

from hybridwsi.files import write_json  # noqa: E402
from hybridwsi.cli import Parser  # noqa: E402

OUT = ROOT / "docs" / "figures" / "raft_oc3_rotor.json"
CASE = ROOT / "src" / "hybridwsi" / "cases" / "oc3_hywind.toml"
TABLE = ROOT / "src" / "hybridwsi" / "data" / "rotor_nrel5mw.nc"
WIND_SPEEDS = (8.0, 11.4, 18.0)
OMEGA = {"surge": 0.0507, "pitch": 0.212}  # rad/s, OC3 natural frequencies (docs)
PI_GAINS = {"baseline": (0.01882681, 0.008068634), "oc3_detuned": (0.006275604, 0.0008965149)}
THETA_K = math.radians(6.302336)           # rad, gain-scheduling pitch (Jonkman 2009 Table 7-2)
I_DRIVETRAIN = 35444067.0 + rt.GEARBOX**2 * 534.116  # kg m^2, rotor side


def airfoils() -> list[dict]:
    """RAFT airfoil entries (alpha [deg], cl, cd, cm) from WISDEM's nrel5mw.yaml."""
    import wisdem
    from wisdem.inputs.validation import load_geometry_yaml

    yaml = Path(wisdem.__file__).resolve().parents[1] / "examples/02_reference_turbines/nrel5mw.yaml"
    out = []
    for foil in load_geometry_yaml(str(yaml))["airfoils"]:
        if foil["name"] not in rt.AIRFOIL:
            continue
        p = foil["polars"][0]["re_sets"][0]
        rows = np.column_stack([p["cl"]["grid"], p["cl"]["values"], p["cd"]["values"],
                                p["cm"]["values"]])
        out.append({"name": foil["name"], "relative_thickness": float(foil["rthick"]),
                    "data": rows.tolist()})
    return out


def schedule() -> dict:
    """RAFT's ``wt_ops`` from the shipped table: wind speed, pitch [deg], rotor speed [rpm]."""
    import xarray as xr

    with xr.open_dataset(TABLE) as ds:
        sel = ds.sel(wind_speed=slice(3.0, 25.0))
        return {"v": sel["wind_speed"].values.tolist(),
                "pitch_op": np.degrees(sel["blade_pitch"].values).tolist(),
                "omega_op": (sel["rotor_speed"].values * rt.RPM).tolist()}


def pitch_control(kp_gen: float, ki_gen: float) -> dict:
    """ROSCO-signed, rotor-speed PI gains scheduled on pitch (RAFT flips the sign). The
    schedule starts just above zero pitch: RAFT takes a zero gain left of it, i.e. region 2
    (the torque law) at the zero pitch below rated."""
    angles = np.radians(np.r_[0.01, np.arange(0.5, 30.5, 0.5)])
    gk = 1.0 / (1.0 + angles / THETA_K)
    return {"GS_Angles": angles.tolist(), "GS_Kp": (-kp_gen * rt.GEARBOX * gk).tolist(),
            "GS_Ki": (-ki_gen * rt.GEARBOX * gk).tolist(), "Fl_Kp": 0.0}


def torque_gain(u: float) -> float:
    """ROSCO-signed proportional torque gain [N m s/rad, rotor side] of the baseline region-2
    law at wind speed u: -d(97 tau_g)/dOmega = -97^2 tau_g'(97 Omega)."""
    import xarray as xr

    with xr.open_dataset(TABLE) as ds:
        omega = float(ds["rotor_speed"].interp(wind_speed=u))
    return -rt.GEARBOX**2 * rt.generator_torque_slope(rt.GEARBOX * omega)


def turbine(aero_servo: int, gains: tuple[float, float], u: float) -> dict:
    lo = rt.ROTOR
    geometry = [[r, c, tw, 0.0, 0.0] for r, c, tw in zip(rt.R_NODES, rt.CHORD, rt.TWIST)]
    geometry.append([lo["Rtip"], rt.CHORD[-1], rt.TWIST[-1], 0.0, 0.0])
    span = lo["Rtip"] - lo["Rhub"]
    stations = [[(r - lo["Rhub"]) / span, name] for r, name in zip(rt.R_NODES, rt.AIRFOIL)]
    stations = [[0.0, rt.AIRFOIL[0]]] + stations + [[1.0, rt.AIRFOIL[-1]]]
    return {
        "mRNA": 350000.0, "IxRNA": 35444067.0, "IrRNA": 26159984.0, "xCG_RNA": -0.27,
        "hHub": 90.0, "overhang": -5.0, "I_drivetrain": I_DRIVETRAIN, "nBlades": lo["B"],
        "Rhub": lo["Rhub"], "precone": -lo["precone"], "shaft_tilt": -lo["tilt"],
        "aeroServoMod": aero_servo, "gear_ratio": 1,
        "blade": {"precurveTip": 0.0, "presweepTip": 0.0, "Rtip": lo["Rtip"],
                  "geometry": geometry, "airfoils": stations},
        "airfoils": airfoils(), "wt_ops": schedule(),
        "pitch_control": pitch_control(*gains),
        "torque_control": {"VS_KP": torque_gain(u), "VS_KI": 0.0},
        "tower": {"name": "tower", "type": "rigid", "rA": [0, 0, 10], "rB": [0, 0, 87.6],
                  "shape": "circ", "gamma": 0.0,
                  "stations": [10, 87.6], "d": [6.5, 3.87], "t": [0.027, 0.019],
                  "Cd": 0.0, "Ca": 0.0, "CdEnd": 0.0, "CaEnd": 0.0, "rho_shell": 8500.0},
    }


def platform(case: dict, l_fill: float, rho_fill: float) -> dict:
    prof = case["body"]["hull"]["profile"]
    return {"potModMaster": 1, "yaw_stiffness": case["mooring"]["yaw_spring"],
            "members": [{
                "name": "center_spar", "type": "rigid", "rA": [0, 0, prof[0][1]],
                "rB": [0, 0, prof[-1][1]], "shape": "circ", "gamma": 0.0, "potMod": False,
                "stations": [p[1] for p in prof[1:]], "d": [2 * p[0] for p in prof[1:]],
                "t": 0.027, "Cd": 0.6, "Ca": 1.0, "CdEnd": 0.6, "CaEnd": 0.6,
                "rho_shell": 8500.0, "l_fill": [l_fill, 0.0, 0.0],
                "rho_fill": [rho_fill, 0.0, 0.0]}]}


def mooring(case: dict) -> dict:
    m = case["mooring"]
    points, lines = [], []
    for i in range(m["n_lines"]):
        a = math.radians(m["line1_heading"] + 120.0 * i)
        points.append({"name": f"anchor{i}", "type": "fixed",
                       "location": [m["anchor_radius"] * math.cos(a),
                                    m["anchor_radius"] * math.sin(a), -m["anchor_depth"]]})
        points.append({"name": f"fair{i}", "type": "vessel",
                       "location": [m["fairlead_radius"] * math.cos(a),
                                    m["fairlead_radius"] * math.sin(a), -m["fairlead_depth"]]})
        lines.append({"name": f"line{i}", "endA": f"anchor{i}", "endB": f"fair{i}",
                      "type": "main", "length": m["unstretched_length"]})
    return {"water_depth": case["environment"]["water_depth"], "points": points, "lines": lines,
            "line_types": [{"name": "main", "diameter": m["diameter"],
                            "mass_density": m["mass_per_length"], "stiffness": m["EA"],
                            "breaking_load": 1e8, "cost": 100.0, "transverse_added_mass": 1.0,
                            "tangential_added_mass": 0.0, "transverse_drag": 1.6,
                            "tangential_drag": 0.1}],
            "anchor_types": [{"name": "drag_embedment", "mass": 1e3, "cost": 1e4,
                              "max_vertical_load": 0.0, "max_lateral_load": 1e5}]}


def design(case: dict, aero_servo: int, gains: tuple[float, float], ballast: tuple,
           u: float = 8.0) -> dict:
    rows = [[u, 0, 0.0, "operating", 0, "still", 10.0, 0.0, 0]]
    return {"name": "OC3-Hywind + NREL 5-MW (hybridwsi case)",
            "settings": {"min_freq": 0.001, "max_freq": 0.3, "XiStart": 0.1, "nIter": 10},
            "site": {"water_depth": case["environment"]["water_depth"],
                     "rho_water": case["environment"]["rho"], "g": case["environment"]["g"],
                     "rho_air": rt.RHO, "mu_air": rt.RHO * rt.KIN_VISC, "shearExp_air": 0.0,
                     "shearExp": 0.0},
            "cases": {"keys": ["wind_speed", "wind_heading", "turbulence", "turbine_status",
                               "yaw_misalign", "wave_spectrum", "wave_period", "wave_height",
                               "wave_heading"], "data": rows},
            "turbine": turbine(aero_servo, gains, u), "platform": platform(case, *ballast),
            "mooring": mooring(case)}


def quiet(fn, *args, **kw):
    """Call ``fn`` with RAFT's and CCBlade's prints captured."""
    with contextlib.redirect_stdout(io.StringIO()):
        return fn(*args, **kw)


def solve_ballast(case: dict) -> tuple[float, float]:
    """Ballast length [m] and density [kg/m^3] giving the case's platform mass and CM."""
    import raft
    import scipy.optimize

    target = next(i for i in case["body"]["items"] if i["name"] == "platform")

    def residual(x: np.ndarray) -> np.ndarray:
        model = quiet(raft.Model, design(case, 1, PI_GAINS["baseline"], tuple(x)))
        fowt = model.fowtList[0]
        fowt.setPosition(np.zeros(fowt.nDOF))
        quiet(fowt.calcStatics)
        return np.array([fowt.m_sub / target["mass"] - 1.0,
                         (fowt.rCG_sub[2] - target["cm"][2]) / 10.0])

    x = scipy.optimize.fsolve(residual, [52.9, 1800.0], xtol=1e-10)
    return float(x[0]), float(x[1])


def run(case: dict, aero_servo: int, gains: tuple[float, float], ballast: tuple) -> dict:
    """Offsets and rotor loads per wind speed for one RAFT configuration."""
    import raft

    out = {}
    for u in WIND_SPEEDS:
        model = quiet(raft.Model, design(case, aero_servo, gains, ballast, u))
        fowt = model.fowtList[0]
        c = dict(zip(model.design["cases"]["keys"], model.design["cases"]["data"][0]))
        quiet(model.solveStatics, c)
        r6 = np.asarray(model.Xs2[-1], dtype=float)
        w, b = model.w, fowt.B_aero[:, :, :, 0]
        rec = {"surge_m": float(r6[0]), "heave_m": float(r6[2]), "pitch_rad": float(r6[4]),
               "thrust_N": float(np.hypot(fowt.f_aero0[0, 0], fowt.f_aero0[2, 0])),
               "f_aero0": fowt.f_aero0[:, 0].tolist(),
               "B11_low_frequency": float(b[0, 0, 0]), "omega_low_frequency": float(w[0])}
        for name, om in OMEGA.items():
            rec[f"B11_at_{name}"] = float(np.interp(om, w, b[0, 0]))
            rec[f"B55_at_{name}"] = float(np.interp(om, w, b[4, 4]))
        stiff = fowt.C_struc + fowt.C_hydro + fowt.C_moor
        rec["stiffness_diag"] = np.diag(stiff).tolist()
        out[f"{u:g}"] = rec
    out["mass_total_kg"] = float(fowt.m)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    t0 = time.time()
    case = tomllib.loads(CASE.read_text())
    ballast = solve_ballast(case)
    print(f"ballast: {ballast[0]:.4f} m of {ballast[1]:.2f} kg/m^3")
    results = {"no_control": run(case, 1, PI_GAINS["baseline"], ballast)}
    for name, gains in PI_GAINS.items():
        results[f"pi_{name}"] = run(case, 2, gains, ballast)
    for label, res in results.items():
        for u in WIND_SPEEDS:
            r = res[f"{u:g}"]
            print(f"{label:16s} U {u:5.1f}: surge {r['surge_m']:7.3f} m, pitch "
                  f"{math.degrees(r['pitch_rad']):6.3f} deg, T {r['thrust_N'] / 1e3:7.1f} kN, "
                  f"B11 at {r['omega_low_frequency']:.4f} rad/s {r['B11_low_frequency'] / 1e3:8.2f}, "
                  f"(surge) {r['B11_at_surge'] / 1e3:8.2f}, (pitch) "
                  f"{r['B11_at_pitch'] / 1e3:8.2f} kN s/m")
    doc = {"title": "RAFT on OC3-Hywind + NREL 5-MW: mean offsets and aerodynamic damping",
           "command": "PYTHONPATH=src python scripts/raft_oc3.py",
           "versions": {"openraft": version("openraft"), "wisdem": version("wisdem"),
                        "moorpy": version("moorpy"), "numpy": np.__version__},
           "wind_speeds_m_s": list(WIND_SPEEDS), "omega_rad_s": OMEGA,
           "pi_gains_generator_side": {k: {"KP_s": v[0], "KI": v[1]} for k, v in PI_GAINS.items()},
           "ballast": {"length_m": ballast[0], "density_kg_m3": ballast[1]},
           "units": {"surge_m": "m", "pitch_rad": "rad", "thrust_N": "N",
                     "B11": "N s/m about the platform reference point (SWL)",
                     "B55": "N m s/rad", "f_aero0": "N, N m about the platform reference point"},
           "results": results, "wall_time_s": round(time.time() - t0, 1)}
    write_json(args.out, doc)
    print(f"wrote {args.out} ({time.time() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    from hybridwsi.cli import run_script

    run_script(main)
