"""Delimited text tables with units in their headers: the CSV side of a TimeHistory.

:class:`TextTable` reads any ``,``/``;``/tab/whitespace table as strings with file line numbers
(for one-line error messages), :func:`split_header`/:func:`unit_factor` turn ``"z [mm]"`` into
SI, :func:`read_csv` builds a TimeHistory from such a table and :func:`to_csv` writes one that
:func:`read_csv` reads back exactly. Headers carry units per DOF (``z_Pitch [rad]``).
"""

from __future__ import annotations

import json
import os
import re
import warnings
from collections.abc import Mapping, Sequence
from functools import lru_cache
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi import dofs as _dofs
from hybridwsi._meta import version
from hybridwsi.errors import InputError
from hybridwsi.files import NETCDF_MAGIC, atomic_write
from hybridwsi.history.model import make_history, units_per_dof
from hybridwsi.history.signal import finalize_import
from hybridwsi.units import UNIT_FACTORS, normalise_unit, quantity_of, unit_factor

@lru_cache(maxsize=65536)
def split_header(header: str) -> tuple[str, str | None]:
    """``"time [s]"`` -> ``("time", "s")``; also ``"z (mm)"``; no unit -> ``(header, None)``."""
    m = re.match(r"^\s*(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$", header)
    return (m.group(1), m.group(2)) if m else (header.strip(), None)


