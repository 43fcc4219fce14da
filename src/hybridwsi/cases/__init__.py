"""The paper's cases as data (TOML files beside this module).

``load_case("paper_sphere")`` returns the dict of ``paper_sphere.toml``: the floating sphere of
the paper, its BEM configuration, the regular-wave case (T = 0.75 s, H = 0.05 m) and the paper's
Table 1 values; ``load_case("kramer2021_decay")`` the decay experiment of Kramer et al. (2021).
"""

from __future__ import annotations

import sys
from importlib import resources
from typing import Any

from hybridwsi.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, published as tomli (pyproject.toml dependency)
    import tomli as tomllib


def available() -> list[str]:
    """Names of the built-in cases."""
    files = resources.files(__name__).iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".toml"))


def load_case(name: str) -> dict[str, Any]:
    """Load a built-in case by name (see :func:`available`)."""
    path = resources.files(__name__) / f"{name}.toml"
    if not path.is_file():
        raise InputError(f"unknown case '{name}' (available: {', '.join(available())})")
    return tomllib.loads(path.read_text())
