"""The bad-input corpus: bad files and bad options for every command (issue 16).

:func:`make_corpus` writes the bad files (and the few good files the bad options need) into a
folder; :func:`cases` lists the command lines to run over them, each with the files it reads.
Every case must end with exit status 2, exactly one stderr line ``error: ...``, no traceback,
no output left behind and its inputs unchanged (``tests/test_corpus.py``).

Run ``python tests/corpus/make_corpus.py DIR`` to write the files for a look by hand.
"""

from __future__ import annotations

import json
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
TESTS = HERE.parent
DATA = TESTS / "data"

#: a valid 1-DOF heave history as CSV text (the body of most bad CSVs)
_T = np.round(np.arange(0.0, 2.0, 0.01), 10)
_Z = 0.01 * np.sin(2 * np.pi * _T / 0.75)
_F = -692.2 * _Z


def _csv(rows: list[list], header: str = "time [s],z [m],F_tot [N]", meta: str = "") -> str:
    lines = [meta] if meta else []
    lines.append(header)
    lines += [",".join(str(v) for v in r) for r in rows]
    return "\n".join(lines) + "\n"


def _good_rows() -> list[list]:
    return [[f"{t:.2f}", f"{z:.8g}", f"{f:.8g}"] for t, z, f in zip(_T, _Z, _F)]


def _with(row: int, col: int, value: str) -> list[list]:
    rows = _good_rows()
    rows[row][col] = value
    return rows


def _text_files() -> dict[str, str]:
    """Bad CSV/text files: name -> content."""
    good = _good_rows()
    f: dict[str, str] = {
        "nan_z.csv": _csv(_with(5, 1, "nan")),
        "inf_z.csv": _csv(_with(5, 1, "inf")),
        "neg_inf_force.csv": _csv(_with(7, 2, "-inf")),
        "nan_time.csv": _csv(_with(9, 0, "nan")),
        "non_numeric.csv": _csv(_with(4, 1, "abc")),
        "empty_cell.csv": _csv(_with(4, 1, "")),
        "unsorted_time.csv": _csv(good[:10] + [good[12], good[11], good[10]] + good[13:]),
        "duplicated_time.csv": _csv(good[:10] + [good[9]] + good[10:]),
        "irregular_time.csv": _csv([r for i, r in enumerate(good) if i % 7 and i % 11]),
        "constant_time.csv": _csv([["1.0", r[1], r[2]] for r in good]),
        "short_row.csv": _csv(good[:20] + [good[20][:2]] + good[21:]),
        "long_row.csv": _csv(good[:20] + [good[20] + ["9"]] + good[21:]),
        "header_only.csv": _csv([]),
        "comments_only.csv": "# a comment\n# another\n",
        "blank_lines.csv": "\n\n   \n\n",
        "too_few_samples.csv": _csv(good[:2]),
        "one_column.csv": _csv([[r[0]] for r in good], header="time [s]"),
        "missing_time.csv": _csv([r[1:] for r in good], header="z [m],F_tot [N]"),
        "unknown_unit.csv": _csv(good, header="time [s],z [furlong],F_tot [N]"),
        "unknown_time_unit.csv": _csv(good, header="time [fortnight],z [m],F_tot [N]"),
        "negative_mass_header.csv": _csv(good, meta="# mass [kg]: -7"),
        "nan_mass_header.csv": _csv(good, meta="# mass [kg]: nan"),
        "zero_mass_header.csv": _csv(good, meta="# mass [kg]: 0"),
        "huge_z.csv": _csv([[r[0], "1e300", r[2]] for r in good]),
        "huge_force.csv": _csv([[r[0], r[1], "1e300"] for r in good]),
        "all_zero_motion.csv": _csv([[r[0], "0", r[2]] for r in good]),
        "unknown_dof_header.csv": _csv(good, meta="# dof: Wobble"),
        "dof_count_mismatch.csv": _csv(good, meta="# dof: Surge,Pitch"),
        "mixed_separators.csv": _csv([[";".join(r[:2]), r[2]] for r in good]),
        "dsph_nan.csv": (DATA / "dsph_floatinginfo.csv").read_text().replace(
            "-0.0005562362976", "nan", 1),
        "dsph_two_rows.csv": "\n".join(
            (DATA / "dsph_floatinginfo.csv").read_text().splitlines()[:3]) + "\n",
        "kramer_text.csv": "t_over_Te0,x3_over_H0m_mean,ci95_lower,ci95_upper,t_s_derived\n"
                           "-0.48,1.0,0.99,1.0,abc\n-0.47,1.0,0.99,1.0,-0.36\n",
        "network.json": json.dumps({"class": "ForceNetwork", "hidden": [10**9, 10**9],
                                    "window": 10**6, "inputs": ["z"]}),
        "wamit_garbage.1": "this is not\na WAMIT file\n",
        "wamit_short_rows.1": "-1 3 3\n0 3 3 1.0\n1.0 3 3\n",
        "wamit_nan.1": "-1 3 3 nan\n0 3 3 1.0\n1.0 3 3 1.0 2.0\n",
        "fake.h5": "not an HDF5 file\n",
        "fake.nc": "time,z\n0,1\n",
        "body_unknown_type.json": '{"type": "Barge"}',
        "body_negative_radius.json": '{"type": "FloatingSphere", "radius": -1, "mass": 7}',
        "body_nan_mass.json": '{"type": "FloatingSphere", "radius": 0.15, "mass": NaN}',
        "body_array.json": "[1, 2, 3]",
        "body_not_json.json": "{type: sphere",
        "body_missing_fields.json": '{"type": "AxisymmetricBody"}',
        "force_no_column.csv": "time [s],eta [m]\n0,0\n5,1\n",
        "force_two_columns.csv": "time [s],F [N],force [N]\n0,0,0\n5,1,1\n",
        "force_nan.csv": "time [s],F [N]\n0,0\n1,nan\n5,1\n",
        "force_too_short.csv": "time [s],F [N]\n0,0\n0.5,1\n",
    }
    return f


