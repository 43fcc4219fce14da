"""OpenFAST output files (``.out``, ``.outb``) through openfast-io into a TimeHistory.

The files are written here: the text ``.out`` in OpenFAST's layout (blank line, "Predictions
were generated ..." banner, description on line 5, tab-separated names on line 7 and
``(unit)`` cells on line 8, channels printed ``ES10.3E2``-like with 4 significant digits), the
binary ``.outb`` in the documented format openfast-io reads (FileFmtID 1-4: int16 channels
with float32 slope/offset scaling, or float64 with FileFmtID 3; openfast-io has no writer).
References are the analytic signals the files were written from: a platform moving as a sum
of sines in every DOF (so every rate is known exactly), loads in kN/kN-m and N/N-m, and, for
the end-to-end diagnose, a pitch moment that is exactly -(A theta'' + B theta' + C theta).
"""

from __future__ import annotations

import json
import struct
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from hybridwsi import history as h
from hybridwsi import importers as im
from hybridwsi.cli import main
from hybridwsi.errors import InputError

pytest.importorskip("openfast_io")

DEG = np.pi / 180
#: per DOF: amplitude (m or deg), period (s), phase (rad) of the written motion
MOTION = {"Surge": (6.0, 120.0, 0.3), "Sway": (0.5, 90.0, 1.1), "Heave": (0.4, 31.0, 0.7),
          "Roll": (0.8, 29.0, 2.0), "Pitch": (3.0, 29.5, 0.1), "Yaw": (0.6, 8.0, 1.7)}
LETTER = {"Surge": ("T", "x"), "Sway": ("T", "y"), "Heave": ("T", "z"), "Roll": ("R", "x"),
          "Pitch": ("R", "y"), "Yaw": ("R", "z")}


def signal(dof: str, t: np.ndarray, deriv: int = 0) -> np.ndarray:
    """The written motion of ``dof`` (m or deg) and its time derivatives."""
    amp, period, phase = MOTION[dof]
    w = 2 * np.pi / period
    return amp * w**deriv * np.cos(w * t + phase + deriv * np.pi / 2)


def platform_channels(t: np.ndarray, rates: bool = True, accels: bool = True,
                      dofs=tuple(MOTION)) -> dict[str, tuple[str, np.ndarray]]:
    """OpenFAST channels ``{name: (unit, values)}`` of a platform moving as :data:`MOTION`."""
    ch = {"Time": ("s", t)}
    for d in dofs:
        rot = LETTER[d][0] == "R"
        ch[f"Ptfm{d}"] = ("deg" if rot else "m", signal(d, t))
    for use, letter, suffix in ((rates, "V", "/s"), (accels, "A", "/s^2")):
        if use:
            for d in dofs:
                kind, a = LETTER[d]
                ch[f"Ptfm{kind}{letter}{a}i"] = (("deg" if kind == "R" else "m") + suffix,
                                                 signal(d, t, 1 if letter == "V" else 2))
    return ch


def write_out(path: Path, channels: dict[str, tuple[str, np.ndarray]],
              time_fmt: str = "{:10.4f}", fmt: str = "{:10.3E}") -> Path:
    """A text ``.out`` laid out as OpenFAST writes it."""
    lines = [
        "",
        "Predictions were generated on 05-Mar-2025 at 10:12:41 using OpenFAST, compiled as a "
        "64-bit application using double precision at commit v3.5.3",
        " linked with  NWTC Subroutine Library; ElastoDyn; InflowWind; ServoDyn; HydroDyn; "
        "MoorDyn",
        "",
        "Description from the FAST input file: hybridwsi test platform",
        "",
        "\t".join(f"{n:<10}" for n in channels),
        "\t".join(f"{'(' + u + ')':<10}" for u, _ in channels.values()),
    ]
    data = np.column_stack([v for _, v in channels.values()])
    for row in data:
        lines.append("\t".join([time_fmt.format(row[0])] + [fmt.format(x) for x in row[1:]]))
    path.write_text("\n".join(lines) + "\n")
    return path


