"""MoorDyn (v2, lumped-mass mooring-line dynamics) as a force component: the dynamic mooring.

:class:`MoorDynForce` couples the rigid body to a MoorDyn-C system (PyPI ``moordyn``, the
optional extra ``hybridwsi[mooring]``) through its **coupled fairlead points**: from the body
pose ``q = (surge, sway, heave [m], roll, pitch, yaw [rad])`` each fairlead sits at
``p_i = q_t + R(q) r_i`` (``R = Rz(yaw) Ry(pitch) Rx(roll)``, MoorPy's convention, as the
quasi-static :mod:`hybridwsi.forces.mooring`), MoorDyn integrates the lines with its own time
step (``dtM`` of the input file, sub-stepped inside every solver step) and returns the force of
each line on its fairlead; the component sums them into the 6-DOF force
``F = Σ f_i``, ``M = Σ (p_i − q_t) × f_i`` [N, N m] (moments about the displaced reference
point, global axes: the quasi-static model's convention, so the two are interchangeable).

Coupling (stateful; docs/OC3_HYWIND.md "MoorDyn"): the stepping solver calls
:meth:`MoorDynForce.begin_step` at every sample ``t_k`` with the body state ``(z_k, ż_k)``.
MoorDyn is then advanced from ``t_{k−1}`` to ``t_k`` with the fairleads moving on the straight
line between their positions at the two samples (MoorDyn's ``Step`` moves a coupled point as
``x + v τ``; the positions are continuous, so no tension spike from a jump), and the force of
the new state, ``F(t_k)``, is the force of the whole step ``[t_k, t_k+1]`` (a zero-order hold:
explicit, one step lagged like the loosely coupled codes). The linear yaw spring of the
definition (the crowfoot stand-in) is not in MoorDyn; the component adds ``−k_ψ ψ`` on the stage
state. As the quasi-static component, the force returned is ``F(q) − F0``: the preload ``F0``
(MoorDyn's own static force at rest) belongs to the static balance about which the motions are
measured.

Also: line tensions per sample (:meth:`MoorDynForce.tensions`, :meth:`MoorDynForce.records`),
the linearisation at rest from finite differences of MoorDyn's static equilibrium
(:meth:`MoorDynForce.stiffness`, ``linear_coefficients``), a prescribed-motion driver
(:meth:`MoorDynForce.drive`, which is also ``force(hist)``), and the state for a resume
(:meth:`MoorDynForce.get_state` / :meth:`MoorDynForce.set_state`, MoorDyn's ``Serialize``).
MoorDyn's console output is silenced; it writes its (empty) output file into a private temporary
directory, never beside the input.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import re
import sys
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi._meta import package_version
from hybridwsi.dofs import RIGID_DOFS, check_dofs, index
from hybridwsi.errors import InputError, SolverError
from hybridwsi.files import cache_dir, write_json
from hybridwsi.forces.base import KnownComponent, kinematic
from hybridwsi.forces.mooring import rotation_matrix

#: options every run gets on top of the file's: no per-step "t = ..." line on the console
RUN_OPTIONS = {"disableOutTime": 1}
#: longest chord [s] of the fairlead path inside a solver step (docs/OC3_HYWIND.md: straight
#: chords between 0.1 s samples put the in-phase surge stiffness at T = 10 s 8 % above its limit,
#: 4 % per halving; 0.025 s chords leave 2 % of it, 0.5 % of the force amplitude; the loop area
#: does not notice)
PATH_STEP = 0.025
#: default translation steps [m] of the finite-difference linearisation (docs: a central
#: difference over ±0.5 m has a truncation error < 1e-4 of K11, K33 for OC3)
FD_STEP = 0.5
_HEADER = re.compile(r"^\s*-{2,}\s*([A-Za-z][A-Za-z ]*?)\s*-{2,}")
_FIXED = ("fixed", "anchor", "fix")
_COUPLED = ("coupled", "vessel", "fairlead", "cpld")


def _require_moordyn() -> Any:
    try:
        import moordyn
    except ImportError:
        raise InputError("the MoorDyn mooring model needs the moordyn package: "
                         "pip install 'hybridwsi[mooring]'") from None
    return moordyn


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """Silence the C library's console output (stdout and stderr at the file-descriptor level:
    MoorDyn prints its banner while reading the file, before its verbosity can be set)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    saved = [os.dup(1), os.dup(2)]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)


# ------------------------------------------------------------------------- the input file
def _sections(text: str) -> list[tuple[str, list[tuple[int, str]]]]:
    """``(NAME, [(line number, raw line), ...])`` of every ``--- NAME ---`` section, in order."""
    out: list[tuple[str, list[tuple[int, str]]]] = []
    for no, raw in enumerate(text.splitlines()):
        m = _HEADER.match(raw)
        if m:
            out.append((m.group(1).strip().upper(), []))
        elif out and raw.strip():
            out[-1][1].append((no, raw))
    return out


def _section(text: str, names: Sequence[str]) -> tuple[str, list[tuple[int, str]]] | None:
    for name, rows in _sections(text):
        if name in names:
            return name, rows
    return None


