"""Rigid-body degrees of freedom as data: names, kinds and units per DOF.

Every stage names DOFs with Capytaine's spelling (``Surge``, ``Sway``, ``Heave``, ``Roll``,
``Pitch``, ``Yaw``). Translations are in m and receive forces in N; rotations are in rad and
receive moments in N m. A coefficient that couples a force on DOF i to a motion of DOF j has
the unit ``force_unit(i) / motion_unit(j)`` times s or s²; :func:`coefficient_unit`
spells it.
No DOF is special: code that needs a unit asks this module.
"""

from __future__ import annotations

from collections.abc import Sequence

from hybridwsi.errors import InputError

#: Capytaine's rigid-body degree-of-freedom names, in its order
RIGID_DOFS = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
TRANSLATIONS = ("Surge", "Sway", "Heave")
ROTATIONS = ("Roll", "Pitch", "Yaw")

#: time-derivative order of a kinematic quantity
_ORDER = {"z": 0, "zdot": 1, "zddot": 2}


def check_dofs(dofs: Sequence[str] | str) -> tuple[str, ...]:
    """Validate degree-of-freedom names (Capytaine spelling) and return them as a tuple.

    Accepts a sequence or a comma-separated string (``"Surge,Pitch"``); case-insensitive.
    """
    if isinstance(dofs, str):
        dofs = [d for d in dofs.split(",") if d.strip()]
    lookup = {d.lower(): d for d in RIGID_DOFS}
    names = tuple(lookup.get(str(d).strip().lower(), str(d)) for d in dofs)
    bad = [d for d in names if d not in RIGID_DOFS]
    if bad or not names:
        raise InputError(f"unknown degree(s) of freedom {bad or '[]'}; choose from {list(RIGID_DOFS)}")
    if len(set(names)) != len(names):
        raise InputError(f"degrees of freedom are repeated: {list(names)}")
    return names


def index(dofs: Sequence[str]) -> list[int]:
    """Positions of ``dofs`` in :data:`RIGID_DOFS` (for slicing 6x6 matrices)."""
    return [RIGID_DOFS.index(d) for d in check_dofs(dofs)]


def is_rotation(dof: str) -> bool:
    """True for Roll, Pitch and Yaw (measured in rad)."""
    return check_dofs([dof])[0] in ROTATIONS


def motion_unit(dof: str, quantity: str = "z") -> str:
    """Unit of a kinematic quantity (``z``, ``zdot``, ``zddot``) of ``dof``: m, m/s, m/s², rad…"""
    base = "rad" if is_rotation(dof) else "m"
    return base + ("", "/s", "/s^2")[_ORDER[quantity]]


def force_unit(dof: str) -> str:
    """Unit of the generalised force on ``dof``: N for translations, N m for rotations."""
    return "N m" if is_rotation(dof) else "N"


_COEF_UNITS = {
    # (influenced is rotation, radiating is rotation) -> unit
    "mass": {(False, False): "kg", (False, True): "kg m", (True, False): "kg m",
             (True, True): "kg m^2"},
    "damping": {(False, False): "N s/m", (False, True): "N s/rad", (True, False): "N m s/m",
                (True, True): "N m s/rad"},
    "stiffness": {(False, False): "N/m", (False, True): "N/rad", (True, False): "N m/m",
                  (True, True): "N m/rad"},
}


def coefficient_unit(influenced: str, radiating: str, quantity: str) -> str:
    """Unit of a coefficient mapping a motion of ``radiating`` to a force on ``influenced``.

    ``quantity`` is ``mass`` (per acceleration), ``damping`` (per velocity) or ``stiffness``
    (per displacement): e.g. surge–surge added mass ``kg``, pitch–surge ``kg m``, pitch–pitch
    ``kg m^2``; surge force per pitch angle ``N/rad``; pitch moment per pitch angle ``N m/rad``.
    """
    if quantity not in _COEF_UNITS:
        raise InputError(f"quantity must be one of {sorted(_COEF_UNITS)}, got {quantity!r}")
    return _COEF_UNITS[quantity][(is_rotation(influenced), is_rotation(radiating))]


def units_label(dofs: Sequence[str], quantity: str = "z") -> str:
    """One label for several DOFs, e.g. ``"m, rad"`` for Surge and Pitch displacements."""
    units = [force_unit(d) if quantity == "force" else motion_unit(d, quantity) for d in dofs]
    return ", ".join(dict.fromkeys(units))
