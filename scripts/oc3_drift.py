"""OC3-Hywind mean wave drift: the panel-convergence table, the shipped table and its figure.

Resumable: the Capytaine solves go through :func:`hybridwsi.hydro.drift.compute_operator`, which
checkpoints every solved frequency in its cache (``--cache-dir``), so an interrupted run solves
only what is missing when started again.

    # far vs near field in surge at a few frequencies for several meshes (docs/OC3_HYWIND.md)
    nice -n 10 python scripts/oc3_drift.py convergence --panel-sizes 2 1 0.65 0.5
    # the shipped table (cases/oc3_hywind.toml [drift]) and docs/figures/oc3_drift.{png,nc}
    nice -n 10 python scripts/oc3_drift.py ship
    # what Newman's approximation misses of the quadratic QTF at the surge and pitch
    # natural frequencies (docs/figures/oc3_drift_qtf.nc)
    nice -n 10 python scripts/oc3_drift.py qtf --panel-size 1.0 --mu 0.05 0.21

Run with ``OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1`` (one process; see hydro/bem/).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi.casemodel import body_from_case
from hybridwsi.cases import load_case
from hybridwsi.cli import Parser, run_script
from hybridwsi.files import to_netcdf
from hybridwsi.hydro import drift

ROOT = Path(__file__).resolve().parent.parent
FIGURE = ROOT / "docs" / "figures" / "oc3_drift"


def motion_matrices(case: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass [kg…], stiffness (hydrostatics incl. weight + MoorPy lines + yaw spring) [N/m…] and
    additional linear damping [N s/m…] of the case in six DOFs, force-equation orientation."""
    from hybridwsi.forces.mooring import MooringLines, MooringSystem
    from hybridwsi.forces.morison import additional_damping

    body = body_from_case(case)
    dofs = list(drift.ALL_DOFS)
    stiffness = body.hydrostatic_stiffness(dofs) + MooringSystem(
        MooringLines.from_case(case)).stiffness()
    damping = additional_damping(case, dofs).linear_coefficients(6)[1]
    return body.mass_matrix(dofs), stiffness, damping


def case_table(case: dict, omega, panel_size: float, cache_dir: str | None,
               verbose: bool = True) -> tuple[xr.Dataset, float]:
    """The drift table of ``case`` at ``omega`` and ``panel_size``; also the solve wall time."""
    cfg = case["drift"]
    body = body_from_case(case)

    def progress(w: float, seconds: float) -> None:
        if verbose:
            print(f"  omega {w:.4g} rad/s solved in {seconds:.1f} s", flush=True)

    start = time.perf_counter()
    op = drift.compute_operator(body, omega, water_depth=case["environment"]["water_depth"],
                                panel_size=panel_size,
                                wave_directions=cfg.get("wave_directions", [0.0]),
                                n_theta=cfg.get("n_theta", drift.N_THETA),
                                cache_dir=cache_dir, progress=progress)
    wall = time.perf_counter() - start
    mass, stiffness, damping = motion_matrices(case)
    rao = drift.motion_rao(op, mass, stiffness, damping)
    from hybridwsi._meta import package_version, version

    attrs = {"source": "scripts/oc3_drift.py (hybridwsi.hydro.drift)", "case": case["name"],
             "panel_size": float(panel_size),
             "motions": "case mass, hydrostatics + MoorPy stiffness (lines and yaw spring), "
                        "[hydrodynamics] additional damping; parked rotor",
             "hybridwsi_version": version(), "capytaine_version": package_version("capytaine")}
    return drift.drift_table(op, rao, attrs), wall


def convergence(panel_sizes: list[float], omegas: list[float], cache_dir: str | None) -> None:
    """Markdown table: far and near field surge drift per frequency and panel size."""
    case = load_case("oc3_hywind")
    print("| panel size [m] | hull + lid panels | ω [rad/s] | far field [N/m²] | "
          "near field [N/m²] | near/far − 1 | solve [s] |")
    print("|---|---|---|---|---|---|---|")
    for h in panel_sizes:
        table, wall = case_table(case, omegas, h, cache_dir, verbose=False)
        far = table["far_field"].sel(influenced_dof="Surge").isel(wave_direction=0).values
        near = table["near_field"].sel(influenced_dof="Surge").isel(wave_direction=0).values
        panels = f"{table.attrs['n_panels']} + {table.attrs['n_lid_panels']}"
        for w, f, n in zip(table["omega"].values, far, near):
            print(f"| {h:g} | {panels} | {w:g} | {f:.5g} | {n:.5g} | "
                  f"{100 * (n / f - 1):+.2f} % | {wall:.0f} |")
        sys.stdout.flush()


