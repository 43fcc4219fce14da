"""Short-crested JONSWAP seas and the excitation at any heading (issue 30), against closed
forms: the cos-2s spreading function's integral and mean cosine, the directional spectrum's
m0 = Hs²/16, a body of revolution's excitation turned with the wave, the platform's mirror
symmetry, and the force variance of a spread sea against the double integral
∫∫ |F(ω, θ)|² S(ω) D(θ − β) dθ dω."""

from __future__ import annotations

import math
from importlib import resources

import numpy as np
import pytest
import scipy.integrate

from hybridwsi import waves
from hybridwsi.errors import InputError
from hybridwsi.hydro.formats import read_coefficients

SIX = ["Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw"]


def _data(name: str):
    return read_coefficients(str(resources.files("hybridwsi") / "data" / name))


@pytest.mark.parametrize("s", [1.0, 5.0, 15.5])
def test_spreading_function_integral_and_mean_cosine(s):
    one = scipy.integrate.quad(lambda t: waves.spreading_function(t, s), -np.pi, np.pi)[0]
    mean_cos = scipy.integrate.quad(lambda t: waves.spreading_function(t, s) * math.cos(t),
                                    -np.pi, np.pi)[0]
    assert one == pytest.approx(1.0, abs=1e-10)
    assert mean_cos == pytest.approx(s / (s + 1.0), abs=1e-10)  # Γ-function closed form


@pytest.mark.parametrize("s", [2.0, 10.0])
def test_spreading_quantile_inverts_the_cumulative(s):
    p = np.array([0.01, 0.2, 0.5, 0.77, 0.99])
    theta = waves.spreading_quantile(p, s)
    cum = [scipy.integrate.quad(lambda t: waves.spreading_function(t, s), -np.pi, th)[0]
           for th in theta]
    assert np.allclose(cum, p, atol=1e-9)


def test_directional_spectrum_holds_m0_and_components_the_spreading():
    sea = waves.JONSWAP(hs=4.0, tp=11.0, seed=3, n_components=400,
                        direction=math.radians(30), spreading=6.0)
    lo, hi = sea.omega_range
    m0 = scipy.integrate.dblquad(lambda th, w: float(sea.directional_spectrum(w, th)),
                                 lo, hi, -np.pi + sea.direction, np.pi + sea.direction,
                                 epsabs=1e-6)[0]
    full = scipy.integrate.quad(sea.spectrum, 1e-3, 20.0, limit=200)[0]
    assert full == pytest.approx(4.0**2 / 16, rel=1e-3)  # Hs²/16
    assert m0 == pytest.approx(full, rel=0.01)  # omega_range holds > 99 %
    comp = sea.components()
    rel = comp.direction - sea.direction
    assert np.mean(np.cos(rel)) == pytest.approx(6.0 / 7.0, abs=2e-3)  # s/(s+1)
    assert abs(np.mean(np.sin(rel))) < 1e-3  # symmetric about the mean direction
    # the same phases and amplitudes as the long-crested sea: the same elevation at the origin
    long = waves.JONSWAP(hs=4.0, tp=11.0, seed=3, n_components=400, direction=math.radians(30))
    t = np.linspace(0, 600, 301)
    assert np.allclose(sea.elevation(t), long.elevation(t), atol=1e-12)
    assert sea.to_dict()["spreading"] == 6.0 and "spreading" not in long.to_dict()
    with pytest.raises(InputError):
        waves.JONSWAP(hs=4.0, tp=11.0, spreading=-1.0)


def test_body_of_revolution_excitation_turns_with_the_wave():
    coeffs = _data("bem_oc3_hywind.nc")  # stored at heading 0 only
    w, f0 = waves.excitation_transfer(coeffs, SIX, [0.0])
    beta = math.radians(37.0)
    _, fb = waves.excitation_transfer(coeffs, SIX, [beta])
    c, s = math.cos(beta), math.sin(beta)
    surge, heave, pitch = f0[:, 0, 0], f0[:, 0, 2], f0[:, 0, 4]
    want = np.stack([c * surge, s * surge, heave, -s * pitch, c * pitch,
                     np.zeros_like(surge)], axis=1)
    assert np.allclose(fb[:, 0], want, rtol=0, atol=1e-9 * np.abs(f0).max())