def write_outb(path: Path, channels: dict[str, tuple[str, np.ndarray]], file_id: int = 4,
               len_name: int = 15) -> Path:
    """A binary ``.outb`` in OpenFAST's format (the layout openfast-io's reader documents).

    FileFmtID 1: int16 channels and int32 packed time; 2 and 4 (with the name length): int16
    channels, time from its first value and increment; 3: float64 channels, no scaling.
    Channel packing as OpenFAST does it: slope = 65535/(max - min), offset = -32768 - slope
    min, value = round(slope x + offset).
    """
    names = list(channels)
    t = channels["Time"][1]
    data = np.column_stack([channels[n][1] for n in names[1:]])
    nt, nc = data.shape
    width = len_name if file_id == 4 else 10
    out = struct.pack("<h", file_id)
    if file_id == 4:
        out += struct.pack("<h", len_name)
    out += struct.pack("<ii", nc, nt)
    if file_id == 1:
        t_scl = (2.0**32 - 1) / (t[-1] - t[0])
        t_off = -(2.0**31) - t_scl * t[0]
        out += struct.pack("<dd", t_scl, t_off)
    else:
        out += struct.pack("<dd", t[0], (t[-1] - t[0]) / (nt - 1))
    if file_id != 3:
        lo, hi = data.min(axis=0), data.max(axis=0)
        scl = np.where(hi > lo, 65535.0 / np.where(hi > lo, hi - lo, 1.0), 1.0).astype(np.float32)
        off = (-32768.0 - scl.astype(float) * lo).astype(np.float32)
        out += scl.astype("<f4").tobytes() + off.astype("<f4").tobytes()
    desc = b"Description from the FAST input file: hybridwsi binary test"
    out += struct.pack("<i", len(desc)) + desc
    out += b"".join(n.ljust(width)[:width].encode() for n in names)
    out += b"".join(f"({u})".ljust(width)[:width].encode() for u, _ in channels.values())
    if file_id == 1:
        out += np.rint(t_scl * t + t_off).astype("<i4").tobytes()
    if file_id == 3:
        out += data.astype("<f8").tobytes()
    else:
        packed = np.clip(np.rint(data * scl.astype(float) + off.astype(float)), -32768, 32767)
        out += packed.astype("<i2").tobytes()
    path.write_bytes(out)
    return path


def quantum(values: np.ndarray) -> float:
    """Resolution of an int16-packed channel."""
    return float(np.ptp(values)) / 65535.0


