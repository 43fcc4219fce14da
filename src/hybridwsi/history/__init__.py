"""TimeHistory: the one labelled type that carries force/motion histories through the pipeline.

A TimeHistory is an :class:`xarray.Dataset` (``time`` × ``dof``; ``z``, ``zdot``, ``zddot``,
force components, optional ``mass``; units per DOF). The package is split along its seams:

- :mod:`~hybridwsi.history.model`: the data model — :func:`make_history`, :func:`validate`,
  :func:`force_names`, :func:`mass_matrix`, :func:`set_mass`, :func:`time_step`,
  :func:`is_uniform`, and the checks :func:`check_mass`, :func:`check_compatible` (histories
  that may be pooled) and :func:`check_regressors` (data a fit can use);
- :mod:`~hybridwsi.files`: atomic writers (:func:`atomic_write`, :func:`write_json`,
  :func:`write_text`) and the NetCDF round trip (:func:`to_netcdf`, :func:`read_netcdf`);
- :mod:`~hybridwsi.units`: the one unit table (:data:`UNIT_FACTORS`,
  :func:`unit_factor`) and :func:`to_si` (a whole history in SI, unknown units refused);
- :mod:`~hybridwsi.history.text`: text tables with units in their headers
  (:class:`TextTable`, :func:`read_csv`, :func:`to_csv`);
- :mod:`~hybridwsi.history.signal`: derivative estimation, resampling and the crossing
  analysis (:func:`estimate_derivatives`, :func:`resample`, :func:`finalize_import`,
  :func:`crossing_periods`) and the error measures of records against a reference
  (:func:`rms_heave_error`, :func:`nrms_per_dof`, :func:`nrms_percent`).

Reading any supported file format (the dispatcher ``read_history``) lives one layer up, in
:mod:`hybridwsi.importers`, which builds on this package; this package never imports it.
The layout is described in docs/DATA_MODEL.md.
"""

from __future__ import annotations

from hybridwsi.files import (
    NETCDF_MAGIC,
    atomic_write,
    read_netcdf,
    to_netcdf,
    write_json,
    write_text,
)
from hybridwsi.history.model import (
    DEFAULT_DOF,
    KINEMATICS,
    UNIFORM_RTOL,
    check_compatible,
    check_mass,
    check_regressors,
    force_names,
    is_uniform,
    make_history,
    mass_matrix,
    select_dofs,
    set_mass,
    time_step,
    units_attrs,
    units_per_dof,
    validate,
)
from hybridwsi.history.signal import (
    crossing_period,
    crossing_periods,
    crossings,
    estimate_derivatives,
    finalize_import,
    fit_damped_oscillator,
    mean_crossing_period,
    nrms_per_dof,
    nrms_percent,
    resample,
    rms_heave_error,
    savgol_window,
)
from hybridwsi.history.text import (
    TextTable,
    detect_separator,
    read_csv,
    read_text_file,
    split_header,
    to_csv,
)
from hybridwsi.units import (
    SI_UNITS,
    UNIT_FACTORS,
    check_si,
    normalise_unit,
    quantity_of,
    to_si,
    unit_factor,
)


__all__ = [
    "DEFAULT_DOF",
    "KINEMATICS",
    "NETCDF_MAGIC",
    "UNIFORM_RTOL",
    "SI_UNITS",
    "UNIT_FACTORS",
    "TextTable",
    "atomic_write",
    "check_compatible",
    "check_mass",
    "check_regressors",
    "check_si",
    "crossing_period",
    "crossing_periods",
    "crossings",
    "detect_separator",
    "estimate_derivatives",
    "fit_damped_oscillator",
    "finalize_import",
    "force_names",
    "is_uniform",
    "make_history",
    "mass_matrix",
    "select_dofs",
    "mean_crossing_period",
    "nrms_per_dof",
    "nrms_percent",
    "normalise_unit",
    "quantity_of",
    "read_csv",
    "read_netcdf",
    "read_text_file",
    "resample",
    "rms_heave_error",
    "savgol_window",
    "set_mass",
    "split_header",
    "time_step",
    "to_csv",
    "to_netcdf",
    "to_si",
    "units_attrs",
    "units_per_dof",
    "unit_factor",
    "validate",
    "write_json",
    "write_text",
]
