"""WAMIT numeric output files ``ROOT.1``, ``ROOT.3``, ``ROOT.hst`` (the files OpenFAST HydroDyn
reads) ↔ the coefficient Dataset.

File layout (WAMIT User Manual v7, ch. 3 "Definition of quantities" and §5.2 "numeric output
files"; OpenFAST ``modules/hydrodyn/src/WAMIT.f90`` ``WAMIT_Init``, which reads them):

- ``.1``  rows ``PER I J Ā_ij B̄_ij``; the limit rows carry ``PER I J Ā_ij`` only;
- ``.3``  rows ``PER BETA I |X̄_i| arg(X̄_i)[deg] Re(X̄_i) Im(X̄_i)``, BETA the wave heading in
  degrees (direction of propagation from the +x axis, as Capytaine's ``wave_direction``);
- ``.hst`` rows ``I J C̄_ij``.

``I`` is the mode that receives the force and ``J`` the mode that moves (``A_ij = ρ∬ n_i φ_j``),
modes 1…6 = Surge…Yaw; pairs absent from a file are zero (WAMIT omits entries that vanish by
symmetry; HydroDyn initialises them to zero).

Limit rows. With periods in the first column (WAMIT's default ``IPEROUT = 1``), ``PER = −1``
(any negative value) is the infinite period, ω = 0, i.e. **A(0)**, and ``PER = 0`` the zero
period, ω = ∞, i.e. **A(∞)**: HydroDyn ``WAMIT_Init`` ("Periods less than zero in WAMIT
represent infinite period = zero frequency … equal to zero represent infinite frequency");
Capytaine's ``capytaine.io.wamit.export_wamit_1`` writes A(ω=0) as ``PER = −1`` and A(ω=∞) as
``PER = 0``; BEMRosetta's ``Wamit::Load_1`` reads them the same way. So the issue's "PER = −1 and
PER = 0 rows are A(0) and A(∞)" is right, in that order. With radian frequencies in the first
column (``IPEROUT = 2``, ``frequency_input=True``) the same rule applies to the listed quantity:
0 is ω = 0 and a negative value ω = ∞ (BEMRosetta reads HAMS' frequency files this way; we could
not check a WAMIT-written frequency file, so prefer period files).

Normalisation (WAMIT manual ch. 3; HydroDyn ``RdtnDim``, ``DffrctDim``, ``SttcDim``), with L
= ULEN, A = wave amplitude (1: coefficients are per unit amplitude) and k counting the rotational
modes among i, j (0, 1, 2):

==========================  ==================================
``Ā_ij = A_ij / (ρ L^(3+k))``     kg, kg m, kg m²
``B̄_ij = B_ij / (ρ ω L^(3+k))``  N s/m, N s/rad | N m s/m, N m s/rad
``X̄_i = X_i / (ρ g A L^(2+k_i))`` N/m, N m/m
``C̄_ij = C_ij / (ρ g L^(2+k))``   N/m, N/rad | N m/m, N m/rad
==========================  ==================================

(so the hydrostatic powers are 2, 3, 4 — not 3, 4, 5 as for added mass.)

Time convention. WAMIT defines complex outputs by ``Re[(U + iV) e^{+iωt}]`` with the incident
wave ``Re[A e^{iωt}]`` at the origin (manual eq. 3.1–3.2); Capytaine (and this project) uses
``Re[F̂ a e^{−iωt}]``. For a real amplitude both describe the same force iff
``F̂ = conj(X)``: reading conjugates, writing conjugates back (as Capytaine's own exporter does).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.errors import InputError
from hybridwsi.files import atomic_write
from hybridwsi.hydro import coefficients as cf
from hybridwsi.hydro.formats.common import build, content_hash, mode_dof, n_rotations, positive

EXTENSIONS = (".1", ".3", ".hst")


# ------------------------------------------------------------------------------ reading
def root_of(path: Path) -> Path:
    """``DIR/ROOT`` of a WAMIT file ``DIR/ROOT.1`` (or ``.3``, ``.hst``)."""
    return path.with_suffix("") if path.suffix.lower() in EXTENSIONS else path


def sibling(root: Path, ext: str) -> Path:
    """``ROOT.ext`` (lower or upper case), or InputError naming the missing file."""
    for cand in (root.with_name(root.name + ext), root.with_name(root.name + ext.upper())):
        if cand.is_file():
            return cand
    raise InputError(f"WAMIT file {root.name}{ext} not found next to {root.name}.1 "
                     f"(need {', '.join(root.name + e for e in EXTENSIONS)})")


def _rows(path: Path, min_cols: int) -> list[tuple[int, list[float]]]:
    """Numeric rows ``(line number, values)`` of a whitespace-separated file."""
    try:
        text = path.read_text(errors="strict")
    except UnicodeDecodeError:
        raise InputError(f"{path.name}: not a text file") from None
    out = []
    for no, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        try:
            vals = [float(t.replace("D", "E").replace("d", "e")) for t in line.split()]
        except ValueError:
            raise InputError(f"{path.name} line {no}: not numeric: {line.strip()[:60]!r}") from None
        if len(vals) < min_cols:
            raise InputError(f"{path.name} line {no}: {len(vals)} columns, expected {min_cols} "
                             f"(truncated or not a WAMIT file)")
        out.append((no, vals))
    if not out:
        raise InputError(f"{path.name}: no data rows")
    return out


def _mode(value: float, path: Path, no: int) -> int:
    if value != int(value):
        raise InputError(f"{path.name} line {no}: mode index {value} is not an integer")
    return int(value)


def _omega(value: float, frequency_input: bool) -> float:
    """ω [rad/s] of a first-column value: period (or frequency) > 0; 0 and < 0 are the limits."""
    if value > 0:
        return value if frequency_input else 2.0 * math.pi / value
    is_zero_listed = value == 0
    # 0 means "this quantity is zero", negative "it is infinite": T = 0 ↔ ω = ∞, ω = 0 ↔ ω = 0
    return (0.0 if is_zero_listed else math.inf) if frequency_input else \
        (math.inf if is_zero_listed else 0.0)


def _read_1(path: Path, frequency_input: bool):
    finite: dict[float, dict[tuple[int, int], tuple[float, float]]] = {}
    limits: dict[float, dict[tuple[int, int], float]] = {0.0: {}, math.inf: {}}
    for no, v in _rows(path, 4):
        w = _omega(v[0], frequency_input)
        pair = (_mode(v[1], path, no), _mode(v[2], path, no))
        for m in pair:
            mode_dof(m, f"{path.name} line {no}")
        if math.isfinite(w) and w > 0:
            if len(v) < 5:
                raise InputError(f"{path.name} line {no}: 4 columns, expected 5 "
                                 f"(PER I J A B) at a finite period")
            finite.setdefault(w, {})[pair] = (v[3], v[4])
        else:
            limits[w][pair] = v[3]
    if not finite:
        raise InputError(f"{path.name}: no finite period")
    pairs = {frozenset(d) for d in finite.values()}
    if len(pairs) > 1:
        raise InputError(f"{path.name}: the periods list different (I, J) pairs "
                         f"(truncated or corrupt file)")
    return finite, limits


def _read_3(path: Path, frequency_input: bool):
    data: dict[tuple[float, float], dict[int, complex]] = {}
    for no, v in _rows(path, 7):
        w = _omega(v[0], frequency_input)
        if not (math.isfinite(w) and w > 0):
            continue  # excitation has no limit rows; HydroDyn skips them too
        mode = _mode(v[2], path, no)
        mode_dof(mode, f"{path.name} line {no}")
        data.setdefault((w, v[1]), {})[mode] = complex(v[5], v[6])
    if not data:
        raise InputError(f"{path.name}: no finite period")
    if len({frozenset(d) for d in data.values()}) > 1:
        raise InputError(f"{path.name}: the (period, heading) blocks list different modes "
                         f"(truncated or corrupt file)")
    return data


def _read_hst(path: Path) -> dict[tuple[int, int], float]:
    out = {}
    for no, v in _rows(path, 3):
        pair = (_mode(v[0], path, no), _mode(v[1], path, no))
        for m in pair:
            mode_dof(m, f"{path.name} line {no}")
        out[pair] = v[2]
    return out


def _match(w_file: np.ndarray, w_ref: np.ndarray, name: str) -> np.ndarray:
    """Index into ``w_ref`` of every ``w_file`` (relative 1e-6: print precision)."""
    idx = np.array([int(np.argmin(np.abs(w_ref - w))) for w in w_file])
    if w_file.size != w_ref.size or not np.allclose(w_ref[idx], w_file, rtol=1e-6, atol=0) \
            or np.unique(idx).size != idx.size:
        raise InputError(f"{name}: its periods differ from the .1 file's (both must come from "
                         f"the same WAMIT run)")
    return idx


def _pair_matrix(entries: dict, pos: dict[int, int], n: int, pick) -> np.ndarray:
    """(n, n) matrix of ``pick(value)`` at the modes' positions ``pos`` (absent pairs: 0)."""
    out = np.zeros((n, n))
    for (i, j), val in entries.items():
        out[pos[i], pos[j]] = pick(val)
    return out