def _table(text: str, names: Sequence[str]) -> list[tuple[int, list[str]]]:
    """Data rows of a table section (after its column-name and unit rows), comments removed."""
    found = _section(text, names)
    if found is None:
        raise InputError(f"MoorDyn input: no '{names[0]}' section (a MoorDyn v2 input file has "
                         "LINE TYPES, POINTS, LINES and OPTIONS sections)")
    return [(no, re.split(r"[!#%]", raw, maxsplit=1)[0].split()) for no, raw in found[1][2:]]


def _options(text: str) -> dict[str, tuple[int, str]]:
    """``{key (lower case): (line number, value)}`` of the OPTIONS section."""
    found = _section(text, ("OPTIONS", "SOLVER OPTIONS"))
    if found is None:
        raise InputError("MoorDyn input: no OPTIONS section")
    out = {}
    for no, raw in found[1]:
        words = re.split(r"[!#%]", raw, maxsplit=1)[0].split()
        if len(words) >= 2:
            out[words[1].lower()] = (no, words[0])
    return out


def set_options(text: str, options: Mapping[str, Any]) -> str:
    """The input with ``options`` (``{key: value}``) set in its OPTIONS section (replaced where
    the key is present, else added as ``value key`` lines at the top of the section)."""
    lines = text.splitlines()
    present = _options(text)
    header = next(no for no, raw in enumerate(lines) if (m := _HEADER.match(raw))
                  and m.group(1).strip().upper() in ("OPTIONS", "SOLVER OPTIONS"))
    new = []
    for key, value in options.items():
        if key.lower() in present:
            no = present[key.lower()][0]
            words = lines[no].split(maxsplit=1)
            lines[no] = f"{value} {words[1]}"
        else:
            new.append(f"{value} {key}")
    return "\n".join(lines[:header + 1] + new + lines[header + 1:]) + "\n"


def set_segments(text: str, segments: int) -> str:
    """The input with every line divided into ``segments`` segments (the LINES NumSegs column)."""
    if int(segments) < 1:
        raise InputError(f"MoorDyn input: segments must be >= 1, got {segments}")
    lines = text.splitlines()
    for no, words in _table(text, ("LINES", "LINE PROPERTIES", "LINE LIST")):
        if len(words) >= 6:
            words[5] = str(int(segments))
            lines[no] = "  ".join(words)
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class MoorDynLayout:
    """The lines of a MoorDyn v2 input, each from a fixed anchor to a coupled fairlead.

    Attributes
    ----------
    anchors, fairleads : ndarray, shape (n_lines, 3)
        Anchor and (at rest) fairlead positions, global frame [m].
    coupled : tuple of int
        For each line, the position of its fairlead among the coupled points (MoorDyn orders
        its coupled degrees of freedom by the points' order in the file, 3 per point).
    anchor_node : tuple of int
        For each line, the node at its anchor (0 if AttachA is the anchor, else NumSegs).
    segments : tuple of int
        NumSegs of each line.
    dtm : float
        MoorDyn's time step ``dtM`` [s].
    """

    anchors: np.ndarray
    fairleads: np.ndarray
    coupled: tuple[int, ...]
    anchor_node: tuple[int, ...]
    segments: tuple[int, ...]
    dtm: float

    @property
    def n_lines(self) -> int:
        return self.anchors.shape[0]


def _points(text: str) -> tuple[dict[str, tuple[str, np.ndarray]], list[str]]:
    """``{id: (kind, xyz)}`` and the coupled point ids in file order."""
    points: dict[str, tuple[str, np.ndarray]] = {}
    coupled = []
    for _, words in _table(text, ("POINTS", "POINT PROPERTIES", "POINT LIST",
                                  "CONNECTION PROPERTIES", "NODE PROPERTIES")):
        if len(words) < 5:
            continue
        kind = words[1].lower()
        if kind not in _FIXED + _COUPLED:
            raise InputError(f"MoorDyn input: point {words[0]} is '{words[1]}'; the component "
                             "couples lines from Fixed anchors to Coupled fairlead points only")
        try:
            xyz = np.array([float(w) for w in words[2:5]])
        except ValueError:
            raise InputError(f"MoorDyn input: point {words[0]} has a non-numeric "
                             "position") from None
        points[words[0]] = ("fixed" if kind in _FIXED else "coupled", xyz)
        if kind in _COUPLED:
            coupled.append(words[0])
    return points, coupled


