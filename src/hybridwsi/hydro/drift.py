"""Mean (second-order) wave drift from Capytaine: far field (Maruo) and near field (Pinkster).

A body in a regular wave of amplitude ``a`` [m] feels, besides the first-order force, a mean force
``F̄ = D(ω) a²``: the mean drift. ``D`` [N/m² per translation DOF, N m/m² per rotation] needs only
the first-order solution, and two independent ways give it (docs/THEORY.md "Second-order wave
drift"):

- **far field** (momentum flux through a control surface at infinity; Maruo 1960, Newman 1967):
  from the Kochin functions H(θ) of the diffraction and radiation problems, horizontal force and
  yaw moment only. Computed by Capytaine's own ``far_field_mean_drift_force``.
- **near field** (direct integration of the second-order pressure over the mean wetted hull;
  Pinkster 1980): relative wave elevation at the waterline, the velocity-squared (Bernoulli)
  pressure, the motion of the hull through the first-order pressure gradient, the rotation of the
  first-order force, and the second-order hydrostatic terms. All six DOFs.

They agree only if the first-order solution is converged, which makes their agreement the usual
check of a drift computation.

The work is split in two so that the expensive part is done once:

1. :func:`solve_operator` runs Capytaine (indirect method, sources kept) at each frequency and
   keeps, per frequency, everything the drift needs in a small Dataset, the *drift operator*:
   the linear coefficients (for the motions), the Kochin functions, and the near-field
   **quadratic forms** ``T[k, p, q]``. With the complex amplitudes ``c = (1, X_1 … X_n)`` (the
   wave, then the body motions per unit wave amplitude), every near-field term is a mean of a
   product of two first-order quantities linear in ``c``, so

       D_k = Re Σ_pq c_p conj(c_q) T[k, p, q].

2. :func:`motion_rao`, :func:`far_field`, :func:`near_field` (pure, milliseconds) then give the
   drift for any mass, stiffness (mooring) and damping, without another BEM solve.

Conventions: Capytaine's (complex amplitudes ``Re[X e^{-iωt}]``; normals out of the body into the
fluid; radiation potentials per unit *displacement*; wave direction β the direction the wave
travels to). Moments about the rotation centre of the body's rotational DOFs (the reference
point). Second-order rotations use the rotation-vector form ``R = I + A + A²/2`` (``A v = α × v``);
the convention only matters for products of two different rotations.

Capytaine 3.0 caveats handled here (docs/CAPYTAINE_NOTES.md pitfalls 8–9):

- ``compute_kochin`` weights the sources with ``cosh k(z+h)/cosh kh`` in finite depth, while
  ``far_field_mean_drift_force`` uses coefficients that match a Kochin function weighted with
  ``cosh k(z+h)/sinh kh``: in finite depth its ∫|H|² term is ``tanh² kh`` and its interference
  term ``tanh kh`` too small (−34 % on a bottom-mounted cylinder at kh = 0.9). The Kochin
  functions are divided by ``tanh kh`` before the call (checked against the analytical drift of
  a bottom-mounted cylinder, tests/test_drift.py).
- ``compute_velocity`` on the hull of a body with a lid adds the self-induced term of panel i to
  the i-th face of hull *and lid*, which are interleaved on a symmetric mesh: the hull velocities
  come out wrong. The velocities here are evaluated on the full mesh including the lid (the
  index-aligned case), checked by the normal velocity reproducing the boundary condition.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi._meta import provenance
from hybridwsi.dofs import check_dofs
from hybridwsi.errors import InputError, SolverError
from hybridwsi.files import read_netcdf, to_netcdf
from hybridwsi.hydro import coefficients as co
from hybridwsi.hydro.bem.cache import default_cache_dir
from hybridwsi.hydro.bem.planning import json_sha256
from hybridwsi.hydro.bem.solve import blas_single_thread, quiet_capytaine
from hybridwsi.waves import dispersion_k

#: the six generalised force components (influenced DOFs) of the near field
ALL_DOFS = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
#: the components the far field gives (horizontal force, yaw moment)
FAR_FIELD_DOFS = ("Surge", "Sway", "Yaw")
#: label of the incident + diffracted wave in the motion-amplitude vector ``c``
WAVE = "Wave"
#: default number of Kochin-function angles over [0, 2π)
N_THETA = 72


# ---------------------------------------------------------------------------- the BEM part
def solve_operator(cbody: Any, omega: Sequence[float] | np.ndarray, *, water_depth: float,
                   wave_directions: Sequence[float] = (0.0,), rho: float = 1025.0,
                   g: float = 9.81, n_theta: int = N_THETA, deep_water_kh: float | None = 3.0,
                   reference_point: Sequence[float] | None = None,
                   done: xr.Dataset | None = None,
                   checkpoint: Callable[[xr.Dataset], None] | None = None,
                   progress: Callable[[float, float], None] | None = None) -> xr.Dataset:
    """The drift operator of a Capytaine body at frequencies ``omega`` (module docstring).

    Parameters
    ----------
    cbody : capytaine.FloatingBody
        Hull (optionally with a lid) and rigid-body DOFs (none for a fixed body). A
        ``RotationSymmetricMesh`` hull and lid keep the cost low (the hull velocities are
        computed from one sector).
    omega : array_like
        Wave frequencies [rad/s], > 0.
    water_depth : float
        Depth [m] (``inf`` for deep water). Frequencies with ``k h ≥ deep_water_kh`` are solved
        in deep water (waves that do not feel the bottom; Capytaine's finite-depth Green
        function loses accuracy there), the others in finite depth.
    wave_directions : sequence of float
        Directions β [rad] the waves travel to.
    rho, g : float
        Water density [kg/m³] and gravity [m/s²].
    n_theta : int
        Kochin-function angles over [0, 2π) (trapezoidal rule, spectrally accurate).
    reference_point : (3,) floats, optional
        Point [m] moments are about; default the rotation centre of the body's rotational DOFs,
        else the origin.
    done : xarray.Dataset, optional
        An operator already computed for some of these frequencies (same body and settings):
        they are kept, only the others are solved (resumable runs).
    checkpoint : callable, optional
        Called with the operator so far after every frequency (e.g. an atomic write).
    progress : callable, optional
        Called with (ω, wall seconds) after every frequency.

    Returns
    -------
    xarray.Dataset
        ``added_mass``, ``radiation_damping`` (omega, radiating_dof, influenced_dof) [kg…,
        N s/m…]; ``excitation_force`` (omega, wave_direction, influenced_dof) [N/m…];
        ``kochin_diffraction`` (omega, wave_direction, theta), ``kochin_radiation`` (omega,
        radiating_dof, theta) as Capytaine defines them (finite-depth weighting, see the
        module docstring); ``near_field_form`` (omega, wave_direction, component, motion_i,
        motion_j) [N/m² or N m/m² per unit amplitudes], ``component`` the six generalised
        force components about the reference point; ``wavenumber``,
        ``solved_depth`` (omega); attributes ``rho``, ``g``, ``water_depth``,
        ``reference_point``, ``n_panels``, ``n_lid_panels``.
    """
    import time

    import capytaine as cpt

    w_all, directions, depth = _check_settings(omega, wave_directions, water_depth, n_theta)
    ref = np.asarray(_reference_point(cbody) if reference_point is None else reference_point,
                     dtype=float)
    solver = cpt.BEMSolver(method="indirect")
    geom = _geometry(cbody, ref)
    parts = [] if done is None else [done]
    have = np.array([]) if done is None else np.asarray(done["omega"].values, dtype=float)
    for w in w_all:
        if have.size and np.any(np.isclose(have, w, rtol=1e-12, atol=0.0)):
            continue
        start = time.perf_counter()
        h = _solve_depth(w, depth, g, deep_water_kh)
        parts.append(_solve_frequency(solver, cbody, geom, float(w), h, directions, rho, g,
                                      int(n_theta)))
        if checkpoint is not None or progress is not None:
            so_far = _join(parts, cbody, ref, depth, rho, g)
            if checkpoint is not None:
                checkpoint(so_far)
            if progress is not None:
                progress(float(w), time.perf_counter() - start)
    if not parts:
        raise InputError("no frequency to solve")
    out = _join(parts, cbody, ref, depth, rho, g)
    keep = np.isin(np.round(out["omega"].values, 12), np.round(w_all, 12))
    return out.isel(omega=np.flatnonzero(keep))


def _check_settings(omega: Any, wave_directions: Any, water_depth: Any, n_theta: Any
                    ) -> tuple[np.ndarray, np.ndarray, float]:
    """Sorted frequencies [rad/s], directions in [0, 2π) [rad] and the depth [m], checked."""
    try:
        w = np.sort(np.atleast_1d(np.asarray(omega, dtype=float)))
        directions = np.mod(np.asarray(wave_directions, dtype=float).reshape(-1), 2 * math.pi)
        depth = float(water_depth)
    except (TypeError, ValueError):
        raise InputError("omega, wave_directions and water_depth must be numbers") from None
    if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise InputError("omega must be a non-empty list of finite values > 0 [rad/s]")
    if np.any(np.diff(w) <= 1e-12 * w[1:]):
        raise InputError("omega contains duplicates")
    if directions.size == 0 or np.unique(directions).size != directions.size \
            or not np.all(np.isfinite(directions)):
        raise InputError("wave_directions must be a non-empty list of distinct angles [rad]")
    if not depth > 0:
        raise InputError(f"water_depth must be > 0 or inf, got {water_depth!r}")
    if int(n_theta) < 8:
        raise InputError(f"n_theta must be >= 8, got {n_theta}")
    return w, directions, depth


def _solve_depth(w: float, depth: float, g: float, deep_kh: float | None) -> float:
    """The depth [m] a frequency is solved in: ``inf`` where k h ≥ ``deep_kh``."""
    if not math.isfinite(depth) or deep_kh is None:
        return depth
    return math.inf if float(dispersion_k(w, depth, g)) * depth >= deep_kh else depth


def _reference_point(cbody: Any) -> np.ndarray:
    """Rotation centre shared by the body's rotational DOFs (origin without any)."""
    centres = [np.asarray(d.rotation_center, dtype=float) for d in cbody.dofs.values()
               if hasattr(d, "rotation_center")]
    if not centres:
        return np.zeros(3)
    if any(not np.allclose(c, centres[0]) for c in centres):
        raise InputError("the rotational DOFs have different rotation centres")
    return centres[0]


