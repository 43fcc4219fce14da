"""The OC3-Hywind mooring in MoorDyn against the quasi-static MoorPy one.

Forced harmonic motion of the body (e.g. surge ``x = X sin ωt`` after a one-cycle ramp) drives
MoorDyn (:meth:`~hybridwsi.forces.moordyn.MoorDynForce.drive`) and MoorPy's quasi-static
solve (:meth:`~hybridwsi.forces.mooring.MooringSystem.force6`) along the same motion. On the
last cycle:

- the loop area ``E = −∮ F dx`` [J per cycle]: the energy the lines dissipate (zero for the
  quasi-static force, a function of x alone);
- the first harmonic: the dynamic stiffness ``K_dyn = −F̂/X̂ = K' + i ω B_eq`` [N/m], its phase
  ``φ = arg K_dyn`` [deg] (how far the restoring force leads the displacement; 0 for the
  quasi-static force) and the equivalent linear damping ``B_eq`` [N s/m];
- the fairlead tension range per line [N].

The independent reference is Huse's quasi-static-shape estimate of the drag dissipation
(:meth:`~hybridwsi.forces.mooring.MooringSystem.drag_dissipation`). ``scripts/oc3_moordyn.py``
runs the convergence study and the figure of docs/OC3_HYWIND.md ("MoorDyn").
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from hybridwsi.dofs import RIGID_DOFS, check_dofs, force_unit, motion_unit  # noqa: E402
from hybridwsi.forces.moordyn import MoorDynForce  # noqa: E402
from hybridwsi.forces.mooring import MooringSystem  # noqa: E402
from hybridwsi.report.fowt import harmonic_amplitude  # noqa: E402


def harmonic_motion(t: np.ndarray, amplitude: float, period: float, ramp_cycles: float = 1.0
                    ) -> tuple[np.ndarray, np.ndarray]:
    """``x = r(t) X sin ωt`` and its rate [units of X, per s]; ``r`` a half-cosine ramp from 0
    to 1 over the first ``ramp_cycles`` periods (MoorDyn starts from rest, static)."""
    omega = 2.0 * np.pi / period
    r, dr = np.ones_like(t), np.zeros_like(t)
    if ramp_cycles > 0:
        t_r = ramp_cycles * period
        ramp = t < t_r
        r[ramp] = 0.5 * (1.0 - np.cos(np.pi * t[ramp] / t_r))
        dr[ramp] = 0.5 * np.pi / t_r * np.sin(np.pi * t[ramp] / t_r)
    s, c = np.sin(omega * t), np.cos(omega * t)
    return amplitude * r * s, amplitude * (dr * s + r * omega * c)


def forced_loop(component: MoorDynForce, system: MooringSystem | None, dof: str,
                amplitude: float, period: float, *, dt: float = 0.1, cycles: int = 4
                ) -> xr.Dataset:
    """One steady cycle of forced harmonic motion of ``dof`` (amplitude in m or rad, period s).

    ``cycles`` periods are run (the first ramps up); the last one is returned: ``x`` and
    ``xdot``, MoorDyn's force ``F_moordyn`` and the quasi-static MoorPy force ``F_quasi_static``
    (both ``F(q) − F0`` on ``dof``, the MoorDyn one without the yaw spring; None system: no
    quasi-static force; then also MoorPy's ``T_fairlead_quasi_static``), ``T_fairlead`` and
    ``T_anchor`` (time, line) [N] of MoorDyn. ``component`` gives
    the MoorDyn input and the arms; it is driven on a copy (its own run is untouched).
    """
    (dof,) = check_dofs([dof])
    i = RIGID_DOFS.index(dof)
    t = np.arange(int(round(cycles * period / dt)) + 1) * dt
    x, xdot = harmonic_motion(t, amplitude, period)
    rec = component.spawn([dof]).drive(t, x[:, None], xdot[:, None])
    last = t >= t[-1] - period - 1e-9
    q = np.zeros((int(last.sum()), 6))
    q[:, i] = x[last]
    out = xr.Dataset(
        {"x": ("time", x[last], {"units": motion_unit(dof)}),
         "xdot": ("time", xdot[last], {"units": motion_unit(dof, "zdot")}),
         "F_moordyn": ("time", rec["force"].values[last, i], {"units": force_unit(dof)}),
         "T_fairlead": (("time", "line"), rec["T_fairlead"].values[last], {"units": "N"}),
         "T_anchor": (("time", "line"), rec["T_anchor"].values[last], {"units": "N"})},
        coords={"time": ("time", t[last], {"units": "s"}), "line": rec["line"].values},
        attrs={"dof": dof, "amplitude": float(amplitude), "period": float(period), "dt": dt,
               "cycles": cycles, "moordyn": component.describe()})
    if system is not None:
        f0 = system.lines_force6(np.zeros(6))[i]
        f_qs, t_qs = np.empty(len(q)), np.empty((len(q), system.lines.n_lines))
        for k, qk in enumerate(q):
            f_qs[k] = system.lines_force6(qk)[i] - f0
            t_qs[k] = [line.TB for line in system.moorpy.lineList]
        out["F_quasi_static"] = ("time", f_qs, {"units": force_unit(dof)})
        out["T_fairlead_quasi_static"] = (("time", "line"), t_qs, {"units": "N"})
    return out


def loop_metrics(loop: xr.Dataset, force: str = "F_moordyn") -> dict[str, float]:
    """Loop area, first-harmonic dynamic stiffness, phase and equivalent damping of a cycle.

    ``E = −∫ F ẋ dt`` over the cycle [J]; ``K_dyn = −F̂/X̂`` [N/m or N m/rad];
    ``phase = arg K_dyn`` [deg]; ``B_eq = Im K_dyn / ω``; ``E_first_harmonic = π X² Im K_dyn``;
    fairlead tension range of each line (``T_fairlead``, or ``T_fairlead_quasi_static`` for
    ``force="F_quasi_static"``) [N].
    """
    t = loop["time"].values
    f, xdot, x = (loop[name].values for name in (force, "xdot", "x"))
    omega = 2.0 * np.pi / loop.attrs["period"]
    energy = -float(np.trapezoid(f * xdot, t))
    # the harmonic fit on one period without its repeated end point (t[-1] = t[0] + period)
    k_dyn = (-harmonic_amplitude(t[:-1], f[:-1], omega)
             / harmonic_amplitude(t[:-1], x[:-1], omega))
    amp = float(loop.attrs["amplitude"])
    tension = loop["T_fairlead_quasi_static" if force == "F_quasi_static" else "T_fairlead"].values
    return {"E": energy, "E_first_harmonic": float(np.pi * amp**2 * k_dyn.imag),
            "K_real": float(k_dyn.real), "B_eq": float(k_dyn.imag / omega),
            "phase_deg": float(np.degrees(np.angle(k_dyn))),
            "T_fairlead_max": tension.max(axis=0).tolist(),
            "T_fairlead_min": tension.min(axis=0).tolist()}


def hysteresis_figure(loops: Mapping[str, xr.Dataset],
                      references: Mapping[str, float] | None = None
                      ) -> tuple[plt.Figure, xr.Dataset]:
    """Force against displacement, MoorDyn and quasi-static, one panel per loop (label ->
    :func:`forced_loop`); ``references``: label -> Huse's loop area [J], quoted in the panel.
    Returns the figure and the data behind it (variables ``<label>__<name>``)."""
    n = len(loops)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.8), squeeze=False)
    data = {}
    for ax, (label, loop) in zip(axes[0], loops.items()):
        dof = loop.attrs["dof"]
        m = loop_metrics(loop)
        ax.plot(loop["x"], loop["F_moordyn"] / 1e6, label="MoorDyn", lw=1.6)
        if "F_quasi_static" in loop:
            ax.plot(loop["x"], loop["F_quasi_static"] / 1e6, "--", label="quasi-static (MoorPy)")
        text = f"E = {m['E'] / 1e6:.3f} MJ, φ = {m['phase_deg']:.1f}°"
        if references and label in references:
            text += f"\nHuse: {references[label] / 1e6:.3f} MJ"
        ax.text(0.03, 0.04, text, transform=ax.transAxes, fontsize=8)
        ax.set_title(f"{dof} {loop.attrs['amplitude']:g} {motion_unit(dof)}, "
                     f"T = {loop.attrs['period']:g} s", fontsize=9)
        ax.set_xlabel(f"{dof} displacement [{motion_unit(dof)}]")
        ax.set_ylabel(f"{dof} mooring force F − F0 [M{force_unit(dof)}]")
        ax.grid(alpha=0.3)
        for name in loop.data_vars:
            data[f"{label}__{name}"] = loop[name].rename({"time": f"time_{label}"})
    axes[0][0].legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    ds = xr.Dataset(data)
    ds.attrs["description"] = ("forced harmonic motion of the OC3-Hywind body: MoorDyn and "
                               "quasi-static (MoorPy) mooring force against displacement, last "
                               "cycle of each run")
    return fig, ds


def statics_summary(component: MoorDynForce, system: MooringSystem) -> dict[str, Any]:
    """MoorDyn's statics at rest against MoorPy: fairlead and anchor tensions, preload F0_z
    and K11, K33, K55, K15 (lines only), each with its relative difference."""
    f0 = system.preload()  # also leaves MoorPy's lines solved at rest (TA, TB below)
    k_md = component.stiffness() - np.diag([0, 0, 0, 0, 0, component.yaw_spring])
    k_mp = system.stiffness(yaw_spring=False)
    t_md = component.tensions()
    out: dict[str, Any] = {}
    for name, a, b in [("T_fairlead", t_md[0, 0], None), ("T_anchor", t_md[0, 1], None),
                       ("F0_z", component.rest_force()[2], f0[2]),
                       ("K11", k_md[0, 0], k_mp[0, 0]), ("K33", k_md[2, 2], k_mp[2, 2]),
                       ("K55", k_md[4, 4], k_mp[4, 4]), ("K15", k_md[0, 4], k_mp[0, 4])]:
        if b is None:
            line = system.moorpy.lineList[0]
            b = line.TB if name == "T_fairlead" else line.TA
        out[name] = {"moordyn": float(a), "moorpy": float(b), "rel_diff": float(a / b - 1.0)}
    return out


def static_curve(component: MoorDynForce, system: MooringSystem, dof: str,
                 offsets: np.ndarray) -> dict[str, Any]:
    """MoorDyn's static force ``F(q) − F0`` on ``dof`` at the offsets (one static solve each)
    against MoorPy's; ``max_rel_diff`` is the largest ``|ΔF| / |F_MoorPy|`` [-]."""
    (dof,) = check_dofs([dof])
    i = RIGID_DOFS.index(dof)
    f0 = system.lines_force6(np.zeros(6))[i]
    md, mp = [], []
    for x in np.asarray(offsets, dtype=float):
        q = np.zeros(6)
        q[i] = x
        copy = component.spawn([dof])
        copy.begin_step(0.0, [x], [0.0], 0.0)
        md.append(float(copy.records()["force"].values[0, i]))
        copy.close()
        mp.append(float(system.lines_force6(q)[i] - f0))
    rel = np.abs(np.array(md) - mp) / np.abs(mp)
    return {"offsets": np.asarray(offsets, float).tolist(), "moordyn": md, "moorpy": mp,
            "max_rel_diff": float(rel.max())}