class TextTable:
    """A delimited text table read as strings, with file line numbers for error messages.

    Attributes
    ----------
    path : Path
    columns : list of str
        Header cells as written (e.g. ``"time [s]"``); empty trailing columns removed.
    meta : dict
        ``key: value`` pairs from ``# key: value`` comment lines before the header.
    sep : str
        The separator used (``","``, ``";"``, ``"\\t"`` or ``"whitespace"``).

    With ``lazy=True`` only the comments and the header are read at construction; the columns
    a caller needs are then parsed by :meth:`load` with NumPy's C reader (only those columns,
    as floats), and the whole file is split into string cells (:attr:`cells`,
    :attr:`line_numbers`) only when that fast path cannot be used or an error message needs
    line numbers: every check and message is the same as in the eager mode.
    """

    #: bytes read to find the header in lazy mode (more comment lines: eager reading)
    HEAD_BYTES = 1 << 16

    def __init__(self, path: str | os.PathLike, sep: str | None = None, *,
                 lazy: bool = False) -> None:
        self.path = Path(path)
        self._given_sep = sep
        self._cells: dict[str, list[str | None]] | None = None
        self._line_numbers: np.ndarray | None = None
        self._values: dict[str, np.ndarray] = {}
        self._lines: list[str] | None = None
        head = _read_head(self.path, self.HEAD_BYTES) if lazy else None
        lines = head if head is not None else read_text_file(self.path).splitlines()
        self.meta: dict[str, str] = {}
        header_idx = None
        for i, line in enumerate(lines):
            s = line.strip()
            if not s:
                continue
            if s.startswith("#"):
                key, colon, value = s.lstrip("#").partition(":")
                if colon and header_idx is None:
                    self.meta[key.strip()] = value.strip()
                continue
            header_idx = i
            break
        if header_idx is None and head is not None:  # header beyond the head: read it all
            self.__init__(path, sep)  # type: ignore[misc]
            return
        if header_idx is None:
            raise InputError(f"{self.path.name}: no header line and no data (only comments)")
        self.sep = sep or detect_separator(lines[header_idx])
        self._header_idx = header_idx
        self._header = self._split(lines[header_idx])
        self._keep = [j for j, h in enumerate(self._header) if h != ""]
        self.columns = [self._header[j] for j in self._keep]
        if len(set(self.columns)) != len(self.columns):
            dup = next(c for c in self.columns if self.columns.count(c) > 1)
            raise InputError(f"{self.path.name}: column name '{dup}' appears twice in the header")
        if head is None:
            self._lines = lines
            self._parse_all()

    # ---------------------------------------------------------------- full (string) parse
    def _parse_all(self) -> None:
        if self._lines is None:
            self._lines = read_text_file(self.path).splitlines()
        self._cells, self._line_numbers = self._parse(self._header_idx)
        self._lines = None  # the cells hold what is needed

    @property
    def cells(self) -> dict[str, list[str | None]]:
        """Column -> its cells as written (None where a row is too short)."""
        if self._cells is None:
            self._parse_all()
        return self._cells  # type: ignore[return-value]

    @cells.setter
    def cells(self, value: dict[str, list[str | None]]) -> None:
        self._cells = value

    @property
    def line_numbers(self) -> np.ndarray:
        """File line number (1-based) of each data row."""
        if self._line_numbers is None:
            self._parse_all()
        return self._line_numbers  # type: ignore[return-value]

    @line_numbers.setter
    def line_numbers(self, value: np.ndarray) -> None:
        self._line_numbers = value

    def _split(self, line: str) -> list[str]:
        line = line.split("#", 1)[0]
        if self.sep == "whitespace":
            return line.split()
        return [c.strip() for c in line.split(self.sep)]

    def _parse(self, header_idx: int):
        assert self._lines is not None
        rows, linenos = [], []
        for i in range(header_idx + 1, len(self._lines)):
            s = self._lines[i].strip()
            if not s or s.startswith("#"):
                continue
            rows.append(self._split(self._lines[i]))
            linenos.append(i + 1)
        # trailing separators (DualSPHysics writes "a;b;") give empty header cells: drop them
        keep, width = self._keep, len(self._header)
        for row, ln in zip(rows, linenos):
            if any(c != "" for c in row[width:]):
                raise InputError(
                    f"{self.path.name}: line {ln} has {len(row)} fields but the header has "
                    f"{len(keep)} columns (mismatched lengths)"
                )
        named = set(keep)
        for j in range(width):
            if j not in named and any(len(r) > j and r[j] != "" for r in rows):
                raise InputError(f"{self.path.name}: column {j + 1} has data but no header name")
        cells: dict[str, list[str | None]] = {c: [] for c in self.columns}
        for row in rows:
            for j, c in zip(keep, self.columns):
                cells[c].append(row[j] if j < len(row) else None)  # None: row too short
        return cells, np.asarray(linenos, dtype=int)

    # ---------------------------------------------------------------- fast numeric parse
    def load(self, columns: Sequence[str]) -> bool:
        """Parse ``columns`` as floats with NumPy's C reader; True when that worked.

        The fast path is taken only when it cannot hide a problem the string parse reports:
        every value of the columns finite, no field beyond the header's width and nothing in
        an unnamed column. Otherwise (or when the table was read eagerly) nothing is loaded
        and :meth:`numeric` parses the strings, with line numbers in its messages.
        """
        if self._cells is not None:
            return False
        want = [c for c in dict.fromkeys(columns) if c not in self._values]
        if not want:
            return True
        width = len(self._header)
        named = set(self._keep)
        unnamed = [j for j in range(width) if j not in named]
        if unnamed not in ([], [width - 1]):
            return False  # empty header cells other than a trailing one: the string parse
        if not _fields_fit(self.path, self._header_idx, self.sep, width, bool(unnamed)):
            return False  # a comment, a row longer than the header, data without a name
        index = {c: self._keep[k] for k, c in enumerate(self.columns)}
        use = [index[c] for c in want]
        try:
            data = _read_columns(self.path, self.sep, self._header_idx + 1, use, width)
        except (ValueError, OSError):
            return False
        values = {c: data[:, k] for k, c in enumerate(want)}
        if not np.isfinite(data).all():
            return False
        self._n_rows = data.shape[0]
        self._values.update(values)
        return True

    @property
    def n_rows(self) -> int:
        if self._line_numbers is None and self._values:
            return self._n_rows
        return int(self.line_numbers.size)

    def find(self, name: str) -> str | None:
        """Column whose full header or unit-less name matches ``name`` (case-insensitive)."""
        want = name.strip().lower()
        for c in self.columns:
            if c.lower() == want:
                return c
        for c in self.columns:
            if split_header(c)[0].lower() == want:
                return c
        return None

    def require(self, name: str, what: str = "column") -> str:
        col = self.find(name)
        if col is None:
            raise InputError(
                f"{what} '{name}' not found in {self.path.name}; available columns: "
                f"{', '.join(self.columns)}"
            )
        return col

    def numeric(self, column: str, quantity: str | None = None, scale: float = 1.0) -> np.ndarray:
        """Column as floats in SI (unit from the header), or a one-line InputError."""
        try:
            factor = 1.0 if quantity is None else unit_factor(split_header(column)[1], quantity, column)
        except InputError as exc:
            raise InputError(f"{self.path.name}: {exc}") from None
        if column in self._values:  # parsed and checked finite by load()
            return self._values[column] * (factor * scale)
        raw = self.cells[column]
        try:  # fast path: every cell a finite number
            out = np.asarray(raw, dtype=float)
            if np.all(np.isfinite(out)):
                return out * factor * scale
        except (TypeError, ValueError):
            out = np.empty(len(raw))
        width = len(self.columns)
        for i, cell in enumerate(raw):
            ln = self.line_numbers[i]
            if cell is None:
                raise InputError(
                    f"{self.path.name}: line {ln} has fewer fields than the header's {width} "
                    f"columns (mismatched lengths; '{column}' is missing)"
                )
            try:
                out[i] = float(cell)
            except ValueError:
                if cell == "":
                    raise InputError(
                        f"{self.path.name}: empty cell in column '{column}' at line {ln}"
                    ) from None
                raise InputError(
                    f"{self.path.name}: non-numeric value '{cell[:30]}' in column '{column}' "
                    f"at line {ln}"
                ) from None
            if not np.isfinite(out[i]):
                what = "NaN" if np.isnan(out[i]) else "infinite"
                raise InputError(
                    f"{self.path.name}: {what} value '{cell}' in column '{column}' at line {ln}"
                )
        return out * factor * scale

    def is_numeric(self, column: str) -> bool:
        """Whether at least one cell of the column parses as a number."""
        if column in self._values:
            return True
        for cell in self.cells[column]:
            try:
                float(cell)  # type: ignore[arg-type]
                return True
            except (TypeError, ValueError):
                continue
        return False

    def check_time(self, t: np.ndarray, min_samples: int = 8) -> None:
        """Sorted, no duplicates, enough samples; messages give file line numbers."""
        name = self.path.name
        if t.size < min_samples:
            raise InputError(f"{name}: {t.size} data rows; at least {min_samples} are needed")
        steps = np.diff(t)
        if np.any(steps == 0):
            i = int(np.flatnonzero(steps == 0)[0]) + 1
            raise InputError(
                f"{name}: time {t[i]:.6g} s is duplicated at line {self.line_numbers[i]}"
            )
        if np.any(steps < 0):
            i = int(np.flatnonzero(steps < 0)[0]) + 1
            raise InputError(
                f"{name}: time is not sorted: line {self.line_numbers[i]} (t = {t[i]:.6g} s) "
                f"comes after line {self.line_numbers[i - 1]} (t = {t[i - 1]:.6g} s)"
            )