def ship(cache_dir: str | None) -> xr.Dataset:
    """Solve ``[drift]`` of the case (or read the cache) and write the table to the package."""
    case = load_case("oc3_hywind")
    cfg = case["drift"]
    table, wall = case_table(case, cfg["omega"], cfg["panel_size"], cache_dir)
    print(f"wall time {wall:.0f} s; input_hash {table.attrs['input_hash']}")
    out = ROOT / "src" / "hybridwsi" / "data" / cfg["table"]  # shipped with the package
    to_netcdf(table, out)
    print(f"-> {out} ({out.stat().st_size / 1e3:.0f} kB)")
    return table


def qtf(panel_size: float, mus: list[float], omegas: list[float], seas: list[tuple]) -> None:
    """Quadratic difference-frequency QTF against Newman's ½ (D_i + D_j) (markdown tables)."""
    from hybridwsi.forces.drift import band_of
    from hybridwsi.waves import JONSWAP

    case = load_case("oc3_hywind")
    body = body_from_case(case)
    mass, stiffness, damping = motion_matrices(case)
    cbody = body.capytaine_body(list(drift.ALL_DOFS), symmetric=True, lid=True,
                                **body.mesh_options(panel_size=panel_size))
    start = time.perf_counter()
    t = drift.quadratic_qtf(cbody, omegas, [0.0, *mus],
                            water_depth=case["environment"]["water_depth"], mass=mass,
                            stiffness=stiffness, damping=damping, rho=body.rho, g=body.g,
                            reference_point=body.reference_point,
                            progress=lambda w, sec: print(f"  omega {w:.4g}: {sec:.1f} s",
                                                          flush=True))
    print(f"wall time {time.perf_counter() - start:.0f} s ({cbody.mesh.nb_faces} panels)")
    w = t["omega"].values
    out = xr.Dataset({"qtf_re": t.real, "qtf_im": t.imag}, attrs={
        "source": "scripts/oc3_drift.py qtf (hybridwsi.hydro.drift.quadratic_qtf)",
        "panel_size": panel_size, "units": "N/m^2, N m/m^2 per unit amplitudes^2",
        "note": "quadratic part only (no second-order potential); Hermitian part of the pair"})
    to_netcdf(out, FIGURE.parent / "oc3_drift_qtf.nc")
    for dof in ("Surge", "Pitch"):
        d = t.sel(mu=0.0, influenced_dof=dof).values.real
        print(f"\n{dof}: | ω | μ | Re T | Im T | Newman ½(D(ω)+D(ω+μ)) | Re T / Newman |")
        for m in mus:
            tm = t.sel(mu=m, influenced_dof=dof).values
            dn = 0.5 * (d + np.interp(w + m, w, d, right=np.nan))
            for wi, ti, ni in zip(w, tm, dn):
                print(f"| {wi:.3g} | {m:g} | {ti.real:.4g} | {ti.imag:.4g} | {ni:.4g} | "
                      f"{ti.real / ni:.3f} |")
    print("\n| sea (Hs, Tp) | DOF | μ [rad/s] | S_F quadratic QTF / S_F Newman |")
    for hs, tp in seas:
        wave = JONSWAP(hs=hs, tp=tp)
        lo, hi = band_of(wave)
        for dof in ("Surge", "Pitch"):
            d = t.sel(mu=0.0, influenced_dof=dof).values.real
            for m in mus:
                ok = (w >= lo) & (w + m <= hi) & (w + m <= w[-1])
                s2 = wave.spectrum(w[ok]) * wave.spectrum(w[ok] + m)
                full = np.trapezoid(s2 * np.abs(t.sel(mu=m, influenced_dof=dof).values[ok])**2,
                                    w[ok])
                newman = np.trapezoid(s2 * (0.5 * (d[ok] + np.interp(w[ok] + m, w, d)))**2,
                                      w[ok])
                print(f"| {hs:g} m, {tp:g} s | {dof} | {m:g} | {full / newman:.3f} |")


def summary(table: xr.Dataset) -> None:
    """Far vs near field in surge per frequency (markdown, the table of docs/OC3_HYWIND.md)."""
    far = table["far_field"].sel(influenced_dof="Surge").isel(wave_direction=0).values
    near = table["near_field"].sel(influenced_dof="Surge").isel(wave_direction=0).values
    pitch = table["near_field"].sel(influenced_dof="Pitch").isel(wave_direction=0).values
    heave = table["near_field"].sel(influenced_dof="Heave").isel(wave_direction=0).values
    print("| ω [rad/s] | far field [N/m²] | near field [N/m²] | near/far − 1 | "
          "heave (near) [N/m²] | pitch (near) [N m/m²] |")
    print("|---|---|---|---|---|---|")
    for w, f, n, hv, p in zip(table["omega"].values, far, near, heave, pitch):
        print(f"| {w:g} | {f:.4g} | {n:.4g} | {100 * (n / f - 1):+.2f} % | {hv:.4g} | "
              f"{p:.4g} |")


