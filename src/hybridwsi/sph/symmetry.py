"""True mirror symmetry planes for the SPH tank (x = 0 and/or y = 0).

A symmetry plane is not a wall: the fluid next to it must see the mirror image of the fluid
*and of every solid* (the floating body, the bottom, the paddle) on the other side, moving with
the normal velocity component reversed. :class:`MirrorDomain` does that: at every
``update_domain`` -- which PySPH's PEC integrator calls after *each* stage, before the forces
are evaluated -- it deletes the previous ghosts and appends to each particle array a copy of
every particle within two kernel supports of a plane, with the normal coordinate mirrored and
the normal velocity negated (corner images across both planes included). The ghosts carry
PySPH's tag ``Ghost``; they are sources in every equation (continuity, momentum, density
diffusion, the wall-pressure extrapolation) and destinations only of the groups declared
``real=False`` (the equation of state and the wall-pressure extrapolation), so ghost walls
get their pressure from the same extrapolation as the real ones.

PySPH 1.0b2 has mirror ghosts of its own (``DomainManager(mirror_in_x=True, ...)``), but
``CPUDomainManager._create_ghosts_mirror`` (``pysph/base/nnps_base.pyx``) does not reset its
per-particle translation buffers between particle arrays, so the second array's images (our
walls and body) would be displaced by the first array's offsets. The images are therefore
made here with NumPy, through PySPH's ``extract_particles``/``append_parray``.

Two kernel supports (``n_layers = 2``, the PySPH default) are needed: a ghost wall particle
within one support of the plane talks to real fluid, and its pressure extrapolation needs the
fluid up to one more support beyond it.

Conventions for the floating body (``equations.WallForce``/``BodyForceReduce``): the force on
each *real* body particle sums its pairs with real and ghost fluid. A (real body, ghost fluid)
pair is the pair (body particle, mirror image of a fluid particle) of the whole domain, and
no pair is counted twice; the whole body's vertical force is then that sum times the number of
symmetric copies (``body[B_SCALE]``: 2 per plane). Ghost body particles are never summed.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: per plane axis, the properties whose sign a mirror image reverses: the coordinate, the
#: velocity and the wall acceleration (which enters the ghost walls' pressure extrapolation)
_NORMAL_PROPS = {0: ("x", "u", "awx"), 1: ("y", "v", "awy")}


def ghost_tag() -> int:
    """PySPH's tag value of ghost particles."""
    from pysph.base.particle_array import get_ghost_tag

    return int(get_ghost_tag())


def check_planes(planes: tuple[int, ...]) -> tuple[int, ...]:
    """Validate symmetry-plane axes (0: x = 0, 1: y = 0); returns them sorted."""
    if any(ax not in (0, 1) for ax in planes) or len(set(planes)) != len(planes):
        raise ValueError(f"symmetry planes must be distinct axes among 0 (x) and 1 (y), "
                         f"got {planes}")
    return tuple(sorted(planes))


def make_ghosts(pa: Any, planes: tuple[int, ...], width: float) -> int:
    """Replace the ghosts of ``pa`` by the mirror images of its particles within ``width`` [m]
    of the planes x_axis = 0 (``planes``), with the normal components of position, velocity
    and wall acceleration negated (every other property copied); returns the ghost count.

    Planes are taken in turn and the images made for one plane are mirrored across the next
    one too, so a particle near the corner x = y = 0 gets its three images. The arrays are
    cut back to the real particles and extended in place (NumPy fancy indexing of every
    property: PySPH's ``remove_tagged_particles``/``append_parray`` took 40 ms per call).
    """
    n = n_real(pa)
    # each image: the real particle it copies and whether x and/or y are mirrored
    src, flip = np.arange(n), np.zeros((n, 2), dtype=bool)
    imgs_src, imgs_flip = [], []
    for ax in planes:
        near = np.flatnonzero(pa.get("xy"[ax])[:n] <= width)
        cand_src = np.concatenate([src[near]] + [s[(pa.get("xy"[ax])[s] <= width)]
                                                 for s in imgs_src])
        cand_flip = np.concatenate([flip[near]] + [f[(pa.get("xy"[ax])[s] <= width)]
                                                   for s, f in zip(imgs_src, imgs_flip)])
        cand_flip[:, ax] = True
        imgs_src.append(cand_src)
        imgs_flip.append(cand_flip)
    g_src = np.concatenate(imgs_src) if imgs_src else np.zeros(0, dtype=int)
    g_flip = np.concatenate(imgs_flip) if imgs_flip else np.zeros((0, 2), dtype=bool)
    k = len(g_src)
    pa.resize(n)
    pa.extend(k)
    for prop in pa.properties:
        arr = pa.get(prop, only_real_particles=False)
        stride = pa.stride.get(prop, 1)
        if stride == 1:
            arr[n:] = arr[g_src]
        else:
            arr.reshape(-1, stride)[n:] = arr.reshape(-1, stride)[g_src]
    for ax in (0, 1):
        f = np.flatnonzero(g_flip[:, ax]) + n
        for name in _NORMAL_PROPS[ax]:
            if len(f) and name in pa.properties:
                pa.get(name, only_real_particles=False)[f] *= -1.0
    pa.get("tag", only_real_particles=False)[n:] = ghost_tag()
    pa.set_num_real_particles(n)
    return k


def mirror_domain(planes: tuple[int, ...], width: float) -> Any | None:
    """A PySPH domain manager whose ``update`` refreshes the mirror ghosts of every array
    (:func:`make_ghosts`), or None without planes. ``width`` [m]: two kernel supports."""
    if not planes:
        return None
    from pysph.base.nnps import DomainManager

    planes = check_planes(planes)

    class MirrorDomain(DomainManager):
        # a Python subclass of PySPH's cdef class: the NNPS calls ``update`` through Python
        # attribute lookup (before binning, at set-up and after each integrator stage)
        def set_pa_wrappers(self, wrappers):
            super().set_pa_wrappers(wrappers)
            self.arrays = [w.pa for w in wrappers]

        def update(self):
            super().update()  # the cell size for binning
            for pa in self.arrays:
                make_ghosts(pa, planes, width)

    return MirrorDomain()


def n_real(pa: Any) -> int:
    """Number of real (non-ghost) particles of a PySPH particle array."""
    return int(pa.get_number_of_particles(real=True))


def remove_ghosts(*arrays: Any) -> None:
    """Delete the ghost particles of ``arrays`` (before a checkpoint is read into them)."""
    tag = ghost_tag()
    for pa in arrays:
        pa.remove_tagged_particles(tag)


def reflect_crossers(pa: Any, planes: tuple[int, ...]) -> int:
    """Put real particles that crossed a symmetry plane back on its real side.

    A particle at normal coordinate -s < 0 and its ghost at +s form the same symmetric pair as
    the reflected particle and its ghost, so reflecting the position and the normal velocity
    changes nothing physically; it keeps the real particles in the simulated part of the
    domain (the probes and the free-surface sampling look there). Returns how many were moved.
    """
    n = n_real(pa)
    moved = 0
    for ax in planes:
        coord = (pa.x, pa.y)[ax]
        vel = (pa.u, pa.v)[ax]
        sel = np.flatnonzero(coord[:n] < 0.0)
        if len(sel):
            coord[sel] = -coord[sel]
            vel[sel] = -vel[sel]
            moved += len(sel)
    return moved