def detect_separator(header_line: str) -> str:
    """``";"``, ``","``, ``"\\t"`` or ``"whitespace"``, from the header line."""
    for sep in (";", ",", "\t"):
        if sep in header_line:
            return sep
    return "whitespace"


def _read_columns(path: Path, sep: str, skip: int, use: list[int], width: int) -> np.ndarray:
    """Columns ``use`` of a table as correctly rounded floats (exact ``to_csv`` round trip).

    Apache Arrow's multi-threaded CSV reader when installed and the separator is one
    character (its float parser is correctly rounded, and it converts only the wanted
    columns); when it is missing or refuses the file, NumPy's C reader when most columns are
    wanted and pandas' C tokenizer with round-trip conversion when few of many are. A parse
    failure of those raises ValueError, and the caller falls back to the string parse (which
    reports line numbers).
    """
    delimiter = None if sep == "whitespace" else sep
    if delimiter is not None:
        data = _read_columns_arrow(path, delimiter, skip, use)
        if data is not None:
            return data
    if 4 * len(use) >= width:
        return np.loadtxt(path, delimiter=delimiter, skiprows=skip, usecols=use,
                          dtype=np.float64, encoding="latin-1", ndmin=2, comments=None)
    import pandas as pd

    frame = pd.read_csv(path, sep=r"\s+" if delimiter is None else delimiter, header=None,
                        names=range(width), usecols=use, skiprows=skip, dtype=np.float64,
                        engine="c", encoding="latin-1", float_precision="round_trip")
    return frame[use].to_numpy()


