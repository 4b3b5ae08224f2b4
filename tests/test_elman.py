"""Elman network (seed 001 §3.4.3, eq. 34): windowed loss, BPTT gradient, training on a task
that needs memory, and the Learner contract.

Data in these tests span exactly [-1, 1] where a hand computation is compared, so the min-max
normalisation is the identity and normalised units equal data units.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tcbench.learners import elman as elman_mod
from tcbench.learners.elman import ElmanNetwork, ElmanParams


def _net(n_inputs=1, seed=0, **params):
    return ElmanNetwork(n_inputs, params, np.random.default_rng(seed))


def _lowpass(n, tau=5.0, seed=1):
    """Piecewise-constant input held 10 samples, and its first-order low-pass (tau samples)."""
    rng = np.random.default_rng(seed)
    x = np.repeat(rng.uniform(-1, 1, n // 10 + 1), 10)[:n]
    a, y, state = 1.0 - math.exp(-1.0 / tau), np.empty(n), 0.0
    for t in range(n):
        state += a * (x[t] - state)
        y[t] = state
    return x, y


def _fd_grad(net, p, w, eps=1e-6):
    def loss(q):
        return net._loss(net._forward(q[None], w)[1], w)[0]
    return np.array([(loss(p + e) - loss(p - e)) / (2 * eps) for e in np.eye(len(p)) * eps])


@pytest.mark.parametrize(("n", "window", "hidden_act", "out_act"), [
    (50, 8, "tanh", "linear"),     # 7 windows, last one padded
    (40, 8, "sigmoid", "tanh"),    # 5 full windows
    (6, 16, "tanh", "tanh"),       # one window (no warm-up), window > n
])
def test_bptt_gradient_matches_finite_differences(n, window, hidden_act, out_act):
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-2, 3, (n, 2)), rng.normal(size=n)
    net = _net(2, hidden=3, window=window, hidden_activation=hidden_act, output_activation=out_act)
    net.scale_to(x, y)
    w = net._windows(*net._scaled(x, y))
    P = rng.uniform(-1, 1, (2, net.n_params))
    loss, grad = net.loss_grad(P, w)
    np.testing.assert_allclose(loss, net.loss_batch(P, x, y), rtol=1e-12)
    for i in range(2):
        fd = _fd_grad(net, P[i], w)
        assert np.abs(fd - grad[i]).max() <= 1e-5 * np.abs(grad[i]).max()


def test_loss_batch_rows_and_hand_computation():
    x, y = np.array([-1.0, 0.5, 1.0]), np.array([1.0, -1.0, 0.2])  # already in [-1, 1]
    net = _net(hidden=2, window=4)
    # layout: W_x (2x1), W_c (2x2), b1 (2), w2 (2), b2 (1)
    p = np.array([0.5, -0.3, 0.2, -0.4, 0.1, 0.3, 0.05, -0.1, 0.7, -0.6, 0.15])
    Wx, Wc, b1, w2, b2 = p[:2], p[2:6].reshape(2, 2), p[6:8], p[8:10], p[10]
    h, err = [0.0, 0.0], 0.0
    for t in range(3):
        h = [math.tanh(Wx[i] * x[t] + Wc[i, 0] * h[0] + Wc[i, 1] * h[1] + b1[i]) for i in range(2)]
        err += (w2[0] * h[0] + w2[1] * h[1] + b2 - y[t]) ** 2
    assert net.loss_batch(p, x, y)[0] == pytest.approx(err / 6, rel=1e-12)

    P = np.random.default_rng(5).uniform(-1, 1, (7, net.n_params))
    P[0] = p
    batch = net.loss_batch(P, x, y)
    assert batch.shape == (7,)
    np.testing.assert_allclose(batch, [net.loss_batch(r, x, y)[0] for r in P], rtol=1e-12)


def test_loss_batch_chunks_and_non_finite(monkeypatch):
    x, y = _lowpass(300)
    net = _net(hidden=4, window=16)
    P = np.random.default_rng(2).uniform(-1, 1, (9, net.n_params))
    whole = net.loss_batch(P, x, y)
    monkeypatch.setattr(elman_mod, "MAX_FLOATS", 1.0)  # one row per chunk
    np.testing.assert_allclose(net.loss_batch(P, x, y), whole, rtol=1e-12)
    P[3, -1] = 1e200  # output threshold b2: the squared error overflows
    assert net.loss_batch(P, x, y)[3] == np.inf


def test_windowed_loss_equals_exact_recurrence_for_one_window():
    x, y = _lowpass(200)
    net = _net(hidden=5, window=200)
    p = net.initial_params(np.random.default_rng(4))
    net.scale_to(x, y)
    net.set_params(p)
    ys = net.y_scaler.forward(net.predict(x))
    exact = np.sum((ys - net.y_scaler.forward(y)) ** 2) / (2 * len(y))
    assert net.loss_batch(p, x, y)[0] == pytest.approx(exact, rel=1e-12)


def test_zero_context_weights_is_feed_forward():
    rng = np.random.default_rng(6)
    x = rng.uniform(-1, 1, (50, 2))
    x[0], x[1] = -1.0, 1.0  # span exactly [-1, 1] per column
    y = rng.uniform(-1, 1, 50)
    y[:2] = -1.0, 1.0
    net = _net(2, hidden=3, window=8)
    net.scale_to(x, y)
    p = rng.uniform(-1, 1, net.n_params)
    p[6:15] = 0.0  # W_c
    net.set_params(p)
    Wx, b1, w2, b2 = p[:6].reshape(3, 2), p[15:18], p[18:21], p[21]
    ff = np.tanh(x @ Wx.T + b1) @ w2 + b2
    np.testing.assert_allclose(net.predict(x), ff, atol=1e-12)
    assert net.loss_batch(p, x, y)[0] == pytest.approx(np.sum((ff - y) ** 2) / 100, rel=1e-12)


def test_training_learns_memory_task():
    x, y = _lowpass(600)
    net = _net(hidden=8, epochs=400, learning_rate=0.02)
    hist = net.fit(x, y)
    assert hist.stopped == "max_epochs" and hist.iterations == 400 and len(hist.loss) == 400
    assert min(hist.loss) <= hist.loss[0] / 10
    A = np.c_[x, np.ones_like(x)]
    static = np.sqrt(np.mean((A @ np.linalg.lstsq(A, y, rcond=None)[0] - y) ** 2))
    rmse = np.sqrt(np.mean((net.predict(x) - y) ** 2))
    assert rmse < 0.4 * static


def test_gd_momentum_trains_and_divergence_is_caught():
    x, y = _lowpass(200)
    hist = _net(hidden=4, training="gd", epochs=100, learning_rate=0.05).fit(x, y)
    assert hist.loss[-1] < hist.loss[0]
    net = _net(hidden=4, training="gd", epochs=100, learning_rate=1e6)
    hist = net.fit(x, y)
    assert hist.stopped == "diverged" and hist.iterations < 100
    assert np.isfinite(net.predict(x)).all()
    assert net.loss_batch(net.get_params(), x, y)[0] == pytest.approx(min(hist.loss))


def test_goal_stops_training():
    x, y = _lowpass(200)
    hist = _net(hidden=4, goal=1e9).fit(x, y)
    assert hist.stopped == "goal" and hist.iterations == 1


def test_params_round_trip_and_determinism():
    x, y = _lowpass(300)
    net = _net(hidden=4, epochs=30)
    assert net.n_params == 4 * 1 + 16 + 4 + 4 + 1
    p = np.arange(net.n_params, dtype=float)
    net.set_params(p)
    got = net.get_params()
    np.testing.assert_array_equal(got, p)
    got[0] = 99.0
    assert net.get_params()[0] == 0.0  # a copy
    with pytest.raises(ValueError, match="expected 29 parameters"):
        net.set_params(np.zeros(5))
    a, b = _net(hidden=4, epochs=30, seed=7), _net(hidden=4, epochs=30, seed=7)
    ha, hb = a.fit(x, y), b.fit(x, y)
    assert ha.loss == hb.loss
    np.testing.assert_array_equal(a.predict(x), b.predict(x))
    init = a.initial_params(np.random.default_rng(1))
    np.testing.assert_array_equal(_net(hidden=4, epochs=5, seed=1).fit(x, y, init).loss,
                                  _net(hidden=4, epochs=5, seed=2).fit(x, y, init).loss)


@pytest.mark.parametrize(("key", "value"), [
    ("hidden", 0), ("hidden_activation", "relu"), ("output_activation", "sigmoid"),
    ("training", "lm"), ("epochs", 0), ("learning_rate", 0.0), ("learning_rate", math.inf),
    ("momentum", 1.0), ("momentum", -0.1), ("window", 0), ("goal", -1.0), ("goal", math.nan),
])
def test_invalid_params_name_the_parameter(key, value):
    with pytest.raises(ValueError, match=key):
        ElmanNetwork(1, {key: value})
    with pytest.raises(ValueError, match=key):
        ElmanParams(**{key: value})


def test_bad_data_is_rejected():
    x, y = _lowpass(50)
    net = _net()
    with pytest.raises(ValueError, match="hidden"):
        ElmanNetwork(1, {"hidden": "10"})
    bad = x.copy()
    bad[7] = np.nan
    with pytest.raises(ValueError, match="inputs row 7"):
        net.fit(bad, y)
    with pytest.raises(ValueError, match="target row 3"):
        net.loss_batch(np.zeros(net.n_params), x, np.where(np.arange(50) == 3, np.inf, y))
    with pytest.raises(ValueError, match="params must have shape"):
        net.loss_batch(np.zeros((2, 3)), x, y)
    with pytest.raises(RuntimeError, match="before fit"):
        _net().predict(x)


@pytest.mark.parametrize("hidden_act", ["tanh", "sigmoid"])
def test_predict_matches_a_plain_loop(hidden_act):
    rng = np.random.default_rng(8)
    x, y = rng.uniform(-1, 1, (40, 2)), rng.normal(size=40)
    net = _net(2, hidden=3, hidden_activation=hidden_act, output_activation="tanh")
    net.scale_to(x, y)
    p = rng.uniform(-1, 1, net.n_params)
    net.set_params(p)
    Wx, Wc, b1, w2, b2 = p[:6].reshape(3, 2), p[6:15].reshape(3, 3), p[15:18], p[18:21], p[21]
    f = np.tanh if hidden_act == "tanh" else (lambda a: 1.0 / (1.0 + np.exp(-a)))
    xs, h, out = net.x_scaler.forward(x), np.zeros(3), []
    for t in range(40):
        h = f(Wx @ xs[t] + Wc @ h + b1)
        out.append(np.tanh(w2 @ h + b2))
    np.testing.assert_allclose(net.predict(x), net.y_scaler.inverse(np.array(out)), atol=1e-12)
