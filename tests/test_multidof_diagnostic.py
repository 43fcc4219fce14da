"""The diagnostic on a 2-DOF (Surge + Pitch) body against closed-form α, β, γ matrices.

Reference system (force-equation orientation ``X[i influenced, j moving]``)::

    M z̈ = F_tot = F_exc − A z̈ − B ż − C z

with a coupled rigid-body mass M (centre of mass below the reference point), constant added
mass A and damping B, and a non-symmetric stiffness C (so that a transposed matrix shows). The
motion is the exact steady state of a multi-sine excitation (complex amplitude
``X_k = [C − ω²(M + A) + iωB]⁻¹ F_k``), so z, ż, z̈ carry no numerical error and every
partition's black-box force is exactly linear in the kinematics:

=================================== ============ ========= =======
known                                α            β         γ
=================================== ============ ========= =======
none                                 M            0         0
hydrostatic + added_mass_inf         M + A        0         C
hydrostatic + excitation             −A           −B        0
all four (+ linear_damping)          0            0         0
=================================== ============ ========= =======

The coefficients describe six DOFs (Surge … Yaw) with couplings to the DOFs the history does
not have; the diagnostic must select the history's two, in the history's order.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from hybridwsi.cli import main
from hybridwsi.diagnostic import CoupledStep, assess, reconstruct, regress
from hybridwsi.diagnostic.partition import peak_omega, select_partition
from hybridwsi.dofs import RIGID_DOFS
from hybridwsi.errors import InputError
from hybridwsi.forces import AddedMass, Hydrostatic, LinearDamping
from hybridwsi.forces.external import PrescribedForce
from hybridwsi.forces.linear import history_matrix, known_from, mass_from, parse_known
from hybridwsi.history import make_history, to_netcdf

DOFS = ("Surge", "Pitch")
# rigid body: m = 10 kg, z_G = -0.2 m, I_yy = 3 kg m² about the reference point
M = np.array([[10.0, -2.0], [-2.0, 3.0]])
A = np.array([[4.0, 1.0], [1.0, 2.0]])
B = np.array([[6.0, 0.5], [0.5, 1.5]])
C = np.array([[60.0, 8.0], [2.0, 90.0]])
OMEGAS = (0.9, 1.7, 2.9, 4.0, 6.1)  # rad/s, around the natural 2.05 and 4.31 rad/s
#: per frequency: complex force amplitudes on (Surge [N], Pitch [N m])
FORCES = ((3.0, 1.0j), (1.0j, 2.0), (2.0 + 1.0j, -1.0), (-1.0, 1.5j), (1.5, 0.5 + 0.5j))
DT, DURATION = 0.02, 30.0
IDX = [RIGID_DOFS.index(d) for d in DOFS]


def _perm(mat: np.ndarray, order: list[int]) -> np.ndarray:
    return mat[np.ix_(order, order)]


def _steady_state():
    """Exact z, ż, z̈ and F_exc (n, 2) of the multi-sine steady state, DOF order DOFS."""
    t = np.arange(0.0, DURATION, DT)
    z, zd, zdd, f = (np.zeros((t.size, 2), complex) for _ in range(4))
    for w, fk in zip(OMEGAS, FORCES):
        fk = np.asarray(fk, complex)
        xk = np.linalg.solve(C - w**2 * (M + A) + 1j * w * B, fk)
        phase = np.exp(1j * w * t)[:, None]
        z, zd, zdd = z + xk * phase, zd + 1j * w * xk * phase, zdd - w**2 * xk * phase
        f = f + fk * phase
    return t, z.real, zd.real, zdd.real, f.real


def history(order: tuple[str, ...] = DOFS, *, mass: bool = True,
            matrices: bool = False) -> xr.Dataset:
    """The 2-DOF reference history with its DOFs in ``order`` (optionally with its mass and
    the (dof, dof_j) matrices a Cummins history carries)."""
    t, z, zd, zdd, f = _steady_state()
    pos = [DOFS.index(d) for d in order]
    extra = {}
    if matrices:
        for name, mat in (("added_mass_inf", A), ("hydrostatic_stiffness", C)):
            extra[name] = (("dof", "dof_j"), _perm(mat, pos), {})
    return make_history(t, z[:, pos], zd[:, pos], zdd[:, pos],
                        {"F_tot": (zdd @ M.T)[:, pos], "F_exc": f[:, pos]}, dof=list(order),
                        mass=_perm(M, pos) if mass or matrices else None, extra_vars=extra)


def _embed(block: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """A 6x6 force-orientation matrix with ``block`` at Surge/Pitch and ``rest`` elsewhere."""
    out = rest.copy()
    out[np.ix_(IDX, IDX)] = block
    return out


def six_dof_coefficients(influenced_reversed: bool = True) -> xr.Dataset:
    """Capytaine-layout coefficients of all six DOFs: the 2x2 system plus couplings to the
    other four DOFs (which the history does not move). Stored ``(radiating, influenced)``, i.e.
    transposed, with the influenced labels in reverse order to exercise the label lookup."""
    rng = np.random.default_rng(7)
    rest = {k: rng.uniform(0.5, 3.0, (6, 6)) for k in ("m", "a", "b", "c")}
    mats = {"mass": _embed(M, rest["m"]), "added_mass_inf": _embed(A, rest["a"]),
            "hydrostatic_stiffness": _embed(C, rest["c"])}
    b6 = _embed(B, rest["b"])
    omega = np.linspace(0.2, 12.0, 30)
    inf = list(RIGID_DOFS[::-1]) if influenced_reversed else list(RIGID_DOFS)
    order = [RIGID_DOFS.index(d) for d in inf]
    pair = ("radiating_dof", "influenced_dof")
    data = {name: (pair, mat.T[:, order]) for name, mat in mats.items()}
    data["radiation_damping"] = (("omega", *pair),
                                 np.broadcast_to(b6.T[:, order], (omega.size, 6, 6)).copy())
    data["added_mass"] = (("omega", *pair),
                          np.broadcast_to(mats["added_mass_inf"].T[:, order], (omega.size, 6, 6)).copy())
    return xr.Dataset(data, coords={"omega": omega, "radiating_dof": list(RIGID_DOFS),
                                    "influenced_dof": inf})


def _quadratic_roots(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Roots μ of det(P − μ Q) = 0 for 2x2 matrices (closed form)."""
    tr = p[0, 0] * q[1, 1] + p[1, 1] * q[0, 0] - p[0, 1] * q[1, 0] - p[1, 0] * q[0, 1]
    return np.roots([np.linalg.det(q), -tr, np.linalg.det(p)])