def _read_columns_arrow(path: Path, delimiter: str, skip: int, use: list[int]
                        ) -> np.ndarray | None:
    """:func:`_read_columns` with ``pyarrow.csv``; None when pyarrow is not installed or
    cannot read the file as plain numbers.

    Quoting is off (a quoted number is not a number here) and every wanted column is typed
    float64, so text in it raises instead of becoming a string column.
    """
    try:
        import pyarrow as pa
        import pyarrow.csv as pacsv
    except ImportError:
        return None
    try:
        table = pacsv.read_csv(
            path,
            read_options=pacsv.ReadOptions(skip_rows=skip, autogenerate_column_names=True),
            parse_options=pacsv.ParseOptions(delimiter=delimiter, quote_char=False),
            convert_options=pacsv.ConvertOptions(
                include_columns=[f"f{j}" for j in use],
                column_types={f"f{j}": pa.float64() for j in use}))
    except (pa.ArrowException, ValueError):
        return None  # e.g. blanks around numbers, short rows: the other readers decide
    if table.num_rows == 0 or any(table.column(k).null_count for k in range(len(use))):
        return None  # empty fields: the other readers decide
    out = np.empty((table.num_rows, len(use)))
    for k in range(len(use)):
        out[:, k] = table.column(k).to_numpy()
    return out


def _fields_fit(path: Path, header_idx: int, sep: str, width: int,
                trailing_unnamed: bool = False) -> bool:
    """Whether the data lines can be read column by column without hiding an error.

    False when a line after the header holds a ``#`` comment, has more fields than the header
    (``width``) or, with ``trailing_unnamed`` (a header ending in a separator, as DualSPHysics
    writes), has data in that unnamed last column: what a reader of some columns only would
    silently accept. Counted on the raw bytes with NumPy (about 1 s per GB).
    """
    buf = np.fromfile(path, dtype=np.uint8)
    newline = np.flatnonzero(buf == 10)
    if newline.size <= header_idx:
        return False
    buf = buf[newline[header_idx] + 1:]
    if (buf == ord("#")).any():
        return False
    blank = np.frombuffer(b" \t\r\n\v\f", dtype=np.uint8)
    if sep == "whitespace":
        space = np.isin(buf, blank)
        marks = np.flatnonzero(~space[1:] & space[:-1]) + 1  # a field starts after a blank
        if buf.size and not space[0]:
            marks = np.concatenate([[0], marks])
        extra = 0  # fields = starts of fields
    else:
        marks = np.flatnonzero(buf == ord(sep))
        extra = 1  # fields = separators + 1
    ends = np.append(np.flatnonzero(buf == 10), buf.size)
    fields = np.diff(np.searchsorted(marks, ends), prepend=0) + extra
    if fields.max(initial=0) > width:
        return False
    if trailing_unnamed:  # a full line must end in the separator (blanks aside)
        starts = np.concatenate([[0], ends[:-1] + 1])
        last = ends - 1
        for _ in range(16):
            step = (last >= starts) & np.isin(buf[np.clip(last, 0, None)], blank)
            if not step.any():
                break
            last = last - step
        if step.any():
            return False
        full = (fields == width) & (last >= starts)
        if (buf[last[full]] != ord(sep)).any():
            return False
    return True


def _read_head(path: Path, n_bytes: int, max_bytes: int = 1 << 26) -> list[str] | None:
    """The first complete lines of a text file, up to and including the header line, with
    the checks of :func:`read_text_file` on them; None when the whole file is short (read it
    all) or no header line ends within ``max_bytes``.

    Reads ``n_bytes`` and doubles while no complete non-comment line has been seen (a
    10 000-column header is longer than the first read).
    """
    if not path.is_file() or path.stat().st_size <= n_bytes:
        return None
    try:
        with open(path, "rb") as f:
            data = f.read(n_bytes)
            while not _has_header_line(data):
                more = f.read(len(data)) if len(data) < max_bytes else b""
                if not more:
                    return None
                data += more
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror or exc}") from None
    if data.startswith(NETCDF_MAGIC) or b"\x00" in data:
        return None  # let read_text_file say what it is
    data = data[: data.rindex(b"\n")]
    try:
        return data.decode("utf-8-sig").splitlines()
    except UnicodeDecodeError:
        return None


