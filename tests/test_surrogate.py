"""Force network, features and autograd linearisation against known linear forces."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from hybridwsi.errors import InputError
from hybridwsi.history import make_history
from hybridwsi.surrogate.features import FeatureSpec, build_features, spec_for
from hybridwsi.surrogate.linearise import linearise, linearise_at
from hybridwsi.surrogate.network import ForceNetwork

torch.set_num_threads(1)
DT = 0.01


def _signals(n: int, seed: int) -> np.ndarray:
    """Independent smooth random signals (sum of sines) so z, zdot, zddot are not collinear."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT
    w = rng.uniform(1.0, 15.0, (3, 6))
    p = rng.uniform(0, 2 * np.pi, (3, 6))
    return np.sin(w[:, :, None] * t + p[:, :, None]).sum(1), t


def _linear_history(alpha: float, beta: float, gamma: float, n: int = 600, seed: int = 0):
    s, t = _signals(n, seed)
    z, v, a = 0.01 * s[0], 0.1 * s[1], s[2]
    f = alpha * a + beta * v + gamma * z + 0.3  # + a mean force (intercept)
    return make_history(t, z, v, a, forces={"F_lin": f}, mass=7.06)


def test_window_features_layout_is_lag_major():
    t = np.arange(12) * DT
    h = make_history(t, np.arange(12.0), 10 + np.arange(12.0), 100 + np.arange(12.0))
    spec = FeatureSpec(("z", "zddot"), window=3, stride=2)
    x = build_features(h, spec)
    assert x.shape == (12 - 4, 6)
    # row 0 is time index 4: lag 0 -> index 4, lag 1 -> index 2, lag 2 -> index 0
    np.testing.assert_array_equal(x[0], [4, 104, 2, 102, 0, 100])
    assert spec.column("zddot", lag=1) == 3
    assert spec.current_columns("z") == [0]
    assert spec.current_columns("zdot") is None


def test_eta_lead_reads_the_future_elevation():
    t = np.arange(10) * DT
    h = make_history(t, np.zeros(10), np.zeros(10), np.zeros(10))
    h["eta"] = (("time", "probe"), np.arange(10.0)[:, None])
    spec = spec_for(h, ("zdot", "eta"), window=2, lead=3)
    x = build_features(h, spec)
    assert x.shape == (10 - 1 - 3, 4)
    np.testing.assert_array_equal(x[0], [0, 4, 0, 3])  # at t index 1: eta(4), eta(3)


def test_exactly_linear_network_gives_exact_sensitivities():
    """hidden=() is a single Linear layer: set its weights to F = 3 zdd - 2 zd + 50 z."""
    h = _linear_history(3.0, -2.0, 50.0)
    net = ForceNetwork(hidden=(), max_epochs=1, inputs=("z", "zdot", "zddot")).fit(h, "F_lin")
    with torch.no_grad():  # physical weights / standardisation -> layer weights
        w_phys = torch.tensor([50.0, -2.0, 3.0], dtype=torch.float64)
        layer = net.model_[0]
        layer.weight[:] = (w_phys * net._xs / net._ys)[None, :]
        layer.bias[:] = ((w_phys * net._xm).sum() - net._ym) / net._ys
    lin = linearise(net, h)
    assert lin.alpha[0, 0] == pytest.approx(3.0, abs=1e-12)
    assert lin.beta[0, 0] == pytest.approx(-2.0, abs=1e-12)
    assert lin.gamma[0, 0] == pytest.approx(50.0, abs=1e-10)
    np.testing.assert_allclose(net.predict(h)[:, 0], h["F_lin"].values[:, 0] - 0.3, atol=1e-9)


