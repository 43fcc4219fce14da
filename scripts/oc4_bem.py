"""OC4-DeepCwind semi-submersible BEM: panel convergence, the shipped coefficient file, its
figure and the comparison with the definition's WAMIT solution.

Resumable: every Capytaine solve goes through :func:`hybridwsi.hydro.bem.compute`, which
checkpoints solved frequencies in its cache (``--cache-dir``), so an interrupted run solves only
what is missing when started again.

    # panel convergence of A11, A33, A55, B33 (table for docs/OC4_SEMI.md)
    python scripts/oc4_bem.py convergence --panel-sizes 2 1.5 1
    # the shipped file (cases/oc4_semi.toml [bem]) and docs/figures/oc4_bem.{png,nc}
    python scripts/oc4_bem.py ship
    # A and B against WAMIT (marin_semi, OpenFAST r-test) at its three finite periods
    python scripts/oc4_bem.py wamit
    # the excitation between the stored headings (0, 30, 60°) against Capytaine every 7.5°
    python scripts/oc4_bem.py headings --panel-size 3

Run with ``nice -n 10`` and ``OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1`` (see hydro/bem/).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import xarray as xr

from bem_tables import convergence_table

from hybridwsi.casemodel import bem_arguments
from hybridwsi.cases import load_case
from hybridwsi.cli import Parser, run_script
from hybridwsi.dofs import coefficient_unit
from hybridwsi.history import read_netcdf, to_netcdf
from hybridwsi.hydro import bem
from hybridwsi.hydro import coefficients as co
from hybridwsi.hydro.formats.wamit import read_radiation

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = ROOT / "src" / "hybridwsi" / "data" / "bem_oc4_semi.nc"
FIGURE = ROOT / "docs" / "figures" / "oc4_bem"
#: the definition's WAMIT solution (trimmed marin_semi, tests/data/oc4_wamit/README.md)
WAMIT_1 = ROOT / "tests" / "data" / "oc4_wamit" / "marin_semi_trimmed.1"
#: DOF pairs (1-based) plotted: added mass and damping
PAIRS = ((1, 1), (3, 3), (5, 5), (6, 6), (1, 5))


def wamit_comparison(ds: xr.Dataset) -> xr.Dataset:
    """WAMIT's A, B (``*_wamit``) and ``ds``'s interpolated linearly in ω at WAMIT's three
    finite frequencies, [ω, influenced, radiating] in SI units."""
    ref = read_radiation(WAMIT_1, rho=float(ds.attrs["rho"]))
    dofs = list(co.dofs(ds))
    out = xr.Dataset(coords={"omega": ref["omega"].values})
    pair = ("omega", "influenced_dof", "radiating_dof")
    for var in ("added_mass", "radiation_damping"):
        out[var] = (pair, np.array([co.at_frequency(ds, var, w, dofs)
                                    for w in ref["omega"].values]))
        out[f"{var}_wamit"] = (pair, ref[var].sel(influenced_dof=dofs, radiating_dof=dofs)
                               .transpose(*pair).values)
    return out


def convergence(panel_sizes: list[float], omegas: list[float], cache_dir: str | None) -> None:
    """Print A11, A33, A55, B33 at ``omegas`` and A(inf) per panel size (markdown table)."""
    convergence_table(bem_arguments(load_case("oc4_semi")), panel_sizes, omegas,
                      [("A11 [kg]", "A", 0, 0), ("A33 [kg]", "A", 2, 2),
                       ("A55 [kg m²]", "A", 4, 4), ("B33 [N s/m]", "B", 2, 2)],
                      cache_dir=cache_dir)


def ship(cache_dir: str | None) -> xr.Dataset:
    """Solve ``[bem]`` of the case (or read it from the cache) and write it to the package
    (``to_netcdf`` writes atomically)."""
    start = time.perf_counter()
    ds = bem.compute(**bem_arguments(load_case("oc4_semi")), cache_dir=cache_dir, n_jobs=1,
                     chunk_size=4)
    to_netcdf(ds, SHIPPED)
    print(f"wall time {time.perf_counter() - start:.0f} s; input_hash "
          f"{ds.attrs['input_hash']} -> {SHIPPED} ({SHIPPED.stat().st_size / 1e6:.2f} MB)")
    return ds


def figure(ds: xr.Dataset, stem: Path = FIGURE) -> None:
    """A and B of :data:`PAIRS` against ω with A(∞) and the WAMIT points (PNG + NetCDF)."""
    import matplotlib.pyplot as plt

    names = list(co.dofs(ds))
    w = co.omega(ds)
    wam = wamit_comparison(ds)
    data = xr.Dataset(coords={"omega": ("omega", w, {"units": "rad/s"}),
                              "omega_wamit": ("omega_wamit", wam["omega"].values,
                                              {"units": "rad/s"})})
    fig, axes = plt.subplots(2, len(PAIRS), figsize=(4 * len(PAIRS), 6.5),
                             constrained_layout=True)
    for col, (i, j) in enumerate(PAIRS):
        di, dj = names[i - 1], names[j - 1]
        for row, (kind, var) in enumerate((("A", "added_mass"), ("B", "radiation_damping"))):
            label = f"{kind}{i}{j}"
            unit = coefficient_unit(di, dj, "mass" if kind == "A" else "damping")
            values = co.matrix_omega(ds, var)[:, i - 1, j - 1]
            ref = wam[f"{var}_wamit"].values[:, i - 1, j - 1]
            data[label] = ("omega", values, {"units": unit, "dofs": f"{di}, {dj}"})
            data[f"{label}_wamit"] = ("omega_wamit", ref, {"units": unit})
            ax = axes[row, col]
            ax.plot(w, values, ".-", ms=2.5, lw=0.8, label="Capytaine (shipped)")
            ax.plot(wam["omega"].values, ref, "o", mfc="none", label="WAMIT marin_semi")
            if kind == "A":
                ax.axhline(co.matrix(ds, "added_mass_inf")[i - 1, j - 1], color="k", ls=":",
                           lw=0.8, label="Capytaine ω → ∞")
            ax.set_title(f"{label} ({di}, {dj})")
            ax.set_xlabel("ω [rad/s]")
            ax.set_ylabel(unit)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("OC4-DeepCwind semi, Capytaine, 200 m depth (deep water for kh ≥ 3), "
                 f"{ds.attrs['n_panels']} hull + {ds.attrs['n_lid_panels']} lid panels; "
                 "WAMIT: OpenFAST r-test marin_semi (columns, pontoons, braces)")
    data.attrs = {"source": "scripts/oc4_bem.py from src/hybridwsi/data/bem_oc4_semi.nc and "
                            "tests/data/oc4_wamit/marin_semi_trimmed.1", "input_hash": ds.attrs["input_hash"]}
    to_netcdf(data, stem.with_suffix(".nc"))
    fig.savefig(stem.with_suffix(".png"), dpi=110)
    print(f"-> {stem.with_suffix('.png')}, {stem.with_suffix('.nc')}")


def wamit(ds: xr.Dataset) -> None:
    """Markdown table: A and B of the shipped file against WAMIT at its finite periods."""
    cmp = wamit_comparison(ds)
    print("| ω [rad/s] | term | Capytaine | WAMIT | difference |")
    print("|---|---|---|---|---|")
    for k, w in enumerate(cmp["omega"].values):
        for var, kind in (("added_mass", "A"), ("radiation_damping", "B")):
            for i, j in PAIRS:
                ours = float(cmp[var].values[k, i - 1, j - 1])
                ref = float(cmp[f"{var}_wamit"].values[k, i - 1, j - 1])
                print(f"| {w:.4f} | {kind}{i}{j} | {ours:.5e} | {ref:.5e} | "
                      f"{100 * (ours / ref - 1):+.2f} % |")


def headings(panel_size: float, omegas: list[float], cache_dir: str | None) -> None:
    """Markdown table: the excitation at headings every 7.5° (0–90°) solved by Capytaine on
    the ``panel_size`` mesh against :func:`hybridwsi.waves.excitation_transfer` from the same
    solve's 0°, 30°, 60° alone (the shipped file's headings): worst difference over the
    headings, in % of the DOF's largest |F| at that frequency."""
    from hybridwsi.casemodel import body_from_case
    from hybridwsi.waves import excitation_transfer

    heads = np.radians(np.arange(0.0, 90.1, 7.5))
    t0 = time.time()
    ds = bem.compute(body_from_case(load_case("oc4_semi")), np.asarray(omegas, dtype=float),
                     water_depth=np.inf, wave_directions=tuple(heads), panel_size=panel_size,
                     cache_dir=cache_dir, progress=False)
    print(f"solved in {time.time() - t0:.0f} s ({ds.attrs['n_panels']} panels)")
    dofs = [str(d) for d in ds["influenced_dof"].values]
    keep = [i for i, h in enumerate(np.degrees(heads)) if round(h, 6) in (0.0, 30.0, 60.0)]
    _, interp = excitation_transfer(ds.isel(wave_direction=keep), dofs, heads)
    solved = ds["excitation_force"].transpose("omega", "wave_direction", "influenced_dof").values
    print("| ω [rad/s] | " + " | ".join(dofs) + " |")
    print("|---" * (len(dofs) + 1) + "|")
    for k, w in enumerate(ds["omega"].values):
        err = np.abs(interp[k] - solved[k]).max(axis=0) / np.abs(solved[k]).max(axis=0)
        print(f"| {w:.2f} | " + " | ".join(f"{100 * e:.2f} %" for e in err) + " |")