def _has_header_line(data: bytes) -> bool:
    """Whether ``data`` holds a complete line that is neither blank nor a ``#`` comment."""
    end = data.rfind(b"\n")
    if data.startswith(NETCDF_MAGIC) or b"\x00" in data:
        return True  # binary: stop reading, the caller refuses it
    if end < 0:
        return False
    return any(line.strip() and not line.strip().startswith(b"#")
               for line in data[:end].splitlines())


def read_text_file(path: Path) -> str:
    """The file's text, or a one-line InputError (missing, empty, binary, undecodable)."""
    if not path.exists():
        raise InputError(f"file not found: {path}")
    if not path.is_file():
        raise InputError(f"not a regular file: {path}")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror or exc}") from None
    if not data.strip():
        raise InputError(f"{path.name} is empty")
    if data.startswith(NETCDF_MAGIC):
        raise InputError(f"{path.name} is a NetCDF file, not a text table (use read_history)")
    if b"\x00" in data[:65536]:
        raise InputError(f"{path.name} is a binary file, not a CSV/text table")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        try:
            text = data.decode("latin-1")
        except UnicodeDecodeError:  # pragma: no cover - latin-1 decodes every byte
            raise InputError(f"{path.name} is not a text file") from None
        # binary garbage decodes as latin-1 too: insist on mostly printable text
        printable = sum(ch.isprintable() or ch in "\r\n\t" for ch in text[:4096])
        if printable < 0.95 * min(len(text), 4096):
            raise InputError(f"{path.name} is a binary file, not a CSV/text table") from None
        return text


# --------------------------------------------------------------------------------------------
# TimeHistory <-> CSV
# --------------------------------------------------------------------------------------------