def _dof_vectors(cbody: Any) -> tuple[list[str], np.ndarray, np.ndarray]:
    """DOF names and per-DOF translation and rotation unit vectors, shape (n, 3) each."""
    names, trans, rot = [], [], []
    for name, dof in cbody.dofs.items():
        direction = np.asarray(getattr(dof, "direction", np.zeros(3)), dtype=float)
        if hasattr(dof, "rotation_center"):
            trans.append(np.zeros(3)), rot.append(direction)
        elif hasattr(dof, "direction"):
            trans.append(direction), rot.append(np.zeros(3))
        else:
            raise InputError(f"DOF {name!r} is not a rigid-body DOF: no drift for it")
        names.append(str(name))
    shape = (len(names), 3)
    return names, np.asarray(trans).reshape(shape), np.asarray(rot).reshape(shape)


def _geometry(cbody: Any, ref: np.ndarray) -> dict[str, Any]:
    """Hull faces, waterline segments, waterplane and volume moments (coordinates about ``ref``).

    The waterline is the set of hull-panel edges lying in z = 0; each segment's normal is the
    horizontal part of its panel's normal (Pinkster's vertical-wall strip). Waterplane moments
    come from the waterline polygon (Green's theorem), the displaced volume and its centre from
    the hull panels (divergence theorem, the waterplane closing the volume at z = 0).
    """
    # one merged mesh (hull and lid; Capytaine caches it on the symmetric mesh and its
    # geometry is computed in Python loops): the hull is its ``hull_mask`` rows
    mil = cbody.mesh_including_lid
    full = mil.merged() if hasattr(mil, "merged") else mil
    mask = np.asarray(cbody.hull_mask)
    centres = np.asarray(full.faces_centers, dtype=float)[mask]
    normals = np.asarray(full.faces_normals, dtype=float)[mask]
    areas = np.asarray(full.faces_areas, dtype=float)[mask]
    verts, faces = np.asarray(full.vertices, dtype=float), np.asarray(full.faces)[mask]
    tol = 1e-6 * max(1.0, float(np.ptp(verts[:, 2])))
    p1, p2, seg_n = [], [], []
    for f, quad in enumerate(faces):
        for a, b in zip(quad, np.roll(quad, -1)):
            if a != b and abs(verts[a, 2]) < tol and abs(verts[b, 2]) < tol:
                nh = normals[f, :2] / max(np.hypot(*normals[f, :2]), 1e-300)
                t = verts[b, :2] - verts[a, :2]
                # counter-clockwise seen from above: the outward normal is t × z
                first, second = (a, b) if t[1] * nh[0] - t[0] * nh[1] > 0 else (b, a)
                p1.append(verts[first]), p2.append(verts[second]), seg_n.append(nh)
    if not p1:
        raise InputError("the hull has no panel edge on the still-water line z = 0 (a "
                         "surface-piercing hull clipped at z = 0 is needed for the near field)")
    p1, p2 = np.asarray(p1) - ref, np.asarray(p2) - ref
    normals3 = np.column_stack([np.asarray(seg_n), np.zeros(len(seg_n))])
    mid = 0.5 * (p1 + p2)
    wl_normals = _generalised(mid, normals3)
    x = centres - ref
    volume = float(np.sum(x[:, 2] * normals[:, 2] * areas))
    buoyancy_centre = (0.5 * np.sum((x**2) * normals * areas[:, None], axis=0)
                       / volume) if volume > 0 else np.zeros(3)
    wl_points = mid + ref
    return {
        "mesh": full, "hull_mask": mask,
        "symmetry": _symmetry(mil, full, wl_points),
        "centres": centres, "x": x, "areas": areas, "normals": _generalised(x, normals),
        "wl_points": wl_points, "wl_x": mid, "wl_length": np.linalg.norm(p2 - p1, axis=1),
        "wl_normals": wl_normals, "waterplane": _waterplane(p1[:, :2], p2[:, :2]),
        "volume": volume, "buoyancy_centre": buoyancy_centre,
    }