def test_trained_network_recovers_linear_force_coefficients():
    """A tanh net fitted to F = 3 zdd - 2 zd + 50 z: autograd Jacobians close to the truth."""
    h = _linear_history(3.0, -2.0, 50.0, n=800)
    net = ForceNetwork(hidden=(16,), max_epochs=400, lr=1e-2, patience=60, seed=1).fit(h, "F_lin")
    lin = linearise(net, h)
    scale = 3.0 * 1.0 + 2.0 * 0.1 + 50.0 * 0.01  # typical magnitude of each term
    assert lin.alpha[0, 0] == pytest.approx(3.0, abs=0.05 * scale / 1.0)
    assert lin.beta[0, 0] == pytest.approx(-2.0, abs=0.05 * scale / 0.1)
    assert lin.gamma[0, 0] == pytest.approx(50.0, abs=0.05 * scale / 0.01)
    held_out = _linear_history(3.0, -2.0, 50.0, n=400, seed=7)
    assert net.score(held_out, "F_lin") > 0.99


def test_linearisation_of_a_nonlinear_force_is_local():
    """F = 20 z^2 is not linear: dF/dz must be 40 z at the linearisation state."""
    s, t = _signals(800, 3)
    z = 0.05 * s[0]
    h = make_history(t, z, 0.1 * s[1], s[2], forces={"F": 20.0 * z**2})
    net = ForceNetwork(hidden=(32,), inputs=("z",), max_epochs=400, lr=1e-2, patience=60).fit(h, "F")
    for z0 in (-0.1, 0.0, 0.1):
        g = linearise_at(net, z0, 0.0, 0.0).gamma[0, 0]
        assert g == pytest.approx(40.0 * z0, abs=0.6)


def test_training_is_deterministic_and_save_load_roundtrip(tmp_path):
    h = _linear_history(1.0, 0.5, 10.0, n=300)
    kw = {"hidden": (8,), "max_epochs": 20, "seed": 3, "window": 2}
    a = ForceNetwork(**kw).fit(h, "F_lin")
    b = ForceNetwork(**kw).fit(h, "F_lin")
    np.testing.assert_array_equal(a.predict(h)[1:], b.predict(h)[1:])
    assert np.isnan(a.predict(h)[0]).all()  # window 2: first row has no past
    pt, js = a.save(tmp_path / "net")
    meta = json.loads(js.read_text())
    assert meta["spec"]["window"] == 2 and meta["params"]["hidden"] == [8]
    assert "hybridwsi_version" in meta and len(meta["x_mean"]) == 6
    c = ForceNetwork.load(tmp_path / "net")
    np.testing.assert_allclose(c.predict(h), a.predict(h), rtol=0, atol=1e-12)
    # the weights file holds only tensors (weights_only loading must accept it)
    sd = torch.load(pt, weights_only=True)
    assert all(isinstance(v, torch.Tensor) for v in sd.values())


def test_early_stopping_keeps_best_validation_weights():
    h = _linear_history(1.0, 0.5, 10.0, n=300)
    net = ForceNetwork(hidden=(8,), max_epochs=500, patience=3, lr=0.05, seed=0).fit(h, "F_lin")
    assert net.n_epochs_ < 500
    assert net.best_val_loss_ == pytest.approx(min(net.history_["val_loss"]))


@pytest.mark.parametrize(
    "kwargs, msg",
    [({"activation": "sigmoidish"}, "activation"), ({"val_fraction": 0.95}, "val_fraction"),
     ({"inputs": ("z", "speed")}, "subset")],
)
def test_bad_parameters_raise_input_error(kwargs, msg):
    h = _linear_history(1.0, 0.5, 10.0, n=100)
    with pytest.raises(InputError, match=msg):
        ForceNetwork(max_epochs=1, **kwargs).fit(h, "F_lin")