def read_csv(
    path: str | os.PathLike,
    *,
    time: str = "time",
    z: str | None = "z",
    zdot: str | None = None,
    zddot: str | None = None,
    forces: Sequence[str] | Mapping[str, str] | str | None = None,
    sep: str | None = None,
    dof: str | Sequence[str] | None = None,
    mass: float | np.ndarray | None = None,
    resample: bool = False,
    eta: str | None = None,
) -> xr.Dataset:
    """Read a TimeHistory from a delimited text file.

    Parameters
    ----------
    path : path-like
        Text table: one header line, ``#`` comments (anywhere; ``# key: value`` lines before
        the header are read as metadata, e.g. ``# dof: Heave`` and ``# mass [kg]: 7.06`` as
        written by :func:`to_csv`), separator ``,``/``;``/tab/whitespace (auto-detected from the
        header unless ``sep`` is given; trailing separators are tolerated).
    time, z, zdot, zddot : str
        Column names, matched case-insensitively against the full header cell or its unit-less
        name (``"time"`` matches ``"time [s]"``). With several DOFs each name is a stem: ``z``
        reads ``z_Surge``, ``z_Pitch``… ``zdot``/``zddot`` default to columns named
        ``zdot``/``zddot`` when present, else they are left out (see
        :func:`hybridwsi.history.estimate_derivatives`).
    forces : str, sequence of str or mapping {variable: column}, optional
        Force columns [N, or N m on rotations]. None: every other numeric column (group of
        ``<name>_<DOF>`` columns with several DOFs) whose unit is a force unit of its DOF or
        absent becomes a force component named after its unit-less header; columns with other
        known units (m, m/s, ...) are kept as extra ``(time, dof)`` variables; wholly
        non-numeric columns are skipped.
    sep : str, optional
        Separator override (``","``, ``";"``, ``"\\t"`` or ``"whitespace"``).
    dof : str or sequence of str, optional
        Degree(s) of freedom (``"Heave"``, ``"Surge,Pitch"``; rotations take angle units).
        Default: the ``# dof:`` metadata line, else ``Heave``.
    mass : float or array, optional
        Rigid-body mass [kg] or matrix (else the ``# mass [unit]:`` metadata line, if any).
    resample : bool
        Interpolate irregular sampling onto a uniform grid (cubic,
        :func:`hybridwsi.history.resample`) instead of rejecting it.
    eta : str, optional
        Column of the wave elevation [m, or the length unit of its header] at the body's
        reference point, read as ``eta(time, probe)`` with the column's unit-less name as the
        probe. Default: a column named ``eta`` when there is one (as :func:`to_csv` writes it).

    Units in headers (``[unit]`` or ``(unit)``) are converted to SI: time s/ms, length m/cm/mm,
    angle rad/deg, force N/kN, moment N m/kN m, ...; an unknown unit raises
    :class:`InputError`.
    """
    table = TextTable(path, sep, lazy=True)
    dof_names = list(_dofs.check_dofs(dof if dof is not None else table.meta.get("dof", "Heave")))
    cols = _kinematic_columns(table, dof_names, time=time, z=z, zdot=zdot, zddot=zddot)
    eta_col = table.require(eta, "wave-elevation column") if eta is not None else table.find("eta")
    used = {c for cs in cols.values() for c in cs} | ({eta_col} if eta_col else set())
    named = _named_force_columns(table, forces, dof_names)
    # only the columns asked for are parsed (all of them when the forces are not named)
    table.load(table.columns if named is None else [*used, *(c for cs in named.values() for c in cs)])
    extra_vars, extra_coords = _eta_variable(table, eta_col)
    t, kin, force_cols, force_data, extra_cols, ignored = _read_history_columns(
        table, cols, used, named, dof_names)
    ds = make_history(
        t, kin.get("z"), kin.get("zdot"), kin.get("zddot"), force_data, dof=dof_names,
        mass=_meta_mass(table) if mass is None else mass,
        source=table.meta.get("source", f"csv:{table.path.name}"),
        inputs={"file": str(table.path), "columns": _flat({**cols, **force_cols}),
                "sep": table.sep, **({"eta": eta_col} if eta_col else {}),
                **({"ignored_columns": ignored} if ignored else {})},
        check=False, extra_vars=extra_vars, extra_coords=extra_coords,
    )
    _add_extra_columns(ds, table, extra_cols)
    ds = finalize_import(ds, resample_to_uniform=resample, require_z=z is not None)
    if named is not None and ignored:  # said once the file is read (never before an error)
        warnings.warn(f"{table.path.name}: {ignored} of {len(table.columns)} columns ignored "
                      "(not the time, motion or named force columns)", UserWarning, stacklevel=2)
    return ds


def _read_history_columns(table: TextTable, cols: dict[str, list[str]], used: set[str],
                          named: dict[str, list[str]] | None, dof_names: list[str]) -> tuple:
    """Time [s], motion per role and forces per variable in SI, the force and extra columns
    (every unused numeric one when the forces are not ``named``) and the count of columns
    not read."""
    t = table.numeric(cols["time"][0], "time")
    table.check_time(t)
    kin = {r: _read_dofs(table, c, r, dof_names) for r, c in cols.items() if r != "time"}
    force_cols, extra_cols = (named, {}) if named is not None else _force_columns(
        table, used, dof_names)
    ignored = len(table.columns) - len(used | {c for cs in force_cols.values() for c in cs}
                                       | {c for cs in extra_cols.values() for c in cs})
    force_data = {v: _read_dofs(table, c, "force", dof_names) for v, c in force_cols.items()}
    return t, kin, force_cols, force_data, extra_cols, ignored


def _kinematic_columns(table: TextTable, dof_names: list[str], **given: str | None
                       ) -> dict[str, list[str]]:
    """The header cells of ``time`` and of the motion per DOF (``z``, ``zdot``, ``zddot``:
    a name given must be there; an unnamed derivative is taken when a column has its name)."""
    cols: dict[str, list[str]] = {"time": [table.require(given["time"], "time column")]}
    for role in ("z", "zdot", "zddot"):
        if given[role] is not None:
            cols[role] = _dof_columns(table, given[role], dof_names, f"{role} column")
        elif role != "z":
            found = _dof_columns(table, role, dof_names)
            if found is not None:
                cols[role] = found
    return cols