# ----------------------------------------------------------------------------- the route
@pytest.mark.parametrize("order", [DOFS, DOFS[::-1]])
def test_known_from_selects_the_history_dofs_in_its_order(order):
    hist = history(order, mass=False)
    co = six_dof_coefficients()
    pos = [DOFS.index(d) for d in order]
    c, a = known_from(hist, co, ["hydrostatic", "added_mass"])  # alias of added_mass_inf
    assert isinstance(c, Hydrostatic) and isinstance(a, AddedMass)
    np.testing.assert_array_equal(c.value, _perm(C, pos))
    np.testing.assert_array_equal(a.value, _perm(A, pos))
    np.testing.assert_array_equal(mass_from(hist, co), _perm(M, pos))
    b = LinearDamping.from_coefficients(co, list(order), omega=3.3)
    np.testing.assert_allclose(b.value, _perm(B, pos), rtol=1e-12)
    # the history's own matrices win over the coefficients (dof_j may be in any order)
    with_m = history(order, matrices=True)
    with_m = with_m.isel(dof_j=[1, 0])
    np.testing.assert_array_equal(Hydrostatic.from_history(with_m).value, _perm(C, pos))
    np.testing.assert_array_equal(history_matrix(with_m, "mass"), _perm(M, pos))
    (c_h,) = known_from(with_m, None, ["hydrostatic"])
    np.testing.assert_array_equal(c_h.value, _perm(C, pos))


def test_known_from_errors_are_one_line_input_errors():
    hist = history(mass=False)
    with pytest.raises(InputError, match="hydrostatic_stiffness"):
        known_from(hist, None, ["hydrostatic"])
    with pytest.raises(InputError, match="needs a value|cannot be read"):
        known_from(hist, six_dof_coefficients(), ["quadratic_damping"])
    co = six_dof_coefficients().sel(radiating_dof=["Heave"], influenced_dof=["Heave"])
    with pytest.raises(InputError, match="no DOF"):
        known_from(hist, co, ["hydrostatic"])
    assert parse_known("added_mass=3.5").describe() == "added_mass_inf=3.5"
    assert parse_known("damping=2").name == "linear_damping"