def read_layout(text: str) -> MoorDynLayout:
    """Parse the anchors, fairleads and lines of a MoorDyn v2 input (:class:`MoorDynLayout`)."""
    for _, words in _table(text, ("LINE TYPES", "LINE DICTIONARY")):
        if len(words) < 10:  # v1: TypeName Diam Mass EA BA Can Cat Cdn Cdt
            raise InputError(f"MoorDyn input: line type '{words[0] if words else ''}' has "
                             f"{len(words)} columns, a v2 file has 10 (TypeName Diam Mass/m EA "
                             "BA/-zeta EI Cd Ca CdAx CaAx); moordyn 2.7 does not read v1 files")
    points, coupled = _points(text)
    anchors, fairleads, order, anchor_node, segments, seen = [], [], [], [], [], set()
    for _, words in _table(text, ("LINES", "LINE PROPERTIES", "LINE LIST")):
        if len(words) < 6:
            continue
        a, b = words[2], words[3]
        kinds = (points.get(a, ("?",))[0], points.get(b, ("?",))[0])
        if sorted(kinds) != ["coupled", "fixed"]:
            raise InputError(f"MoorDyn input: line {words[0]} must join a Fixed anchor and a "
                             f"Coupled fairlead point (it joins {a} and {b})")
        anchor, fair = (a, b) if kinds[0] == "fixed" else (b, a)
        if fair in seen:
            raise InputError(f"MoorDyn input: fairlead point {fair} carries more than one line")
        seen.add(fair)
        try:
            segments.append(int(words[5]))
        except ValueError:
            raise InputError(f"MoorDyn input: line {words[0]} NumSegs is not an integer") from None
        anchors.append(points[anchor][1])
        fairleads.append(points[fair][1])
        order.append(coupled.index(fair))
        anchor_node.append(0 if anchor == a else segments[-1])
    if not anchors:
        raise InputError("MoorDyn input: no lines")
    if len(seen) != len(coupled):
        raise InputError("MoorDyn input: a coupled point carries no line")
    dtm = _options(text).get("dtm")
    if dtm is None:
        raise InputError("MoorDyn input: OPTIONS must set dtM (MoorDyn's time step, s)")
    return MoorDynLayout(np.array(anchors), np.array(fairleads), tuple(order),
                         tuple(anchor_node), tuple(segments), float(dtm[1]))


# ------------------------------------------------------------------------- one MoorDyn system
class _System:
    """One MoorDyn system, created in a private temporary directory (MoorDyn writes its output
    file beside its input) with the console silenced; positions are the fairleads', (n, 3)."""

    def __init__(self, text: str, layout: MoorDynLayout, positions: np.ndarray, t: float,
                 *, solve_statics: bool = True) -> None:
        md = _require_moordyn()
        self.md, self.layout = md, layout
        self._dir = tempfile.TemporaryDirectory(prefix="hybridwsi-moordyn-")
        path = Path(self._dir.name) / "mooring.dat"
        path.write_text(set_options(text, RUN_OPTIONS))
        self.sys = None
        try:
            self._create(path, positions, solve_statics)
        except BaseException:
            self.close()
            raise
        self.lines = [md.GetLine(self.sys, i + 1) for i in range(layout.n_lines)]
        self.x = np.array(positions, dtype=float)
        self.t = float(t)
        coupled = [md.GetPoint(self.sys, i + 1) for i in range(md.GetNumberPoints(self.sys))]
        coupled = [p for p in coupled if md.GetPointType(p) == md.POINT_TYPE_COUPLED]
        self.point_forces = np.array([md.GetPointForce(coupled[j]) for j in layout.coupled])

    def _create(self, path: Path, positions: np.ndarray, solve_statics: bool) -> None:
        md = self.md
        with _quiet():
            try:
                self.sys = md.Create(str(path))
            except Exception as exc:  # the wrapper raises RuntimeError on a bad file
                raise InputError(f"MoorDyn could not read the input file: {exc}") from None
            md.SetVerbosity(self.sys, md.LEVEL_NONE)
            init = md.Init if solve_statics else md.Init_NoIC
            n_cpl = md.NCoupledDOF(self.sys)
            if n_cpl != 3 * self.layout.n_lines:
                raise InputError(f"MoorDyn input: {n_cpl} coupled DOFs, expected 3 per line")
            rc = init(self.sys, self._flat(positions), [0.0] * n_cpl)
        if rc != 0:
            raise SolverError(f"MoorDyn initialisation failed (error code {rc})")

    def _flat(self, positions: np.ndarray) -> list[float]:
        """Fairlead positions per line (n, 3) -> MoorDyn's coupled-DOF vector (file order)."""
        out = np.empty((self.layout.n_lines, 3))
        out[list(self.layout.coupled)] = positions
        return out.ravel().tolist()

    def step(self, positions: np.ndarray, t: float) -> None:
        """Advance to ``t`` with the fairleads moving linearly from ``self.x`` to ``positions``."""
        h = t - self.t
        vel = (positions - self.x) / h
        try:
            f = self.md.Step(self.sys, self._flat(self.x), self._flat(vel), self.t, h)
        except Exception as exc:  # MoorDyn's own failures (NaN states, ...)
            raise SolverError(f"MoorDyn failed at t = {t:.6g} s: {exc}") from None
        f = np.asarray(f, dtype=float).reshape(-1, 3)[list(self.layout.coupled)]
        if f.shape != (self.layout.n_lines, 3) or not np.all(np.isfinite(f)):
            raise SolverError(f"MoorDyn failed at t = {t:.6g} s (non-finite line force); "
                              "check dtM of the input file")
        self.point_forces, self.x, self.t = f, np.array(positions, dtype=float), float(t)

    def tensions(self) -> np.ndarray:
        """(n_lines, 2): fairlead tension |force of the line on its fairlead| and anchor
        tension |tension of the anchor segment| [N]."""
        fair = np.linalg.norm(self.point_forces, axis=1)
        anchor = [np.linalg.norm(self.md.GetLineNodeTen(line, node))
                  for line, node in zip(self.lines, self.layout.anchor_node)]
        return np.column_stack([fair, anchor])

    def serialize(self) -> bytes:
        return bytes(self.md.Serialize(self.sys))

    def deserialize(self, data: bytes) -> None:
        self.md.Deserialize(self.sys, data)

    def close(self) -> None:
        if self.sys is not None:
            with _quiet(), contextlib.suppress(Exception):
                self.md.Close(self.sys)
            self.sys = None
        self._dir.cleanup()