def _add_extra_columns(ds: xr.Dataset, table: TextTable, extra_cols: dict[str, list[str]]
                       ) -> None:
    """The extra ``(time, dof)`` variables (columns of known non-force units) with their units,
    and the ``estimated`` notes of derivatives written by :func:`to_csv`, in place."""
    for var, cs in extra_cols.items():
        units = [split_header(c)[1] or "" for c in cs]
        ds[var] = (("time", "dof"), np.column_stack([table.numeric(c) for c in cs]),
                   {"units": ", ".join(dict.fromkeys(units)), "units_per_dof": json.dumps(units)})
    for role in ("zdot", "zddot"):
        note = table.meta.get(f"estimated.{role}")
        if note and role in ds:
            ds[role].attrs["estimated"] = note


def _eta_variable(table: TextTable, column: str | None) -> tuple[dict | None, dict | None]:
    """``eta(time, probe)`` [m] of the wave-elevation column (its unit-less name the probe),
    as ``make_history``'s ``extra_vars`` and ``extra_coords``; ``(None, None)`` without one."""
    if column is None:
        return None, None
    values = table.numeric(column, "length")[:, None]
    return ({"eta": (("time", "probe"), values, {"units": "m", "long_name": "wave elevation",
                                                 "column": column})},
            {"probe": [split_header(column)[0]]})


def _column_names(stem: str, dofs: Sequence[str]) -> list[str]:
    """CSV column of ``stem`` per DOF: ``stem`` alone for one DOF, else ``stem_<DOF>``."""
    return [stem] if len(dofs) == 1 else [f"{stem}_{d}" for d in dofs]


def _dof_columns(table: TextTable, stem: str, dofs: Sequence[str],
                 what: str | None = None) -> list[str] | None:
    """Columns of ``stem`` for every DOF: required when ``what`` names them, else None when
    one is missing."""
    names = _column_names(stem, dofs)
    if what is not None:
        return [table.require(n, what) for n in names]
    found = [table.find(n) for n in names]
    return None if any(f is None for f in found) else found  # type: ignore[return-value]


def _read_dofs(table: TextTable, cols: Sequence[str], role: str,
               dofs: Sequence[str]) -> np.ndarray:
    """``(time, dof)`` values of a role in SI, each column converted with its DOF's unit."""
    return np.column_stack([table.numeric(c, quantity_of(role, d)) for c, d in zip(cols, dofs)])


def _flat(columns: Mapping[str, list[str]]) -> dict[str, str | list[str]]:
    """Column record of ``inputs``: a name per role for one DOF, a list per role otherwise."""
    return {k: v[0] if len(v) == 1 else list(v) for k, v in columns.items()}


def _meta_mass(table: TextTable) -> float | np.ndarray | None:
    """Mass from a ``# mass [unit]: value`` line (scalar, or JSON matrix for several DOFs)."""
    for key, value in table.meta.items():
        if split_header(key)[0].lower() != "mass":
            continue
        try:
            return np.asarray(json.loads(value), dtype=float)
        except (ValueError, TypeError):
            raise InputError(f"{table.path.name}: metadata '{key}' is not a number") from None
    return None


def _is_force_unit(unit: str | None, dof: str) -> bool:
    return unit is None or normalise_unit(unit) in UNIT_FACTORS[quantity_of("force", dof)]


def _named_force_columns(
    table: TextTable, forces: Sequence[str] | Mapping[str, str] | str | None, dofs: Sequence[str],
) -> dict[str, list[str]] | None:
    """``{variable: columns}`` of the force columns named by the caller (None: none named)."""
    if forces is None:
        return None
    if isinstance(forces, str):
        forces = [forces]
    mapping = dict(forces) if isinstance(forces, Mapping) else {f: f for f in forces}
    return {_var_name(v): _dof_columns(table, c, dofs, "force column")  # type: ignore[misc]
            for v, c in mapping.items()}


