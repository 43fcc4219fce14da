"""Radiation state-space fits of the shipped bodies: B(ω) error, B11(0.05 rad/s), K̂(0), passivity.

For each shipped coefficient file (paper sphere, OC3-Hywind, OC4 semi) the kernel K(t) is
computed from B(ω) (:func:`hybridwsi.hydro.irf.radiation_irf`) and fitted with the settings its
callers use (sphere and OC3: ``cummins.simulate``'s tolerance 0.005; OC4 semi: the case's
``[radiation]`` table), then compared with the BEM's B(ω) in the body's wave band. The
passivity index is the smallest eigenvalue of the Hermitian part of K̂(iω), each DOF scaled by
its largest Re K̂_ii, on a 6000-point grid from 1e-5 to 1e3 rad/s plus the poles' |Im λ|
(negative: the model generates energy). Printed only (seconds); docs/THEORY.md quotes it.

    python scripts/radiation_passivity.py [sphere oc3 oc4]
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from hybridwsi.cases import load_case  # noqa: E402
from hybridwsi.cli import Parser  # noqa: E402
from hybridwsi.hydro import bem  # noqa: E402
from hybridwsi.hydro.irf import radiation_irf  # noqa: E402
from hybridwsi.hydro.statespace import RadiationSS, fit_radiation_ss  # noqa: E402

#: body: (coefficient file, DOFs, wave band [rad/s], fit settings or a case with [radiation])
BODIES = {
    "sphere": ("bem_paper_sphere.nc", ["Heave"], (3.0, 20.0), {"tol": 0.005}),
    "oc3": ("bem_oc3_hywind.nc", ["Surge", "Heave", "Pitch"], (0.2, 2.0), {"tol": 0.005}),
    "oc4": ("bem_oc4_semi.nc", ["Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"], (0.2, 2.5),
            "oc4_semi"),
}


def passivity_index(ss: RadiationSS) -> float:
    """Smallest scaled eigenvalue of the Hermitian part of K̂(iω) on a wide dense grid."""
    omega = np.unique(np.concatenate([np.geomspace(1e-5, 1e3, 6000), np.abs(ss.poles.imag)]))
    return float(ss.passivity(omega).min())


def report(name: str) -> str:
    """One line of numbers for one body."""
    fname, dofs, band, fit = BODIES[name]
    with xr.open_dataset(bem.PAPER_COEFFS.parent / fname) as ds:
        coeffs = ds.load()
    if isinstance(fit, str):
        table = load_case(fit)["radiation"]
        irf_kw = {k: table[k] for k in ("t_max", "dt") if k in table}
        fit = {k: table[k] for k in ("tol", "max_order", "balance") if k in table}
    else:
        irf_kw = {}
    sel = {"radiating_dof": dofs, "influenced_dof": dofs}
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the IRF tail and a tol not met are in the numbers
        ss = fit_radiation_ss(radiation_irf(coeffs, **irf_kw).sel(sel), coeffs=coeffs, **fit)
    cpu = time.process_time() - t0
    w = coeffs["omega"].values
    ref = coeffs["radiation_damping"].sel(sel).transpose("omega", ...).values
    est = np.real(ss.frequency_response(w))
    inb = (w >= band[0]) & (w <= band[1])
    err = np.linalg.norm(est[inb] - ref[inb]) / np.linalg.norm(ref[inb])
    i05 = int(np.argmin(np.abs(w - 0.05)))
    return (f"{name}: order {ss.order}, B(ω) RMS error {band[0]:g}-{band[1]:g} rad/s {err:.4f}, "
            f"B11(0.05) {ss.equivalent_damping(0.05)[0, 0]:.4g} N s/m (BEM at {w[i05]:.3f}: "
            f"{ref[i05, 0, 0]:.4g}), max|K̂(0)| {np.abs(ss.frequency_response([0.0])).max():.2g}, "
            f"passivity index {passivity_index(ss):.2g} (fit's own {ss.passivity_min:.2g}), "
            f"time error {ss.fit_error['time']:.4f}, fit {cpu:.1f} s CPU")


def main(argv: list[str] | None = None) -> int:
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("bodies", nargs="*", help=f"any of {', '.join(BODIES)} (default: all)")
    args = ap.parse_args(argv)
    unknown = [b for b in args.bodies if b not in BODIES]
    if unknown:
        ap.error(f"unknown body {unknown} (use {', '.join(BODIES)})")
    for name in args.bodies or list(BODIES):
        print(report(name), flush=True)
    return 0


if __name__ == "__main__":
    from hybridwsi.cli import run_script

    run_script(main)