def _hermite(q0: np.ndarray, v0: np.ndarray, q1: np.ndarray, v1: np.ndarray, h: float,
             s: float) -> np.ndarray:
    """Cubic Hermite interpolant of the pose at ``t0 + s h`` from the end values and rates."""
    s2, s3 = s * s, s * s * s
    return ((2 * s3 - 3 * s2 + 1) * q0 + (s3 - 2 * s2 + s) * h * v0
            + (-2 * s3 + 3 * s2) * q1 + (s3 - s2) * h * v1)


def _wrench(forces: np.ndarray, arms: np.ndarray) -> np.ndarray:
    """6-DOF force [N, N m] of point forces (n, 3) at arms (n, 3) from the reference point."""
    return np.concatenate([forces.sum(axis=0), np.cross(arms, forces).sum(axis=0)])


def _skew(r: np.ndarray) -> np.ndarray:
    """``[r]×``: ``_skew(r) @ a = r × a``."""
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def assemble_stiffness(point_stiffness: np.ndarray, forces: np.ndarray, arms: np.ndarray
                       ) -> np.ndarray:
    """6x6 ``K = −∂F/∂q`` at ``q = 0`` of point forces that depend on their own position only.

    ``point_stiffness`` (n, 3, 3) ``K_i = −∂f_i/∂p_i`` [N/m], ``forces`` (n, 3) ``f_i`` [N] at
    rest, ``arms`` (n, 3) ``r_i`` [m]. With ``p_i = q_t + R r_i`` and ``∂(R r)/∂θ = −[r]×`` at
    rest: ``K = [[ΣK_i, −ΣK_i S_i], [ΣS_i K_i, −Σ([f_i]× S_i + S_i K_i S_i)]]`` with
    ``S_i = [r_i]×`` (the ``[f_i]× S_i`` term is the geometric stiffness of the rotating arms).
    Units N/m, N/rad, N m/m, N m/rad; rows force DOF, columns displacement DOF.
    """
    k = np.zeros((6, 6))
    for k_i, f_i, r_i in zip(point_stiffness, forces, arms):
        s = _skew(r_i)
        k[:3, :3] += k_i
        k[:3, 3:] -= k_i @ s
        k[3:, :3] += s @ k_i
        k[3:, 3:] -= _skew(f_i) @ s + s @ k_i @ s
    return k


# ------------------------------------------------------------------------- statics, cached
#: in-process copy of the static solutions (key -> arrays)
_STATICS: dict[str, dict[str, np.ndarray]] = {}
#: bump when the static computation below changes (it is part of every cache key)
_STATICS_VERSION = 1
#: static solutions of the shipped input(s), keyed like the cache (``scripts/oc3_moordyn.py
#: ship``), so a fresh install does not spend the ~30 s of static solves
SHIPPED_STATICS = "moordyn_statics.json"


def statics_cache_dir() -> Path:
    """``$HYBRIDWSI_CACHE/moordyn`` if that variable is set, else ``~/.cache/hybridwsi/moordyn``."""
    return cache_dir("moordyn")


def statics_key(text: str, what: str, step: float) -> str:
    """Cache key of a static solution: the input text, ``what`` ("rest", "stiffness"), the
    finite-difference step [m], the moordyn version and :data:`_STATICS_VERSION`."""
    return what + "-" + hashlib.sha1(json.dumps(
        {"text": text, "what": what, "step": float(step), "version": _STATICS_VERSION,
         "moordyn": package_version("moordyn")}).encode()).hexdigest()


def _shipped_statics(key: str) -> dict[str, Any] | None:
    from importlib import resources

    with contextlib.suppress(OSError, ValueError):
        shipped = json.loads((resources.files("hybridwsi.data") / SHIPPED_STATICS).read_text())
        return shipped.get(key) if isinstance(shipped, dict) else None
    return None


