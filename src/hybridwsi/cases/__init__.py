"""The project's cases as data: TOML files, built in (beside this module) or the user's own.

``load_case("paper_sphere")`` returns the validated content of ``paper_sphere.toml``: the
floating sphere of the paper, its BEM configuration, the regular-wave case (T = 0.75 s,
H = 0.05 m) and the paper's Table 1 values; ``load_case("kramer2021_decay")`` the decay
experiment of Kramer et al. (2021); ``load_case("oc3_hywind")`` the OC3-Hywind spar with the
NREL 5-MW turbine (docs/OC3_HYWIND.md); ``load_case("oc4_semi")`` the OC4-DeepCwind
semi-submersible with the same turbine (docs/OC4_SEMI.md); ``load_case("path/to/my_spar.toml")`` a user's case
file. Every case is checked against one schema (:mod:`hybridwsi.cases.schema`,
docs/CASES.md); paths inside a case file are relative to it.

This package is data only (it imports no body, force or solver): the body, the coefficients
and the force components of a case are built above the force layer, in
:mod:`hybridwsi.casemodel` (``body_from_case``, ``bem_arguments``, ``CaseModel``).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from hybridwsi.cases.schema import MOORING_MODELS, canonical_hash, validate
from hybridwsi.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, published as tomli (pyproject.toml dependency)
    import tomli as tomllib


class Case(dict):
    """A validated case: its content as plain values (:func:`load_case`), plus where it came
    from.

    Attributes
    ----------
    name : str
        The ``name`` entry, else the file name without ``.toml``.
    path : Path or None
        The case file (None for a case built from a dict without a file).
    directory : Path
        The folder relative paths in the case are taken from.
    sha256 : str
        Canonical content hash (:func:`hybridwsi.cases.schema.canonical_hash`): the same for
        a copy under another name or folder, different for any change of a value or of a
        referenced file. Computed once, at loading; edit a copy with :func:`from_dict`.
    """

    def __init__(self, data: Mapping[str, Any], *, name: str, path: Path | None,
                 directory: Path, sha256: str) -> None:
        super().__init__(data)
        self.name = name
        self.path = path
        self.directory = directory
        self.sha256 = sha256

    @property
    def label(self) -> str:
        """How messages name the case: its file, else its name."""
        return str(self.path) if self.path is not None else f"case {self.name!r}"


def available() -> list[str]:
    """Names of the built-in cases."""
    files = resources.files(__name__).iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".toml"))


def _builtin(name: str) -> Path | None:
    path = Path(str(resources.files(__name__))) / f"{name}.toml"
    return path if path.is_file() and os.sep not in name and "/" not in name else None


def is_builtin(case: str | os.PathLike) -> bool:
    """Whether ``case`` names a built-in case (not a file)."""
    text = os.fspath(case)
    return not text.endswith(".toml") and _builtin(text) is not None


def case_path(case: str | os.PathLike) -> Path:
    """The file of a case given as a built-in name or a path to a TOML file."""
    text = os.fspath(case)
    builtin = _builtin(text) if not text.endswith(".toml") else None
    if builtin is not None:
        return builtin
    path = Path(text).expanduser()
    if path.is_file():
        return path
    if text.endswith(".toml") or os.sep in text or "/" in text:
        raise InputError(f"case file {text} not found")
    raise InputError(f"unknown case '{text}': not a built-in case ({', '.join(available())}) "
                     "and no such file")


def _label(case: str | os.PathLike, path: Path) -> str:
    return path.name if path.parent == Path(str(resources.files(__name__))) else os.fspath(case)


def raw_case(case: str | os.PathLike) -> dict[str, Any]:
    """The TOML content of a case file as written (not validated): to edit and check again
    with :func:`from_dict`."""
    path = case_path(case)
    label = _label(case, path)
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as exc:
        raise InputError(f"{label}: cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise InputError(f"{label}: not a UTF-8 text file (a case is a TOML file)") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{label}: not valid TOML: {exc}") from None


def load_case(case: str | os.PathLike) -> Case:
    """A case by built-in name (see :func:`available`) or path to a TOML file, validated.

    Raises
    ------
    InputError
        One line naming the file and the key: not found, not TOML, unknown key, missing or
        malformed value, wrong unit (:mod:`hybridwsi.cases.schema`).
    """
    if isinstance(case, Case):
        return case
    path = case_path(case)
    return from_dict(raw_case(case), label=_label(case, path), path=path.resolve())


def from_dict(raw: Mapping[str, Any], *, label: str = "case",
              path: str | os.PathLike | None = None,
              directory: str | os.PathLike | None = None) -> Case:
    """A case from its TOML content as a dict (validated like a file; relative paths from
    ``directory``, default the folder of ``path``, else the working directory)."""
    path = None if path is None else Path(path)
    folder = Path(directory) if directory is not None else (
        path.parent if path is not None else Path.cwd())
    content, files = validate(raw, label, folder)
    name = content.get("name") or (path.stem if path is not None else label)
    return Case(content, name=str(name), path=path, directory=folder,
                sha256=canonical_hash(content, files))


def mooring_model(case: Mapping[str, Any], override: str | None = None) -> str:
    """The case's mooring model (``[forces] mooring``: moordyn, quasi-static, table or none),
    or ``override`` (the command line's ``--mooring``) when given; an override needs the
    case's ``[mooring]`` table."""
    model = case.get("forces", {}).get("mooring", "table" if "mooring" in case else "none")
    if override is None or override == model:
        return model
    if override not in MOORING_MODELS:
        raise InputError(f"mooring model must be one of {', '.join(MOORING_MODELS)}, got "
                         f"{override!r}")
    if "mooring" not in case:
        raise InputError(f"--mooring {override}: the case has no [mooring] table")
    if override == "moordyn" and "moordyn_file" not in case["mooring"]:
        raise InputError("--mooring moordyn: the case's [mooring] has no moordyn_file (the "
                         "MoorDyn v2 input)")
    return override


def with_values(case: Case, updates: Mapping[str, Mapping[str, Any]]) -> Case:
    """A copy of ``case`` with entries of its tables replaced, validated again: ``updates``
    maps a table name to ``{key: value}`` (``{"rotor": {"wind_speed": 11.4}, "forces":
    {"drift": True}}``; the command line's overrides). Without updates the case itself.

    The copy's ``sha256`` covers the new values (a sweep's settings hash sees them); relative
    paths stay relative to the case's folder. Starts from the file as written when there is
    one (so the defaults the schema derives, e.g. ``[forces]``, are derived again).

    Raises
    ------
    InputError
        A value the schema refuses (one line naming the key).
    """
    updates = {k: dict(v) for k, v in updates.items() if v}
    if not updates:
        return case
    raw = raw_case(case.path) if case.path is not None else dict(case)
    for table, values in updates.items():
        current = raw.get(table, {})
        if not isinstance(current, Mapping):
            raise InputError(f"{case.label}: [{table}] is not a table")
        raw[table] = {**current, **values}
    label = case.path.name if case.path is not None else case.name
    return from_dict(raw, label=label, path=case.path, directory=case.directory)

