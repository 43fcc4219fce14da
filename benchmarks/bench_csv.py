"""CSV reader at scale (issue 16 item 6): our ``read_csv`` beside ``pandas.read_csv``.

1. A 2.35 M-row CSV (time, z, zdot, zddot, F_tot; ~220 MB) read by
   :func:`hybridwsi.history.read_csv` (a validated TimeHistory, floats correctly rounded:
   Apache Arrow's CSV reader) and by ``pandas.read_csv`` on the same file in the same
   process, ``--repeat`` rounds alternating them (``benchmarks/timing.py``; target: ours within 2x of pandas' default parser, which
   is not correctly rounded: the benchmark prints how many of its floats differ and by how
   many units in the last place; pandas with ``float_precision="round_trip"`` is shown too).
2. A 10 000-column CSV with the force column named (target: seconds).

The files are generated in a temporary folder and removed. Run::

    PYTHONPATH=src python benchmarks/bench_csv.py [--rows 2350000] [--columns 10000]
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import REPEAT, Figure, compare, conditions  # noqa: E402


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


def main() -> None:
    import pandas as pd

    from hybridwsi.history import read_csv

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rows", type=int, default=2_350_000)
    ap.add_argument("--columns", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=REPEAT, help="alternating rounds")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        long_csv = Path(tmp) / "long.csv"
        write_long(long_csv, args.rows)
        size = long_csv.stat().st_size / 1e6
        print(f"long CSV: {args.rows} rows, {size:.0f} MB")
        last = {}  # the last result of each reader, for the checks below

        def keep(name, read):
            return Figure(lambda: last.__setitem__(name, read()))
        t = compare(keep("fast", lambda: pd.read_csv(long_csv, engine="c")),
                    {"ours": keep("ours", lambda: read_csv(long_csv, forces=["F_tot"])),
                     "round_trip": keep("exact", lambda: pd.read_csv(
                         long_csv, engine="c", float_precision="round_trip"))},
                    repeat=args.repeat)  # warm-up: imports (Arrow), the file in the page cache
        exact, fast, ds = last["exact"], last["fast"], last["ours"]
        assert ds.sizes["time"] == args.rows
        print(f"  pandas.read_csv (default float parser):  {t['baseline'].time_text()}")
        print(f"  pandas.read_csv (round_trip floats):     {t['round_trip'].time_text()}")
        print(f"  hybridwsi read_csv (validated history):  {t['ours'].time_text()}")
        print(f"  ratio ours / pandas default: {t['ours'].ratio_text()} (target <= 2); "
              f"ours / pandas round_trip: "
              f"{t['ours'].median / t['round_trip'].median:.2f} (medians)")
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
            ds = read_csv(wide_csv, forces=["F_tot"])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the note above, once per read
            t = compare(Figure(lambda: pd.read_csv(wide_csv, engine="c")),
                        {"ours": Figure(lambda: read_csv(wide_csv, forces=["F_tot"]))},
                        repeat=args.repeat, warmup=False)
        print(f"  hybridwsi read_csv --force-column F_tot: {t['ours'].time_text()} "
              f"({len(ds.data_vars)} variables; {caught[0].message if caught else 'no note'})")
        print(f"  pandas.read_csv (all columns):           {t['baseline'].time_text()}; "
              f"ours / pandas {t['ours'].ratio_text()}")
    print(conditions(repeat=args.repeat))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory of the process: {peak:.0f} MB")


if __name__ == "__main__":
    main()