def _cached(text: str, what: str, step: float, compute: Any, use_cache: bool = True
            ) -> dict[str, np.ndarray]:
    """``compute()`` (a dict of arrays) looked up in memory, the disk cache
    (:func:`statics_cache_dir`) and the shipped solutions, else computed and cached
    (``use_cache`` False: computed, nothing read or written)."""
    if not use_cache:
        return compute()
    key = statics_key(text, what, step)
    if key in _STATICS:
        return _STATICS[key]
    path = statics_cache_dir() / f"{key}.json"
    try:
        found = json.loads(path.read_text())
    except (OSError, ValueError):
        found = _shipped_statics(key)
    if not isinstance(found, dict):
        found = {k: v.tolist() for k, v in compute().items()}
        with contextlib.suppress(InputError, OSError):  # a read-only home: memory cache only
            path.parent.mkdir(parents=True, exist_ok=True)
            write_json(path, found)
    _STATICS[key] = {k: np.asarray(v, dtype=float) for k, v in found.items()}
    return _STATICS[key]


def rest_statics(text: str, use_cache: bool = True) -> dict[str, np.ndarray]:
    """MoorDyn's static equilibrium with the fairleads at their positions in ``text``:
    ``forces`` (n_lines, 3) [N] of each line on its fairlead, ``tensions`` (n_lines, 2) [N]
    (fairlead, anchor). One static solve, cached (:func:`_cached`)."""
    layout = read_layout(text)

    def compute() -> dict[str, np.ndarray]:
        system = _System(text, layout, layout.fairleads, 0.0)
        try:
            return {"forces": system.point_forces.copy(), "tensions": system.tensions()}
        finally:
            system.close()

    return _cached(text, "rest", 0.0, compute, use_cache)


def fairlead_stiffness(text: str, step: float = FD_STEP, use_cache: bool = True) -> np.ndarray:
    """Each line's fairlead stiffness ``K_i = −∂f_i/∂p_i`` at rest, (n_lines, 3, 3) [N/m]:
    central differences of MoorDyn's static equilibrium with all fairleads translated by
    ``±step`` [m] along X, Y, Z (6 static solves; the lines are independent), cached."""
    layout = read_layout(text)

    def compute() -> dict[str, np.ndarray]:
        k = np.zeros((layout.n_lines, 3, 3))
        for j in range(3):
            pair = []
            for sign in (1.0, -1.0):
                shift = np.zeros(3)
                shift[j] = sign * step
                system = _System(text, layout, layout.fairleads + shift, 0.0)
                pair.append(system.point_forces.copy())
                system.close()
            k[:, :, j] = -(pair[0] - pair[1]) / (2.0 * step)
        return {"stiffness": k}

    return _cached(text, "stiffness", float(step), compute, use_cache)["stiffness"]