def test_peak_frequency_counts_every_dof():
    """Surge splits its power between ω1 (60 %) and ω2 (40 %); Pitch (rad, 100x smaller) is
    all at ω2: the normalised sum peaks at ω2 (DOF 0 alone would say ω1)."""
    t = np.arange(0.0, 100.0, 0.01)
    w1, w2 = 2 * np.pi * 16 / 100, 2 * np.pi * 80 / 100  # on FFT bins: no leakage
    surge = np.sqrt(0.6) * np.sin(w1 * t) + np.sqrt(0.4) * np.sin(w2 * t)
    pitch = 0.01 * np.sin(w2 * t + 0.3)
    hist = make_history(t, np.column_stack([surge, pitch]), dof=list(DOFS))
    assert peak_omega(hist) == pytest.approx(w2, rel=1e-12)
    assert peak_omega(hist.isel(dof=[0])) == pytest.approx(w1, rel=1e-12)


# ----------------------------------------------------------------------- regress / assess
CASES = {
    "none": ([], (M, 0 * M, 0 * M)),
    "hydrostatic+added_mass_inf": ([Hydrostatic(C), AddedMass(A)], (M + A, 0 * M, C)),
    "hydrostatic+excitation": ([Hydrostatic(C), PrescribedForce("F_exc")], (-A, -B, 0 * M)),
    "all": ([Hydrostatic(C), AddedMass(A), LinearDamping(B), PrescribedForce("F_exc")],
            (0 * M, 0 * M, 0 * M)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_regression_returns_the_closed_form_matrices(case):
    known, (alpha, beta, gamma) = CASES[case]
    res = regress(history(), known=known)
    scale = np.abs(M + A).max()
    np.testing.assert_allclose(res.alpha, alpha, atol=1e-7 * scale)
    np.testing.assert_allclose(res.beta, beta, atol=1e-7 * np.abs(B).max())
    np.testing.assert_allclose(res.gamma, gamma, atol=1e-7 * np.abs(C).max())
    assert res.dof == list(DOFS)
    if case != "all":  # (with nothing left, F_bb is round-off: nothing to identify)
        assert res.identifiable  # five frequencies separate the terms
    json.dumps(res.to_dict())


def _assess(hist, known):
    """The stability of the residual of ``known`` (semi-implicit Euler at DT)."""
    reg = regress(hist, known=known)
    return assess(CoupledStep.from_components(M, known, reg, dt=DT,
                                              scheme="semi_implicit_euler"))


def test_assess_matches_closed_form_eigenvalues():
    hist = history()
    # hydrostatic + A∞ known: α = M + A is the whole inertia
    known = CASES["hydrostatic+added_mass_inf"][0]
    rep = _assess(hist, known)
    # (a) (M + A) ë + C e = 0: λ = ±i ω_n with ω_n² the roots of det(C − ω²(M + A)) = 0
    wn2 = np.sort(_quadratic_roots(C, M + A).real)
    lam = rep.prescribed.eigenvalues
    assert rep.prescribed.verdict == "neutral"
    np.testing.assert_allclose(np.sort(np.abs(lam.imag))[::2], np.sqrt(wn2), rtol=1e-8)
    # (b) the surrogate cancels the inertia; (c) added-mass ratio 1: unstable at every Δt
    assert rep.continuous.verdict == "unstable"
    assert rep.loosely_coupled.conditions["added_mass_ratio"] == pytest.approx(1.0, rel=1e-8)
    assert rep.loosely_coupled.max_stable_dt == 0.0

    # hydrostatic + excitation known: α_s = −A, β_s = −B
    known = CASES["hydrostatic+excitation"][0]
    rep = _assess(hist, known)
    # (b) (M + A) λ² + B λ + C = 0: each eigenvalue makes the matrix singular, all decay
    lam = rep.continuous.eigenvalues
    assert rep.continuous.verdict == "stable" and lam.size == 4 and np.all(lam.real < 0)
    for li in lam:
        s = np.linalg.svd(li**2 * (M + A) + li * B + C, compute_uv=False)
        assert s[-1] < 1e-7 * s[0]
    # (c) added-mass ratio = spectral radius of M⁻¹A (> 1 here: lagged coupling fails)
    ratio = np.max(np.abs(_quadratic_roots(A, M)))
    assert rep.loosely_coupled.conditions["added_mass_ratio"] == pytest.approx(ratio, rel=1e-8)
    assert ratio > 1 and rep.loosely_coupled.verdict == "unstable"


def test_reconstruction_with_everything_known_reproduces_the_motion():
    hist = history()
    known = CASES["all"][0]
    rec = reconstruct(hist, known=known)
    assert max(rec.metrics["nrms_error"]) < 1e-5
    assert rec.stability.prescribed.verdict == "damped"  # (M + A) ë + B ė + C e = 0 with B > 0
    assert rec.inputs["known"][-1] == "prescribed(F_exc)"


# ------------------------------------------------------------------ selection on a subset
@pytest.mark.parametrize("order", [DOFS, DOFS[::-1]])
def test_selection_on_a_dof_subset_of_six_dof_coefficients(order):
    """Used to raise ValueError (a 6x6 matrix reshaped to 2x2); mass from the coefficients."""
    hist = history(order, mass=False)
    pos = [DOFS.index(d) for d in order]
    cands = ["hydrostatic", "added_mass_inf", "linear_damping", "excitation"]
    table = select_partition(hist, six_dof_coefficients(), cands, dt=DT,
                             reconstruct_each=False).set_index("partition")
    np.testing.assert_allclose(table.attrs["mass"], _perm(M, pos))
    row = table.loc["hydrostatic+added_mass_inf"]
    np.testing.assert_allclose(row["alpha"], _perm(M + A, pos), rtol=1e-7)
    np.testing.assert_allclose(row["gamma"], _perm(C, pos), rtol=1e-7)
    assert not row["feasible"]
    row = table.loc["hydrostatic+excitation"]
    np.testing.assert_allclose(row["alpha"], -_perm(A, pos), rtol=1e-7)
    np.testing.assert_allclose(row["beta"], -_perm(B, pos), rtol=1e-7)
    assert row["added_mass_ratio"] == pytest.approx(np.max(np.abs(_quadratic_roots(A, M))),
                                                    rel=1e-8)
    row = table.loc["hydrostatic+added_mass_inf+linear_damping+excitation"]
    assert np.abs(row["alpha"]).max() < 1e-7 and np.abs(row["gamma"]).max() < 1e-6
    assert row["feasible"] and row["rank"] == 1


def test_selection_from_history_matrices_without_coefficients():
    table = select_partition(history(matrices=True), None, dt=DT).set_index("partition")
    assert set(table.index) == {"(none)", "hydrostatic", "added_mass_inf", "excitation",
                                "hydrostatic+added_mass_inf", "hydrostatic+excitation",
                                "added_mass_inf+excitation",
                                "hydrostatic+added_mass_inf+excitation"}
    row = table.loc["hydrostatic+added_mass_inf+excitation"]
    # B is left to the residual: α ≈ 0, β = −B, γ ≈ 0, reconstructed closely
    np.testing.assert_allclose(row["beta"], -B, rtol=1e-7)
    assert row["feasible"] and row["recon_nrms"] < 1e-4


def test_diagnose_cli_takes_known_matrices_from_coeffs(tmp_path):
    f, c, out = tmp_path / "h.nc", tmp_path / "c.nc", tmp_path / "r.json"
    to_netcdf(history(DOFS[::-1], mass=False), f)
    to_netcdf(six_dof_coefficients(), c)
    assert main(["diagnose", str(f), "--coeffs", str(c), "--known", "hydrostatic",
                 "--known", "added_mass", "--target-dt", str(DT), "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    np.testing.assert_allclose(res["alpha"], _perm(M + A, [1, 0]), rtol=1e-7)
    np.testing.assert_allclose(res["gamma"], _perm(C, [1, 0]), rtol=1e-7)
    verdicts = {r["setting"]: r["verdict"] for r in res["stability"]}  # mass from --coeffs
    assert verdicts["prescribed_force"] == "neutral" and verdicts["surrogate"] == "unstable"