def _netcdf_files(folder: Path) -> dict[str, Path]:
    """Bad NetCDF files (histories and coefficients)."""
    import xarray as xr

    from hybridwsi.commands.diagnose import example_history
    from hybridwsi.files import to_netcdf

    good = example_history().isel(time=slice(0, 600))
    out: dict[str, Path] = {}

    def put(name: str, ds: xr.Dataset) -> None:
        out[name] = to_netcdf(ds, folder / name)

    put("wrong_variables.nc", xr.Dataset({"a": ("x", np.arange(5.0)), "b": ("x", np.ones(5))}))
    z = good["z"].copy()
    z[10, 0] = np.nan
    put("nan_z.nc", good.assign(z=z))
    put("unsorted_time.nc", good.isel(time=np.r_[0:10, 11, 10, 12:600]))
    put("no_z.nc", good.drop_vars(["z", "zdot", "zddot"]))
    put("wrong_unit_z.nc", good.assign(z=good["z"].assign_attrs(units="furlong")))
    put("wrong_unit_force.nc", good.assign(F_tot=good["F_tot"].assign_attrs(units="kelvin")))
    unitless = good.copy()
    for name in unitless.data_vars:
        unitless[name].attrs.pop("units", None)
        unitless[name].attrs.pop("units_per_dof", None)
    put("unitless.nc", unitless)
    put("negative_mass.nc", good.assign(mass=-good["mass"]))
    huge = good.copy()
    huge["z"] = huge["z"] * 1e300
    put("huge_z.nc", huge)
    trunc = folder / "truncated.nc"
    data = (folder / "nan_z.nc").read_bytes()
    trunc.write_bytes(data[: len(data) // 3])
    out["truncated.nc"] = trunc
    (folder / "empty.nc").write_bytes(b"")
    out["empty.nc"] = folder / "empty.nc"
    (folder / "hdf5_magic_only.nc").write_bytes(b"\x89HDF\r\n\x1a\n" + b"\x00" * 100)
    out["hdf5_magic_only.nc"] = folder / "hdf5_magic_only.nc"
    sys.path.insert(0, str(TESTS))
    import synthetic_hydro as sh

    co = sh.coefficients(np.linspace(0.1, 40.0, 40))
    a = co["added_mass"].copy()
    a[3] = np.nan
    put("coeffs_nan.nc", co.assign(added_mass=a))
    put("coeffs_no_stiffness.nc", co.drop_vars("hydrostatic_stiffness"))
    return out


def _binary_files() -> dict[str, bytes]:
    rng = np.random.default_rng(16)
    good = _csv(_good_rows())
    return {
        "binary_garbage.csv": rng.integers(0, 256, 4096, dtype=np.uint8).tobytes(),
        "binary_nul.csv": good.encode()[:200] + b"\x00\x01\x02" + good.encode()[200:],
        "utf16.csv": good.encode("utf-16"),
        "utf32.csv": good.encode("utf-32"),
        "latin1_garbage.csv": bytes(range(128, 256)) * 20,
    }


def _filesystem(folder: Path) -> list[str]:
    """Paths that are not regular files: links, folders, a missing file."""
    (folder / "loop_a.csv").symlink_to(folder / "loop_b.csv")
    (folder / "loop_b.csv").symlink_to(folder / "loop_a.csv")
    (folder / "dangling.csv").symlink_to(folder / "nowhere" / "x.csv")
    (folder / "directory.csv").mkdir()
    fake = folder / "fake.zarr"
    fake.mkdir()
    (fake / ".zgroup").write_text("{not json")
    (folder / "file.zarr").write_text("not a store\n")
    os.mkfifo(folder / "fifo.csv")
    return ["loop_a.csv", "dangling.csv", "directory.csv", "fake.zarr", "file.zarr",
            "fifo.csv", "does_not_exist.csv"]


def _good_files(folder: Path) -> None:
    """The valid inputs the bad options are combined with."""
    from hybridwsi.commands.diagnose import example_history
    from hybridwsi.files import to_netcdf

    sys.path.insert(0, str(TESTS))
    import synthetic_hydro as sh

    to_netcdf(example_history().isel(time=slice(0, 1000)), folder / "good_hist.nc")
    to_netcdf(example_history().isel(time=slice(1000, 2000)), folder / "good_hist2.nc")
    to_netcdf(sh.coefficients(np.linspace(0.1, 40.0, 60)), folder / "good_coeffs.nc")
    (folder / "good_force.csv").write_text("time [s],F [N]\n0,0\n100,1\n")
    (folder / "good_hist.csv").write_text(_csv(_good_rows()))
    # a case file with one unknown key (the bad-option cases of --case read it)
    (folder / "case_unknown_key.toml").write_text(
        '[body]\ntype = "sphere"\nradius = 0.15\ncolour = "red"\n')


def make_corpus(folder: str | os.PathLike) -> list[str]:
    """Write the corpus into ``folder``; return the names of the bad files."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    names = []
    for name, text in _text_files().items():
        (folder / name).write_text(text, encoding="utf-8")
        names.append(name)
    for name, data in _binary_files().items():
        (folder / name).write_bytes(data)
        names.append(name)
    names += list(_netcdf_files(folder))
    names += _filesystem(folder)
    _good_files(folder)
    return sorted(names)


# ----------------------------------------------------------------------------- the cases

#: which bad files each file-taking command line is run over
HISTORY_FILES = "history"  # every bad file: any of them is a bad history
COEFF_FILES = "coeffs"  # every bad file except those that are valid coefficient-free inputs
BODY_FILES = "body"
FORCE_FILES = "force"


@dataclass
class Case:
    """One command line of the corpus: ``argv`` (relative paths resolve in the corpus folder,
    ``{out}`` in a fresh per-case folder), the id shown by pytest and the corpus files it reads."""

    id: str
    argv: list[str]
    inputs: list[str] = field(default_factory=list)
    timeout: float = 90.0


#: commands that read a history FILE: argv template with {f} for the bad file
HISTORY_COMMANDS = {
    "diagnose": ["diagnose", "{f}"],
    "import": ["import", "{f}", "--out", "{out}/h.nc"],
    "select": ["select", "{f}", "--json", "{out}/s.json"],
    "hybrid": ["hybrid", "{f}", "good_hist2.nc", "--out", "{out}/net", "--epochs", "1"],
    "reproduce": ["reproduce", "--quick", "--no-decay", "--no-hybrid", "--sph-history", "{f}",
                  "--out", "{out}/results"],
}
#: commands that read a coefficient FILE
COEFF_COMMANDS = {
    "simulate": ["simulate", "--coeffs", "{f}", "--decay", "0.02", "--duration", "1",
                 "--out", "{out}/h.nc"],
    "sweep": ["sweep", "--coeffs", "{f}", "--hs", "0.05", "--tp", "1", "--duration", "1",
              "--out", "{out}/sweep"],
    "coeffs": ["coeffs", "{f}", "--out", "{out}/c.nc"],
    "select-coeffs": ["select", "good_hist.nc", "--coeffs", "{f}", "--no-reconstruct"],
    "diagnose-coeffs": ["diagnose", "--example", "--known", "hydrostatic", "--coeffs", "{f}"],
}
#: (command id, file) pairs where the file is valid input: converting zero motion is fine
#: (only a regression of it is meaningless); coefficients without C can be converted, and
#: select then leaves out the hydrostatic candidate
NOT_BAD = {("import", "all_zero_motion.csv"), ("coeffs", "coeffs_no_stiffness.nc"),
           ("select-coeffs", "coeffs_no_stiffness.nc")}
#: seconds after which a case counts as hung (reproduce runs BEM and Cummins once an input
#: has been accepted: a refusal must come long before)
TIMEOUT = {"reproduce": 30.0}
BODY_COMMAND = ["bem", "--body", "{f}", "--out", "{out}/c.nc", "--no-cache", "--quiet"]
FORCE_COMMAND = ["simulate", "--coeffs", "good_coeffs.nc", "--external-force", "{f}",
                 "--duration", "1", "--out", "{out}/h.nc", "--quiet"]

#: bad options: id -> argv (good inputs from the corpus folder)
BAD_OPTIONS: dict[str, list[str]] = {
    # the root parser
    "root-unknown-command": ["frobnicate"],
    "root-unknown-option": ["--bogus"],
    "diagnose-unknown-option": ["diagnose", "--example", "--bogus"],
    # diagnose
    "diagnose-no-input": ["diagnose"],
    "diagnose-file-and-example": ["diagnose", "good_hist.nc", "--example"],
    "diagnose-target-dt-0": ["diagnose", "--example", "--target-dt", "0"],
    "diagnose-target-dt-nan": ["diagnose", "--example", "--target-dt", "nan"],
    "diagnose-mass-neg": ["diagnose", "--example", "--mass", "-1"],
    "diagnose-mass-nan": ["diagnose", "--example", "--mass", "nan"],
    "diagnose-force-accuracy-0": ["diagnose", "--example", "--force-accuracy", "0"],
    "diagnose-savgol-window-0": ["diagnose", "good_hist.csv", "--savgol-window", "0"],
    "diagnose-savgol-window-abc": ["diagnose", "good_hist.csv", "--savgol-window", "abc"],
    "diagnose-fix-alpha-inf": ["diagnose", "--example", "--fix-alpha", "inf"],
    "diagnose-known-unknown": ["diagnose", "--example", "--known", "spring=3"],
    "diagnose-force-column-absent": ["diagnose", "--example", "--force-column", "F_nope"],
    "diagnose-format-bad": ["diagnose", "good_hist.csv", "--format", "excel"],
    "diagnose-dofs-unknown": ["diagnose", "--example", "--dofs", "Wobble"],
    "diagnose-dofs-absent": ["diagnose", "good_hist.nc", "--dofs", "Pitch"],
    "diagnose-json-is-input": ["diagnose", "good_hist.csv", "--json", "good_hist.csv"],
    "diagnose-json-dev-full": ["diagnose", "--example", "--json", "/dev/full"],
    "diagnose-json-directory": ["diagnose", "--example", "--json", "directory.csv"],
    "diagnose-json-under-file": ["diagnose", "--example", "--json", "good_force.csv/r.json"],
    # import
    "import-out-suffix": ["import", "good_hist.csv", "--out", "{out}/h.txt"],
    "import-out-is-input": ["import", "good_hist.csv", "--out", "good_hist.csv"],
    "import-out-dev-full": ["import", "good_hist.csv", "--out", "/dev/full"],
    "import-mass-neg": ["import", "good_hist.csv", "--mass", "-7", "--out", "{out}/h.nc"],
    "import-mass-zero": ["import", "good_hist.csv", "--mass", "0", "--out", "{out}/h.nc"],
    "import-dofs-unknown": ["import", "good_hist.csv", "--dofs", "Wobble", "--out", "{out}/h.nc"],
    "import-dofs-repeated": ["import", "good_hist.csv", "--dofs", "Heave,heave", "--out",
                             "{out}/h.nc"],
    "import-mkbound-neg": ["import", "good_hist.csv", "--mkbound", "-1", "--out", "{out}/h.nc"],
    "import-out-missing": ["import", "good_hist.csv"],
    # bem
    "bem-panels-huge": ["bem", "--panels", "100000000", "--out", "{out}/c.nc", "--no-cache"],
    "bem-panels-zero": ["bem", "--panels", "0", "--out", "{out}/c.nc"],
    "bem-panels-abc": ["bem", "--panels", "abc", "--out", "{out}/c.nc"],
    "bem-panels-and-size": ["bem", "--panels", "400", "--panel-size", "0.1", "--out",
                            "{out}/c.nc"],
    "bem-omega-min-neg": ["bem", "--omega-min", "-1", "--out", "{out}/c.nc"],
    "bem-omega-order": ["bem", "--omega-min", "5", "--omega-max", "1", "--out", "{out}/c.nc"],
    "bem-n-omega-1": ["bem", "--n-omega", "1", "--out", "{out}/c.nc"],
    "bem-depth-zero": ["bem", "--depth", "0", "--out", "{out}/c.nc"],
    "bem-depth-nan": ["bem", "--depth", "nan", "--out", "{out}/c.nc"],
    "bem-rho-neg": ["bem", "--rho", "-1", "--out", "{out}/c.nc"],
    "bem-radius-zero": ["bem", "--radius", "0", "--out", "{out}/c.nc"],
    "bem-mass-zero": ["bem", "--mass", "0", "--out", "{out}/c.nc"],
    "bem-workers-zero": ["bem", "--workers", "0", "--out", "{out}/c.nc"],
    "bem-dofs-unknown": ["bem", "--dofs", "Foo", "--out", "{out}/c.nc"],
    "bem-cache-dir-file": ["bem", "--cache-dir", "good_force.csv", "--panels", "60",
                           "--n-omega", "3", "--out", "{out}/c.nc"],
    "bem-out-dev-full": ["bem", "--out", "/dev/full"],
    "bem-out-directory": ["bem", "--out", "directory.csv"],
    "bem-out-is-body": ["bem", "--body", "body_unknown_type.json", "--out",
                        "body_unknown_type.json"],
    "bem-body-json-text": ["bem", "--body", '{"type": "Barge"}', "--out", "{out}/c.nc"],
    # simulate
    "simulate-dt-zero": ["simulate", "--coeffs", "good_coeffs.nc", "--dt", "0", "--out",
                         "{out}/h.nc"],
    "simulate-dt-neg": ["simulate", "--coeffs", "good_coeffs.nc", "--dt", "-0.01", "--out",
                        "{out}/h.nc"],
    "simulate-dt-nan": ["simulate", "--coeffs", "good_coeffs.nc", "--dt", "nan", "--out",
                        "{out}/h.nc"],
    "simulate-dt-tiny": ["simulate", "--coeffs", "good_coeffs.nc", "--dt", "1e-9", "--out",
                         "{out}/h.nc"],
    "simulate-duration-huge": ["simulate", "--coeffs", "good_coeffs.nc", "--duration", "1e9",
                               "--out", "{out}/h.nc"],
    "simulate-duration-lt-dt": ["simulate", "--coeffs", "good_coeffs.nc", "--duration", "0.001",
                                "--out", "{out}/h.nc"],
    "simulate-panels-huge": ["simulate", "--panels", "100000000", "--out", "{out}/h.nc"],
    "simulate-no-source": ["simulate", "--out", "{out}/h.nc"],
    "simulate-mass-neg": ["simulate", "--coeffs", "good_coeffs.nc", "--mass", "-7", "--out",
                          "{out}/h.nc"],
    "simulate-dofs-unknown": ["simulate", "--coeffs", "good_coeffs.nc", "--dofs", "Wobble",
                              "--out", "{out}/h.nc"],
    "simulate-dofs-absent": ["simulate", "--coeffs", "good_coeffs.nc", "--dofs", "Pitch",
                             "--out", "{out}/h.nc"],
    "simulate-regular-nan": ["simulate", "--coeffs", "good_coeffs.nc", "--regular", "nan",
                             "0.1", "--out", "{out}/h.nc"],
    "simulate-jonswap-zero": ["simulate", "--coeffs", "good_coeffs.nc", "--jonswap", "0.1",
                              "0", "--out", "{out}/h.nc"],
    "simulate-ramp-neg": ["simulate", "--coeffs", "good_coeffs.nc", "--ramp", "-1", "--out",
                          "{out}/h.nc"],
    "simulate-seed-neg": ["simulate", "--coeffs", "good_coeffs.nc", "--seed", "-1", "--out",
                          "{out}/h.nc"],
    "simulate-out-is-coeffs": ["simulate", "--coeffs", "good_coeffs.nc", "--decay", "0.02",
                               "--out", "good_coeffs.nc"],
    "simulate-out-is-force": ["simulate", "--coeffs", "good_coeffs.nc", "--external-force",
                              "good_force.csv", "--out", "good_force.csv"],
    "simulate-out-dev-full": ["simulate", "--coeffs", "good_coeffs.nc", "--out", "/dev/full"],
    "simulate-out-directory": ["simulate", "--coeffs", "good_coeffs.nc", "--out", "directory.csv"],
    "simulate-out-under-file": ["simulate", "--coeffs", "good_coeffs.nc", "--out",
                                "good_force.csv/h.nc"],
    # select
    "select-json-is-input": ["select", "good_hist.nc", "--json", "good_hist.nc"],
    "select-target-dt-neg": ["select", "good_hist.nc", "--target-dt", "-1"],
    "select-mass-neg": ["select", "good_hist.nc", "--mass", "-7"],
    "select-drag-nan": ["select", "good_hist.nc", "--quadratic-drag", "nan"],
    "select-candidates-unknown": ["select", "good_hist.nc", "--candidates", "spring"],
    "select-dofs-absent": ["select", "good_hist.nc", "--dofs", "Surge"],
    # sweep
    "sweep-workers-zero": ["sweep", "--hs", "0.05", "--tp", "1", "--workers", "0", "--out",
                           "{out}/s"],
    "sweep-workers-neg": ["sweep", "--hs", "0.05", "--tp", "1", "--workers", "-1", "--out",
                          "{out}/s"],
    "sweep-scheduler-notaurl": ["sweep", "--hs", "0.05", "--tp", "1", "--scheduler", "notaurl",
                                "--out", "{out}/s"],
    "sweep-hs-nan": ["sweep", "--hs", "nan", "--tp", "1", "--out", "{out}/s"],
    "sweep-hs-text": ["sweep", "--hs", "0.1,x", "--tp", "1", "--out", "{out}/s"],
    "sweep-hs-neg": ["sweep", "--hs", "-0.1", "--tp", "1", "--out", "{out}/s"],
    "sweep-tp-zero": ["sweep", "--hs", "0.1", "--tp", "0", "--out", "{out}/s"],
    "sweep-seeds-zero": ["sweep", "--hs", "0.1", "--tp", "1", "--seeds", "0", "--out", "{out}/s"],
    "sweep-dt-zero": ["sweep", "--hs", "0.1", "--tp", "1", "--dt", "0", "--out", "{out}/s"],
    "sweep-duration-huge": ["sweep", "--hs", "0.1", "--tp", "1", "--duration", "1e9", "--out",
                            "{out}/s"],
    "sweep-ramp-neg": ["sweep", "--hs", "0.1", "--tp", "1", "--ramp", "-1", "--out", "{out}/s"],
    "sweep-mass-neg": ["sweep", "--hs", "0.1", "--tp", "1", "--mass", "-1", "--out", "{out}/s"],
    # absurd magnitudes: refused with the range (issue 31 item 7)
    "sweep-hs-huge": ["sweep", "--hs", "1e300", "--tp", "1", "--out", "{out}/s"],
    "sweep-hs-above-record": ["sweep", "--hs", "0.1,31", "--tp", "1", "--out", "{out}/s"],
    "sweep-mass-huge": ["sweep", "--hs", "0.1", "--tp", "1", "--mass", "1e300", "--out",
                        "{out}/s"],
    "diagnose-mass-huge": ["diagnose", "--example", "--mass", "1e300"],
    "diagnose-mass-tiny": ["diagnose", "--example", "--mass", "1e-300"],
    "simulate-mass-huge": ["simulate", "--coeffs", "good_coeffs.nc", "--mass", "1e11", "--out",
                           "{out}/h.nc"],
    "import-mass-huge": ["import", "good_hist.csv", "--mass", "1e300", "--out", "{out}/h.nc"],
    "select-mass-huge": ["select", "good_hist.nc", "--mass", "1e300"],
    "bem-mass-huge": ["bem", "--mass", "1e300", "--out", "{out}/c.nc"],
    "simulate-jonswap-hs-huge": ["simulate", "--coeffs", "good_coeffs.nc", "--jonswap", "1e300",
                                 "8", "--out", "{out}/h.nc"],
    "simulate-regular-height-huge": ["simulate", "--coeffs", "good_coeffs.nc", "--regular", "8",
                                     "31", "--out", "{out}/h.nc"],
    # every case fails on the workers: one line (no worker "Compute Failed" traceback), no
    # manifest or parts left behind (a LocalCluster of one worker: ~10 s)
    "sweep-every-case-fails": ["sweep", "--hs", "25", "--tp", "0.8", "--nonlinear-hydrostatics",
                               "--duration", "2", "--workers", "1", "--quiet", "--out",
                               "{out}/s"],
    "sweep-dofs-surge": ["sweep", "--hs", "0.1", "--tp", "1", "--dofs", "Surge", "--out",
                         "{out}/s"],
    "sweep-case-unknown": ["sweep", "--case", "nope", "--hs", "1", "--tp", "10", "--out",
                           "{out}/s"],
    "sweep-case-with-mass": ["sweep", "--case", "oc3_hywind", "--hs", "1", "--tp", "10",
                             "--mass", "5", "--out", "{out}/s"],
    "sweep-no-kinematics-without-case": ["sweep", "--hs", "0.1", "--tp", "1",
                                         "--no-wave-kinematics", "--out", "{out}/s"],
    "sweep-out-file": ["sweep", "--hs", "0.1", "--tp", "1", "--out", "good_force.csv"],
    "sweep-mooring-without-case": ["sweep", "--hs", "0.1", "--tp", "1", "--mooring", "table",
                                   "--out", "{out}/s"],
    "sweep-case-broken-file": ["sweep", "--case", "case_unknown_key.toml", "--hs", "1", "--tp",
                               "10", "--out", "{out}/s"],
    # cases and wave inputs (issue 28)
    "simulate-case-unknown": ["simulate", "--case", "nope", "--out", "{out}/h.nc"],
    "simulate-case-broken-file": ["simulate", "--case", "case_unknown_key.toml", "--out",
                                  "{out}/h.nc"],
    "simulate-case-with-mass": ["simulate", "--case", "oc3_hywind", "--mass", "5", "--out",
                                "{out}/h.nc"],
    "simulate-mooring-unknown": ["simulate", "--case", "oc3_hywind", "--mooring", "elastic",
                                 "--out", "{out}/h.nc"],
    "simulate-mooring-without-case": ["simulate", "--coeffs", "good_coeffs.nc", "--mooring",
                                      "table", "--out", "{out}/h.nc"],
    "simulate-decay-nan": ["simulate", "--coeffs", "good_coeffs.nc", "--decay", "0.1,nan",
                           "--out", "{out}/h.nc"],
    "simulate-wave-elevation-not-eta": ["simulate", "--coeffs", "good_coeffs.nc",
                                        "--wave-elevation", "good_force.csv", "--out",
                                        "{out}/h.nc"],
    "simulate-eta-without-record": ["simulate", "--coeffs", "good_coeffs.nc", "--eta", "F",
                                    "--out", "{out}/h.nc"],
    "bem-case-broken-file": ["bem", "--case", "case_unknown_key.toml", "--out", "{out}/c.nc"],
    "import-eta-absent": ["import", "good_hist.csv", "--eta", "swell", "--out", "{out}/h.nc"],
    # hybrid
    "hybrid-hidden-abc": ["hybrid", "good_hist.nc", "good_hist2.nc", "--hidden", "abc", "--out",
                          "{out}/n"],
    "hybrid-hidden-zero": ["hybrid", "good_hist.nc", "good_hist2.nc", "--hidden", "32,0",
                           "--out", "{out}/n"],
    "hybrid-hidden-huge": ["hybrid", "good_hist.nc", "good_hist2.nc", "--hidden", "100000000",
                           "--out", "{out}/n"],
    "hybrid-test-fraction-1": ["hybrid", "good_hist.nc", "good_hist2.nc", "--test-fraction",
                               "1", "--out", "{out}/n"],
    "hybrid-test-fraction-nan": ["hybrid", "good_hist.nc", "good_hist2.nc", "--test-fraction",
                                 "nan", "--out", "{out}/n"],
    "hybrid-epochs-zero": ["hybrid", "good_hist.nc", "good_hist2.nc", "--epochs", "0", "--out",
                           "{out}/n"],
    "hybrid-learning-rate-neg": ["hybrid", "good_hist.nc", "good_hist2.nc", "--learning-rate",
                                 "-1", "--out", "{out}/n"],
    "hybrid-batch-size-zero": ["hybrid", "good_hist.nc", "good_hist2.nc", "--batch-size", "0",
                               "--out", "{out}/n"],
    "hybrid-feature-window-zero": ["hybrid", "good_hist.nc", "good_hist2.nc",
                                   "--feature-window", "0", "--out", "{out}/n"],
    "hybrid-one-history": ["hybrid", "good_hist.nc", "--out", "{out}/n"],
    "hybrid-out-file": ["hybrid", "good_hist.nc", "good_hist2.nc", "--out", "good_force.csv"],
    "hybrid-dofs-absent": ["hybrid", "good_hist.nc", "good_hist2.nc", "--dofs", "Pitch",
                           "--out", "{out}/n"],
    "hybrid-partition-unknown": ["hybrid", "good_hist.nc", "good_hist2.nc", "--partition",
                                 "nope", "--out", "{out}/n"],
    # coeffs
    "coeffs-out-is-input": ["coeffs", "good_coeffs.nc", "--out", "good_coeffs.nc"],
    "coeffs-out-dev-full": ["coeffs", "good_coeffs.nc", "--out", "/dev/full"],
    "coeffs-rho-neg": ["coeffs", "good_coeffs.nc", "--rho", "-1", "--out", "{out}/c.nc"],
    "coeffs-ulen-zero": ["coeffs", "good_coeffs.nc", "--ulen", "0", "--out", "{out}/c.nc"],
    "coeffs-to-unknown": ["coeffs", "good_coeffs.nc", "--to", "excel", "--out", "{out}/c.nc"],
    # reproduce
    "reproduce-sph-dp-zero": ["reproduce", "--sph-dp", "0", "--out", "{out}/r"],
    "reproduce-sph-dp-nan": ["reproduce", "--sph-dp", "nan", "--out", "{out}/r"],
    "reproduce-out-file": ["reproduce", "--quick", "--out", "good_force.csv"],
    "reproduce-sph-both": ["reproduce", "--recompute-sph", "--sph-history", "good_hist.nc",
                           "--out", "{out}/r"],
    # sph
    "sph-unknown-case": ["sph", "tsunami"],
    "sph-dp-neg": ["sph", "hydrostatic", "--dp", "-1", "--out", "{out}/s.nc"],
    "sph-dp-nan": ["sph", "hydrostatic", "--dp", "nan", "--out", "{out}/s.nc"],
    "sph-checkpoint-every-neg": ["sph", "hydrostatic", "--checkpoint-every", "-5", "--out",
                                 "{out}/s.nc"],
    "sph-tf-zero": ["sph", "hydrostatic", "--tf", "0", "--out", "{out}/s.nc"],
    "sph-hold-neg": ["sph", "decay2d", "--hold", "-1", "--out", "{out}/s.nc"],
    "sph-out-dev-full": ["sph", "hydrostatic", "--out", "/dev/full"],
    "sph-out-directory": ["sph", "hydrostatic", "--out", "directory.csv"],
    "sph-alpha-body-neg": ["sph", "decay2d", "--alpha-body", "-0.1", "--out", "{out}/s.nc"],
    "sph-alpha-body-above-one": ["sph", "decay2d", "--alpha-body", "2", "--out", "{out}/s.nc"],
    "sph-alpha-wall-above-one": ["sph", "decay3d", "--alpha-wall", "1.5", "--out", "{out}/s.nc"],
}

def cases(bad_files: list[str]) -> list[Case]:
    """Every command over every bad file that applies, plus the bad options."""
    templates = {**HISTORY_COMMANDS, **COEFF_COMMANDS, "bem-body": BODY_COMMAND,
                 "simulate-external-force": FORCE_COMMAND}
    out: list[Case] = []
    for name in bad_files:
        for cmd, argv in templates.items():
            if (cmd, name) not in NOT_BAD:
                out.append(Case(f"{cmd}[{name}]", [a.replace("{f}", name) for a in argv],
                                [name], TIMEOUT.get(cmd, 90.0)))
    for cid, argv in BAD_OPTIONS.items():
        out.append(Case(cid, list(argv)))
    return out


if __name__ == "__main__":
    names = make_corpus(sys.argv[1] if len(sys.argv) > 1 else "corpus_out")
    print(f"{len(names)} bad files, {len(cases(names))} cases")
