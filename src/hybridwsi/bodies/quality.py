"""Quality checks of a wetted-hull panel mesh: watertight up to the waterline, consistently
oriented, outward normals, and its volume.

A hull mesh clipped at the still-water level is a surface whose only boundary is the waterline:
closed by the waterplane z = 0 it encloses the displaced volume. :func:`mesh_quality` checks that
on the panels themselves (vertices merged within a tolerance):

- every edge is shared by at most two panels (no T-junctions, no non-manifold edges);
- edges used by one panel only (the boundary) all lie at z = 0;
- every interior edge is traversed once in each direction by its two panels (consistent
  orientation);
- the divergence theorem with the panel normals gives the volume three ways,
  ``V = ∫ x n_x dS = ∫ y n_y dS = ∫ z n_z dS`` (the waterplane adds nothing to the last: z = 0
  there, nor to the others when it is closed), all positive when the normals point out of the
  body (into the water).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MeshQuality:
    """Result of :func:`mesh_quality`.

    Attributes
    ----------
    n_faces : int
        Panels (triangles count as panels).
    boundary_edges, boundary_edges_off_waterline : int
        Edges used by one panel, and those of them not at z = 0 (0 when watertight).
    nonmanifold_edges : int
        Edges used by more than two panels (0 for a valid surface).
    misoriented_edges : int
        Interior edges traversed in the same direction by both panels (0 when consistently
        oriented).
    volume_xyz : (float, float, float)
        ``∫ x n_x dS``, ``∫ y n_y dS``, ``∫ z n_z dS`` [m^3] (exact for flat panels).
    waterline_length : float
        Total length of the boundary edges [m].
    max_panel_size : float
        Largest panel diameter (longest diagonal or edge) [m].
    """

    n_faces: int
    boundary_edges: int
    boundary_edges_off_waterline: int
    nonmanifold_edges: int
    misoriented_edges: int
    volume_xyz: tuple[float, float, float]
    waterline_length: float
    max_panel_size: float

    @property
    def watertight(self) -> bool:
        """Closed up to the waterline, manifold and consistently oriented."""
        return (self.boundary_edges_off_waterline == 0 and self.nonmanifold_edges == 0
                and self.misoriented_edges == 0)

    @property
    def volume(self) -> float:
        """Mean of :attr:`volume_xyz` [m^3] (> 0 with outward normals)."""
        return float(np.mean(self.volume_xyz))

    @property
    def outward(self) -> bool:
        """All three volume integrals positive: normals point into the water."""
        return all(v > 0 for v in self.volume_xyz)


def mesh_quality(mesh, tol: float = 1e-6) -> MeshQuality:
    """Check a Capytaine hull mesh (symmetric meshes are merged first); module docstring.

    Parameters
    ----------
    mesh : capytaine mesh
        The wetted hull, clipped at z = 0.
    tol : float
        Vertices closer than this [m] are the same vertex; edges with both ends within it of
        z = 0 are on the waterline.
    """
    if hasattr(mesh, "merged"):
        mesh = mesh.merged()
    verts = np.asarray(mesh.vertices, dtype=float)
    key = np.round(verts / tol).astype(np.int64)
    _, ids = np.unique(key, axis=0, return_inverse=True)
    ids = ids.ravel()
    faces = [list(dict.fromkeys(ids[f])) for f in np.asarray(mesh.faces)]  # drop repeats
    directed = [(f[k], f[(k + 1) % len(f)]) for f in faces if len(f) >= 3
                for k in range(len(f))]
    d = np.array(directed)
    undirected = np.sort(d, axis=1)
    uniq, inverse, count = np.unique(undirected, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    forward = np.zeros(len(uniq), int)
    np.add.at(forward, inverse, (d[:, 0] < d[:, 1]).astype(int))
    interior = count == 2
    misoriented = int(np.sum(interior & (forward != 1)))
    merged_pos = np.zeros((ids.max() + 1, 3))
    merged_pos[ids] = verts
    boundary = uniq[count == 1]
    ends = merged_pos[boundary]
    off = int(np.sum(np.any(np.abs(ends[..., 2]) > tol, axis=1)))
    length = float(np.sum(np.linalg.norm(ends[:, 0] - ends[:, 1], axis=1))) if len(ends) else 0.0
    normals = np.asarray(mesh.faces_normals)
    centres = np.asarray(mesh.faces_centers)
    areas = np.asarray(mesh.faces_areas)
    vol = tuple(float(np.sum(centres[:, k] * normals[:, k] * areas)) for k in range(3))
    radii = np.asarray(mesh.faces_radiuses) if hasattr(mesh, "faces_radiuses") else np.zeros(1)
    return MeshQuality(n_faces=int(mesh.nb_faces), boundary_edges=int(np.sum(count == 1)),
                       boundary_edges_off_waterline=off,
                       nonmanifold_edges=int(np.sum(count > 2)), misoriented_edges=misoriented,
                       volume_xyz=vol, waterline_length=length,
                       max_panel_size=float(2 * np.max(radii)))