def figure(table: xr.Dataset, stem: Path = FIGURE) -> None:
    """Surge drift far vs near field with a sea's spectrum, their difference, and the near-field
    heave force and pitch moment (PNG + NetCDF)."""
    import matplotlib.pyplot as plt

    from hybridwsi.waves import JONSWAP

    to_netcdf(table, stem.with_suffix(".nc"))
    w = table["omega"].values
    far = table["far_field"].isel(wave_direction=0)
    near = table["near_field"].isel(wave_direction=0)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6), constrained_layout=True)
    ax = axes[0]
    ax.semilogy(w, np.abs(far.sel(influenced_dof="Surge")), "o-", ms=3, label="far field (Maruo)")
    ax.semilogy(w, np.abs(near.sel(influenced_dof="Surge")), "x--", ms=4,
                label="near field (Pinkster)")
    ax.set_ylabel("|D_surge| [N/m²]")
    ax.set_title("surge mean drift per unit amplitude²")
    sea = JONSWAP(hs=5.0, tp=11.0)
    twin = ax.twinx()
    fine = np.linspace(0.15, 4.0, 400)
    twin.plot(fine, sea.spectrum(fine), color="0.6", lw=1, label="JONSWAP Hs 5 m, Tp 11 s")
    twin.set_ylabel("S(ω) [m² s/rad]", color="0.4")
    twin.legend(fontsize=8, loc="center right")
    ax = axes[1]
    ax.plot(w, 100 * (near.sel(influenced_dof="Surge") / far.sel(influenced_dof="Surge") - 1),
            "o-", ms=3)
    for y in (-5, 5):
        ax.axhline(y, color="r", ls=":", lw=0.8)
    ax.set_ylabel("near / far − 1 [%]")
    ax.set_title("surge: near vs far field")
    ax = axes[2]
    off = w >= 0.25
    ax.plot(w[off], near.sel(influenced_dof="Heave")[off], "o-", ms=3, label="heave [N/m²]")
    ax.plot(w[off], near.sel(influenced_dof="Pitch")[off] / 10.0, "s-", ms=3,
            label="pitch / 10 m [N m/m² / m]")
    ax.set_title("near field: heave, pitch about SWL (ω ≥ 0.25)")
    for ax in axes[:2]:
        ax.axvspan(0.15, 0.25, color="orange", alpha=0.15,
                   label="heave/pitch resonance (near field cancels)")
    for ax in axes:
        ax.set_xlabel("ω [rad/s]")
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8, loc="lower right" if ax is axes[0] else "best")
    fig.suptitle(f"OC3-Hywind mean wave drift, Capytaine indirect, {table.attrs['n_panels']} hull "
                 f"+ {table.attrs['n_lid_panels']} lid panels, head seas, motions with mooring and "
                 "additional damping (parked rotor)")
    fig.savefig(stem.with_suffix(".png"), dpi=110)
    print(f"-> {stem.with_suffix('.png')}, {stem.with_suffix('.nc')}")


def main(argv: list[str] | None = None) -> int:
    parser = Parser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    conv = sub.add_parser("convergence", help="far vs near field for several meshes")
    conv.add_argument("--panel-sizes", type=float, nargs="+", default=[2.0, 1.0, 0.65])
    conv.add_argument("--omega", type=float, nargs="+", default=[0.3, 0.5, 0.7, 1.0, 1.4, 2.0],
                      help="frequencies [rad/s]")
    shp = sub.add_parser("ship", help="solve [drift], write the package table, plot")
    sub.add_parser("plot", help="the summary table and figure of the shipped table")
    qt = sub.add_parser("qtf", help="quadratic difference-frequency QTF vs Newman")
    qt.add_argument("--panel-size", type=float, default=1.0)
    qt.add_argument("--mu", type=float, nargs="+", default=[0.05, 0.21],
                    help="difference frequencies [rad/s] (OC3: surge 0.05, pitch 0.21)")
    qt.add_argument("--omega", type=float, nargs="+",
                    default=[round(0.4 + 0.05 * i, 2) for i in range(25)])
    for p in (conv, shp):
        p.add_argument("--cache-dir", default=None)
    args = parser.parse_args(argv)
    if args.command == "convergence":
        convergence(args.panel_sizes, args.omega, args.cache_dir)
        return 0
    if args.command == "qtf":
        qtf(args.panel_size, args.mu, args.omega, [(5.0, 11.0), (4.0, 10.0)])
        return 0
    case = load_case("oc3_hywind")
    from hybridwsi.forces.drift import load_table

    table = ship(args.cache_dir) if args.command == "ship" else load_table(
        case["drift"]["table"])
    summary(table)
    figure(table)
    return 0


if __name__ == "__main__":
    run_script(main)