def _radiation(p1: Path, rho: float, ulen: float, frequency_input: bool):
    """ω, DOFs, A(ω), B(ω) ``[ω, influenced, radiating]`` and the limits ``{0: A(0), inf:
    A(∞)}`` (None when absent) of a ``.1`` file, dimensional (module docstring)."""
    finite, limits = _read_1(p1, frequency_input)
    omega = np.array(sorted(finite))
    modes = sorted({m for d in (*finite.values(), *limits.values()) for pair in d for m in pair})
    dofs = [RIGID_DOFS[m - 1] for m in modes]
    pos = {m: k for k, m in enumerate(modes)}
    n = len(modes)
    # scale[i, j] = L^(k) for the pair; rotations add one length each
    lpow = np.array([[n_rotations(a, b) for b in dofs] for a in dofs])
    rad_scale = rho * ulen ** (3 + lpow)

    def matrix(entries: dict, pick) -> np.ndarray:
        return _pair_matrix(entries, pos, n, pick)

    a = np.array([matrix(finite[w], lambda v: v[0]) for w in omega]) * rad_scale
    b = np.array([matrix(finite[w], lambda v: v[1]) for w in omega]) * rad_scale \
        * omega[:, None, None]
    lim = {w: (matrix(limits[w], float) * rad_scale if limits[w] else None) for w in limits}
    return omega, dofs, a, b, lim