def _force_columns(
    table: TextTable, used: set[str], dofs: Sequence[str],
) -> tuple[dict[str, list[str]], dict[str, list[str]]]:
    """``({variable: columns} of forces, {variable: columns} of extra variables)`` when the
    forces are not named: every other numeric column, grouped per DOF."""
    groups: dict[str, dict[str, str]] = {}
    for col in table.columns:
        if col in used or not table.is_numeric(col):
            continue
        base = split_header(col)[0]
        if len(dofs) == 1:
            groups.setdefault(base, {})[dofs[0]] = col
            continue
        for d in dofs:
            if base.endswith(f"_{d}"):
                groups.setdefault(base[: -len(d) - 1], {})[d] = col
    out: dict[str, list[str]] = {}
    extra: dict[str, list[str]] = {}
    for stem, by_dof in groups.items():
        if set(by_dof) != set(dofs):
            continue  # a column of some DOFs only is not a (time, dof) variable
        cs = [by_dof[d] for d in dofs]
        force = all(_is_force_unit(split_header(c)[1], d) for c, d in zip(cs, dofs))
        (out if force else extra)[_var_name(stem)] = cs
    return out, extra


def _var_name(name: str) -> str:
    """A NetCDF-safe variable name (``/`` is not allowed)."""
    return name.strip().replace("/", "_") or "unnamed"


def to_csv(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write a TimeHistory as CSV atomically (read back exactly by :func:`read_csv`).

    The header carries units per DOF: ``time [s],z [m],...`` for one DOF, ``z_Surge [m],
    z_Pitch [rad],F_tot_Surge [N],F_tot_Pitch [N m],...`` for several. ``#`` lines before it
    carry the version, source, DOFs, mass, inputs and estimation notes. Values are written
    with 17 significant digits so that a round trip is exact.
    """
    dof = [str(d) for d in ds["dof"].values]
    names = [n for n in ds.data_vars if ds[n].dims == ("time", "dof")]
    header, data = ["time [s]"], [np.asarray(ds["time"].values, dtype=float)]
    if "eta" in ds:  # one probe: the column read_csv takes as the wave elevation
        eta = np.asarray(ds["eta"].values, dtype=float).reshape(ds.sizes["time"], -1)
        if eta.shape[1] != 1:
            raise InputError(f"a CSV history holds one wave-elevation column; this history "
                             f"has {eta.shape[1]} probes (write NetCDF instead)")
        header.append("eta [m]")
        data.append(eta[:, 0] * unit_factor(ds["eta"].attrs.get("units"), "length", "eta"))
    for n in names:
        values = np.asarray(ds[n].values, dtype=float)
        for j, (col, unit) in enumerate(zip(_column_names(str(n), dof), units_per_dof(ds, n))):
            header.append(f"{col} [{unit}]".replace(" []", ""))
            data.append(values[:, j])
    meta = [
        "hybridwsi TimeHistory",
        f"hybridwsi_version: {version()}",
        f"source: {ds.attrs.get('source', 'unknown')}",
        f"dof: {', '.join(dof)}",
    ]
    if "mass" in ds:
        m = np.asarray(ds["mass"].values, dtype=float)
        if len(dof) == 1:
            meta.append(f"mass [{ds['mass'].attrs.get('units', 'kg')}]: {float(m.ravel()[0])!r}")
        else:  # units per DOF pair (hybridwsi.dofs.coefficient_unit); JSON floats round-trip
            meta.append(f"mass: {json.dumps(m.tolist())}")
    for n in ("zdot", "zddot"):
        if n in ds and "estimated" in ds[n].attrs:
            meta.append(f"estimated.{n}: {ds[n].attrs['estimated']}")
    meta.append(f"inputs: {ds.attrs.get('inputs', '{}')}")
    table = np.column_stack(data)

    def writer(tmp: str) -> None:
        with open(tmp, "w", encoding="utf-8") as f:
            f.writelines(f"# {line}\n" for line in meta)
            f.write(",".join(header) + "\n")
            np.savetxt(f, table, delimiter=",", fmt="%.17g")

    return atomic_write(path, writer)
