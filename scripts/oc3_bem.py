"""OC3-Hywind BEM: the panel-convergence table, the shipped coefficient file and its figure.

Resumable: every Capytaine solve goes through :func:`hybridwsi.hydro.bem.compute`, which
checkpoints solved frequencies in its cache (``--cache-dir``), so an interrupted run solves only
what is missing when started again.

    # panel convergence of A33, A55, B11 (table for docs/OC3_HYWIND.md)
    python scripts/oc3_bem.py convergence --panel-sizes 2 1 0.5
    # the shipped file (cases/oc3_hywind.toml [bem]) and docs/figures/oc3_bem.{png,nc}
    python scripts/oc3_bem.py ship --jobs 1

Run with ``OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1`` (see hydro/bem/).
"""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import xarray as xr

from bem_tables import convergence_table

from hybridwsi.casemodel import bem_arguments
from hybridwsi.cases import load_case
from hybridwsi.cli import Parser, run_script
from hybridwsi.history import read_netcdf, to_netcdf
from hybridwsi.hydro import bem
from hybridwsi.hydro import coefficients as co

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = ROOT / "src" / "hybridwsi" / "data" / "bem_oc3_hywind.nc"
FIGURE = ROOT / "docs" / "figures" / "oc3_bem"
#: (DOF pair, kind) plotted and written to the figure's NetCDF
CURVES = ((("Surge", "Surge"), "A"), (("Heave", "Heave"), "A"), (("Pitch", "Pitch"), "A"),
          (("Surge", "Pitch"), "A"), (("Surge", "Surge"), "B"), (("Heave", "Heave"), "B"),
          (("Pitch", "Pitch"), "B"))


def convergence(panel_sizes: list[float], omegas: list[float], cache_dir: str | None,
                jobs: int) -> None:
    """Print A33, A55, B11 at ``omegas`` and A(inf) for each panel size (markdown table)."""
    convergence_table(bem_arguments(load_case("oc3_hywind")), panel_sizes, omegas,
                      [("A33 [kg]", "A", 1, 1), ("A55 [kg m²]", "A", 2, 2),
                       ("B11 [N s/m]", "B", 0, 0)], dofs=("Surge", "Heave", "Pitch"),
                      cache_dir=cache_dir, jobs=jobs)


def ship(cache_dir: str | None, jobs: int) -> xr.Dataset:
    """Solve ``[bem]`` of the case (or read it from the cache) and copy it to the package."""
    start = time.perf_counter()
    ds = bem.compute(**bem_arguments(load_case("oc3_hywind")), cache_dir=cache_dir, n_jobs=jobs)
    print(f"wall time {time.perf_counter() - start:.0f} s; input_hash {ds.attrs['input_hash']}")
    tmp = SHIPPED.with_suffix(".tmp.nc")
    to_netcdf(ds, tmp)
    shutil.move(tmp, SHIPPED)
    print(f"-> {SHIPPED} ({SHIPPED.stat().st_size / 1e6:.2f} MB)")
    return ds


def curves(ds: xr.Dataset) -> xr.Dataset:
    """The plotted coefficients as one Dataset (variables ``A11``, ``B33``…, SI units)."""
    names = list(co.dofs(ds))
    out = xr.Dataset(coords={"omega": ("omega", co.omega(ds), {"units": "rad/s"})})
    from hybridwsi.dofs import coefficient_unit

    for (i, j), kind in CURVES:
        name = "added_mass" if kind == "A" else "radiation_damping"
        m = co.matrix_omega(ds, name)[:, names.index(i), names.index(j)]
        label = f"{kind}{names.index(i) + 1}{names.index(j) + 1}"
        unit = coefficient_unit(i, j, "mass" if kind == "A" else "damping")
        out[label] = ("omega", m, {"units": unit, "dofs": f"{i}, {j}"})
        if kind == "A":
            out[f"{label}_inf"] = ((), co.matrix(ds, "added_mass_inf")[names.index(i),
                                                                       names.index(j)])
    out.attrs = {"source": "scripts/oc3_bem.py from src/hybridwsi/data/bem_oc3_hywind.nc",
                 "input_hash": ds.attrs["input_hash"]}
    return out


def figure(ds: xr.Dataset, stem: Path = FIGURE) -> None:
    """A11, A33, A55, A15 and B11, B33, B55 against ω (PNG + NetCDF)."""
    import matplotlib.pyplot as plt

    data = curves(ds)
    to_netcdf(data, stem.with_suffix(".nc"))
    fig, axes = plt.subplots(2, 4, figsize=(15, 6.5), constrained_layout=True)
    w = data["omega"].values
    for ax, name in zip(axes.ravel(), [v for v in data.data_vars if not v.endswith("_inf")]):
        ax.plot(w, data[name].values, ".-", ms=2.5, lw=0.8)
        if f"{name}_inf" in data:
            ax.axhline(float(data[f"{name}_inf"]), color="k", ls=":", lw=0.8, label="ω → ∞")
            ax.legend(fontsize=8)
        ax.set_title(f"{name} ({data[name].attrs['dofs']})")
        ax.set_xlabel("ω [rad/s]")
        ax.set_ylabel(data[name].attrs["units"])
        ax.grid(alpha=0.3)
    axes.ravel()[-1].set_axis_off()
    fig.suptitle("OC3-Hywind spar, Capytaine, 320 m depth (deep water for kh ≥ 3), "
                 f"{ds.attrs['n_panels']} hull + {ds.attrs['n_lid_panels']} lid panels")
    fig.savefig(stem.with_suffix(".png"), dpi=110)
    print(f"-> {stem.with_suffix('.png')}, {stem.with_suffix('.nc')}")


def main(argv: list[str] | None = None) -> int:
    parser = Parser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    conv = sub.add_parser("convergence", help="panel-convergence table")
    conv.add_argument("--panel-sizes", type=float, nargs="+", default=[2.0, 1.0, 0.5])
    conv.add_argument("--omega", type=float, nargs="+", default=[0.05, 0.2, 0.21, 1.0, 2.0, 3.5],
                      help="frequencies [rad/s] (surge, heave, pitch natural frequencies, ...)")
    shp = sub.add_parser("ship", help="solve [bem], copy to the package, plot")
    plot = sub.add_parser("plot", help="only the figure of the shipped file")
    for p in (conv, shp):
        p.add_argument("--cache-dir", default=None)
        p.add_argument("--jobs", type=int, default=1)
    del plot
    args = parser.parse_args(argv)
    if args.command == "convergence":
        convergence(args.panel_sizes, args.omega, args.cache_dir, args.jobs)
    elif args.command == "ship":
        figure(ship(args.cache_dir, args.jobs))
    else:
        figure(read_netcdf(SHIPPED))
    return 0


if __name__ == "__main__":
    run_script(main)
