"""Quasi-static catenary mooring with MoorPy, and its tabulated interpolant for the time loop.

Three objects, from the definition to the ODE:

- :class:`MooringLines`: the line data (anchors, fairleads, one line type), e.g. the OC3-Hywind
  mooring of ``cases/oc3_hywind.toml`` (:meth:`MooringLines.from_case`), plus an optional linear
  yaw spring (the OC3 stand-in for the crowfoot).
- :class:`MooringSystem`: the MoorPy model of those lines. ``force6(q)`` is the full nonlinear
  6-DOF quasi-static force on the platform at the displacement ``q`` (every line statically
  solved at its displaced fairlead), ``stiffness()`` its analytic linearisation
  ``K = -dF/dq`` at ``q = 0`` (the sign convention of OC3 Eq. 5-1) and ``preload()`` the force
  ``F0 = F(0)``. Needs the optional extra ``hybridwsi[mooring]`` (MoorPy).
- :class:`MooringTable`: the interpolant. Every line shares one line type and its anchor lies on
  the seabed, so the force a line exerts on its fairlead depends only on the fairlead's
  horizontal and vertical distance from the anchor, ``(l_h, l_v)``: one 2-D table of the
  horizontal and vertical fairlead force, solved by MoorPy's catenary routine, serves every line
  (the catenary's own symmetry, no approximation). The 6-DOF force is assembled from the
  displaced fairlead geometry exactly as MoorPy does, so the only error is the bicubic
  interpolation in ``(l_h, l_v)``. A full 6-D tensor table would need ~10^6-10^9 MoorPy solves
  for the same accuracy; this one needs ~600 (half a second). The table is an
  :class:`xarray.Dataset` (``table.dataset``, read back with :meth:`MooringTable.from_dataset`),
  and evaluating it needs no MoorPy.

:class:`MooringForce` (the interpolant) and :class:`QuasiStaticMooring` (MoorPy solved at every
call) are the :class:`~hybridwsi.forces.base.KnownComponent` s for the Cummins equation and the
diagnostic. Their force is the mooring force MINUS the preload, ``F(q) - F0``: the static
balance ``rho g V0 - m g + F0_z = 0`` is already built into the equilibrium about which the
linear hydrostatics ``-C q`` are written (docs/OC3_HYWIND.md).

Line tensions: a mooring component that can say them implements :class:`LineTensions`
(``line_tensions(hist)`` -> (n_time, n_lines, 2) [N], fairlead then anchor); the case model
records them in a TimeHistory as ``T_fairlead`` and ``T_anchor`` (dims ``time``, ``line``).
Both components here do; a component with internal states (MoorDyn) returns what it recorded
while the ODE ran. In the quasi-static models the anchor tension follows from the fairlead's:
with no seabed friction the vertical force drops along the line by the weight of its suspended
part, so ``V_anchor = max(V_fairlead - w L, 0)`` (``w`` the weight in water per unstretched
length, ``L`` the unstretched length) and ``T = hypot(H, V)`` at either end.

Conventions: ``q = (surge, sway, heave [m], roll, pitch, yaw [rad])`` of the reference point
(OC3: the platform centreline at the still-water level); rotations as MoorPy's
``rotationMatrix`` (intrinsic z-y'-x'', ``R = Rz(yaw) Ry(pitch) Rx(roll)``); forces [N] in the
global axes, moments [N m] about the displaced reference point, global axes.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
import xarray as xr
from scipy.interpolate import RectBivariateSpline

from hybridwsi.dofs import RIGID_DOFS, check_dofs, index
from hybridwsi.errors import InputError, SolverError
from hybridwsi.files import cache_dir, read_netcdf, to_netcdf
from hybridwsi.forces.base import KnownComponent, kinematic

#: default tabulation box, half-widths per DOF [m, m, m, rad, rad, rad] (docs/OC3_HYWIND.md:
#: mean rotor thrust offset ~20 m plus the largest regular sea's surge, heave RAO << 1 below the
#: 31 s heave period, mean pitch under rated thrust ~0.05 rad plus waves)
DEFAULT_RANGES: dict[str, float] = {
    "Surge": 40.0, "Sway": 20.0, "Heave": 6.0, "Roll": 0.1, "Pitch": 0.15, "Yaw": 0.15,
}
#: default table spacing in (l_h, l_v) [m]: for OC3 the 6-DOF force is then within 3e-5 of
#: each DOF's force excursion over the default box (1 m: 4e-6, 4 m: 2e-4; docs/OC3_HYWIND.md)
DEFAULT_SPACING = 2.0
#: margin added around the (l_h, l_v) extent of the box [m]
_MARGIN = 2.0
#: catenary tolerance of the table solves [m] (MoorPy's default is 1e-4 m)
_TABLE_TOL = 1e-8


def _require_moorpy() -> Any:
    try:
        import moorpy
    except ImportError:
        raise InputError(
            "the mooring model needs MoorPy: pip install 'hybridwsi[mooring]'"
        ) from None
    return moorpy


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise InputError(f"mooring: {name} must be a positive finite number, got {value}")
    return value


def _ring(n: int, radius: float, z: float, heading_deg: float) -> np.ndarray:
    """``n`` points equally spaced on a horizontal circle, the first at ``heading_deg``."""
    angles = np.radians(heading_deg + 360.0 * np.arange(n) / n)
    return np.column_stack([radius * np.cos(angles), radius * np.sin(angles), np.full(n, z)])


@dataclass(frozen=True)
class MooringLines:
    """Catenary lines of one line type, anchored on a flat seabed.

    Parameters
    ----------
    anchors : array, shape (n_lines, 3)
        Anchor positions, global frame [m] (on the seabed: z = -water_depth).
    fairleads : array, shape (n_lines, 3)
        Fairlead positions in the body frame, relative to the reference point [m].
    length : float
        Unstretched line length [m].
    mass_per_length : float
        Line mass per unit length [kg/m].
    weight_in_water : float
        Apparent (submerged) weight per unit length [N/m].
    EA : float
        Extensional stiffness [N].
    water_depth, rho, g : float
        Depth [m], water density [kg/m³], gravity [m/s²].
    yaw_spring : float
        Additional linear yaw stiffness [N m/rad] (OC3: replaces the crowfoot), 0 for none.
    diameter : float
        Nominal line diameter [m] (MoorPy's line-type bookkeeping; the statics use the weight).
    """

    anchors: np.ndarray
    fairleads: np.ndarray
    length: float
    mass_per_length: float
    weight_in_water: float
    EA: float
    water_depth: float
    rho: float
    g: float
    yaw_spring: float = 0.0
    diameter: float = 0.0

    def __post_init__(self) -> None:
        anchors = np.asarray(self.anchors, dtype=float)
        fairleads = np.asarray(self.fairleads, dtype=float)
        if anchors.ndim != 2 or anchors.shape[1] != 3 or anchors.shape != fairleads.shape:
            raise InputError("mooring: anchors and fairleads must both have shape (n_lines, 3)")
        for name in ("length", "mass_per_length", "weight_in_water", "EA", "water_depth",
                     "rho", "g"):
            object.__setattr__(self, name, _positive(name, getattr(self, name)))
        if self.yaw_spring < 0.0 or not math.isfinite(self.yaw_spring):
            raise InputError(f"mooring: yaw_spring must be >= 0, got {self.yaw_spring}")
        if not np.allclose(anchors[:, 2], -self.water_depth):
            raise InputError("mooring: every anchor must lie on the seabed (z = -water_depth)")
        if self.mass_per_length * self.g <= self.weight_in_water:
            raise InputError("mooring: weight in water must be below the weight in air")
        object.__setattr__(self, "anchors", anchors)
        object.__setattr__(self, "fairleads", fairleads)

    @classmethod
    def symmetric(
        cls,
        n_lines: int,
        *,
        anchor_radius: float,
        fairlead_radius: float,
        fairlead_depth: float,
        heading: float = 0.0,
        **line: float,
    ) -> MooringLines:
        """Lines equally spaced around the centreline, line 1 at ``heading`` [deg] from +X.

        ``line`` holds the other fields (``length``, ``mass_per_length``, ``weight_in_water``,
        ``EA``, ``water_depth``, ``rho``, ``g``, ``yaw_spring``, ``diameter``).
        """
        if int(n_lines) < 1:
            raise InputError(f"mooring: n_lines must be >= 1, got {n_lines}")
        depth = _positive("water_depth", line.get("water_depth", float("nan")))
        return cls(
            anchors=_ring(int(n_lines), anchor_radius, -depth, heading),
            fairleads=_ring(int(n_lines), fairlead_radius, -fairlead_depth, heading),
            **line,
        )

    @classmethod
    def from_case(cls, case: Mapping[str, Any]) -> MooringLines:
        """The ``[mooring]`` and ``[environment]`` tables of a case (``load_case(...)``)."""
        try:
            moor, env = case["mooring"], case["environment"]
            return cls.symmetric(
                int(moor["n_lines"]),
                anchor_radius=moor["anchor_radius"],
                fairlead_radius=moor["fairlead_radius"],
                fairlead_depth=moor["fairlead_depth"],
                heading=moor.get("line1_heading", 0.0),
                length=moor["unstretched_length"],
                mass_per_length=moor["mass_per_length"],
                weight_in_water=moor["weight_in_water"],
                EA=moor["EA"],
                water_depth=env["water_depth"],
                rho=env["rho"],
                g=env["g"],
                yaw_spring=moor.get("yaw_spring", 0.0),
                diameter=moor.get("diameter", 0.0),
            )
        except KeyError as exc:
            raise InputError(f"case has no mooring entry {exc}") from None

    @property
    def n_lines(self) -> int:
        return self.anchors.shape[0]

    @property
    def volumetric_diameter(self) -> float:
        """Diameter [m] whose displaced water makes the weight in water what it is."""
        displaced = self.mass_per_length - self.weight_in_water / self.g  # [kg/m]
        return math.sqrt(4.0 * displaced / (self.rho * math.pi))

    def to_dict(self) -> dict[str, Any]:
        """JSON-able description (the table's provenance and hash)."""
        return {
            "anchors": self.anchors.tolist(), "fairleads": self.fairleads.tolist(),
            "length": self.length, "mass_per_length": self.mass_per_length,
            "weight_in_water": self.weight_in_water, "EA": self.EA,
            "water_depth": self.water_depth, "rho": self.rho, "g": self.g,
            "yaw_spring": self.yaw_spring, "diameter": self.diameter,
        }


def rotation_matrix(roll: Any, pitch: Any, yaw: Any, xp: Any = np) -> Any:
    """MoorPy's rotation ``Rz(yaw) Ry(pitch) Rx(roll)`` as nested 3x3 tuples of entries.

    Entries are floats (``xp=math``) or arrays (``xp=numpy``) of the same shape as the angles.
    """
    from hybridwsi.forces._compiled import rotation_from  # one formula with the kernel

    return rotation_from(xp.sin(yaw), xp.cos(yaw), xp.sin(pitch), xp.cos(pitch), xp.sin(roll),
                         xp.cos(roll))


def _as_states(q: Any) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    if q.shape[-1:] != (6,) or q.ndim > 2:
        raise InputError(f"mooring: displacement must have shape (6,) or (n, 6), got {q.shape}")
    return q  # NaN fails the table's range check (SolverError): no separate test here


class MooringSystem:
    """The MoorPy model of :class:`MooringLines`: a coupled body with the fairleads on it."""

    def __init__(self, lines: MooringLines) -> None:
        moorpy = _require_moorpy()
        self.lines = lines
        ms = moorpy.System(depth=lines.water_depth, rho=lines.rho, g=lines.g)
        # moorpy 1.3 needs dnommm to build a line type from explicit properties
        ms.setLineType(dnommm=1000.0 * (lines.diameter or lines.volumetric_diameter),
                       name="line", mass=lines.mass_per_length, d_vol=lines.volumetric_diameter,
                       w=lines.weight_in_water, EA=lines.EA)
        self.body = ms.addBody(-1, np.zeros(6))  # -1: moved by us (coupled), not equilibrated
        for anchor, fairlead in zip(lines.anchors, lines.fairleads):
            a = ms.addPoint(1, anchor)
            f = ms.addPoint(1, fairlead, body=self.body.number)
            ms.addLine(lines.length, "line", pointA=a.number, pointB=f.number)
        ms.initialize()
        self.moorpy = ms

    @classmethod
    def from_case(cls, case: Mapping[str, Any]) -> MooringSystem:
        return cls(MooringLines.from_case(case))

    def lines_force6(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Force of the catenary lines alone on the platform at ``q`` [N, N m], shape (6,)."""
        q = _as_states(q)
        if q.ndim != 1:
            raise InputError("MooringSystem.force6 takes one displacement of shape (6,); "
                             "use MooringTable.force6 for batches")
        self.body.setPosition(q)
        for line in self.moorpy.lineList:  # each line statically solved at its fairlead
            line.staticSolve()
        return np.array(self.body.getForces(lines_only=True), dtype=float)

    def tensions(self) -> np.ndarray:
        """Fairlead and anchor tension of every line at the last position solved [N], shape
        (n_lines, 2) (MoorPy's ``Line.TB`` and ``Line.TA``)."""
        return np.array([[line.TB, line.TA] for line in self.moorpy.lineList], dtype=float)

    def force6(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Full nonlinear quasi-static mooring force at ``q``: lines plus yaw spring [N, N m]."""
        f = self.lines_force6(q)
        f[5] -= self.lines.yaw_spring * float(np.asarray(q)[5])
        return f

    def preload(self) -> np.ndarray:
        """``F0 = F(0)`` [N, N m], shape (6,) (OC3: vertical about -1 607 kN)."""
        return self.force6(np.zeros(6))

    def stiffness(self, yaw_spring: bool = True) -> np.ndarray:
        """Analytic 6x6 ``K = -dF/dq`` at ``q = 0`` (MoorPy), with the yaw spring or without.

        Rows: force DOF, columns: displacement DOF; units N/m, N/rad (force per rotation),
        N m/m, N m/rad.
        """
        self.body.setPosition(np.zeros(6))
        for line in self.moorpy.lineList:
            line.staticSolve()
        k = np.array(self.moorpy.getCoupledStiffnessA(lines_only=True), dtype=float)
        if yaw_spring:
            k[5, 5] += self.lines.yaw_spring
        return k

    def fairlead_force(self, l_h: float, l_v: float, guess: tuple[float, float] = (0.0, 0.0)
                       ) -> tuple[float, float]:
        """Horizontal and vertical force of one line on its fairlead [N], both >= 0.

        ``l_h``, ``l_v``: fairlead position relative to the anchor, horizontal distance and
        height [m]. The horizontal force points from the fairlead towards the anchor, the
        vertical one down. MoorPy's catenary routine with the arguments ``Line.staticSolve``
        uses for an anchor on the seabed; ``guess`` warm-starts it.
        """
        from moorpy.Catenary import catenary  # after _require_moorpy in __init__

        lines = self.lines
        _, _, h_b, v_b, _ = catenary(l_h, l_v, lines.length, lines.EA, lines.weight_in_water,
                                     CB=0.0, alpha=0.0, HF0=guess[0], VF0=guess[1],
                                     Tol=_TABLE_TOL, depth=lines.water_depth)
        return -float(h_b), -float(v_b)

    def line_shapes(self, q: Sequence[float] | np.ndarray, n_nodes: int = 201) -> np.ndarray:
        """Quasi-static shape of every line at the body pose ``q``: positions [m] of ``n_nodes``
        material points equally spaced in unstretched arc length from the anchor, global
        frame, shape (n_lines, n_nodes, 3).

        The fairlead force comes from MoorPy's catenary solve (:meth:`fairlead_force`); the
        profile is the elastic catenary with a frictionless seabed part in closed form
        (Jonkman 2007, NREL/TP-500-41958, Eqs. 2-2/2-3; not MoorPy's node profile, whose
        seabed and suspended branches differ by up to the seabed part's stretch at the
        touchdown point, a jump of ~0.3 m for OC3).
        """
        lines = self.lines
        q = _as_states(q)
        r = np.array(rotation_matrix(q[3], q[4], q[5]), dtype=float)
        s = np.linspace(0.0, lines.length, int(n_nodes))
        w, ea = lines.weight_in_water, lines.EA
        out = np.empty((lines.n_lines, s.size, 3))
        for i, (anchor, fairlead) in enumerate(zip(lines.anchors, lines.fairleads)):
            d = q[:3] + r @ fairlead - anchor
            l_h = math.hypot(d[0], d[1])
            h, v = self.fairlead_force(l_h, d[2])
            v_a = v - w * lines.length  # vertical force at the anchor end (< 0: on the seabed)
            bottom = max(0.0, -v_a / w)  # length on the seabed
            sus = np.maximum(s - bottom, 0.0)  # suspended arc length past the touchdown point
            v0 = max(v_a, 0.0)
            x = (np.minimum(s, bottom) * (1.0 + h / ea)
                 + h / w * (np.arcsinh((v0 + w * sus) / h) - np.arcsinh(v0 / h)) + h * sus / ea)
            z = (h / w * (np.hypot(1.0, (v0 + w * sus) / h) - math.hypot(1.0, v0 / h))
                 + (v0 * sus + 0.5 * w * sus**2) / ea)
            u = np.array([d[0], d[1]]) / l_h
            out[i, :, :2] = anchor[:2] + x[:, None] * u
            out[i, :, 2] = anchor[2] + z
        return out

    def drag_dissipation(self, amplitude: Sequence[float], period: float, *, cd: float,
                         cd_axial: float, diameter: float, n_nodes: int = 201,
                         n_phase: int = 64, mean: Sequence[float] | None = None
                         ) -> dict[str, float]:
        """Energy [J] the lines' drag dissipates per cycle of the harmonic motion
        ``q(t) = mean + amplitude sin(2π t / period)`` (6 DOFs, m and rad), by Huse's
        quasi-static-shape method (E. Huse, "Influence of mooring line damping upon rig
        motions", OTC 5204, 1986): every material point of a line moves as the quasi-static
        catenary does, ``v(s, t) = ∂P(s; q)/∂q · q̇(t)``, and the Morison drag of that velocity,
        ``½ ρ d (Cd |v_n|³ + Cd_axial π |v_t|³)`` per unit length (normal and tangential parts,
        MoorDyn's drag formula), is integrated along the lines and over the cycle (``n_phase``
        phases, ``n_nodes`` points per line). Valid where the line's own inertia and elastic
        waves do not matter (periods well above the line's transverse natural periods); the
        line's shape is re-solved at every phase, so the amplitude may be large.

        Returns ``{"total", "normal", "axial"}`` [J per cycle].
        """
        amp = np.asarray(amplitude, dtype=float).reshape(6)
        q0 = np.zeros(6) if mean is None else np.asarray(mean, dtype=float).reshape(6)
        omega = 2.0 * np.pi / _positive("period", period)
        h = 1e-4  # central-difference step along the motion direction, in units of `amplitude`
        rho = self.lines.rho
        normal = axial = 0.0
        for phase in 2.0 * np.pi * np.arange(int(n_phase)) / int(n_phase):
            q = q0 + amp * math.sin(phase)
            shape = self.line_shapes(q, n_nodes)
            dpdq = (self.line_shapes(q + h * amp, n_nodes)
                    - self.line_shapes(q - h * amp, n_nodes)) / (2.0 * h)
            v = dpdq * omega * math.cos(phase)  # velocity of each material point [m/s]
            tangent = np.gradient(shape, axis=1)
            ds = np.linalg.norm(tangent, axis=2)  # stretched length per node spacing [m]
            tangent /= ds[..., None]
            v_t = np.einsum("lnk,lnk->ln", v, tangent)
            v_n = np.linalg.norm(v - v_t[..., None] * tangent, axis=2)
            weights = ds.copy()
            weights[:, [0, -1]] *= 0.5  # trapezoid along the line
            normal += 0.5 * rho * cd * diameter * float(np.sum(weights * v_n**3))
            axial += 0.5 * rho * cd_axial * np.pi * diameter * float(
                np.sum(weights * np.abs(v_t)**3))
        scale = 2.0 * np.pi / omega / int(n_phase)  # dt of the periodic trapezoid over a cycle
        return {"total": (normal + axial) * scale, "normal": normal * scale,
                "axial": axial * scale}

    def tabulate(self, ranges: Mapping[str, float] | None = None,
                 spacing: float = DEFAULT_SPACING) -> MooringTable:
        """The interpolant over the displacement box ``±ranges`` (default :data:`DEFAULT_RANGES`)."""
        ranges = box_ranges(ranges)
        spacing = _positive("spacing", spacing)
        (h_lo, h_hi), (v_lo, v_hi) = span_bounds(self.lines, ranges)
        l_h = np.linspace(h_lo, h_hi, int(math.ceil((h_hi - h_lo) / spacing)) + 1)
        l_v = np.linspace(v_lo, v_hi, int(math.ceil((v_hi - v_lo) / spacing)) + 1)
        force = np.zeros((2, l_h.size, l_v.size))
        for j, lv in enumerate(l_v):
            guess = (0.0, 0.0)
            for i, lh in enumerate(l_h):  # along l_h the previous solve is a good start
                guess = self.fairlead_force(lh, lv, guess)
                force[:, i, j] = guess
        ds = xr.Dataset(
            {
                "horizontal_force": (("l_h", "l_v"), force[0], {"units": "N"}),
                "vertical_force": (("l_h", "l_v"), force[1], {"units": "N"}),
            },
            coords={"l_h": ("l_h", l_h, {"units": "m"}), "l_v": ("l_v", l_v, {"units": "m"})},
            attrs={
                "lines": json.dumps(self.lines.to_dict()),
                "ranges": json.dumps(dict(ranges)),
                "spacing": spacing,
                "moorpy_version": _moorpy_version(),
                "description": "force of one mooring line on its fairlead vs the fairlead's "
                               "horizontal distance l_h and height l_v from the anchor",
            },
        )
        ds.attrs["input_hash"] = table_hash(self.lines, ranges, spacing)
        return MooringTable.from_dataset(ds)


def _moorpy_version() -> str:
    from importlib.metadata import version

    return version("moorpy")


def table_hash(lines: MooringLines, ranges: Mapping[str, float], spacing: float) -> str:
    """SHA-256 of everything a table depends on (line data, box, spacing, MoorPy version)."""
    key = {"lines": lines.to_dict(), "ranges": dict(box_ranges(ranges)), "spacing": spacing,
           "moorpy": _moorpy_version()}
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()


def cached_table(lines: MooringLines, ranges: Mapping[str, float] | None,
                 spacing: float = DEFAULT_SPACING) -> MooringTable:
    """:meth:`MooringSystem.tabulate`, kept in ``$HYBRIDWSI_CACHE/mooring/<table_hash>.nc``
    (every command of a case tabulated its mooring again, ~1.3 s of MoorPy); an unreadable
    entry is tabulated again and replaced, an unwritable folder only costs the tabulation."""
    path = cache_dir("mooring") / f"{table_hash(lines, ranges, spacing)}.nc"
    try:
        if path.is_file():
            return MooringTable.from_dataset(read_netcdf(path))
    except (OSError, InputError):  # an unreadable folder or entry: tabulated again
        pass
    table = MooringSystem(lines).tabulate(ranges, spacing)
    try:
        to_netcdf(table.dataset, path)
    except OSError:
        pass
    return table


def box_ranges(ranges: Mapping[str, float] | None) -> dict[str, float]:
    """Half-widths of the displacement box for all 6 DOFs (missing DOFs: the default)."""
    out = dict(DEFAULT_RANGES)
    for dof, value in (ranges or {}).items():
        (name,) = check_dofs([dof])
        value = float(value)
        if not math.isfinite(value) or value < 0.0:
            raise InputError(f"mooring: range of {name} must be >= 0, got {value}")
        out[name] = value
    return out


def span_bounds(lines: MooringLines, ranges: Mapping[str, float], n: int = 5
                ) -> tuple[tuple[float, float], tuple[float, float]]:
    """Extent of the fairlead-to-anchor spans ``(l_h, l_v)`` over the displacement box [m].

    Sampled on an ``n``-point grid per DOF (the spans vary smoothly and almost monotonically
    with each DOF, so the extremes sit at the box faces) and widened by a margin; a state whose
    spans leave the table later raises :class:`SolverError`, never extrapolates.
    """
    axes = [np.linspace(-ranges[d], ranges[d], n) for d in RIGID_DOFS]
    q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 6)
    l_h, l_v = _spans(lines.anchors, lines.fairleads, q)
    return ((l_h.min() - _MARGIN, l_h.max() + _MARGIN), (l_v.min() - _MARGIN, l_v.max() + _MARGIN))


def _spans(anchors: np.ndarray, fairleads: np.ndarray, q: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal and vertical fairlead-anchor distances, shape (n_states, n_lines) [m]."""
    r = np.array(rotation_matrix(q[:, 3], q[:, 4], q[:, 5])).transpose(2, 0, 1)  # (n, 3, 3)
    d = q[:, None, :3] + fairleads @ r.transpose(0, 2, 1) - anchors
    return np.hypot(d[..., 0], d[..., 1]), d[..., 2]


def bicubic_patches(x: np.ndarray, y: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Coefficients ``a[cell, p, q]`` of ``f = sum a u^p v^q`` on each cell of a uniform grid.

    C1 bicubic Hermite patches with the node values and derivatives of the interpolating cubic
    spline; ``u, v`` in [0, 1] are the local cell coordinates. Shape (n_x-1, n_y-1, 4, 4).
    """
    spline = RectBivariateSpline(x, y, values, kx=3, ky=3)
    dx, dy = x[1] - x[0], y[1] - y[0]
    f = spline(x, y)
    fx = spline(x, y, dx=1) * dx
    fy = spline(x, y, dy=1) * dy
    fxy = spline(x, y, dx=1, dy=1) * dx * dy

    def corners(a: np.ndarray) -> np.ndarray:  # (nx-1, ny-1, 2, 2): [i + di, j + dj]
        return np.stack([np.stack([a[:-1, :-1], a[:-1, 1:]], -1),
                         np.stack([a[1:, :-1], a[1:, 1:]], -1)], -2)

    # F = [[f, f_v], [f_u, f_uv]] at the four corners; a = M F M^T
    top = np.concatenate([corners(f), corners(fy)], axis=-1)
    bottom = np.concatenate([corners(fx), corners(fxy)], axis=-1)
    big_f = np.concatenate([top, bottom], axis=-2)
    m = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0], [-3, 3, -2, -1], [2, -2, 1, 1]])
    return m @ big_f @ m.T


_OUTSIDE = ("mooring: displacement outside the tabulated range (or not finite); "
            "tabulate a larger box (ranges=...)")


class _ScalarMath:
    """Evaluation backend for one state: Python floats (fastest for single calls)."""

    sin, cos, hypot = math.sin, math.cos, math.hypot

    @staticmethod
    def total(per_line: float) -> float:
        return per_line

    @staticmethod
    def locate(x: float, y: float, nx: int, ny: int) -> tuple[int, float, float]:
        """Cell number and local coordinates of the grid point ``(x, y)`` (in grid steps)."""
        if not (0.0 <= x <= nx and 0.0 <= y <= ny):
            raise SolverError(_OUTSIDE)
        i, j = min(int(x), nx - 1), min(int(y), ny - 1)
        return i * ny + j, x - i, y - j


class _ArrayMath:
    """Evaluation backend for a batch of states: one NumPy array per quantity."""

    sin, cos, hypot = np.sin, np.cos, np.hypot

    @staticmethod
    def total(per_line: np.ndarray) -> np.ndarray:
        return per_line.sum(axis=-1)

    @staticmethod
    def locate(x: np.ndarray, y: np.ndarray, nx: int, ny: int
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if not (np.all(x >= 0.0) and np.all(x <= nx) and np.all(y >= 0.0) and np.all(y <= ny)):
            raise SolverError(_OUTSIDE)
        i = np.minimum(x.astype(np.intp), nx - 1)
        j = np.minimum(y.astype(np.intp), ny - 1)
        return i * ny + j, x - i, y - j


class _Columns:
    """``columns[k]`` -> the 32 coefficient rows of the cells ``k`` (array backend)."""

    def __init__(self, array: np.ndarray) -> None:
        self.array = array

    def __getitem__(self, k: np.ndarray) -> np.ndarray:
        return self.array[:, k]


class MooringTable:
    """Tabulated quasi-static mooring force: 6-DOF force from a 2-D fairlead-force table.

    Build it with :meth:`MooringSystem.tabulate` (MoorPy) or :meth:`from_dataset` (a saved
    table, no MoorPy needed).
    """

    def __init__(self, dataset: xr.Dataset, lines: MooringLines) -> None:
        self.dataset = dataset
        self.lines = lines
        l_h, l_v = dataset["l_h"].values, dataset["l_v"].values
        self._origin = (float(l_h[0]), float(l_v[0]))
        self._step = (float(l_h[1] - l_h[0]), float(l_v[1] - l_v[0]))
        self._n = (l_h.size - 1, l_v.size - 1)
        patches = np.stack([bicubic_patches(l_h, l_v, dataset[name].values)
                            for name in ("horizontal_force", "vertical_force")], axis=2)
        flat = patches.reshape(self._n[0] * self._n[1], 32)  # cell -> (H 16, V 16)
        self._cells_flat = np.ascontiguousarray(flat)  # (n_cells, 32): the compiled kernel
        self._cells_array = _Columns(np.ascontiguousarray(flat.T))  # (32, n_cells): batches
        self._cells_list = [tuple(row) for row in flat.tolist()]  # for single states
        # (anchor x, y, z, fairlead x, y, z): per line for one state, all lines at once as
        # arrays for a batch (broadcast against states of shape (n, 1))
        self._lines_each = [tuple(map(float, a)) + tuple(map(float, f))
                            for a, f in zip(lines.anchors, lines.fairleads)]
        self._lines_all = [tuple(np.concatenate([lines.anchors, lines.fairleads], axis=1).T)]
        # one state through the Numba kernel when available (no Python per-line overhead)
        self._single = self.compiled(list(range(6)), np.zeros(6))
        self._out6 = np.empty(6)
        self._no_rate = np.zeros(6)

    @classmethod
    def from_dataset(cls, dataset: xr.Dataset) -> MooringTable:
        """A table saved with ``table.dataset.to_netcdf(...)``."""
        try:
            lines = json.loads(dataset.attrs["lines"])
        except (KeyError, ValueError):
            raise InputError("not a mooring table: attribute 'lines' missing or unreadable") from None
        return cls(dataset, MooringLines(**lines))

    @property
    def ranges(self) -> dict[str, float]:
        """The displacement box the table was made for (half-widths per DOF)."""
        return json.loads(self.dataset.attrs["ranges"])

    def force6(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Nonlinear mooring force at ``q``, shape (6,) or (n, 6) like ``q`` [N, N m].

        Includes the preload and the yaw spring. Raises :class:`SolverError` when a fairlead
        leaves the table (the state is outside the tabulated box).
        """
        q = _as_states(q)
        if q.ndim == 1:
            return self._force6_one(q) if self._single is not None else self._force6_scalar(q)
        if self._single is not None:
            return self._force6_rows(q)
        f = np.stack(self._wrench(q.T[:, :, None], _ArrayMath, self._cells_array,
                                  self._lines_all), axis=-1)
        f[:, 5] -= self.lines.yaw_spring * q[:, 5]
        return f

    def _force6_one(self, q: np.ndarray) -> np.ndarray:
        """One state (6,) through the Numba kernel: the arithmetic of :meth:`_force6_scalar`."""
        c = self._single
        if c.kernel(0.0, np.ascontiguousarray(q), self._no_rate, self._out6, c.fdata, c.idata):
            raise SolverError(_OUTSIDE)
        return self._out6.copy()

    def _force6_rows(self, q: np.ndarray) -> np.ndarray:
        """A batch (n, 6) through the Numba kernel, row by row."""
        from hybridwsi.forces._compiled import mooring_rows

        c = self._single
        out = np.empty(q.shape)
        if mooring_rows(np.ascontiguousarray(q), out, c.fdata, c.idata):
            raise SolverError(_OUTSIDE)
        return out

    def _force6_scalar(self, q: np.ndarray) -> np.ndarray:
        """One state (6,) in Python floats (without Numba)."""
        state = q.tolist()
        f = self._wrench(state, _ScalarMath, self._cells_list, self._lines_each)
        f[5] -= self.lines.yaw_spring * state[5]
        return np.array(f)

    def _wrench(self, q: Any, xp: Any, cells: Any, lines: Any) -> list[Any]:
        """Sum over lines of the fairlead forces and their moments; ``q`` unpacks to 6 items.

        Written once for floats and for arrays (``xp``); kept flat because the single-state
        call sits inside the ODE right-hand side.
        """
        from hybridwsi.forces._compiled import bicubic, line_pull  # one formula with the kernel

        x0, y0, z0, roll, pitch, yaw = q
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rotation_matrix(roll, pitch, yaw, xp)
        (h0, v0), (dh, dv), (nh, nv) = self._origin, self._step, self._n
        hypot, locate = xp.hypot, xp.locate
        f1 = f2 = f3 = m1 = m2 = m3 = 0.0
        for ax, ay, az, px, py, pz in lines:
            bx = r00 * px + r01 * py + r02 * pz  # fairlead arm in global axes
            by = r10 * px + r11 * py + r12 * pz
            bz = r20 * px + r21 * py + r22 * pz
            dx, dy, dz = bx + x0 - ax, by + y0 - ay, bz + z0 - az
            lh = hypot(dx, dy)
            k, u, v = locate((lh - h0) / dh, (dz - v0) / dv, nh, nv)
            c = cells[k]  # bicubic coefficients: horizontal 0-15, vertical 16-31
            fx, fy, fz, mx, my, mz = line_pull(bicubic(c, 0, u, v), bicubic(c, 16, u, v), lh,
                                               dx, dy, bx, by, bz)
            f1 += fx
            f2 += fy
            f3 += fz
            m1 += mx
            m2 += my
            m3 += mz
        total = xp.total
        return [total(f1), total(f2), total(f3), total(m1), total(m2), total(m3)]

    def compiled(self, index: Sequence[int], f0: np.ndarray) -> Any:
        """Numba kernel of ``force6(q) − f0`` on the DOFs ``index`` of q, or None without Numba
        (:mod:`hybridwsi.forces._compiled`; same arithmetic as the single-state path)."""
        from hybridwsi.forces._compiled import mooring_force

        return mooring_force(self._origin, self._step, self._n, self.lines.yaw_spring, f0,
                             self.lines.anchors, self.lines.fairleads, self._cells_flat,
                             [int(i) for i in index], _OUTSIDE)

    def preload(self) -> np.ndarray:
        """``F0 = F(0)`` from the table [N, N m], shape (6,)."""
        return self.force6(np.zeros(6))

    def tensions(self, q: Sequence[float] | np.ndarray) -> np.ndarray:
        """Fairlead and anchor tension of every line at ``q`` [N]: shape (n_lines, 2) for one
        state (6,), (n, n_lines, 2) for a batch (n, 6).

        The fairlead forces come from the same patches as :meth:`force6`; the anchor's
        vertical force is ``max(V_fairlead - w L, 0)`` (module docstring).
        """
        from hybridwsi.forces._compiled import bicubic  # one formula with the kernel

        q = _as_states(q)
        states = np.atleast_2d(q)
        l_h, l_v = _spans(self.lines.anchors, self.lines.fairleads, states)
        (h0, v0), (dh, dv), (nh, nv) = self._origin, self._step, self._n
        k, u, v = _ArrayMath.locate((l_h - h0) / dh, (l_v - v0) / dv, nh, nv)
        cells = self._cells_array[k]
        horizontal, vertical = bicubic(cells, 0, u, v), bicubic(cells, 16, u, v)
        suspended_weight = self.lines.weight_in_water * self.lines.length
        anchor_v = np.maximum(vertical - suspended_weight, 0.0)
        out = np.stack([np.hypot(horizontal, vertical), np.hypot(horizontal, anchor_v)], axis=-1)
        return out[0] if q.ndim == 1 else out

    def stiffness(self, step: Sequence[float] = (0.05, 0.05, 0.05, 1e-4, 1e-4, 1e-4)
                  ) -> np.ndarray:
        """``K = -dF/dq`` at ``q = 0`` of the interpolant (central differences), shape (6, 6)."""
        h = np.asarray(step, dtype=float)
        dq = np.diag(h)
        f = self.force6(np.concatenate([dq, -dq]))
        return -(f[:6] - f[6:]).T / (2.0 * h)


@runtime_checkable
class LineTensions(Protocol):
    """A mooring component that reports its line tensions (the case model records them).

    ``n_lines`` lines; ``line_tensions(hist)`` gives, at every sample of the history the
    component ran in, the tension at each line's fairlead (``[..., 0]``) and anchor
    (``[..., 1]``) [N], shape (n_time, n_lines, 2). A stateless component evaluates it on the
    history's displacements; one with internal states (MoorDyn) returns the values it recorded
    at those times while the ODE ran.
    """

    n_lines: int

    def line_tensions(self, hist: xr.Dataset) -> np.ndarray: ...


def _history_states(hist: xr.Dataset, dofs: tuple[str, ...], index6: list[int]) -> np.ndarray:
    """The history's displacements as full 6-DOF states (n_time, 6); other DOFs 0."""
    have = tuple(str(d) for d in hist["dof"].values)
    if have != dofs:
        raise InputError(f"mooring component DOFs {list(dofs)} differ from the history's "
                         f"{list(have)}")
    z = kinematic(hist, "z")
    q = np.zeros((z.shape[0], 6))
    q[:, index6] = z
    return q


class _QuasiStatic(KnownComponent):
    """What the quasi-static mooring components share: the DOFs they act on (the others held
    at 0), the preload ``F0`` they leave out and the stiffness ``K`` of their linear part."""

    name = "mooring"

    def _set_up(self, dofs: Sequence[str] | str, preload: np.ndarray,
                stiffness: np.ndarray) -> None:
        self.dofs = check_dofs(dofs)
        self._index = index(self.dofs)
        self._f0 = preload
        self._k = stiffness

    def _check(self, n_dof: int) -> None:
        if n_dof != len(self.dofs):
            raise InputError(f"mooring component is set up for {len(self.dofs)} DOFs "
                             f"({', '.join(self.dofs)}), got {n_dof}")

    def linear_coefficients(self, n_dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        self._check(n_dof)
        zero = np.zeros((n_dof, n_dof))
        return zero, zero.copy(), self._k[np.ix_(self._index, self._index)]


class MooringForce(_QuasiStatic):
    """Quasi-static mooring as a force component: ``F(q) - F0`` on the chosen DOFs.

    Parameters
    ----------
    table : MooringTable
        The interpolant (:meth:`MooringSystem.tabulate`).
    dofs : sequence of str
        The DOFs of the histories and ODE states this component acts on (any subset of the 6;
        the others are held at 0).

    Notes
    -----
    The preload ``F0`` is excluded: it belongs to the static balance (buoyancy - weight + F0_z
    = 0) around which the motions are measured. ``linear_coefficients`` gives ``C = K`` of the
    interpolant restricted to ``dofs`` (Eq. 5-1 sign convention); no added mass, no damping.
    """

    def __init__(self, table: MooringTable, dofs: Sequence[str] | str = RIGID_DOFS) -> None:
        self.table = table
        self._set_up(dofs, table.preload(), table.stiffness())

    @classmethod
    def from_case(cls, case: Mapping[str, Any], dofs: Sequence[str] | str | None = None
                  ) -> MooringForce:
        """The case's mooring tabulated over its ``[mooring.table]`` box (MoorPy, ~1 s).

        ``dofs`` default: the case's ``default_dofs`` (OC3: Surge, Heave, Pitch).
        """
        box = dict(case.get("mooring", {}).get("table", {}))
        spacing = box.pop("spacing", DEFAULT_SPACING)
        table = cached_table(MooringLines.from_case(case), box, spacing)
        return cls(table, dofs if dofs is not None else case.get("default_dofs", RIGID_DOFS))

    def _full(self, z: np.ndarray) -> np.ndarray:
        q = np.zeros(z.shape[:-1] + (6,))
        q[..., self._index] = z
        return q

    @property
    def n_lines(self) -> int:
        return self.table.lines.n_lines

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """``F(z) - F0`` on the history's displacements, shape (n_time, n_dof) [N, N m]."""
        q = _history_states(hist, self.dofs, self._index)
        return (self.table.force6(q) - self._f0)[:, self._index]

    def line_tensions(self, hist: xr.Dataset) -> np.ndarray:
        """Fairlead and anchor tensions on the history's displacements (n_time, n_lines, 2) [N]."""
        return self.table.tensions(_history_states(hist, self.dofs, self._index))

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        z = np.asarray(z, dtype=float)
        self._check(z.shape[-1])
        return (self.table.force6(self._full(z)) - self._f0)[..., self._index]

    def compiled_force(self, n_dof: int) -> Any:
        """Numba kernel of :meth:`ode_force` (the table's), or None without Numba."""
        self._check(n_dof)
        return self.table.compiled(self._index, self._f0)

    def describe(self) -> str:
        n_h, n_v = self.table.dataset.sizes["l_h"], self.table.dataset.sizes["l_v"]
        return (f"mooring({self.table.lines.n_lines} lines, yaw spring "
                f"{self.table.lines.yaw_spring:.4g} N m/rad, table {n_h}x{n_v}, "
                f"DOFs {','.join(self.dofs)})")


class QuasiStaticMooring(_QuasiStatic):
    """The mooring solved by MoorPy at every call: ``F(q) - F0`` on the chosen DOFs.

    What :class:`MooringForce` interpolates, without the interpolation: each call places the
    body at ``q`` and solves every catenary statically (MoorPy warm-starts each line from its
    previous solution, so along a trajectory this costs ~3 ms per call; OC3: ~50 x the table).
    The other DOFs are held at 0. The last result at each time the ODE called it is kept with
    its exact state, so that :meth:`force` and :meth:`line_tensions` on the history the ODE
    produced do not solve again (another state at that time is solved).

    Parameters
    ----------
    system : MooringSystem
        The MoorPy model.
    dofs : sequence of str
        DOFs of the histories and ODE states this component acts on.
    """

    def __init__(self, system: MooringSystem, dofs: Sequence[str] | str = RIGID_DOFS) -> None:
        self.system = system
        self._set_up(dofs, system.preload(), system.stiffness())
        self._solved: dict[int, tuple[bytes, np.ndarray, np.ndarray]] = {}

    @classmethod
    def from_case(cls, case: Mapping[str, Any], dofs: Sequence[str] | str | None = None
                  ) -> QuasiStaticMooring:
        """The case's mooring as a MoorPy system; ``dofs`` default the case's
        ``default_dofs``."""
        return cls(MooringSystem.from_case(case),
                   dofs if dofs is not None else case.get("default_dofs", RIGID_DOFS))

    @property
    def n_lines(self) -> int:
        return self.system.lines.n_lines

    def _solve(self, q: np.ndarray, t: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(F(q) - F0, tensions)`` of one state (6,); the last call at each time ``t`` is
        kept (the stepping solver's last call at a sample time is the accepted state)."""
        key = None if t is None else round(float(t) * 1e6)
        kept = self._solved.get(key) if key is not None else None
        if kept is not None and kept[0] == q.tobytes():
            return kept[1], kept[2]
        if not np.all(np.isfinite(q)):
            raise SolverError("mooring: displacement is not finite")
        force, tensions = self.system.force6(q) - self._f0, self.system.tensions()
        if key is not None:
            self._solved[key] = (q.tobytes(), force, tensions)
        return force, tensions

    def ode_force(self, t: float, z: np.ndarray, zdot: np.ndarray, x: np.ndarray) -> np.ndarray:
        z = np.asarray(z, dtype=float)
        self._check(z.shape[-1])
        rows = z.reshape(-1, z.shape[-1])
        q = np.zeros((rows.shape[0], 6))
        q[:, self._index] = rows
        f = np.stack([self._solve(row, t if rows.shape[0] == 1 else None)[0]
                      for row in q])[:, self._index]
        return f.reshape(z.shape)

    def force(self, hist: xr.Dataset) -> np.ndarray:
        """``F(z) - F0`` on the history's displacements, shape (n_time, n_dof) [N, N m]."""
        q = _history_states(hist, self.dofs, self._index)
        t = np.asarray(hist["time"].values, dtype=float)
        return np.stack([self._solve(row, tk)[0] for row, tk in zip(q, t)])[:, self._index]

    def line_tensions(self, hist: xr.Dataset) -> np.ndarray:
        """Fairlead and anchor tensions on the history's displacements (n_time, n_lines, 2) [N]."""
        q = _history_states(hist, self.dofs, self._index)
        t = np.asarray(hist["time"].values, dtype=float)
        return np.stack([self._solve(row, tk)[1] for row, tk in zip(q, t)])

    def describe(self) -> str:
        return (f"mooring_quasi_static({self.n_lines} lines, MoorPy each call, yaw spring "
                f"{self.system.lines.yaw_spring:.4g} N m/rad, DOFs {','.join(self.dofs)})")
