"""Strip-theory (Morison inertia) coefficients of the slender members a panel model leaves out,
added to a BEM coefficient Dataset: the platform's hydrodynamics as one Dataset.

A semi-submersible's pontoons and braces (OC4-DeepCwind: 1.6 m diameter) are slender: their
radiation damping is negligible and their inertia follows Morison's equation. Per element
(volume V, axis t, ``P = 1 − t tᵀ``, coefficient Ca, Jacobian J of :func:`point_jacobians`):

- added mass (frequency independent): ``A_m = Σ ρ Ca V Jᵀ P J`` [kg, kg m, kg m²];
- excitation per unit wave amplitude (Froude-Krylov + diffraction of a slender cylinder):
  ``F̂ = Σ Jᵀ ρ (1 + Ca) V P â``, with the complex Airy particle acceleration at the element
  ``â = −iω (û_h cos β, û_h sin β, ŵ)``, ``û_h = ω cosh(k(z + h))/sinh(kh) e^{iks}``,
  ``ŵ = −iω sinh(k(z + h))/sinh(kh) e^{iks}``, ``s = x cos β + y sin β`` (the project's and
  Capytaine's convention ``F(t) = Re[F̂ a e^{−iωt}]`` for ``η = Re[a e^{−iωt}]`` at the origin).

:func:`with_slender_members` adds ``A_m`` to ``added_mass`` (every ω) and to its limits, and
``F̂`` to ``excitation_force``, and records what it added in ``attrs["strip_theory"]``; the
time-domain Morison component then carries the drag only
(``MemberMorison(..., inertia=False)``), so nothing is counted twice.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from hybridwsi.bodies.members import (DEFAULT_ELEMENT_LENGTH, MemberElements, member_elements,
                                      point_jacobians)
from hybridwsi.dofs import index
from hybridwsi.errors import InputError
from hybridwsi.hydro import coefficients as co
from hybridwsi.waves import airy_depth_factor, airy_vertical_factor, dispersion_k


def slender_coefficients(elements: MemberElements, omega: np.ndarray, directions: np.ndarray,
                         *, rho: float, g: float, water_depth: float, dofs: Sequence[str],
                         reference_point: Sequence[float] = (0.0, 0.0, 0.0)
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Added mass ``A_m`` (n, n) and excitation ``F̂`` (n_ω, n_β, n) of the elements flagged
    for Morison inertia (module docstring); ``dofs`` order, ``[influenced, radiating]``."""
    keep = elements.inertia
    jac = point_jacobians(elements.centre[keep], reference_point)[:, :, index(dofs)]
    t = elements.tangent[keep]
    normal_jac = jac - np.einsum("nk,nl,nld->nkd", t, t, jac)  # P J
    vol = elements.volume[keep]
    ca = elements.ca[keep]
    added = np.einsum("n,nkd,nke->de", rho * ca * vol, normal_jac, normal_jac)
    w = np.asarray(omega, dtype=float)
    k = dispersion_k(w, water_depth, g)
    z = elements.centre[keep, 2]
    horizontal = airy_depth_factor(k, z, water_depth) * w  # (n_el, n_ω), per unit amplitude
    vertical = airy_vertical_factor(k, z, water_depth) * w
    exc = np.zeros((w.size, len(directions), len(dofs)), dtype=complex)
    for j, beta in enumerate(directions):
        s = elements.centre[keep, :2] @ np.array([math.cos(beta), math.sin(beta)])
        phase = np.exp(1j * np.outer(s, k))  # (n_el, n_ω)
        acc = -1j * w * np.stack([horizontal * phase * math.cos(beta),
                                  horizontal * phase * math.sin(beta),
                                  -1j * vertical * phase], axis=1)  # (n_el, 3, n_ω)
        exc[:, j, :] = np.einsum("n,nkd,nkw->wd", rho * (1.0 + ca) * vol, normal_jac, acc)
    return added, exc


def with_slender_members(coeffs: xr.Dataset, elements: MemberElements,
                         reference_point: Sequence[float] | None = None) -> xr.Dataset:
    """``coeffs`` plus the strip-theory added mass and excitation of the slender members.

    Raises
    ------
    InputError
        Coefficients that already hold them (``attrs["strip_theory"]``), or without
        ``excitation_force``.
    """
    if "strip_theory" in coeffs.attrs:
        raise InputError("these coefficients already include the slender members")
    if "excitation_force" not in coeffs:
        raise InputError("coefficients have no excitation_force")
    dofs = list(co.dofs(coeffs))
    ref = coeffs.attrs.get("reference_point", (0.0, 0.0, 0.0)) if reference_point is None \
        else reference_point
    directions = np.atleast_1d(np.asarray(coeffs["wave_direction"].values, dtype=float))
    added, exc = slender_coefficients(
        elements, co.omega(coeffs), directions, rho=float(coeffs.attrs["rho"]),
        g=float(coeffs.attrs["g"]), water_depth=float(coeffs.attrs.get("water_depth", math.inf)),
        dofs=dofs, reference_point=[float(v) for v in ref])
    out = coeffs.copy(deep=True)
    pair = ("radiating_dof", "influenced_dof")  # stored transposed: A_m is symmetric anyway
    for name in ("added_mass", "added_mass_inf", "added_mass_zero"):
        if name in out:
            out[name] = out[name] + xr.DataArray(added.T, dims=pair)
    fe = out["excitation_force"]
    out["excitation_force"] = fe + xr.DataArray(exc, dims=("omega", "wave_direction",
                                                           "influenced_dof")).transpose(*fe.dims)
    for name in ("added_mass", "added_mass_inf", "added_mass_zero", "excitation_force"):
        out[name].attrs = coeffs[name].attrs
    members = sorted(set(np.array(elements.member)[elements.inertia]))
    out.attrs["strip_theory"] = json.dumps({
        "members": members, "n_elements": int(np.sum(elements.inertia)),
        "added_mass_diagonal": np.diag(added).tolist(),
        "description": "Morison inertia of the slender members (hybridwsi.hydro.strip): added "
                       "mass rho Ca V (1 - t t^T) and excitation rho (1 + Ca) V (1 - t t^T) "
                       "a_wave added to the panel model's coefficients"})
    return out


def case_elements(case: Mapping[str, Any]) -> MemberElements:
    """Elements of the members of a case's ``[body.hull]`` (``[morison] element_length``)."""
    try:
        members = case["body"]["hull"]["members"]
    except (KeyError, TypeError):
        raise InputError("case has no [[body.hull.members]]") from None
    length = case.get("morison", {}).get("element_length", DEFAULT_ELEMENT_LENGTH)
    return member_elements(members, float(length))
