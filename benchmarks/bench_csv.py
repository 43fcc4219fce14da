"""CSV reader at scale (issue 16 item 6): our ``read_csv`` beside ``pandas.read_csv``.

1. A 2.35 M-row CSV (time, z, zdot, zddot, F_tot; ~220 MB) read by
   :func:`hybridwsi.history.read_csv` (a validated TimeHistory, floats correctly rounded:
   Apache Arrow's CSV reader) and by ``pandas.read_csv`` on the same file in the same
   process, best of two runs each (target: ours within 2x of pandas' default parser, which
   is not correctly rounded: the benchmark prints how many of its floats differ and by how
   many units in the last place; pandas with ``float_precision="round_trip"`` is shown too).
2. A 10 000-column CSV with the force column named (target: seconds).

The files are generated in a temporary folder and removed. Run::

    PYTHONPATH=src python benchmarks/bench_csv.py [--rows 2350000] [--columns 10000]
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np


def write_long(path: Path, rows: int) -> None:
    """A heave decay sampled at 1 kHz: time [s], z [m], zdot, zddot, F_tot [N]."""
    t = np.arange(rows) * 1e-3
    w, m = 2 * np.pi / 0.76, 7.06
    z = 0.03 * np.exp(-0.05 * t) * np.cos(w * t)
    zdot = np.gradient(z, t)
    zddot = np.gradient(zdot, t)
    data = np.column_stack([t, z, zdot, zddot, m * zddot])
    with open(path, "w") as f:
        f.write("time [s],z [m],zdot [m/s],zddot [m/s^2],F_tot [N]\n")
        np.savetxt(f, data, delimiter=",", fmt="%.15g")


def write_wide(path: Path, columns: int, rows: int = 2000) -> None:
    """time, z, F_tot and ``columns - 3`` other numeric columns."""
    t = np.arange(rows) * 0.01
    other = np.random.default_rng(0).standard_normal((rows, columns - 3))
    data = np.column_stack([t, 0.01 * np.sin(6 * t), 7.06 * np.cos(6 * t), other])
    header = ["time [s]", "z [m]", "F_tot [N]"] + [f"probe{k}" for k in range(columns - 3)]
    with open(path, "w") as f:
        f.write(",".join(header) + "\n")
        np.savetxt(f, data, delimiter=",", fmt="%.8g")


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def main() -> None:
    import pandas as pd

    from hybridwsi.history import read_csv

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", type=int, default=2_350_000)
    ap.add_argument("--columns", type=int, default=10_000)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        long_csv = Path(tmp) / "long.csv"
        write_long(long_csv, args.rows)
        size = long_csv.stat().st_size / 1e6
        print(f"long CSV: {args.rows} rows, {size:.0f} MB")
        exact, t_pd_rt = timed(lambda: pd.read_csv(long_csv, engine="c",
                                                   float_precision="round_trip"))
        t_pd, t_ours = np.inf, np.inf
        for _ in range(2):  # interleaved, best of two: the machine may be shared
            fast, t = timed(lambda: pd.read_csv(long_csv, engine="c"))
            t_pd = min(t_pd, t)
            ds, t = timed(lambda: read_csv(long_csv, forces=["F_tot"]))
            t_ours = min(t_ours, t)
        assert ds.sizes["time"] == args.rows
        print(f"  pandas.read_csv (default float parser):  {t_pd:7.2f} s")
        print(f"  pandas.read_csv (round_trip floats):     {t_pd_rt:7.2f} s")
        print(f"  hybridwsi read_csv (validated history):  {t_ours:7.2f} s")
        print(f"  ratio ours / pandas default: {t_ours / t_pd:.2f} (target <= 2); "
              f"ours / pandas round_trip: {t_ours / t_pd_rt:.2f}")
        ref = exact.to_numpy()
        ours = np.column_stack([ds["time"].values, ds["z"].values[:, 0]])
        ulp = np.abs(fast.to_numpy() - ref) / np.spacing(np.abs(ref))
        print(f"  floats differing from the correctly rounded value: ours "
              f"{np.count_nonzero(ours != ref[:, :2])}, pandas default "
              f"{np.count_nonzero(ulp)} of {ref.size} (up to {ulp.max():.0f} ulp)")
        long_csv.unlink()

        wide_csv = Path(tmp) / "wide.csv"
        write_wide(wide_csv, args.columns)
        print(f"wide CSV: {args.columns} columns, {wide_csv.stat().st_size / 1e6:.0f} MB")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ds, t_wide = timed(lambda: read_csv(wide_csv, forces=["F_tot"]))
        print(f"  hybridwsi read_csv --force-column F_tot: {t_wide:7.2f} s "
              f"({len(ds.data_vars)} variables; {caught[0].message if caught else 'no note'})")
        _, t_wide_pd = timed(lambda: pd.read_csv(wide_csv, engine="c"))
        print(f"  pandas.read_csv (all columns):           {t_wide_pd:7.2f} s")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory of the process: {peak:.0f} MB")


if __name__ == "__main__":
    main()