def read_radiation(path: str | Path, *, rho: float, ulen: float = 1.0,
                   frequency_input: bool = False) -> xr.Dataset:
    """Only the radiation coefficients of a ``ROOT.1`` file (no ``.3``/``.hst`` needed), e.g. a
    reference solution to check a BEM run against.

    Returns
    -------
    xarray.Dataset
        ``added_mass`` [kg, kg m, kg m²] and ``radiation_damping`` [N s/m, …] on (omega,
        influenced_dof, radiating_dof), ``added_mass_inf`` and ``added_mass_zero`` on
        (influenced_dof, radiating_dof) (NaN without limit rows); dimensional with ``rho``
        [kg/m³] and ``ulen`` [m].
    """
    p1 = Path(path)
    if not p1.is_file():
        raise InputError(f"WAMIT file {p1} not found")
    omega, dofs, a, b, lim = _radiation(p1, positive(rho, "rho"), positive(ulen, "ulen"),
                                        frequency_input)
    pair = ("influenced_dof", "radiating_dof")
    nan = np.full((len(dofs), len(dofs)), np.nan)
    return xr.Dataset(
        {"added_mass": (("omega", *pair), a), "radiation_damping": (("omega", *pair), b),
         "added_mass_inf": (pair, nan if lim[math.inf] is None else lim[math.inf]),
         "added_mass_zero": (pair, nan if lim[0.0] is None else lim[0.0])},
        coords={"omega": ("omega", omega, {"units": "rad/s"}), "influenced_dof": dofs,
                "radiating_dof": dofs},
        attrs={"source": f"WAMIT {p1.name}", "rho": rho, "ulen": ulen})


