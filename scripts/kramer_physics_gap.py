"""Issue 14 item 1: why does our exact-hydrostatics Cummins model score 0.0133 at 0.1D and LPF2 0.0107?

Each candidate effect is changed *alone* on the physics baseline (exact hydrostatics, shipped BEM
coefficients, radiation state space, RK4 at 1 ms: :func:`hybridwsi.surrogate.structured.
integrate_decay`, identical to ``cummins.simulate(nonlinear_hydrostatics=True)``) and the RMS of
heave/H0 over [0, 5 Te0] (the decay table's) is printed for the three drops; then the decay rate
and period of every published code are fitted (damped oscillator over [1, 5] Te0) and the missing
damping ΔB = 2 (m + A(ω_n)) Δσ is computed.

    PYTHONPATH=src OMP_NUM_THREADS=1 python scripts/kramer_physics_gap.py [--bem]

``--bem`` adds the two effects that need new BEM runs (coarse, 400 panels, 60 frequencies, so
only the *difference* between the pair is meaningful): water depth 0.9 m against deep water, and
the lid (irregular frequencies) on against off. Takes ~5 min more.
"""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np

from hybridwsi.cli import Parser, run_script
from hybridwsi import bodies
from hybridwsi.forces import RadiationMemory
from hybridwsi.hydro import bem
from hybridwsi.hydro.irf import radiation_irf
from hybridwsi.hydro.statespace import fit_radiation_ss
from hybridwsi.importers.kramer import kramer_numerical_files, read_kramer_numerical
from hybridwsi.surrogate import kramer as kh
from hybridwsi.surrogate import structured as st
from hybridwsi.history import rms_heave_error
from hybridwsi.importers.kramer import read_kramer_drop


def scores(setup, exp, coef=None, lead=0.0, dt=None) -> list[float]:
    h0 = np.array([setup.drop_heights[d] for d in kh.DROPS])
    t, z = st.integrate_decay(setup, h0, coef, duration=4.0, dt=dt)
    out = []
    for k, d in enumerate(kh.DROPS):
        te, ze = exp[d]
        out.append(rms_heave_error(np.r_[-1.0, t - lead], np.r_[1.0, z[k] / h0[k]], te, ze,
                                   setup.te0))
    return out


def memory_from(coeffs, **irf_kw) -> RadiationMemory:
    return RadiationMemory(fit_radiation_ss(radiation_irf(coeffs, **irf_kw)))


def release_lead(setup, exp) -> dict[str, float]:
    """Shift δ [s] that matches the model's first 30 ms to the data (t = 0 of the data)."""
    out = {}
    for d in kh.DROPS:
        te, ze = exp[d]
        t, z = st.integrate_decay(setup, setup.drop_heights[d], duration=0.1, dt=1e-4)
        early = (te > 0.005) & (te < 0.035)
        leads = np.arange(-0.004, 0.008, 1e-4)
        err = [np.sum((np.interp(te[early] + s, t, z / setup.drop_heights[d]) - ze[early]) ** 2)
               for s in leads]
        out[d] = float(leads[int(np.argmin(err))])
    return out