def read(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return im.read_history(path, **kw)


# ------------------------------------------------------------------ text .out


def test_text_out_units_degrees_loads_and_estimated_accelerations(tmp_path):
    t = np.arange(0.0, 300.0, 0.05)
    ch = platform_channels(t, accels=False, dofs=("Surge", "Heave", "Pitch"))
    w = 2 * np.pi / 29.5
    ch["HydroFxi"] = ("N", 2.0e5 * np.cos(w * t))
    ch["HydroFzi"] = ("N", -1.0e5 * np.sin(w * t))
    ch["HydroMyi"] = ("N-m", 3.0e7 * np.sin(w * t))
    ch["PtfmFxi"] = ("kN", 400.0 * np.cos(w * t))
    ch["PtfmFzi"] = ("kN", -80.0 * np.sin(w * t))
    ch["PtfmMyi"] = ("kN-m", 5.0e4 * np.sin(w * t))
    ch["HydroFyi"] = ("N", np.zeros_like(t))  # a sway load: no Sway DOF, ignored
    for k in (1, 2, 3):
        ch[f"FAIRTEN{k}"] = ("N", 1.0e6 + 1.0e4 * k * np.sin(w * t))
    ch["Wave1Elev"] = ("m", 2.0 * np.cos(w * t))
    p = write_out(tmp_path / "spar.out", ch)
    assert im.detect_format(p) == "openfast"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # everything found: nothing to warn about
        ds = im.read_history(p)
    assert ds.attrs["format"] == "openfast"
    assert list(ds["dof"].values) == ["Surge", "Heave", "Pitch"]
    assert h.is_uniform(ds) and h.time_step(ds) == pytest.approx(0.05)
    # 4 significant digits in the file: compare to the written signals at that precision
    for j, d in enumerate(("Surge", "Heave", "Pitch")):
        scale = DEG if d == "Pitch" else 1.0
        np.testing.assert_allclose(ds["z"].values[:, j], scale * signal(d, t),
                                   atol=5e-4 * scale * MOTION[d][0])
        np.testing.assert_allclose(ds["zdot"].values[:, j], scale * signal(d, t, 1),
                                   rtol=0, atol=6e-4 * np.max(np.abs(scale * signal(d, t, 1))))
    assert json.loads(ds["z"].attrs["units_per_dof"]) == ["m", "m", "rad"]
    assert json.loads(ds["zdot"].attrs["units_per_dof"]) == ["m/s", "m/s", "rad/s"]
    # accelerations are not in the file: estimated, flagged, and close to -w^2 z
    assert "PtfmTAxi" in ds["zddot"].attrs["estimated"]
    assert "savgol" in ds["zddot"].attrs["estimated"]
    assert "estimated" not in ds["zdot"].attrs
    inner = slice(200, -200)  # Savitzky-Golay edges aside
    for j, d in enumerate(("Surge", "Heave", "Pitch")):
        exact = (DEG if d == "Pitch" else 1.0) * signal(d, t, 2)
        err = ds["zddot"].values[inner, j] - exact[inner]
        # 4 printed digits of z are the noise floor of a second derivative (about 1 % RMS)
        assert np.sqrt(np.mean(err**2)) < 0.02 * np.max(np.abs(exact)), d
    # loads: kN -> N, kN-m -> N m, N-m -> N m; the total hydrodynamic and the platform load
    np.testing.assert_allclose(ds["F_platform"].values[:, 0], 4.0e5 * np.cos(w * t), atol=2e2)
    np.testing.assert_allclose(ds["F_platform"].values[:, 2], 5.0e7 * np.sin(w * t), atol=3e4)
    np.testing.assert_allclose(ds["F_hydro"].values[:, 2], 3.0e7 * np.sin(w * t), atol=2e4)
    assert json.loads(ds["F_hydro"].attrs["units_per_dof"]) == ["N", "N", "N m"]
    assert "HydroMyi" in ds["F_hydro"].attrs["description"]
    assert set(h.force_names(ds)) == {"F_hydro", "F_platform"}
    assert ds["T_fairlead"].dims == ("time", "line")
    assert list(ds["line"].values) == [1, 2, 3]
    np.testing.assert_allclose(ds["T_fairlead"].values[:, 2],
                               1.0e6 + 3.0e4 * np.sin(w * t), rtol=6e-4)
    np.testing.assert_allclose(ds["eta"].values[:, 0], 2.0 * np.cos(w * t), atol=1e-3)


def test_rates_missing_for_one_dof_are_estimated_and_loads_incomplete_left_out(tmp_path):
    t = np.arange(0.0, 200.0, 0.1)
    ch = platform_channels(t, rates=False, accels=False, dofs=("Surge", "Pitch"))
    ch["PtfmTVxi"] = ("m/s", signal("Surge", t, 1))  # surge rate only: no PtfmRVyi
    ch["HydroFxi"] = ("N", np.ones_like(t))  # no HydroMyi: F_hydro cannot cover Pitch
    p = write_out(tmp_path / "partial.out", ch)
    with pytest.warns(UserWarning) as rec:
        ds = im.read_openfast(p)
    messages = " | ".join(str(r.message) for r in rec)
    assert "F_hydro left out: HydroMyi" in messages
    assert "F_hydro" not in ds
    assert "PtfmRVyi" in ds["zdot"].attrs["estimated"]
    exact = DEG * signal("Pitch", t, 1)
    assert np.max(np.abs(ds["zdot"].values[50:-50, 1] - exact[50:-50])) < 0.01 * np.ptp(exact)


def test_constant_dof_gets_exact_zero_rates(tmp_path):
    t = np.arange(0.0, 100.0, 0.1)
    ch = platform_channels(t, rates=False, accels=False, dofs=("Surge",))
    ch["PtfmSway"] = ("m", np.zeros_like(t))  # head seas: no sway at all
    ds = read(write_out(tmp_path / "head.out", ch))
    assert list(ds["dof"].values) == ["Surge", "Sway"]
    assert np.all(ds["zdot"].values[:, 1] == 0) and np.all(ds["zddot"].values[:, 1] == 0)
    assert "zero for constant Sway" in ds["zddot"].attrs["estimated"]
    exact = signal("Surge", t, 1)
    assert np.max(np.abs(ds["zdot"].values[50:-50, 0] - exact[50:-50])) < 0.01 * np.ptp(exact)


def test_time_printed_with_four_decimals_is_put_back_on_its_grid(tmp_path):
    t = np.arange(0.0, 60.0, 0.00625)  # prints as 0.0062, 0.0125, 0.0188 ...: not uniform
    p = write_out(tmp_path / "fine.out", platform_channels(t, dofs=("Heave",)))
    ds = read(p)
    # the step is known to the printed precision over the record: 1e-4 s / 60 s
    assert h.is_uniform(ds) and h.time_step(ds) == pytest.approx(0.00625, rel=2e-6)
    assert "0.0001 s" in ds.attrs["time_regridded"]
    assert "resampled" not in ds.attrs
    np.testing.assert_allclose(ds["time"].values, t, rtol=0, atol=1e-4)


# ------------------------------------------------------------------ binary .outb


@pytest.mark.parametrize("file_id", [1, 2, 3, 4])
def test_binary_outb_every_file_id(tmp_path, file_id):
    t = np.arange(0.0, 100.0, 0.025)
    ch = platform_channels(t)
    ch["PtfmFxi"] = ("kN", 3.0e2 * np.cos(2 * np.pi * t / 29.5))
    ch["PtfmMyi"] = ("kN-m", 2.0e5 * np.sin(2 * np.pi * t / 29.5))
    p = write_outb(tmp_path / f"run{file_id}.outb", ch, file_id=file_id)
    assert im.detect_format(p) == "openfast"
    ds = read(p, dofs=["Surge", "Pitch"])
    assert list(ds["dof"].values) == ["Surge", "Pitch"]
    # FileFmtID 1 packs time in int32 (resolution 100 s / 2^32)
    np.testing.assert_allclose(ds["time"].values, t, rtol=0, atol=5e-8 if file_id == 1 else 1e-12)
    for role, deriv in (("z", 0), ("zdot", 1), ("zddot", 2)):
        assert "estimated" not in ds[role].attrs
        for j, d in enumerate(("Surge", "Pitch")):
            scale = DEG if d == "Pitch" else 1.0
            written = signal(d, t, deriv)
            tol = 1e-9 if file_id == 3 else 1.01 * quantum(written)
            np.testing.assert_allclose(ds[role].values[:, j], scale * written,
                                       rtol=0, atol=scale * tol)
    np.testing.assert_allclose(ds["F_platform"].values[:, 1],
                               2.0e8 * np.sin(2 * np.pi * t / 29.5),
                               atol=1e-3 if file_id == 3 else 1e3 * quantum(ch["PtfmMyi"][1]))
    assert json.loads(ds["zddot"].attrs["units_per_dof"]) == ["m/s^2", "rad/s^2"]


def test_mass_matrix_gives_total_force_and_scalar_mass_rotations_are_refused(tmp_path):
    t = np.arange(0.0, 60.0, 0.05)
    p = write_outb(tmp_path / "m.outb", platform_channels(t, dofs=("Surge", "Pitch")), file_id=3)
    mass = np.array([[8.07e6, -6.3e8], [-6.3e8, 6.0e10]])  # kg, kg m, kg m^2 (spar-like)
    ds = im.read_openfast(p, mass=mass)
    zdd = np.column_stack([signal("Surge", t, 2), DEG * signal("Pitch", t, 2)])
    np.testing.assert_allclose(ds["F_tot"].values, zdd @ mass.T, rtol=1e-9, atol=1e-3)
    np.testing.assert_allclose(ds["mass"].values, mass)
    with pytest.warns(UserWarning, match="scalar mass does not apply to rotations"):
        ds = im.read_openfast(p, mass=8.07e6)
    assert "F_tot" not in ds
    surge = im.read_openfast(p, mass=8.07e6, dofs="Surge")
    np.testing.assert_allclose(surge["F_tot"].values[:, 0], 8.07e6 * signal("Surge", t, 2),
                               rtol=1e-9, atol=1e-6)


def test_dof_selection(tmp_path):
    t = np.arange(0.0, 30.0, 0.05)
    p = write_outb(tmp_path / "s.outb", platform_channels(t, dofs=("Surge", "Heave")), file_id=3)
    assert list(read(p)["dof"].values) == ["Surge", "Heave"]  # every DOF in the file
    assert list(read(p, dof="Heave")["dof"].values) == ["Heave"]  # the CLI's --dof spelling
    with pytest.raises(InputError, match="no displacement channel for Pitch.*PtfmPitch"):
        read(p, dofs="Surge,Pitch")
    with pytest.raises(InputError, match="unknown degree"):
        read(p, dofs="Bob")
    # OpenFAST's sign flip: an OutList entry "-PtfmHeave" writes minus the heave
    flipped = write_outb(tmp_path / "f.outb", {"Time": ("s", t),
                                               "-PtfmHeave": ("m", -signal("Heave", t))},
                         file_id=3)
    np.testing.assert_allclose(read(flipped)["z"].values[:, 0], signal("Heave", t), rtol=1e-12)


# ------------------------------------------------------------------ bad files


def bad_text(tmp_path: Path, name: str, edit) -> Path:
    t = np.arange(0.0, 10.0, 0.05)
    p = write_out(tmp_path / name, platform_channels(t, dofs=("Heave",)))
    lines = p.read_text().splitlines()
    p.write_text("\n".join(edit(lines)) + "\n")
    return p


@pytest.mark.parametrize("name, edit, match", [
    ("truncated.out", lambda ls: ls[:-1] + [ls[-1][:15]], r"line 208 has 2 fields, not 4 \(truncated"),
    ("text.out", lambda ls: ls[:50] + [ls[50].replace("E", "x", 1)] + ls[51:], "non-numeric"),
    ("nodata.out", lambda ls: ls[:8], "no data rows"),
    ("noheader.out", lambda ls: ls[6:], "not an OpenFAST text output"),
    ("invalid.out", lambda ls: ls[:7] + [ls[7].replace("(m)", "(INVALID)", 1)] + ls[8:],
     "unit 'INVALID'"),
])
def test_bad_text_files(tmp_path, name, edit, match):
    p = bad_text(tmp_path, name, edit)
    with pytest.raises(InputError, match=match) as err:
        read(p, format="openfast")
    assert "\n" not in str(err.value)


def test_bad_binary_files(tmp_path):
    t = np.arange(0.0, 10.0, 0.05)
    good = write_outb(tmp_path / "good.outb", platform_channels(t, dofs=("Heave",)))
    data = good.read_bytes()
    cut = tmp_path / "cut.outb"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match="truncated or corrupt"):
        read(cut)
    short = tmp_path / "short.outb"
    short.write_bytes(data[:-7])  # header intact, last values missing
    with pytest.raises(InputError, match="truncated or corrupt"):
        read(short)
    garbage = tmp_path / "garbage.outb"
    garbage.write_bytes(b"\x07\x00" + bytes(range(256)) * 4)
    with pytest.raises(InputError, match="not an OpenFAST binary"):
        read(garbage, format="openfast")
    empty = tmp_path / "empty.outb"
    empty.write_bytes(b"")
    with pytest.raises(InputError, match="empty"):
        read(empty, format="openfast")
    with pytest.raises(InputError, match="file not found"):
        read(tmp_path / "absent.outb", format="openfast")
    nodisp = write_outb(tmp_path / "loads.outb", {"Time": ("s", t), "HydroFxi": ("N", t)})
    with pytest.raises(InputError, match="no platform displacement channel"):
        read(nodisp)