# ------------------------------------------------------------------------- the component
class MoorDynForce(KnownComponent):
    """MoorDyn's mooring-line force on the body: ``F(q) − F0`` on the chosen DOFs (module doc).

    Parameters
    ----------
    input_text : str
        A MoorDyn v2 input file's text: lines from Fixed anchors to Coupled fairlead points
        (fairlead positions at rest, global frame [m]); ``dtM`` in OPTIONS.
    dofs : sequence of str
        DOFs of the histories and ODE states (any subset of the 6; the others are held at 0).
    dt : float, optional
        The solver's step [s] (recorded; MoorDyn sub-steps with its own ``dtM``).
    reference_point : (3,) floats
        O [m], the point rotations and moments are about (the fairlead arms are the file's
        fairlead positions minus O).
    yaw_spring : float
        Additional linear yaw stiffness k_ψ [N m/rad] outside MoorDyn (OC3: 9.834e7).
    source : str
        Where the text came from (for ``describe``).

    Notes
    -----
    Stateful: the stepping solver calls :meth:`begin_step` at every sample (the force of a step
    is MoorDyn's force at its start, a zero-order hold); ``n_states = 0`` because MoorDyn keeps
    its own state. ``linear_coefficients`` gives ``C = K`` from finite differences of MoorDyn's
    static equilibrium (:meth:`stiffness`: 6 static solves, cached on disk in
    :func:`statics_cache_dir`) plus the yaw spring,
    no added mass and no damping: the lines' inertia and drag act through MoorDyn's force
    itself (an ``A_k`` would count them twice in the ODE).
    """

    name = "moordyn"

    def __init__(self, input_text: str, dofs: Sequence[str] | str = RIGID_DOFS, *,
                 dt: float | None = None, reference_point: Sequence[float] = (0.0, 0.0, 0.0),
                 yaw_spring: float = 0.0, source: str = "") -> None:
        self.text = str(input_text)
        self.layout = read_layout(self.text)
        self.dofs = check_dofs(dofs)
        self._index = index(self.dofs)
        if dt is not None and not (math.isfinite(float(dt)) and float(dt) > 0.0):
            raise InputError(f"MoorDyn: dt must be a positive number, got {dt}")
        self.dt = None if dt is None else float(dt)
        self.reference_point = np.asarray(reference_point, dtype=float).reshape(3)
        self.arms = self.layout.fairleads - self.reference_point  # body frame [m]
        self.yaw_spring = float(yaw_spring)
        if not (math.isfinite(self.yaw_spring) and self.yaw_spring >= 0.0):
            raise InputError(f"MoorDyn: yaw_spring must be >= 0, got {yaw_spring}")
        self.source = source
        self._f0: np.ndarray | None = None  # lines' 6-DOF force at rest [N, N m]
        self._live: _System | None = None  # the MoorDyn system of the current run
        self._reset_records()

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_case(cls, case: Mapping[str, Any], dofs: Sequence[str] | str | None = None, *,
                  dt: float | None = None, case_dir: str | os.PathLike | None = None
                  ) -> MoorDynForce:
        """The MoorDyn model of a case: ``[mooring] moordyn_file`` (relative to ``case_dir``;
        default the built-in cases' directory), ``yaw_spring`` and ``[body] reference_point``.

        ``dofs`` default: the case's ``default_dofs``.
        """
        moor = case.get("mooring", {}) if isinstance(case, Mapping) else {}
        name = moor.get("moordyn_file")
        if not name:
            raise InputError("case has no [mooring] moordyn_file (the MoorDyn v2 input file)")
        if case_dir is None:
            from importlib import resources

            path = Path(str(resources.files("hybridwsi.cases") / str(name)))
        else:
            path = Path(case_dir) / str(name)
        try:
            text = path.read_text()
        except OSError as exc:
            raise InputError(f"cannot read the MoorDyn input file {path}: {exc.strerror}") from None
        ref = case.get("body", {}).get("reference_point", (0.0, 0.0, 0.0))
        return cls(text, dofs if dofs is not None else case.get("default_dofs", RIGID_DOFS),
                   dt=dt, reference_point=ref, yaw_spring=moor.get("yaw_spring", 0.0),
                   source=str(path))

    def spawn(self, dofs: Sequence[str] | str | None = None) -> MoorDynForce:
        """A new component on the same input (its own MoorDyn run)."""
        new = MoorDynForce(self.text, self.dofs if dofs is None else dofs, dt=self.dt,
                           reference_point=self.reference_point, yaw_spring=self.yaw_spring,
                           source=self.source)
        new._f0 = self._f0
        return new

    def __getstate__(self) -> dict[str, Any]:  # pickling (Dask): MoorDyn systems stay behind
        state = dict(self.__dict__)
        state["_live"] = None
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)

    def close(self) -> None:
        """Free the MoorDyn systems (also done when the component is garbage-collected)."""
        system = self.__dict__.get("_live")
        if system is not None:
            system.close()
        self.__dict__["_live"] = None

    def __del__(self) -> None:
        with contextlib.suppress(Exception):
            self.close()

    # ------------------------------------------------------------------ geometry
    def _pose(self, z: np.ndarray) -> np.ndarray:
        z = np.asarray(z, dtype=float).reshape(-1)
        if z.size != len(self.dofs):
            raise InputError(f"MoorDyn component is set up for {len(self.dofs)} DOFs "
                             f"({', '.join(self.dofs)}), got {z.size}")
        q = np.zeros(6)
        q[self._index] = z
        return q

    def _arms(self, q: np.ndarray) -> np.ndarray:
        """Fairlead arms in global axes at pose ``q`` [m], (n_lines, 3)."""
        r = np.array(rotation_matrix(q[3], q[4], q[5]), dtype=float)
        return self.arms @ r.T

    def fairleads(self, q: Sequence[float]) -> np.ndarray:
        """Fairlead positions [m] at the 6-DOF pose ``q``, global frame, (n_lines, 3)."""
        q = np.asarray(q, dtype=float)
        return q[:3] + self.reference_point + self._arms(q)

    # ------------------------------------------------------------------ statics
    def rest_force(self) -> np.ndarray:
        """``F0``: the lines' 6-DOF force [N, N m] in MoorDyn's static equilibrium at rest."""
        if self._f0 is None:
            self._f0 = _wrench(rest_statics(self.text)["forces"], self.arms)
        return self._f0.copy()

    def stiffness(self, step: float = FD_STEP) -> np.ndarray:
        """6x6 ``K = −∂F/∂q`` at rest [N/m, N/rad, N m/m, N m/rad], lines plus yaw spring:
        :func:`fairlead_stiffness` (MoorDyn statics, finite differences of ``±step`` m)
        assembled with the rotating arms by :func:`assemble_stiffness`. Cached on disk."""
        k = assemble_stiffness(fairlead_stiffness(self.text, step),
                               rest_statics(self.text)["forces"], self.arms)
        k[5, 5] += self.yaw_spring
        return k

    # ------------------------------------------------------------------ stepping
    def _reset_records(self) -> None:
        self._rec_t: list[float] = []
        self._rec_f: list[np.ndarray] = []
        self._rec_tension: list[np.ndarray] = []
        self._rec_q: list[np.ndarray] = []
        self._q = np.zeros(6)  # pose and its rate at the live state's time
        self._qdot = np.zeros(6)
        self._force6 = np.zeros(6)  # lines' force minus F0 of the current state [N, N m]

    def _start(self, t: float, q: np.ndarray) -> None:
        """A new run at time ``t`` from MoorDyn's static equilibrium at pose ``q``."""
        self.rest_force()
        self.close()
        self._live = _System(self.text, self.layout, self.fairleads(q), t)
        self._reset_records()

    def _update(self, q: np.ndarray, qdot: np.ndarray, tension: np.ndarray | None = None
                ) -> None:
        """Force and records of the live state at pose ``q`` (``tension``: known already)."""
        live = self._live
        self._q, self._qdot = q, qdot
        self._force6 = _wrench(live.point_forces, self._arms(q)) - self._f0
        self._rec_t.append(live.t)
        self._rec_q.append(q)
        self._rec_f.append(self._force6)
        self._rec_tension.append(live.tensions() if tension is None else tension)

    def begin_step(self, t: float, z: np.ndarray, zdot: np.ndarray, dt: float) -> None:
        """Bring MoorDyn to time ``t`` [s] with the body at ``z`` [m, rad] (the solver's hook).

        Called at every sample: a later ``t`` advances MoorDyn from its current time along the
        cubic Hermite path of the pose between the two samples (positions and rates, ``z``,
        ``zdot`` [m/s, rad/s]), in chords of at most :data:`PATH_STEP` (MoorDyn moves a coupled
        point at constant velocity within a call and sub-steps each chord with its ``dtM``); the
        same ``t`` keeps the state (a repeated call, or the first call after
        :meth:`set_state`); an earlier ``t``, or the first call, starts a new run from
        MoorDyn's static equilibrium at ``z``. ``dt`` is not needed.
        """
        q, qdot = self._pose(z), self._pose(zdot)
        t = float(t)
        if not (math.isfinite(t) and np.all(np.isfinite(q)) and np.all(np.isfinite(qdot))):
            raise SolverError(f"MoorDyn: the body state at t = {t:.6g} s is not finite")
        live = self._live
        tol = 1e-9 * max(1.0, abs(t))
        if live is None or t < live.t - tol or not self._rec_t:
            self._start(t, q)
        elif t > live.t + tol:
            t0, q0, v0 = live.t, self._q, self._qdot
            h = t - t0
            n = max(1, math.ceil(h / PATH_STEP - 1e-9))
            for j in range(1, n + 1):
                live.step(self.fairleads(_hermite(q0, v0, q, qdot, h, j / n)), t0 + h * j / n)
        else:
            return
        self._update(q, qdot)

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        """``F(t_k) − F0`` held over the step on the component's DOFs, plus ``−k_ψ ψ`` at z."""
        if self._live is None:
            raise SolverError("MoorDynForce is stateful: the solver must call begin_step(t, z, "
                              "zdot, dt) at every step before ode_force")
        q = self._pose(z)
        f = self._force6.copy()
        f[5] -= self.yaw_spring * q[5]
        return f[self._index]

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if n_dof != len(self.dofs):
            raise InputError(f"MoorDyn component is set up for {len(self.dofs)} DOFs, got {n_dof}")
        zero = np.zeros((n_dof, n_dof))
        return zero, zero.copy(), self.stiffness()[np.ix_(self._index, self._index)]

    def tensions(self) -> np.ndarray:
        """Fairlead and anchor tension of each line in the latest state, (n_lines, 2) [N]."""
        if not self._rec_tension:  # no run yet: the static equilibrium at rest
            return rest_statics(self.text)["tensions"].copy()
        return self._rec_tension[-1].copy()

    def records(self) -> xr.Dataset:
        """The samples of the current run: ``force(time, dof)`` [N, N m] (lines' force minus
        ``F0``, without the yaw spring, all 6 DOFs), ``T_fairlead``, ``T_anchor``
        ``(time, line)`` [N]."""
        t = np.array(self._rec_t)
        tension = np.array(self._rec_tension).reshape(t.size, self.layout.n_lines, 2)
        lines = np.arange(1, self.layout.n_lines + 1)
        return xr.Dataset(
            {"force": (("time", "dof"), np.array(self._rec_f).reshape(t.size, 6),
                       {"units": "N (translations), N m (rotations)"}),
             "T_fairlead": (("time", "line"), tension[:, :, 0], {"units": "N"}),
             "T_anchor": (("time", "line"), tension[:, :, 1], {"units": "N"})},
            coords={"time": ("time", t, {"units": "s"}), "dof": list(RIGID_DOFS), "line": lines})

    # ------------------------------------------------------------------ prescribed motion
    def drive(self, t: np.ndarray, z: np.ndarray, zdot: np.ndarray | None = None
              ) -> xr.Dataset:
        """MoorDyn along a prescribed motion: ``z`` (n_time, n_dof) [m, rad] and its rate
        ``zdot`` [m/s, rad/s] (default: ``numpy.gradient`` of ``z``) at times ``t`` [s], from
        the static equilibrium at ``z[0]``; returns :meth:`records` of that run plus
        ``F(time, dof_c)`` the component's force on its DOFs (yaw spring included). Runs on a
        :meth:`spawn` copy: this component's own run is untouched."""
        t = np.asarray(t, dtype=float)
        if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise InputError("MoorDyn drive: time must be finite and increasing (2+ samples)")
        z = np.asarray(z, dtype=float).reshape(t.size, -1)
        zdot = (np.gradient(z, t, axis=0) if zdot is None
                else np.asarray(zdot, dtype=float).reshape(z.shape))
        if not (np.all(np.isfinite(z)) and np.all(np.isfinite(zdot))):
            raise InputError("MoorDyn drive: the motion is not finite")
        copy = self.spawn()
        try:
            out = np.empty_like(z)
            for k, (tk, zk, vk) in enumerate(zip(t, z, zdot)):
                copy.begin_step(tk, zk, vk, 0.0)
                out[k] = copy.ode_force(tk, zk, vk, np.zeros(0))
            rec = copy.records()
        finally:
            copy.close()
        return rec.assign(F=(("time", "dof_c"), out, {"units": "N, N m per DOF"}),
                          dof_c=list(self.dofs))

    def _ran_in(self, hist: xr.Dataset) -> bool:
        """True when ``hist`` is the run this component recorded (same times, same motion)."""
        t = hist["time"].values
        if len(self._rec_t) != t.size:
            return False
        q = np.array(self._rec_q)[:, self._index]
        return (np.allclose(self._rec_t, t, rtol=0.0, atol=1e-9 * max(1.0, float(t[-1])))
                and np.array_equal(q, kinematic(hist, "z")))

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """The force on the history, (n_time, n_dof) [N, N m]: what entered the ODE when
        ``hist`` is the run this component was coupled in (its records), else MoorDyn driven
        along the history's ``z``, ``zdot`` (:meth:`drive`)."""
        dofs = tuple(str(d) for d in hist["dof"].values)
        if dofs != self.dofs:
            raise InputError(f"MoorDyn component DOFs {list(self.dofs)} differ from the "
                             f"history's {list(dofs)}")
        if self._ran_in(hist):
            f = np.array(self._rec_f)
            f[:, 5] -= self.yaw_spring * np.array(self._rec_q)[:, 5]
            return f[:, self._index]
        return self.drive(hist["time"].values, kinematic(hist, "z"),
                          kinematic(hist, "zdot"))["F"].values

    @property
    def n_lines(self) -> int:
        """Number of mooring lines."""
        return self.layout.n_lines

    def line_tensions(self, hist: xr.Dataset) -> np.ndarray:
        """Fairlead and anchor tension of every line at the history's samples,
        (n_time, n_lines, 2) [N] (the :class:`~hybridwsi.forces.mooring.LineTensions`
        protocol): the recorded ones when ``hist`` is this component's run, else from
        :meth:`drive` along the history."""
        if self._ran_in(hist):
            return np.array(self._rec_tension)
        rec = self.drive(hist["time"].values, kinematic(hist, "z"), kinematic(hist, "zdot"))
        return np.stack([rec["T_fairlead"].values, rec["T_anchor"].values], axis=-1)

    # ------------------------------------------------------------------ resume
    def get_state(self) -> dict[str, Any]:
        """The live run's state: time, pose, fairlead positions and forces, tensions and
        MoorDyn's own serialised state (bytes); :meth:`set_state` continues from it."""
        if self._live is None or not self._rec_t:
            raise SolverError("MoorDyn: no run to save (begin_step has not been called)")
        live = self._live
        return {"t": live.t, "q": self._q.copy(), "qdot": self._qdot.copy(), "x": live.x.copy(),
                "point_forces": live.point_forces.copy(),
                "tension": self._rec_tension[-1].copy(), "moordyn": live.serialize()}

    def set_state(self, state: Mapping[str, Any]) -> None:
        """Continue a run saved by :meth:`get_state` (records restart at its sample)."""
        try:
            t, data = float(state["t"]), bytes(state["moordyn"])
            q, x = np.asarray(state["q"], float), np.asarray(state["x"], float)
        except (KeyError, TypeError, ValueError):
            raise InputError("MoorDyn: not a saved state (needs t, q, x, moordyn)") from None
        self.rest_force()
        self.close()
        live = _System(self.text, self.layout, x, t, solve_statics=False)
        try:
            live.deserialize(data)
        except Exception as exc:
            live.close()
            raise InputError(f"MoorDyn: the saved state does not fit this input ({exc})") from None
        live.point_forces = np.asarray(state["point_forces"], float).reshape(-1, 3)
        self._live = live
        self._reset_records()
        self._update(q, np.asarray(state.get("qdot", np.zeros(6)), float),
                     np.asarray(state["tension"], float).reshape(-1, 2))

    def describe(self) -> str:
        segments = "/".join(map(str, sorted(set(self.layout.segments))))
        return (f"moordyn({self.layout.n_lines} lines, {segments} segments, dtM "
                f"{self.layout.dtm:g} s, yaw spring {self.yaw_spring:.4g} N m/rad, DOFs "
                f"{','.join(self.dofs)}{', ' + self.source if self.source else ''})")