def main() -> None:
    ap = Parser()
    ap.add_argument("--bem", action="store_true")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    setup = kh.kramer_setup()
    exp = {}
    for d in kh.DROPS:
        e = read_kramer_drop(d, normalised=True)
        exp[d] = (e["time"].values, e["z"].values[:, 0])
    rows: dict[str, list[float]] = {}
    b = np.zeros(len(st.STRUCTURED_TERMS))
    rows["baseline (1 ms, state space, shipped BEM)"] = scores(setup, exp)
    rows["time step 0.5 ms"] = scores(setup, exp, dt=0.0005)
    rows["time step 4 ms"] = scores(setup, exp, dt=0.004)
    leads = release_lead(setup, exp)
    for d in kh.DROPS:
        rows[f"release {1e3 * leads[d]:.1f} ms early (fitted on {d}'s first 30 ms)"] = scores(
            setup, exp, lead=leads[d])
    rows["IRF without the high-frequency tail (B cut at 40 rad/s)"] = scores(
        dataclasses.replace(setup, memory=memory_from(setup.coeffs, tail="none")), exp)
    low = setup.coeffs.sel(omega=slice(None, 20.0))
    rows["BEM only up to 20 rad/s (tail fitted there)"] = scores(
        dataclasses.replace(setup, memory=memory_from(low)), exp)
    a40 = float(setup.coeffs["added_mass"].values[-1, 0, 0])
    rows[f"A_inf = A(40 rad/s) = {a40:.3f} kg instead of {setup.added_mass_inf:.3f}"] = scores(
        dataclasses.replace(setup, added_mass_inf=a40), exp)
    rows["A_inf + 1 %"] = scores(dataclasses.replace(setup, added_mass_inf=1.01 * setup.added_mass_inf), exp)
    rows["m = 7.06 kg instead of 7.056"] = scores(dataclasses.replace(setup, mass=7.06), exp)
    g81 = bodies.FloatingSphere(radius=0.15, mass=7.056 * 9.81 / 9.82 * 9.82 / 9.81,
                                center_of_mass=(0.0, 0.0, -0.0348),
                                inertia=(0.098252, 0.098252, 0.073052), rho=998.2, g=9.81)
    rows["g = 9.81 (C and the exact force)"] = scores(
        dataclasses.replace(setup, body=g81, stiffness=setup.stiffness * 9.81 / 9.82), exp)
    rho = 1000.0
    r1000 = bodies.FloatingSphere(radius=0.15, mass=7.056 * rho / 998.2,
                                  center_of_mass=(0.0, 0.0, -0.0348),
                                  inertia=(0.098252, 0.098252, 0.073052), rho=rho, g=9.82)
    f = rho / 998.2
    c1000 = setup.coeffs.copy()
    for v in ("added_mass", "radiation_damping", "added_mass_inf", "hydrostatic_stiffness"):
        c1000[v] = setup.coeffs[v] * f
    rows["rho = 1000 (A, B, C, m scaled: floats at the same draft)"] = scores(
        dataclasses.replace(setup, body=r1000, mass=setup.mass * f, added_mass_inf=setup.added_mass_inf * f,
                            stiffness=setup.stiffness * f, memory=memory_from(c1000)), exp)
    b[st.STRUCTURED_TERMS.index("b1")] = 0.6
    rows["+ 0.6 N s/m linear damping (the LPF codes' missing damping)"] = scores(setup, exp, b)
    if args.bem:
        body = bodies.FloatingSphere.kramer2021()
        w = np.geomspace(0.1, 40, 60)
        pairs = {"depth 0.9 m": dict(water_depth=0.9), "deep water": dict(water_depth=np.inf),
                 "deep water, lid": dict(water_depth=np.inf, lid=True),
                 "deep water, no lid": dict(water_depth=np.inf, lid=False)}
        for name, kw in pairs.items():
            c = bem.compute(body, w, n_panels=400, progress=False, **kw)
            s = dataclasses.replace(setup, memory=memory_from(c),
                                    added_mass_inf=float(c["added_mass_inf"].values[0, 0]))
            rows[f"coarse BEM (400 panels, 60 ω): {name}"] = scores(s, exp)
    print("| effect (changed alone) | 01D | 03D | 05D |\n|---|---|---|---|")
    for k, v in rows.items():
        print(f"| {k} | " + " | ".join(f"{x:.4f}" for x in v) + " |")
    # decay rates and periods of the codes and the experiment (damped-oscillator fit)
    m_eff = setup.mass + float(np.interp(2 * np.pi / setup.te0, setup.coeffs["omega"].values,
                                         setup.coeffs["added_mass"].values[:, 0, 0]))
    print("\n| drop | code | decay rate σ [1/s] | σ error [%] | ΔB = 2(m+A)Δσ [N s/m] |"
          " period / Te0 |\n|---|---|---|---|---|---|")
    fits = {}
    for d in kh.DROPS:
        te, ze = exp[d]
        s_exp = kh.decay_rate(te, ze, setup.te0)
        h0 = setup.drop_heights[d]
        t, z = st.integrate_decay(setup, h0, duration=4.0)
        curves = {"experiment": (te, ze), "ours (physics)": (t, z / h0)}
        for code, path in kramer_numerical_files(d).items():
            num = read_kramer_numerical(path, require_uniform=False)
            zz = num["z"].values[:, 0]
            curves[code] = (num["time"].values, zz / zz[0])
        for code, (tt, zz) in curves.items():
            s = kh.decay_rate(tt, zz, setup.te0)
            per = kh.decay_measures(tt, zz, setup, te, ze)["period_over_Te0"]
            fits[f"{d}:{code}"] = s
            print(f"| {d} | {code} | {s:.4f} | {100 * (s / s_exp - 1):+.1f} | "
                  f"{2 * m_eff * (s_exp - s):+.2f} | {per:.4f} |")
    print(json.dumps({"rows": rows, "release_lead_s": leads, "decay_rates": fits}))


if __name__ == "__main__":
    run_script(main)