def test_without_openfast_io_one_error_names_the_extra(tmp_path, monkeypatch):
    t = np.arange(0.0, 10.0, 0.05)
    p = write_out(tmp_path / "a.out", platform_channels(t, dofs=("Heave",)))
    monkeypatch.setitem(sys.modules, "openfast_io", None)
    assert im.detect_format(p) == "openfast"  # detection needs no openfast-io
    with pytest.raises(InputError, match=r"hybridwsi\[openfast\]"):
        im.read_history(p)


# ------------------------------------------------------------------ commands


def pitch_case(t: np.ndarray) -> tuple[dict, float, float, float]:
    """A platform pitching as three sines, moment -(A theta'' + B theta' + C theta) [kN-m]."""
    a55, b55, c55 = 7.0e9, 5.0e7, 1.4e9  # kg m^2, N m s/rad, N m/rad
    th = np.zeros_like(t)
    thd, thdd = np.zeros_like(t), np.zeros_like(t)
    for amp, period, phase in ((2.0, 29.0, 0.0), (1.0, 12.0, 1.0), (0.5, 7.0, 2.0)):
        w = 2 * np.pi / period
        th += amp * np.sin(w * t + phase)
        thd += amp * w * np.cos(w * t + phase)
        thdd -= amp * w**2 * np.sin(w * t + phase)
    moment = -(a55 * thdd + b55 * thd + c55 * th) * DEG / 1e3
    ch = {"Time": ("s", t), "PtfmPitch": ("deg", th), "PtfmRVyi": ("deg/s", thd),
          "PtfmRAyi": ("deg/s^2", thdd), "PtfmMyi": ("kN-m", moment)}
    return ch, a55, b55, c55


def test_cli_import_outb_and_diagnose_out(tmp_path, capsys):
    t = np.arange(0.0, 600.0, 0.1)
    ch, a55, b55, c55 = pitch_case(t)
    outb = write_outb(tmp_path / "pitch.outb", ch, file_id=3)
    nc = tmp_path / "h.nc"
    assert main(["import", str(outb), "--out", str(nc)]) == 0
    assert "(openfast)" in capsys.readouterr().out
    back = im.read_history(nc)
    np.testing.assert_allclose(back["z"].values[:, 0], DEG * ch["PtfmPitch"][1], rtol=1e-12)
    # diagnose the text file: the regression of the pitch moment returns -A, -B, -C
    out = write_out(tmp_path / "pitch.out", ch, fmt="{:14.7E}")
    res_file = tmp_path / "r.json"
    assert main(["diagnose", str(out), "--force-column", "F_platform", "--json", str(res_file)]) == 0
    res = json.loads(res_file.read_text())
    assert res["input"]["format"] == "openfast"
    assert res["alpha"] == pytest.approx(-a55, rel=1e-4)
    assert res["beta"] == pytest.approx(-b55, rel=1e-3)
    assert res["gamma"] == pytest.approx(-c55, rel=1e-4)