def read(path: str | Path, *, rho: float | None, g: float | None, ulen: float = 1.0,
         frequency_input: bool = False, water_depth: float = math.inf) -> xr.Dataset:
    """Read ``ROOT.1`` with its siblings ``ROOT.3`` and ``ROOT.hst`` into a coefficient Dataset.

    Parameters
    ----------
    path : ``ROOT.1`` (or ``ROOT.3``/``ROOT.hst``/``ROOT``).
    rho, g : water density [kg/m³] and gravity [m/s²] of the WAMIT run (the files do not hold
        them).
    ulen : WAMIT's ULEN [m] (length scale of the normalisation).
    frequency_input : the first column is ω [rad/s] (``IPEROUT = 2``) instead of the period [s].
    water_depth : [m] for the attrs (WAMIT's numeric files do not hold it; ``inf`` default).

    Returns
    -------
    xarray.Dataset
        ``added_mass``, ``radiation_damping``, ``excitation_force``, ``added_mass_inf`` and
        ``added_mass_zero`` (NaN where the file has no limit rows), ``hydrostatic_stiffness``;
        no ``mass`` (WAMIT keeps it in the ``.frc``/``.mmx``, which are not read).
    """
    rho, g, ulen = positive(rho, "rho"), positive(g, "g"), positive(ulen, "ulen")
    root = root_of(Path(path))
    p1, p3, phst = sibling(root, ".1"), sibling(root, ".3"), sibling(root, ".hst")
    omega, dofs, a, b, lim = _radiation(p1, rho, ulen, frequency_input)
    n = len(dofs)
    pos = {RIGID_DOFS.index(d) + 1: k for k, d in enumerate(dofs)}
    lpow = np.array([[n_rotations(x, y) for y in dofs] for x in dofs])

    def matrix(entries: dict, pick) -> np.ndarray:
        return _pair_matrix(entries, pos, n, pick)

    exc_rows = _read_3(p3, frequency_input)
    w3 = np.array(sorted({w for w, _ in exc_rows}))
    _match(w3, omega, p3.name)
    betas = np.array(sorted({beta for _, beta in exc_rows}))
    if len(exc_rows) != w3.size * betas.size:
        raise InputError(f"{p3.name}: not every period lists every heading (truncated file)")
    exc = np.zeros((omega.size, betas.size, n), dtype=complex)
    xscale = np.array([rho * g * ulen ** (2 + n_rotations(d)) for d in dofs])
    for (w, beta), modes_x in exc_rows.items():
        iw = int(np.argmin(np.abs(omega - w)))
        ib = int(np.searchsorted(betas, beta))
        for m, x in modes_x.items():
            if m in pos:  # modes without radiation data are not part of the Dataset
                exc[iw, ib, pos[m]] = np.conj(x) * xscale[pos[m]]
    hst = _read_hst(phst)
    c = matrix({k: v for k, v in hst.items() if k[0] in pos and k[1] in pos}, float) \
        * (rho * g * ulen ** (2 + lpow))
    settings = {"rho": rho, "g": g, "ulen": ulen, "frequency_input": frequency_input}
    return build(omega=omega, dofs=dofs, added_mass=a, radiation_damping=b, excitation=exc,
                 directions=np.deg2rad(betas), added_mass_inf=lim[math.inf],
                 added_mass_zero=lim[0.0], hydrostatic_stiffness=c, mass=None, rho=rho, g=g,
                 water_depth=water_depth, source=f"WAMIT {root.name}.1/.3/.hst",
                 input_hash=content_hash([p1, p3, phst], settings), where=p1.name,
                 attrs={"ulen": ulen, "frequency_input": int(frequency_input)})


# ------------------------------------------------------------------------------ writing
def _fmt(x: float) -> str:
    return f"{x: .12E}"


def _limit(coeffs: xr.Dataset, name: str, dofs: Sequence[str]) -> np.ndarray | None:
    """A(0) or A(∞) ``[influenced, radiating]`` when present and finite, else ``None``."""
    if not cf.has(coeffs, name):
        return None
    try:
        return cf.matrix(coeffs, name, dofs)
    except InputError:  # NaN: not computed for this depth / not in the source file
        return None


