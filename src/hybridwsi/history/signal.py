"""Signal processing of TimeHistories: derivatives, resampling and crossing periods.

- :func:`estimate_derivatives` fills ``zdot``/``zddot`` from ``z`` (Savitzky–Golay with a
  window chosen from the spectrum and the noise, or a smoothing spline);
- :func:`resample` puts an irregularly sampled history on a uniform grid and
  :func:`finalize_import` applies the one rule every reader follows for irregular sampling;
- :func:`crossings`, :func:`crossing_periods` and :func:`mean_crossing_period`: the one
  crossing analysis of the package (decay validation, SPH decay and wave records all use it).
  Crossings are taken about the equilibrium: TimeHistory ``z`` is measured from it, so the
  default level is 0; a record about a shifted mean passes its level (or ``None`` to use the
  record's mean, right for steady oscillations).
- :func:`fit_damped_oscillator`: damped period, damping ratio and equilibrium of a decay
  record (free-decay validation: Kramer drops, SPH decays).
- :func:`rms_heave_error` and :func:`crossing_period`: the decay table's error measure and
  period of a record normalised by its drop height (the Kramer validation and hybrid);
  :func:`nrms_percent`: a rollout's RMS error per DOF in % of the reference's RMS.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from hybridwsi.errors import InputError
from hybridwsi.history.model import check_regressors, is_uniform, time_step, units_attrs, validate
from hybridwsi.units import to_si

# --------------------------------------------------------------------------------------------
# Derivative estimation
# --------------------------------------------------------------------------------------------

#: cumulative share of the displacement power that defines the signal band (the rest is noise)
SIGNAL_POWER_SHARE = 0.999


def _signal_band(z: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Welch spectrum of ``z`` inside its signal band.

    Returns the angular frequencies [rad/s] and the power per bin [m^2] of the band holding
    ``SIGNAL_POWER_SHARE`` of the (linearly detrended) power, and the dominant period [s].
    """
    from scipy.signal import welch

    f, p = welch(z, fs=1.0 / dt, nperseg=min(z.size, 1024), detrend="linear")
    f, p = f[1:], p[1:] * (f[1] - f[0])  # drop the mean; PSD -> power per bin
    if p.sum() <= 0:
        raise InputError("z is constant: its derivatives cannot be estimated")
    k = int(np.searchsorted(np.cumsum(p), SIGNAL_POWER_SHARE * p.sum())) + 1
    return 2 * np.pi * f[:k], p[:k], float(1.0 / f[int(np.argmax(p))])


def _noise_std(z: np.ndarray) -> float:
    """Robust white-noise level [m]: MAD of the 4th difference (variance 70 sigma^2)."""
    d4 = np.diff(z, 4)
    return float(1.4826 * np.median(np.abs(d4 - np.median(d4))) / np.sqrt(70.0))