def test_semi_excitation_mirror_rotation_and_stored_headings():
    coeffs = _data("bem_oc4_semi.nc")  # 0, 30, 60 degrees; dihedral symmetry of order 3
    assert waves.heading_symmetry(coeffs) == 3
    deg = [30.0, -30.0, 150.0, 60.0, 180.0, 15.0, -15.0]
    _, f = waves.excitation_transfer(coeffs, SIX, np.radians(deg))
    stored = coeffs["excitation_force"].transpose("omega", "wave_direction",
                                                  "influenced_dof").values
    assert np.array_equal(f[:, 0], stored[:, 1]) and np.array_equal(f[:, 3], stored[:, 2])
    flip = np.array([1, -1, 1, -1, 1, -1])  # the mirror y -> -y: sway, roll, yaw change sign
    tol = 1e-9 * np.abs(stored).max()
    assert np.allclose(f[:, 1], f[:, 0] * flip, atol=tol)
    assert np.allclose(f[:, 6], f[:, 5] * flip, atol=tol)
    # 180° is 60° turned by 120°: the force vector and the moment turn with it
    q = np.array([[-0.5, -math.sqrt(3) / 2], [math.sqrt(3) / 2, -0.5]])
    want = f[:, 3].copy()
    want[:, :2], want[:, 3:5] = f[:, 3, :2] @ q.T, f[:, 3, 3:5] @ q.T
    assert np.allclose(f[:, 4], want, atol=tol)
    # 150° is 30° turned by 120° (a stored heading, reached through the interpolation path's
    # rotation of the 30° value)
    want = f[:, 0].copy()
    want[:, :2], want[:, 3:5] = f[:, 0, :2] @ q.T, f[:, 0, 3:5] @ q.T
    assert np.allclose(f[:, 2], want, atol=tol)


def test_heading_without_symmetry_or_neighbours_is_refused():
    coeffs = _data("bem_oc4_semi.nc")
    one = coeffs.isel(wave_direction=[1])
    one.attrs["body"] = "{}"  # no known symmetry, one stored heading (30°)
    with pytest.raises(InputError, match="wave direction"):
        waves.excitation_transfer(one, SIX, [0.0])
    sphere = _data("bem_paper_sphere.nc")  # heave only, axisymmetric: any heading
    _, f = waves.excitation_transfer(sphere, ["Heave"], [0.0, 1.0])
    assert np.array_equal(f[:, 0], f[:, 1])


def _interp_omega(grid: np.ndarray, f: np.ndarray, w: np.ndarray) -> np.ndarray:
    """|F(w, heading, dof)|² from the transfer function on ``grid`` (linear in ω)."""
    out = np.empty((w.size,) + f.shape[1:])
    for j in range(f.shape[1]):
        for i in range(f.shape[2]):
            out[:, j, i] = np.abs(np.interp(w, grid, f[:, j, i].real)
                                  + 1j * np.interp(w, grid, f[:, j, i].imag)) ** 2
    return out


def test_spread_sea_force_variance_is_the_directional_integral():
    """The realisation's force variance over its period is Σ a_j²/2 |F(ω_j, θ_j)|² (exact);
    its expectation over the seeded pairing of directions with frequencies (every component
    equally likely to take each quantile direction) is the double integral
    ∫∫ |F|² S(ω) D(θ − β) dθ dω; one realisation scatters about it by the few components
    near the peak (here −9 to +16 % with 600 components)."""
    coeffs = _data("bem_oc4_semi.nc")
    dofs = ["Surge", "Sway", "Yaw"]
    sea = waves.JONSWAP(hs=4.0, tp=12.0, seed=7, n_components=600,
                        direction=math.radians(20.0), spreading=4.0)
    comp = sea.components()
    lo, hi = sea.omega_range
    t = np.linspace(0.0, 2 * math.pi / ((hi - lo) / sea.n_components), 8192, endpoint=False)
    var = waves.excitation_force(sea, coeffs, t, dofs).var(axis=0)
    grid, f_q = waves.excitation_transfer(coeffs, dofs, comp.direction)
    f2 = _interp_omega(grid, f_q, comp.omega)  # (component ω, quantile direction, dof)
    realised = np.sum(0.5 * comp.amplitude[:, None] ** 2
                      * f2[np.arange(comp.omega.size), np.arange(comp.omega.size)], axis=0)
    # over 2π/Δω the difference-frequency products average out exactly, the sum-frequency
    # ones (ω_i + ω_j, not multiples of Δω) to ~1/(T ω): a few 1e-4
    assert np.allclose(var, realised, rtol=5e-3)
    expected = np.sum(0.5 * comp.amplitude[:, None] ** 2 * f2.mean(axis=1), axis=0)
    # the closed form by quadrature over a (ω, θ) grid
    w = np.linspace(lo, hi, 400)
    th = sea.direction + np.linspace(-np.pi, np.pi, 361)[:-1]
    grid, f = waves.excitation_transfer(coeffs, dofs, th)
    dens = sea.directional_spectrum(w[:, None], th[None, :])[:, :, None]
    want = np.trapezoid(np.sum(_interp_omega(grid, f, w) * dens, axis=1)
                        * (2 * np.pi / th.size), w, axis=0)
    assert np.allclose(expected, want, rtol=0.01)
    long = waves.JONSWAP(hs=4.0, tp=12.0, seed=7, n_components=600,
                         direction=math.radians(20.0))
    var_long = waves.excitation_force(long, coeffs, t, dofs).var(axis=0)
    assert var[0] < var_long[0]  # spreading takes surge force out of the mean direction