def excitation(coeffs: xr.Dataset, dofs: Sequence[str]) -> np.ndarray:
    """``excitation_force`` as ``[ω, wave_direction, influenced]`` for ``dofs`` (complex)."""
    if not cf.has(coeffs, "excitation_force"):
        raise InputError("coefficients have no 'excitation_force' (needed for the WAMIT .3 file)")
    da = coeffs["excitation_force"].transpose("omega", "wave_direction", "influenced_dof")
    return np.asarray(da.sel(influenced_dof=list(dofs)).values, dtype=complex)


def write(coeffs: xr.Dataset, root: str | Path, *, ulen: float = 1.0) -> list[Path]:
    """Write ``ROOT.1``, ``ROOT.3`` and ``ROOT.hst`` (same normalisation as :func:`read`).

    Rows follow WAMIT's order: the A(0) (``PER = −1``) and A(∞) (``PER = 0``) rows first when
    the coefficients hold them (HydroDyn needs both), then increasing period; every DOF pair is
    written, zeros included. ``hydrostatic_stiffness`` is written as stored; HydroDyn adds the
    body-weight moment itself, so a ``.hst`` for HydroDyn should hold the buoyancy part only.

    Returns
    -------
    list of pathlib.Path
        The three files written.
    """
    ulen = positive(ulen, "ulen")
    rho = positive(coeffs.attrs.get("rho"), "coefficients attrs 'rho'")
    g = positive(coeffs.attrs.get("g"), "coefficients attrs 'g'")
    dofs = cf.dofs(coeffs)
    modes = [RIGID_DOFS.index(d) + 1 for d in dofs]
    lpow = np.array([[n_rotations(a, b) for b in dofs] for a in dofs])
    rad_scale = rho * ulen ** (3 + lpow)
    omega = cf.omega(coeffs)
    a = cf.matrix_omega(coeffs, "added_mass", dofs) / rad_scale
    b = cf.matrix_omega(coeffs, "radiation_damping", dofs) / (rad_scale * omega[:, None, None])
    period = 2.0 * math.pi / omega
    lines1 = []
    for per, name in ((-1.0, "added_mass_zero"), (0.0, "added_mass_inf")):
        lim = _limit(coeffs, name, dofs)
        if lim is not None:
            lim = lim / rad_scale
            lines1 += [f"{_fmt(per)} {mi:5d} {mj:5d} {_fmt(lim[i, j])}\n"
                       for i, mi in enumerate(modes) for j, mj in enumerate(modes)]
    for k in np.argsort(period):
        lines1 += [f"{_fmt(period[k])} {mi:5d} {mj:5d} {_fmt(a[k, i, j])} {_fmt(b[k, i, j])}\n"
                   for i, mi in enumerate(modes) for j, mj in enumerate(modes)]
    exc = excitation(coeffs, dofs)
    betas = np.rad2deg(np.asarray(coeffs["wave_direction"].values, dtype=float))
    xscale = np.array([rho * g * ulen ** (2 + n_rotations(d)) for d in dofs])
    lines3 = []
    for k in np.argsort(period):
        for ib, beta in enumerate(betas):
            for i, mi in enumerate(modes):
                x = np.conj(exc[k, ib, i]) / xscale[i]  # back to WAMIT's e^{+iωt}
                lines3.append(f"{_fmt(period[k])} {_fmt(beta)} {mi:5d} {_fmt(abs(x))} "
                              f"{_fmt(math.degrees(np.angle(x)))} {_fmt(x.real)} {_fmt(x.imag)}\n")
    c = cf.matrix(coeffs, "hydrostatic_stiffness", dofs) / (rho * g * ulen ** (2 + lpow))
    lines_hst = [f"{mi:5d} {mj:5d} {_fmt(c[i, j])}\n"
                 for i, mi in enumerate(modes) for j, mj in enumerate(modes)]
    root = Path(root)
    root.parent.mkdir(parents=True, exist_ok=True)
    out = []
    for ext, lines in ((".1", lines1), (".3", lines3), (".hst", lines_hst)):
        text = "".join(lines)
        out.append(atomic_write(root.with_name(root.name + ext),
                                lambda tmp, text=text: Path(tmp).write_text(text)))
    return out