def main(argv: list[str] | None = None) -> int:
    parser = Parser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    conv = sub.add_parser("convergence", help="panel-convergence table")
    conv.add_argument("--panel-sizes", type=float, nargs="+", default=[2.0, 1.5, 1.0])
    conv.add_argument("--omega", type=float, nargs="+", default=[0.1, 0.5, 0.79, 1.26],
                      help="frequencies [rad/s]: low, and WAMIT's 12.57 s, 7.95 s, 4.99 s")
    shp = sub.add_parser("ship", help="solve [bem], copy to the package, plot")
    sub.add_parser("plot", help="only the figure of the shipped file")
    sub.add_parser("wamit", help="A, B of the shipped file against WAMIT")
    hd = sub.add_parser("headings", help="excitation between the stored headings vs solved")
    hd.add_argument("--panel-size", type=float, default=3.0)
    hd.add_argument("--omega", type=float, nargs="+", default=[0.3, 0.6, 0.9, 1.2])
    for p in (conv, shp, hd):
        p.add_argument("--cache-dir", default=None)
    args = parser.parse_args(argv)
    if args.command == "convergence":
        convergence(args.panel_sizes, args.omega, args.cache_dir)
    elif args.command == "ship":
        figure(ship(args.cache_dir))
    elif args.command == "headings":
        headings(args.panel_size, args.omega, args.cache_dir)
    elif args.command == "wamit":
        wamit(read_netcdf(SHIPPED))
    else:
        figure(read_netcdf(SHIPPED))
    return 0


if __name__ == "__main__":
    run_script(main)