def _generalised(x: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Generalised normals ``(n, x × n)``, shape (n_points, 6)."""
    return np.column_stack([n, np.cross(x, n)])


def _waterplane(p1: np.ndarray, p2: np.ndarray) -> dict[str, float]:
    """Area [m²], first [m³] and second [m⁴] moments of the polygon with counter-clockwise edges
    ``p1 → p2`` (x, y about the reference point): A, Sx = ∫x, Sy = ∫y, Ixx = ∫x², Iyy = ∫y²,
    Ixy = ∫xy."""
    x1, y1, x2, y2 = p1[:, 0], p1[:, 1], p2[:, 0], p2[:, 1]
    cr = x1 * y2 - x2 * y1
    return {
        "A": float(np.sum(cr) / 2), "Sx": float(np.sum(cr * (x1 + x2)) / 6),
        "Sy": float(np.sum(cr * (y1 + y2)) / 6),
        "Ixx": float(np.sum(cr * (x1**2 + x1 * x2 + x2**2)) / 12),
        "Iyy": float(np.sum(cr * (y1**2 + y1 * y2 + y2**2)) / 12),
        "Ixy": float(np.sum(cr * (x1 * y2 + 2 * x1 * y1 + 2 * x2 * y2 + x2 * y1)) / 24),
    }


def _solve_frequency(solver: Any, cbody: Any, geom: dict[str, Any], w: float, depth: float,
                     directions: np.ndarray, rho: float, g: float, n_theta: int) -> xr.Dataset:
    """Solve diffraction (per direction) and radiation (per DOF) at ``w`` and reduce them to the
    operator's variables for this one frequency."""
    from capytaine.io.xarray import kochin_data_array

    names, _, _ = _dof_vectors(cbody)
    results, fields = _solve_results(solver, cbody, geom, w, depth, directions, rho, g)
    k = float(results[0].wavenumber)
    step = 2 * math.pi / n_theta
    theta = xr.DataArray(np.arange(-1, n_theta + 1) * step, dims="theta")
    theta = theta.assign_coords(theta=theta.values)
    kochin = kochin_data_array(results, theta)
    ds = _coefficients(results, names, directions, w)
    ds["kochin_diffraction"] = (("omega", "wave_direction", "theta"),
                                _kochin(kochin, "kochin_diffraction", "wave_direction",
                                        directions, theta.size))
    ds["kochin_radiation"] = (("omega", "radiating_dof", "theta"),
                              _kochin(kochin, "kochin_radiation", "radiating_dof", names,
                                      theta.size))
    ds = ds.assign_coords(theta=theta.values, wavenumber=("omega", [k]),
                          solved_depth=("omega", [depth]))
    ds["near_field_form"] = (("omega", "wave_direction", "component", "motion_i", "motion_j"),
                             _near_field_forms(fields, geom, names, cbody, w, rho, g)[None])
    return ds.assign_coords(motion_i=[WAVE, *names], motion_j=[WAVE, *names],
                            component=list(ALL_DOFS))


def _solve_results(solver: Any, cbody: Any, geom: dict[str, Any], w: float, depth: float,
                   directions: np.ndarray, rho: float, g: float) -> tuple[list, list[dict]]:
    """Capytaine results (diffraction per direction, then radiation per DOF; sources kept) and
    their hull and waterline fields (:func:`_fields`) at one frequency."""
    import capytaine as cpt

    names, _, _ = _dof_vectors(cbody)
    common = dict(body=cbody, omega=w, water_depth=depth, rho=rho, g=g)
    with blas_single_thread(), quiet_capytaine():  # e.g. "no dofs" for a fixed body
        problems = [cpt.DiffractionProblem(wave_direction=float(b), **common) for b in directions]
        problems += [cpt.RadiationProblem(radiating_dof=d, **common) for d in names]
        results = solver.solve_all(problems, keep_details=True, progress_bar=False)
        if any(r.sources is None for r in results):
            raise SolverError(f"Capytaine failed at omega = {w:g} rad/s")
        return results, _fields(solver, cbody, geom, results)


def _kochin(kochin: xr.Dataset, name: str, dim: str, labels: Sequence[Any],
            n_theta: int) -> np.ndarray:
    """One Kochin variable as (1, len(labels), theta), zeros when there is none (fixed body)."""
    if name not in kochin or len(labels) == 0:
        return np.zeros((1, len(labels), n_theta), dtype=complex)
    da = kochin[name]
    da = da.isel({d: 0 for d in da.dims if d not in (dim, "theta")}, drop=True)
    if dim == "radiating_dof":
        da = da.assign_coords(radiating_dof=[str(v) for v in da[dim].values])
        da = da.sel(radiating_dof=list(labels))
    else:
        da = da.sel(wave_direction=list(labels), method="nearest")
    return np.asarray(da.transpose(dim, "theta").values)[None]


def _coefficients(results: list, names: list[str], directions: np.ndarray,
                  w: float) -> xr.Dataset:
    """A(ω), B(ω), F_exc(ω, β) of one frequency from Capytaine's ``assemble_dataset``."""
    from capytaine.io.xarray import assemble_dataset

    n = len(names)
    raw = assemble_dataset(results, hydrostatics=False) if n else xr.Dataset()
    out = xr.Dataset(coords={"omega": [w], "wave_direction": directions,
                             "radiating_dof": names, "influenced_dof": names})
    for name in ("added_mass", "radiation_damping"):
        vals = np.zeros((1, n, n))
        if n and name in raw:
            da = raw[name].isel({d: 0 for d in raw[name].dims
                                 if d not in ("radiating_dof", "influenced_dof")}, drop=True)
            da = da.assign_coords(radiating_dof=[str(v) for v in da["radiating_dof"].values],
                                  influenced_dof=[str(v) for v in da["influenced_dof"].values])
            vals = da.sel(radiating_dof=names, influenced_dof=names).values[None]
        out[name] = (("omega", "radiating_dof", "influenced_dof"), np.asarray(vals, float))
    exc = np.zeros((1, directions.size, n), dtype=complex)
    if n:
        da = raw["excitation_force"]
        da = da.isel({d: 0 for d in da.dims if d not in ("wave_direction", "influenced_dof")},
                     drop=True)
        da = da.assign_coords(influenced_dof=[str(v) for v in da["influenced_dof"].values])
        exc = da.sel(influenced_dof=names).sel(wave_direction=directions, method="nearest")
        exc = np.asarray(exc.transpose("wave_direction", "influenced_dof").values)[None]
    out["excitation_force"] = (("omega", "wave_direction", "influenced_dof"), exc)
    return out


def _fields(solver: Any, cbody: Any, geom: dict[str, Any], results: list) -> list[dict]:
    """Per result: potential and velocity on the hull panels, potential at the waterline
    midpoints (incident wave included for diffraction problems), and the result itself."""
    from capytaine.bem.airy_waves import airy_waves_potential, airy_waves_velocity

    sym, full = geom["symmetry"], geom["mesh"]
    green = solver.engine.green_function
    params = dict(free_surface=0.0, water_depth=results[0].water_depth,
                  wavenumber=results[0].wavenumber)
    # the Green function is called directly on the merged mesh held in ``geom``: the engine's
    # build_*_matrix copy (``merged()``) the mesh at every call and recompute its geometry
    sources = np.stack([np.asarray(r.sources) for r in results], axis=1)  # (N, n_res)
    if sym is None:  # every collocation point; the self term is index-aligned on the full mesh
        k_full = green.evaluate(full, full, early_dot_product=False, **params)[1]
        grad = np.einsum("cij,jr->ric", np.asarray(k_full), sources)
        s_wl = green.evaluate(geom["wl_points"], full, diagonal_term_in_double_layer=False,
                              **params)[0]
        phi_wl = (np.asarray(s_wl) @ sources).T
    else:
        k0 = np.asarray(green.evaluate(sym["sector"], full, early_dot_product=False,
                                       **params)[1])
        grad = _rotate_to_sectors(_by_sector(k0, sources, sym), sym)
        s0 = np.asarray(green.evaluate(sym["wl_sector"], full,
                                       diagonal_term_in_double_layer=False, **params)[0])
        phi_wl = _by_sector(s0[None], sources, sym)[..., 0].reshape(len(results), -1)
    mask = geom["hull_mask"]
    out = []
    for i, res in enumerate(results):
        phi, vel, wl = np.asarray(res.potential)[mask], grad[i][mask], phi_wl[i]
        if not hasattr(res, "radiating_dof"):  # diffraction: add the incident wave
            pb = res.problem
            phi = phi + airy_waves_potential(geom["centres"], pb)
            vel = vel + airy_waves_velocity(geom["centres"], pb)
            wl = wl + airy_waves_potential(geom["wl_points"], pb)
        out.append({"result": res, "phi": phi, "grad": vel, "phi_wl": wl})
    return out


def _symmetry(mil: Any, full: Any, wl_points: np.ndarray) -> dict[str, Any] | None:
    """The rotation symmetry of the mesh including the lid, if Capytaine has one (``z+``: sector
    s is sector 0 turned by 2πs/n, sector-major face order), with sector 0's collocation
    mesh and waterline points; None otherwise."""
    from capytaine.meshes.symmetric_meshes import RotationSymmetricMesh

    if not (isinstance(mil, RotationSymmetricMesh) and mil.axis == "z+"):
        return None
    m, n = mil.wedge.nb_faces, mil.n
    if wl_points.shape[0] % n:
        return None
    ang = 2 * math.pi * np.arange(n) / n
    c = np.asarray(full.faces_centers)
    for pts, per in ((c, m), (wl_points, wl_points.shape[0] // n)):
        turned = _turn(np.broadcast_to(pts[:per], (n, per, 3)), ang)
        if not np.allclose(turned.reshape(-1, 3), pts, atol=1e-9 * max(1.0, np.abs(pts).max())):
            raise SolverError("unexpected sector ordering of the rotation-symmetric mesh")
    return {"n": n, "m": m, "angles": ang, "sector": mil.wedge,
            "wl_sector": wl_points[: wl_points.shape[0] // n]}


def _turn(v: np.ndarray, ang: np.ndarray) -> np.ndarray:
    """Vectors ``v`` (n, ..., 3) turned about z by ``ang`` (n,) [rad], one angle per sector."""
    shape = (-1,) + (1,) * (v.ndim - 2)
    cs, sn = np.cos(ang).reshape(shape), np.sin(ang).reshape(shape)
    return np.stack([cs * v[..., 0] - sn * v[..., 1], sn * v[..., 0] + cs * v[..., 1],
                     v[..., 2]], axis=-1)


def _by_sector(m0: np.ndarray, sources: np.ndarray, sym: dict[str, Any]) -> np.ndarray:
    """``m0`` (c, p, N) is an influence matrix for sector 0's p points; returns its product with
    the sources seen from every sector, (n_res, n, p, c), in sector-0 axes: the field at point
    i of sector s is ``Σ_j m0[i, j] σ[(j + s m) mod N]`` (rotation invariance of the Green
    function about z)."""
    n, m = sym["n"], sym["m"]
    big_n, n_res = sources.shape
    idx = (np.arange(big_n)[None, :] + m * np.arange(n)[:, None]) % big_n  # (n, N)
    shifted = sources[idx].transpose(1, 0, 2).reshape(big_n, n * n_res)
    c, p = m0.shape[0], m0.shape[1]
    out = (m0.reshape(c * p, big_n) @ shifted).reshape(c, p, n, n_res)
    return out.transpose(3, 2, 1, 0)


def _rotate_to_sectors(v: np.ndarray, sym: dict[str, Any]) -> np.ndarray:
    """Vectors (n_res, n, p, 3) in sector-0 axes → global axes, flattened to (n_res, n p, 3)."""
    turned = np.stack([_turn(vr, sym["angles"]) for vr in v])
    return turned.reshape(v.shape[0], -1, 3)


def _near_field_forms(fields: list[dict], geom: dict[str, Any], names: list[str], cbody: Any,
                      w: float, rho: float, g: float) -> np.ndarray:
    """``T[β, k, p, q]`` of one frequency: the near-field drift is ``Re Σ c_p c̄_q T[k, p, q]``
    with ``c = (1, X_1 … X_n)`` (module docstring; each term in docs/THEORY.md "Second-order
    wave drift")."""
    _, trans, rot = _dof_vectors(cbody)
    n_dir = len(fields) - len(names)
    rad = fields[n_dir:]
    out = []
    for wave in fields[:n_dir]:
        basis = [wave, *rad]
        t = np.vstack([np.zeros(3), trans])  # (P, 3): translation per unit c_p
        a = np.vstack([np.zeros(3), rot])  # rotation per unit c_p
        out.append(_dynamic_terms(basis, geom, t, a, w, rho, g)
                   + _static_terms(geom, t, a, rho, g))
    return np.asarray(out)


def _dynamic_terms(basis: list[dict], geom: dict[str, Any], t: np.ndarray, a: np.ndarray,
                   w: float, rho: float, g: float, other: tuple[list[dict], float] | None = None
                   ) -> np.ndarray:
    """Waterline, velocity-squared, hull-motion and rotation terms, shape (6, P, P).

    I   −½ρg ∮ ζ_r² N dl        (ζ_r = ζ − X_z at the waterline, ζ = iω φ / g)
    II  ½ρ ∫∫ |∇φ|² N dS
    III ρ ∫∫ (X · ∇Φ_t) N dS      (X = t + a × x, Φ_t = −iω φ)
    IV  α × F⁽¹⁾ (force), ξ × F⁽¹⁾ + α × M⁽¹⁾ (moment), F⁽¹⁾ the first-order dynamic pressure
        force and moment −iωρ ∫∫ φ N dS.
    A product u v of two first-order signals has the mean ½ Re(u ū) at one frequency and the
    difference-frequency part ½ Re(u_i v̄_j e^{-i(ω_i − ω_j) t}) for two: with ``other =
    (basis_j, ω_j)`` the q side is taken at ω_j, which gives the quadratic part of the
    difference-frequency QTF (no second-order potential).
    """
    basis_q, w_q = (basis, w) if other is None else other
    x, areas, normals = geom["x"], geom["areas"], geom["normals"]
    disp = t[:, None, :] + np.cross(a[:, None, :], x[None])  # (P, F, 3)
    disp_wl = t[:, None, :] + np.cross(a[:, None, :], geom["wl_x"][None])

    def side(b: list[dict], freq: float):
        rel = 1j * freq / g * np.stack([v["phi_wl"] for v in b]) - disp_wl[..., 2]  # (P, S)
        grad = np.stack([v["grad"] for v in b])  # (P, F, 3)
        first = -1j * freq * rho * np.stack([v["phi"] for v in b]) @ (areas[:, None] * normals)
        return rel, grad, first

    rel_p, grad_p, _ = side(basis, w)
    rel_q, grad_q, first_q = side(basis_q, w_q)
    wl = geom["wl_length"][:, None] * geom["wl_normals"]  # (S, 6)
    an = areas[:, None] * normals  # (F, 6)
    form = -0.25 * rho * g * np.einsum("sk,ps,qs->kpq", wl, rel_p, rel_q.conj())
    form += 0.25 * rho * np.einsum("fk,pfi,qfi->kpq", an, grad_p, grad_q.conj())
    form += 0.5 * rho * np.einsum("fk,pfi,qfi->kpq", an, disp, (-1j * w_q * grad_q).conj())
    fq, mq = first_q[:, :3].conj(), first_q[:, 3:].conj()  # F⁽¹⁾, M⁽¹⁾ per unit c_q
    form[:3] += 0.5 * np.cross(a[:, None, :], fq[None, :, :]).transpose(2, 0, 1)
    form[3:] += 0.5 * (np.cross(t[:, None, :], fq[None, :, :])
                       + np.cross(a[:, None, :], mq[None, :, :])).transpose(2, 0, 1)
    return form


def _static_terms(geom: dict[str, Any], t: np.ndarray, a: np.ndarray, rho: float,
                  g: float) -> np.ndarray:
    """Second-order part of the hydrostatic pressure on the moving hull, shape (6, P, P).

    Exact for the hull below the body's own waterplane (divergence theorem: force
    ``ρg R (V e − ẑ W₀)``, moment ``ρg ξ × R(V e − ẑ W₀) + ρg R (V x_B × e − W₁)`` with
    ``e = Rᵀẑ`` and W₀, W₁ the waterplane integrals of the depth ``ξ₃ + x·e``), expanded to
    second order; the strip above the body's waterplane is term I. Only the fluid pressure:
    the weight's second-order moment belongs to the body, not to the drift.
    """
    wp, vol, xb = geom["waterplane"], geom["volume"], geom["buoyancy_centre"]
    z = np.array([0.0, 0.0, 1.0])
    n_p = t.shape[0]

    def w0(xi3, e):  # waterplane integral of ξ3 + x e_x + y e_y
        return xi3 * wp["A"] + e[..., 0] * wp["Sx"] + e[..., 1] * wp["Sy"]

    def w1(xi3, e):  # waterplane integral of (ξ3 + x·e)(x × ẑ)
        return np.stack([xi3 * wp["Sy"] + e[..., 0] * wp["Ixy"] + e[..., 1] * wp["Iyy"],
                         -xi3 * wp["Sx"] - e[..., 0] * wp["Ixx"] - e[..., 1] * wp["Ixy"],
                         np.zeros(np.shape(xi3))], axis=-1)

    e1 = -np.cross(a, z)  # first-order part of e per unit c_q
    w0_1, w1_1 = w0(t[:, 2], e1), w1(t[:, 2], e1)  # (P,), (P, 3)
    # mean of e⁽²⁾ = ½ (α α_z − ẑ |α|²) as a form over (p, q)
    e2 = 0.25 * (a[:, None, :] * a[None, :, 2:3] - z * np.einsum("pi,qi->pq", a, a)[..., None])
    c0 = vol * np.cross(xb, z)
    force = -rho * g * (0.5 * np.cross(a, z)[:, None, :] * w0_1[None, :, None]
                        + z * w0(np.zeros((n_p, n_p)), e2)[..., None])
    inner = vol * np.cross(xb, e1) - w1_1  # first-order part of V x_B × e − W₁ per unit c_q
    moment = rho * g * (-0.5 * np.cross(t, z)[:, None, :] * w0_1[None, :, None]
                        + 0.25 * np.cross(a[:, None, :], np.cross(a[None, :, :], c0))
                        + 0.5 * np.cross(a[:, None, :], inner[None, :, :])
                        + vol * np.cross(xb, e2) - w1(np.zeros((n_p, n_p)), e2))
    return np.concatenate([force, moment], axis=-1).transpose(2, 0, 1)


def _join(parts: list[xr.Dataset], cbody: Any, ref: np.ndarray, depth: float, rho: float,
          g: float) -> xr.Dataset:
    """Concatenate per-frequency operators (sorted by ω) and set the attributes."""
    ds = xr.concat(parts, dim="omega", data_vars="minimal", coords="minimal",
                   compat="override", join="override").sortby("omega")
    lid = getattr(cbody, "lid_mesh", None)
    ds.attrs.update({
        "rho": float(rho), "g": float(g), "water_depth": float(depth),
        "reference_point": [float(v) for v in ref],
        "n_panels": int(cbody.mesh.nb_faces),
        "n_lid_panels": 0 if lid is None else int(lid.nb_faces),
        "method": "indirect",
    })
    for name, unit in (("omega", "rad/s"), ("wave_direction", "rad"), ("theta", "rad"),
                       ("wavenumber", "rad/m"), ("solved_depth", "m")):
        ds[name].attrs["units"] = unit
    ds["near_field_form"].attrs["description"] = (
        "mean drift D_k = Re sum_pq c_p conj(c_q) T[k,p,q], c = (1, RAO) [N/m^2, N m/m^2]")
    return ds


# ---------------------------------------------------------------------------- pure functions
def motion_rao(operator: xr.Dataset, mass: np.ndarray, stiffness: np.ndarray,
               damping: np.ndarray | None = None) -> xr.DataArray:
    """Body motions per unit wave amplitude from the operator's own A(ω), B(ω), F_exc(ω, β).

    Solves ``[−ω² (M + A) − iω (B + B_ext) + C] X = F_exc`` (Capytaine's convention).

    Parameters
    ----------
    operator : xarray.Dataset
        From :func:`solve_operator`.
    mass, stiffness, damping : (n, n) arrays
        Rigid-body mass about the reference point [kg, kg m, kg m²], total stiffness
        (hydrostatics, weight and mooring) [N/m, N m/rad…] and external linear damping
        [N s/m…] in force-equation orientation (row = force DOF), in the operator's DOF order.

    Returns
    -------
    xarray.DataArray
        ``rao`` (omega, wave_direction, radiating_dof), complex [m/m, rad/m].
    """
    names = co.dofs(operator)
    n = len(names)
    w = co.omega(operator)
    dirs = operator["wave_direction"].values
    coords = {"omega": w, "wave_direction": dirs, "radiating_dof": names}
    if n == 0:
        return xr.DataArray(np.zeros((w.size, dirs.size, 0), complex), coords=coords,
                            dims=("omega", "wave_direction", "radiating_dof"), name="rao")
    m, c = (_square(v, n, label) for v, label in ((mass, "mass"), (stiffness, "stiffness")))
    b_ext = np.zeros((n, n)) if damping is None else _square(damping, n, "damping")
    a, b = co.matrix_omega(operator, "added_mass"), co.matrix_omega(operator, "radiation_damping")
    impedance = (-w[:, None, None] ** 2 * (m + a) - 1j * w[:, None, None] * (b + b_ext) + c)
    exc = np.asarray(operator["excitation_force"].transpose(
        "omega", "wave_direction", "influenced_dof").sel(influenced_dof=names).values)
    x = np.linalg.solve(impedance[:, None], exc[..., None])[..., 0]
    out = xr.DataArray(x, coords=coords, dims=("omega", "wave_direction", "radiating_dof"),
                       name="rao")
    out.attrs["units"] = "m/m (translations), rad/m (rotations)"
    return out


def _square(value: Any, n: int, label: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n, n) or not np.all(np.isfinite(arr)):
        raise InputError(f"{label} must be a finite {n}x{n} matrix, got shape {arr.shape}")
    return arr


def near_field(operator: xr.Dataset, rao: xr.DataArray) -> xr.DataArray:
    """Near-field mean drift ``D`` (omega, wave_direction, influenced_dof = all six)
    [N/m² on translations, N m/m² on rotations, per unit wave amplitude squared]."""
    form = operator["near_field_form"]
    labels = [str(v) for v in form["motion_i"].values]
    x = rao.sel(radiating_dof=labels[1:]).transpose("omega", "wave_direction", "radiating_dof")
    c = np.concatenate([np.ones((*x.shape[:2], 1)), x.values], axis=-1)
    t = form.transpose("omega", "wave_direction", "component", "motion_i", "motion_j").values
    d = np.einsum("wbkpq,wbp,wbq->wbk", t, c, c.conj()).real
    return xr.DataArray(d, dims=("omega", "wave_direction", "influenced_dof"),
                        coords={"omega": form["omega"].values,
                                "wave_direction": form["wave_direction"].values,
                                "influenced_dof": [str(v) for v in form["component"].values]},
                        name="near_field")


def far_field(operator: xr.Dataset, rao: xr.DataArray) -> xr.DataArray:
    """Far-field mean drift ``D`` (omega, wave_direction, influenced_dof = Surge, Sway, Yaw)
    [N/m², N m/m²] by Capytaine's ``far_field_mean_drift_force`` (Maruo's formula), one call
    per solved depth, with the finite-depth Kochin normalisation fixed (module docstring);
    the yaw moment is moved from the vertical axis through the origin to the reference point.
    """
    from capytaine.post_pro.mean_drift_force import far_field_mean_drift_force

    depth = operator["solved_depth"].values
    blocks = []
    for h in np.unique(depth):
        sel = np.flatnonzero(depth == h)
        part = operator.isel(omega=sel)
        k = part["wavenumber"]
        scale = 1.0 if not math.isfinite(h) else np.tanh(k * h)
        cds = xr.Dataset(
            {"kochin_diffraction": part["kochin_diffraction"] / scale,
             "kochin_radiation": part["kochin_radiation"] / scale,
             "wavenumber": k.drop_vars(["solved_depth", "wavenumber"], errors="ignore")
             .reset_coords(drop=True),
             "water_depth": float(h), "rho": float(operator.attrs["rho"]),
             "g": float(operator.attrs["g"])},
        )
        x = rao.isel(omega=sel).transpose("omega", "wave_direction", "radiating_dof")
        res = far_field_mean_drift_force(x, cds)
        blocks.append(np.stack([np.diagonal(res[f"drift_force_{c}"].values, axis1=1,
                                            axis2=2).real for c in ("surge", "sway", "yaw")],
                               axis=-1))
    d = np.concatenate(blocks, axis=0)
    order = np.concatenate([np.flatnonzero(depth == h) for h in np.unique(depth)])
    d = d[np.argsort(order)]
    ref = operator.attrs.get("reference_point", [0.0, 0.0, 0.0])
    d[..., 2] -= ref[0] * d[..., 1] - ref[1] * d[..., 0]
    return xr.DataArray(d, dims=("omega", "wave_direction", "influenced_dof"),
                        coords={"omega": operator["omega"].values,
                                "wave_direction": operator["wave_direction"].values,
                                "influenced_dof": list(FAR_FIELD_DOFS)}, name="far_field")


# ---------------------------------------------------------------------------- cached runs, tables
def compute_operator(body: Any, omega: Sequence[float] | np.ndarray, *, water_depth: float,
                     panel_size: float, wave_directions: Sequence[float] = (0.0,),
                     n_theta: int = N_THETA, deep_water_kh: float | None = 3.0,
                     cache_dir: str | None = None,
                     progress: Callable[[float, float], None] | None = None) -> xr.Dataset:
    """:func:`solve_operator` for a :class:`hybridwsi.bodies.Body` (all six DOFs about its
    reference point, axisymmetric mesh and lid at ``panel_size`` [m]), resumable.

    Every solved frequency is merged into ``<cache>/drift/operator_<hash>.nc`` (atomic write;
    cache as :func:`hybridwsi.hydro.bem.default_cache_dir`), keyed by every input but the
    frequencies, so an interrupted run continues where it stopped and a later run with more
    frequencies solves only the new ones. ``attrs["input_hash"]`` is the key.
    """
    import json
    dofs = list(ALL_DOFS)
    mesh = body.mesh_options(panel_size=panel_size)
    config = {"body": body.to_dict(), "mesh": body.mesh_description(**mesh),
              "water_depth": float(water_depth) if math.isfinite(water_depth) else "inf",
              "wave_directions": [float(b) for b in wave_directions], "n_theta": int(n_theta),
              "deep_water_kh": deep_water_kh, "dofs": dofs, "method": "indirect",
              "versions": provenance("capytaine")}
    key = json_sha256(config)
    root = (Path(cache_dir).expanduser() if cache_dir is not None
            else default_cache_dir().parent) / "drift"
    store = root / f"operator_{key[:24]}.nc"
    done = read_netcdf(store) if store.is_file() else None
    cbody = body.capytaine_body(dofs, symmetric=True, lid=True, **mesh)
    op = solve_operator(cbody, omega, water_depth=water_depth, wave_directions=wave_directions,
                        rho=body.rho, g=body.g, n_theta=n_theta, deep_water_kh=deep_water_kh,
                        reference_point=body.reference_point, done=done,
                        checkpoint=lambda ds: to_netcdf(ds.assign_attrs(input_hash=key), store),
                        progress=progress)
    return op.assign_attrs(input_hash=key, inputs=json.dumps(config, sort_keys=True))


def drift_table(operator: xr.Dataset, rao: xr.DataArray,
                attrs: dict[str, Any] | None = None) -> xr.Dataset:
    """The mean drift coefficients of a body moving with ``rao``: a small Dataset.

    Variables (omega, wave_direction, influenced_dof = the six DOFs): ``far_field`` (NaN on
    heave, roll, pitch, which the momentum formula does not give) and ``near_field``
    [N/m² on translations, N m/m² on rotations: the mean force is D a² in a regular wave of
    amplitude a]; ``rao`` (omega, wave_direction, radiating_dof) the motions used
    [m/m, rad/m]; ``wavenumber`` (omega) [rad/m]. ``attrs``: the operator's solve settings
    plus ``attrs``.
    """
    far, near = far_field(operator, rao), near_field(operator, rao)
    far = far.reindex(influenced_dof=list(ALL_DOFS))
    units = "N/m^2 (Surge, Sway, Heave), N m/m^2 (Roll, Pitch, Yaw) per unit wave amplitude^2"
    out = xr.Dataset({
        "far_field": far.assign_attrs(units=units, description=(
            "momentum (Maruo) from Capytaine Kochin functions; NaN where not defined")),
        "near_field": near.assign_attrs(units=units, description=(
            "pressure integration (Pinkster): waterline, velocity squared, hull motion, "
            "rotation and second-order hydrostatic terms")),
        "rao": rao.assign_attrs(units="m/m (translations), rad/m (rotations)"),
        "wavenumber": ("omega", np.asarray(operator["wavenumber"].values),
                       {"units": "rad/m"}),
    })
    out["omega"].attrs["units"] = "rad/s"
    out["wave_direction"].attrs["units"] = "rad"
    keep = ("rho", "g", "water_depth", "reference_point", "n_panels", "n_lid_panels", "method",
            "input_hash", "inputs")
    out.attrs = {k: operator.attrs[k] for k in keep if k in operator.attrs}
    out.attrs["n_theta"] = int(operator.sizes["theta"]) - 2
    out.attrs.update(attrs or {})
    return out


def table_coefficients(table: xr.Dataset, dofs: Sequence[str], *, direction: float = 0.0,
                       field: str = "combined") -> tuple[np.ndarray, np.ndarray]:
    """ω grid [rad/s] and D (n_omega, n_dof) [N/m², N m/m²] of a drift table for ``dofs`` and
    the wave ``direction`` [rad].

    ``field``: ``"far_field"``, ``"near_field"`` or ``"combined"`` (far field where it is
    defined, i.e. surge, sway and yaw, near field for heave, roll and pitch).
    """
    if field not in ("far_field", "near_field", "combined"):
        raise InputError(f"drift field must be far_field, near_field or combined, got {field!r}")
    for name in ("far_field", "near_field"):
        if name not in table:
            raise InputError(f"drift table has no '{name}' (not a drift table?)")
    dofs = list(check_dofs(dofs))
    dirs = np.asarray(table["wave_direction"].values, dtype=float)
    gap = np.abs(np.angle(np.exp(1j * (dirs - float(direction)))))
    i = int(np.argmin(gap))
    if gap[i] > 1e-6:
        raise InputError(f"the drift table has no wave direction {direction:g} rad (it has "
                         f"{', '.join(f'{d:g}' for d in dirs)}; the body's drift for other "
                         "headings needs a solve with them)")
    pick = "near_field" if field == "near_field" else "far_field"
    d = table[pick].isel(wave_direction=i).sel(influenced_dof=dofs).values
    if field == "combined":
        near = table["near_field"].isel(wave_direction=i).sel(influenced_dof=dofs).values
        d = np.where(np.isnan(d), near, d)
    if not np.all(np.isfinite(d)):
        bad = [n for n, col in zip(dofs, d.T) if not np.all(np.isfinite(col))]
        raise InputError(f"the drift table's {pick} has no value for {bad}; use "
                         "field='near_field' or 'combined'")
    w = np.asarray(table["omega"].values, dtype=float)
    if w.size < 2 or np.any(np.diff(w) <= 0):
        raise InputError("drift table frequencies must be increasing (>= 2 of them)")
    return w, np.asarray(d, dtype=float)


# ---------------------------------------------------------------------------- off the diagonal
def quadratic_qtf(cbody: Any, omega: Sequence[float], mu: Sequence[float], *,
                  water_depth: float, mass: np.ndarray, stiffness: np.ndarray,
                  damping: np.ndarray | None = None, wave_direction: float = 0.0,
                  rho: float = 1025.0, g: float = 9.81, deep_water_kh: float | None = 3.0,
                  reference_point: Sequence[float] | None = None,
                  progress: Callable[[float, float], None] | None = None) -> xr.DataArray:
    """The quadratic part of the difference-frequency QTF, ``T(ω, ω + μ)`` (complex).

    The near-field terms of the mean drift evaluated with one first-order factor at ω and the
    other at ω + μ (same code, :func:`_dynamic_terms` ``other=``): the slow-drift force of two
    wave components ``a_i cos θ_i + a_j cos θ_j`` is ``2 a_i a_j Re[T_ij e^{-i(θ_i − θ_j)}]``
    (T the Hermitian part of the two orderings of the pair) plus the second-order potential's
    part, which this leaves out. ``T(ω, ω)`` is the near-field
    mean drift. Used to measure what Newman's approximation ``T_ij ≈ ½ (D_i + D_j)`` misses
    of it (docs/OC3_HYWIND.md "Slow drift"). Each distinct frequency is solved once.

    Returns
    -------
    xarray.DataArray
        (omega, mu, influenced_dof = the six) [N/m², N m/m² per unit amplitudes²], complex.
    """
    import time

    import capytaine as cpt

    solver = cpt.BEMSolver(method="indirect")
    ref = np.asarray(_reference_point(cbody) if reference_point is None else reference_point,
                     dtype=float)
    geom = _geometry(cbody, ref)
    names, trans, rot = _dof_vectors(cbody)
    t = np.vstack([np.zeros(3), trans])
    a = np.vstack([np.zeros(3), rot])
    static = _static_terms(geom, t, a, rho, g)
    direction = np.array([float(wave_direction) % (2 * math.pi)])
    solved: dict[float, tuple[list[dict], np.ndarray]] = {}

    def at(w: float) -> tuple[list[dict], np.ndarray]:
        key = round(float(w), 12)
        if key not in solved:
            start = time.perf_counter()
            depth = _solve_depth(w, float(water_depth), g, deep_water_kh)
            results, fields = _solve_results(solver, cbody, geom, float(w), depth, direction,
                                              rho, g)
            coeffs = _coefficients(results, names, direction, float(w))
            x = motion_rao(coeffs, mass, stiffness, damping).values[0, 0]
            solved[key] = (fields, np.concatenate([[1.0], x]))
            if progress is not None:
                progress(float(w), time.perf_counter() - start)
        return solved[key]

    def pair(w1: float, w2: float) -> np.ndarray:
        (b1, c1), (b2, c2) = at(w1), at(w2)
        form = _dynamic_terms(b1, geom, t, a, w1, rho, g, other=(b2, w2)) + static
        return np.einsum("kpq,p,q->k", form, c1, c2.conj())

    out = np.zeros((len(omega), len(mu), 6), dtype=complex)
    for i, w in enumerate(omega):
        for j, m in enumerate(mu):
            # the pair (i, j) and (j, i) together: the Hermitian part
            out[i, j] = 0.5 * (pair(float(w), float(w + m)) + pair(float(w + m), float(w)).conj())
    return xr.DataArray(out, dims=("omega", "mu", "influenced_dof"),
                        coords={"omega": np.asarray(omega, float), "mu": np.asarray(mu, float),
                                "influenced_dof": list(ALL_DOFS)}, name="quadratic_qtf")