def test_simulate_spreading_option(tmp_path, capsys):
    from hybridwsi import cli

    data = str(resources.files("hybridwsi") / "data" / "bem_oc4_semi.nc")
    base = ["simulate", "--coeffs", data, "--dofs", "Surge,Sway", "--mass", "1.4e7", "--quiet",
            "--duration", "20", "--dt", "0.2", "--radiation", "none"]
    assert cli.main(base + ["--regular", "12", "2", "--spreading", "5", "--out",
                            str(tmp_path / "a.nc")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and "--jonswap" in err and len(err.splitlines()) == 1
    assert cli.main(base + ["--jonswap", "3", "12", "--spreading", "5", "--wave-direction",
                            "15", "--out", str(tmp_path / "b.nc")]) == 0
    import xarray as xr
    with xr.open_dataset(tmp_path / "b.nc") as hist:
        assert np.all(np.isfinite(hist["z"].values)) and np.abs(hist["z"].values[:, 1]).max() > 0
        assert '"spreading": 5.0' in str(hist.attrs)


class _OneComponent(waves.Wave):
    """One component of a sea as a long-crested wave in its own direction."""

    def __init__(self, comp: waves.WaveComponents, j: int, direction: float) -> None:
        self._comp = waves.WaveComponents(comp.amplitude[j:j + 1], comp.omega[j:j + 1],
                                          comp.phase[j:j + 1])
        self.direction = direction

    def components(self) -> waves.WaveComponents:
        return self._comp


def test_member_kinematics_of_a_spread_sea_are_the_sum_of_its_components():
    """``AiryPoints`` (one complex matrix-vector product per call) against the line kinematics
    ``particle_velocity`` (``AiryKinematics``, a separate implementation) summed over the
    components, each long-crested in its own direction, at points off the origin in 200 m of
    water; the acceleration against a central difference of the velocity."""
    sea = waves.JONSWAP(hs=3.0, tp=10.0, seed=2, n_components=40,
                        direction=math.radians(30.0), spreading=3.0)
    comp = sea.components()
    pts = np.array([[20.0, -10.0, -5.0], [20.0, -10.0, -17.0], [-28.9, 0.0, -14.0]])
    kin = waves.AiryPoints(sea, pts, depth=200.0)
    t = 37.3
    vel, acc = kin.velocity_acceleration(t)
    want = np.zeros_like(vel)
    for j, beta in enumerate(comp.direction):
        one = _OneComponent(comp, j, float(beta))
        for i, (x, y, z) in enumerate(pts):
            u, w = waves.particle_velocity(one, t, x, z, y=y, depth=200.0)
            want[i] += [u * math.cos(beta), u * math.sin(beta), w]
    assert np.allclose(vel, want, rtol=0, atol=1e-10 * np.abs(want).max())
    h = 1e-4
    fd = (kin.velocity_acceleration(t + h)[0] - kin.velocity_acceleration(t - h)[0]) / (2 * h)
    assert np.allclose(acc, fd, rtol=0, atol=1e-6 * np.abs(acc).max())
    # the kept last two times: asked again (after a third time pushed the first out), each
    # time gives its own values, read-only (a caller cannot change what the next one reads)
    for when in (t + h, t, t - h, t, t + h):
        again = kin.velocity_acceleration(when)
        fresh = waves.AiryPoints(sea, pts, depth=200.0).velocity_acceleration(when)
        for a, b in zip(again, fresh):
            np.testing.assert_array_equal(a, b)
            assert not a.flags.writeable