def test_bad_data_raise_input_error(tmp_path):
    h = _linear_history(1.0, 0.5, 10.0, n=100)
    with pytest.raises(InputError, match="no target force"):
        ForceNetwork(max_epochs=1).fit(h, "F_missing")
    with pytest.raises(InputError, match="shape"):
        ForceNetwork(max_epochs=1).fit(h, np.zeros(7))
    with pytest.raises(InputError, match="not fitted"):
        ForceNetwork().predict(h)
    with pytest.raises(InputError, match="eta"):
        ForceNetwork(max_epochs=1, inputs=("eta",)).fit(h, "F_lin")
    with pytest.raises(InputError, match="not found"):
        ForceNetwork.load(tmp_path / "nothing")
    bad = tmp_path / "bad"
    (tmp_path / "bad.json").write_text("{}")
    (tmp_path / "bad.pt").write_bytes(b"junk")
    with pytest.raises(InputError, match="metadata"):
        ForceNetwork.load(bad)


@pytest.mark.parametrize("activation, hidden", [("tanh", (32,)), ("relu", (16, 8)),
                                                ("silu", (12,)), ("gelu", (8, 8))])
def test_numpy_forward_equals_torch_forward(activation, hidden):
    """The folded NumPy network (normalisation inside the end layers) is the torch network."""
    from hybridwsi.surrogate.fast import folded_layers, numpy_forward

    h = _linear_history(3.0, -2.0, 50.0, n=300)
    net = ForceNetwork(hidden=hidden, activation=activation, window=3, max_epochs=5,
                       seed=2).fit(h, "F_lin")
    x = build_features(h, net.spec_)
    ref = net.predict_features(x)
    got = numpy_forward(folded_layers(net), x)
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def _with_time_step(h, dt: float):
    return h.assign_coords(time=np.arange(h.sizes["time"]) * dt)


def test_training_set_of_mixed_step_or_mass_or_nan_force_is_refused():
    a = _linear_history(1.0, 0.5, 10.0, n=100)
    with pytest.raises(InputError, match="time step"):
        ForceNetwork(max_epochs=1).fit([a, _with_time_step(a, 2 * DT)], "F_lin")
    # a step equal to 1e-12 relative is the same step
    ForceNetwork(max_epochs=1).fit([a, _with_time_step(a, DT * (1 + 1e-12))], "F_lin")
    heavy = a.copy()
    heavy["mass"] = heavy["mass"] * 2.0
    with pytest.raises(InputError, match="mass"):
        ForceNetwork(max_epochs=1).fit([a, heavy], "F_lin")
    nan = a.copy(deep=True)
    nan["F_lin"][40, 0] = np.nan  # e.g. a file read without validation
    with pytest.raises(InputError, match="history 1 .*NaN.*row 40"):
        ForceNetwork(max_epochs=1).fit([a, nan], "F_lin")


def test_output_head_learns_other_columns_than_the_dofs(tmp_path):
    """``n_out``: a head of two outputs on one DOF's features (the OC3 tension head's use):
    a linear map of the inputs is learned (R² > 0.99 on a held-out history), survives
    save/load, and a target of another width is still refused."""
    def outputs(h):
        z, v = h["z"].values[:, 0], h["zdot"].values[:, 0]
        return np.stack([2.0 * z + 0.5 * v, -z + 3.0 * v], axis=1)

    train, held = _linear_history(0, 0, 0, n=800), _linear_history(0, 0, 0, n=400, seed=7)
    net = ForceNetwork(hidden=(16,), inputs=("z", "zdot"), max_epochs=300, lr=1e-2,
                       patience=60, seed=1).fit(train, [outputs(train)], n_out=2)
    want, got = outputs(held), net.predict(held)
    assert got.shape == want.shape
    assert 1.0 - np.sum((got - want) ** 2) / np.sum((want - want.mean(0)) ** 2) > 0.99
    net.save(tmp_path / "head")
    np.testing.assert_allclose(ForceNetwork.load(tmp_path / "head").predict(held), got,
                               rtol=0, atol=1e-12)
    with pytest.raises(InputError, match="n_out"):
        ForceNetwork(max_epochs=1).fit(train, [outputs(train)], n_out=3)