def savgol_window(z: np.ndarray, dt: float, polyorder: int = 3, deriv: int = 2) -> int:
    """Savitzky–Golay window length [samples] that balances truncation error and noise.

    For each odd window up to one dominant period, the predicted mean-square error of the
    ``deriv``-th derivative is the filter's exact frequency-response error summed over the
    signal band of ``z`` (Welch spectrum), plus the white-noise level (from the 4th difference
    of ``z``) times the squared norm of the filter coefficients. The window with the smallest
    predicted error is returned. Clean, finely sampled data thus get short windows; noisy data
    get longer ones, never more than a dominant period.
    """
    from scipy.signal import savgol_coeffs

    omega, power, period = _signal_band(z, dt)
    sigma2 = _noise_std(z) ** 2
    w_min = polyorder + 1 + (polyorder % 2)  # smallest odd window > polyorder
    w_max = min(z.size - (1 - z.size % 2), max(w_min, int(period / dt) | 1))
    best, best_err = w_min, np.inf
    for w in range(w_min, w_max + 1, 2):
        c = savgol_coeffs(w, polyorder, deriv=deriv, delta=dt, use="dot")
        lag = (np.arange(w) - w // 2) * dt
        if deriv == 1:
            resp = np.sin(np.outer(omega, lag)) @ c / omega
        else:
            resp = np.cos(np.outer(omega, lag)) @ c / -(omega**2)
        err = np.sum(power * omega ** (2 * deriv) * (resp - 1.0) ** 2) + sigma2 * np.sum(c**2)
        if err < best_err:
            best, best_err = w, err
    return best


def _savgol(z: np.ndarray, dt: float, deriv: int, window: int | None, polyorder: int):
    from scipy.signal import savgol_filter

    w = savgol_window(z, dt, polyorder, deriv) if window is None else int(window)
    if w % 2 == 0 or w <= polyorder or w > z.size:
        raise InputError(
            f"Savitzky-Golay window must be odd, > polyorder ({polyorder}) and <= the number "
            f"of samples ({z.size}); got {w}"
        )
    est = savgol_filter(z, w, polyorder, deriv=deriv, delta=dt, mode="interp")
    return est, f"savgol(window={w}, polyorder={polyorder}, deriv={deriv}, dt={dt:.6g})"


def estimate_derivatives(
    ds: xr.Dataset,
    method: str = "savgol",
    window: int | None = None,
    polyorder: int = 3,
    overwrite: bool = False,
    lam: float | None = None,
) -> xr.Dataset:
    """Fill missing ``zdot`` [m/s or rad/s] and ``zddot`` [m/s² or rad/s²] from ``z``.

    Parameters
    ----------
    ds : xarray.Dataset
        A uniformly sampled TimeHistory with ``z``.
    method : {"savgol", "spline"}
        ``"savgol"``: :func:`scipy.signal.savgol_filter` with ``deriv=1/2`` and ``delta=dt``
        (local least-squares polynomial of degree ``polyorder``; at the ends the polynomial of
        the first/last window is differentiated). When ``window`` is None it is chosen per
        derivative and per DOF by :func:`savgol_window` from ``dt``, the spectrum of ``z``
        (dominant period and signal band) and its noise level.
        ``"spline"``: :func:`scipy.interpolate.make_smoothing_spline` (cubic smoothing spline,
        smoothing ``lam`` chosen by generalised cross-validation when None), differentiated
        analytically. It is a natural spline, so ``zddot`` is biased towards 0 at both ends.
    window : int, optional
        Savitzky–Golay window length [samples], odd, > ``polyorder``.
    polyorder : int
        Savitzky–Golay polynomial degree. With a symmetric window an odd degree ``p`` gives
        the same interior second derivative as ``p - 1``.
    overwrite : bool
        Re-estimate variables that are already present.
    lam : float, optional
        Smoothing parameter of ``method="spline"``.

    Returns
    -------
    xarray.Dataset
        A copy with the estimated variables added; each carries ``attrs["estimated"]``
        describing the method (e.g. ``"savgol(window=9, polyorder=3, deriv=2, dt=0.01)"``).
    """
    if method not in ("savgol", "spline"):
        raise InputError(f"unknown derivative method '{method}' (choose savgol or spline)")
    validate(ds)
    targets = [(name, d) for name, d in (("zdot", 1), ("zddot", 2)) if overwrite or name not in ds]
    if not targets:
        return ds
    dt = time_step(ds)
    t = np.asarray(ds["time"].values, dtype=float)
    z = np.asarray(ds["z"].values, dtype=float)
    check_regressors({"z": z})  # the spectra below square z: refuse what would overflow
    out = ds.copy()
    for name, deriv in targets:
        cols, notes = [], []
        for j in range(z.shape[1]):
            if method == "savgol":
                est, note = _savgol(z[:, j], dt, deriv, window, polyorder)
            else:
                est, note = _spline(t, z[:, j], deriv, lam)
            cols.append(est)
            notes.append(note)
        desc = notes[0] if len(set(notes)) == 1 else "; ".join(
            f"{d}: {n}" for d, n in zip(ds["dof"].values, notes)
        )
        dof = [str(d) for d in ds["dof"].values]
        out[name] = (("time", "dof"), np.column_stack(cols),
                     {**units_attrs(name, dof), "estimated": desc})
    return out


def _spline(t: np.ndarray, z: np.ndarray, deriv: int, lam: float | None):
    from scipy.interpolate import make_smoothing_spline

    try:
        spl = make_smoothing_spline(t, z, lam=lam)
    except ValueError as exc:
        raise InputError(f"smoothing spline failed: {exc}") from None
    return spl.derivative(deriv)(t), f"smoothing_spline(lam={'GCV' if lam is None else lam}, deriv={deriv})"


# --------------------------------------------------------------------------------------------
# Resampling
# --------------------------------------------------------------------------------------------

_INTERPOLATORS = ("cubic", "linear", "pchip", "akima")


def resample(ds: xr.Dataset, dt: float | None = None, method: str = "cubic") -> xr.Dataset:
    """Interpolate an irregularly sampled history onto a uniform grid.

    Parameters
    ----------
    ds : xarray.Dataset
        History with strictly increasing (possibly irregular) ``time`` [s].
    dt : float, optional
        New time step [s]; default the median of the original steps.
    method : {"cubic", "linear", "pchip", "akima"}
        :class:`scipy.interpolate.CubicSpline` (not-a-knot), :func:`numpy.interp`,
        :class:`~scipy.interpolate.PchipInterpolator` or
        :class:`~scipy.interpolate.Akima1DInterpolator`.

    Returns
    -------
    xarray.Dataset
        Every variable along ``time`` interpolated on ``t0 + k dt`` (k = 0, 1, ... up to the
        last original time); ``attrs["resampled"]`` records the method and the original grid.
    """
    from scipy import interpolate

    if method not in _INTERPOLATORS:
        raise InputError(f"unknown resampling method '{method}' (choose {', '.join(_INTERPOLATORS)})")
    validate(ds, require_uniform=False, require_z=False)
    t = np.asarray(ds["time"].values, dtype=float)
    steps = np.diff(t)
    dt = float(np.median(steps)) if dt is None else float(dt)
    if not np.isfinite(dt) or dt <= 0:
        raise InputError(f"resampling step must be a positive number of seconds, got {dt}")
    n_new = int(np.floor((t[-1] - t[0]) / dt * (1 + 1e-12))) + 1
    t_new = t[0] + dt * np.arange(n_new)

    def interp(y: np.ndarray) -> np.ndarray:
        if method == "linear":
            return np.apply_along_axis(lambda c: np.interp(t_new, t, c), 0, y)
        cls = {"cubic": interpolate.CubicSpline, "pchip": interpolate.PchipInterpolator,
               "akima": interpolate.Akima1DInterpolator}[method]
        return cls(t, y, axis=0)(t_new)

    data_vars = {}
    for name, var in ds.data_vars.items():
        if "time" not in var.dims:
            data_vars[name] = var
            continue
        moved = var.transpose("time", ...)
        values = interp(np.asarray(moved.values, dtype=float))
        data_vars[name] = (moved.dims, values, dict(var.attrs))
    coords = {k: v for k, v in ds.coords.items() if "time" not in v.dims}
    coords["time"] = ("time", t_new, dict(ds["time"].attrs))
    out = xr.Dataset(data_vars, coords=coords, attrs=dict(ds.attrs))
    out.attrs["resampled"] = (
        f"{method}(dt={dt:.6g}) from {t.size} samples with dt {steps.min():.6g}..{steps.max():.6g} s"
    )
    return out


def finalize_import(
    ds: xr.Dataset,
    *,
    resample_to_uniform: bool = False,
    require_uniform: bool = True,
    require_z: bool = True,
) -> xr.Dataset:
    """Convert a freshly imported history to SI and validate it; resample it first when asked
    and irregular.

    Used by every ``read_*`` function so that units (:func:`hybridwsi.units.to_si`:
    NetCDF ``units`` attributes honoured, unknown ones refused) and irregular sampling are
    handled the same way: irregular sampling is rejected with a clear message unless
    ``resample_to_uniform`` (or ``require_uniform=False``).
    """
    ds = to_si(ds)
    validate(ds, require_uniform=False, require_z=require_z)
    if resample_to_uniform and not is_uniform(ds):
        ds = resample(ds)
    return validate(ds, require_uniform=require_uniform, require_z=require_z)


# --------------------------------------------------------------------------------------------
# Crossings of the equilibrium
# --------------------------------------------------------------------------------------------

_DIRECTIONS = ("any", "up", "down")


def crossings(
    t: np.ndarray, z: np.ndarray, z_eq: float | None = 0.0, direction: str = "any"
) -> tuple[np.ndarray, np.ndarray]:
    """Where a record crosses its equilibrium level, linearly interpolated.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Increasing sample times [s] (or any time unit, e.g. t/Te0).
    z : ndarray, shape (n,)
        The record (m, rad, ...).
    z_eq : float or None
        Equilibrium level, same unit as ``z``. 0 (the default) for a TimeHistory ``z``, which is
        measured from its equilibrium; None: the record's mean (for steady oscillations; a
        decaying record's mean is biased towards its release side, so give its level).
    direction : {"any", "up", "down"}
        Which crossings: every sign change, only upward ones, or only downward ones. A sample
        exactly at the level counts as above it, so a record touching the level once crosses
        once.

    Returns
    -------
    index : ndarray of int
        Sample ``i`` after which each crossing happens (between ``i`` and ``i + 1``).
    times : ndarray
        Interpolated crossing times, same unit as ``t``.
    """
    if direction not in _DIRECTIONS:
        raise InputError(f"direction must be one of {', '.join(_DIRECTIONS)}, got {direction!r}")
    t = np.asarray(t, dtype=float)
    z = np.asarray(z, dtype=float)
    if t.shape != z.shape or t.ndim != 1:
        raise InputError("t and z must be 1-D arrays of the same length")
    level = float(np.mean(z)) if z_eq is None else float(z_eq)
    e = z - level
    above = ~np.signbit(e)  # the sign test the decay validation has always used (-0.0: below)
    if direction == "up":
        i = np.flatnonzero(~above[:-1] & above[1:])
    elif direction == "down":
        i = np.flatnonzero(above[:-1] & ~above[1:])
    else:
        i = np.flatnonzero(above[:-1] != above[1:])
    return i, t[i] - e[i] * (t[i + 1] - t[i]) / (e[i + 1] - e[i])


def crossing_periods(t: np.ndarray, z: np.ndarray, z_eq: float | None = 0.0) -> np.ndarray:
    """Successive full-period estimates: twice the spacing of consecutive crossings of ``z_eq``.

    Crossings must be taken about the record's own equilibrium (see :func:`crossings`): a
    strongly damped record oscillating about a shifted mean otherwise gives spurious long
    "periods". Same unit as ``t``.
    """
    return 2.0 * np.diff(crossings(t, z, z_eq)[1])


def mean_crossing_period(
    t: np.ndarray,
    z: np.ndarray,
    window: tuple[float, float] | None = None,
    z_eq: float | None = 0.0,
    skip: int = 1,
) -> float:
    """Mean period over ``window`` from the crossings of ``z_eq`` (same unit as ``t``).

    The first ``skip`` crossings are left out (the first half cycle of a decay depends on
    the release); the period is twice the mean spacing of the remaining ones. NaN when fewer
    than two crossings remain.
    """
    t, z = np.asarray(t, dtype=float), np.asarray(z, dtype=float)
    if window is not None:
        sel = (t >= window[0]) & (t <= window[1])
        t, z = t[sel], z[sel]
    tc = crossings(t, z, z_eq)[1][skip:]
    if tc.size < 2:
        return float("nan")
    return float(2.0 * np.mean(np.diff(tc)))


def fit_damped_oscillator(t: np.ndarray, z: np.ndarray, period_guess: float,
                          window: tuple[float, float] | None = None,
                          sigma_guess: float = 0.8) -> dict[str, float]:
    """Least-squares fit of z ~ A exp(-sigma s) cos(omega_d s + phi) + c, s = t - t_first,
    over ``window`` (same unit as ``t``, default the whole record).

    The equilibrium ``c`` is free (a decay need not settle where it started from), and the
    fit starts from six phases to avoid a local minimum. Returns ``period_d`` = 2 pi /
    omega_d (unit of ``t``), ``sigma`` (1/unit of ``t``), the damping ratio ``zeta`` =
    sigma / sqrt(sigma^2 + omega_d^2), ``z_eq`` = c and ``amplitude`` = A (unit of ``z``) and
    ``rms`` of the residual; all NaN with fewer than 20 finite samples in the window.
    """
    from scipy.optimize import least_squares

    t, z = np.asarray(t, dtype=float), np.asarray(z, dtype=float)
    sel = np.isfinite(z) & np.isfinite(t)
    if window is not None:
        sel &= (t >= window[0]) & (t <= window[1])
    tt, zz = t[sel], z[sel]
    keys = ("period_d", "sigma", "zeta", "z_eq", "amplitude", "rms")
    if tt.size < 20:
        return dict.fromkeys(keys, float("nan"))
    s = tt - tt[0]

    def res(p: np.ndarray) -> np.ndarray:
        a, sig, w, ph, c = p
        return a * np.exp(-sig * s) * np.cos(w * s + ph) + c - zz

    amp = float(np.abs(zz).max())
    fits = [least_squares(res, [amp, sigma_guess, 2 * np.pi / period_guess, ph, 0.0])
            for ph in np.linspace(-np.pi, np.pi, 6, endpoint=False)]
    a, sig, w, _, c = min(fits, key=lambda f: f.cost).x
    w = abs(w)
    return {"period_d": float(2 * np.pi / w), "sigma": float(sig),
            "zeta": float(sig / np.hypot(sig, w)), "z_eq": float(c), "amplitude": float(a),
            "rms": float(np.sqrt(np.mean(res(np.array([a, sig, w, _, c])) ** 2)))}


# --------------------------------------------------------------------------------------------
# Error measures of model records against a reference
# --------------------------------------------------------------------------------------------

def rms_heave_error(
    t_model: np.ndarray,
    zn_model: np.ndarray,
    t_exp: np.ndarray,
    zn_exp: np.ndarray,
    te0: float,
    window: tuple[float, float] = (0.0, 5.0),
) -> float:
    """RMS of normalised heave error over ``t/Te0 ∈ window`` on the experiment's grid.

    Parameters
    ----------
    t_model, zn_model : ndarray
        Model time [s] (increasing) and heave / H0 [-].
    t_exp, zn_exp : ndarray
        Experiment time [s] and mean heave / H0 [-].
    te0 : float
        Normalisation period [s].
    window : (float, float)
        Window in units of ``te0``.

    Returns
    -------
    float
        RMS error [-].
    """
    t_model = np.asarray(t_model, float)
    lo, hi = window[0] * te0, window[1] * te0
    sel = (t_exp >= lo - 1e-12) & (t_exp <= hi + 1e-12)
    if t_model[0] > lo + 1e-9 or t_model[-1] < hi - 1e-9:
        raise InputError(
            f"model record [{t_model[0]:.3f}, {t_model[-1]:.3f}] s does not cover the RMS window "
            f"[{lo:.3f}, {hi:.3f}] s"
        )
    zi = np.interp(t_exp[sel], t_model, zn_model)
    return float(np.sqrt(np.mean((zi - zn_exp[sel]) ** 2)))


def crossing_period(t: np.ndarray, z: np.ndarray, window: tuple[float, float]) -> float:
    """Mean crossing period of a decay record over ``window`` (same unit as ``t``).

    Every record here (experiment, published codes, our models) is heave measured from its
    equilibrium, so the crossings are those of z = 0; the first half cycle, which depends on
    the release, is skipped (:func:`hybridwsi.history.mean_crossing_period`).
    """
    return mean_crossing_period(t, z, window, z_eq=0.0, skip=1)


def nrms_per_dof(hist: xr.Dataset, ref: xr.Dataset, start: float | None = None) -> np.ndarray:
    """RMS(z − z_ref) / RMS(z_ref) per DOF over the hybrid's times (from ``start`` [s]), inf
    when the hybrid is not finite."""
    t = np.asarray(hist["time"].values, float)
    keep = t >= (start if start is not None else -np.inf)
    z = np.asarray(hist["z"].values, float)[keep]
    z_ref = np.asarray(ref["z"].sel(time=t[keep], method="nearest").values, float)
    if not np.all(np.isfinite(z)):
        return np.full(z.shape[1], np.inf)
    return np.sqrt(np.mean((z - z_ref) ** 2, 0)) / np.maximum(
        np.sqrt(np.mean(z_ref ** 2, 0)), 1e-300)


def nrms_percent(hist: xr.Dataset, ref: xr.Dataset) -> list[float]:
    """:func:`nrms_per_dof` over all the hybrid's times, in % (inf when not finite)."""
    return (100.0 * nrms_per_dof(hist, ref)).tolist()
