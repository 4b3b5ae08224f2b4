"""BP network (seed 000 eq. 2-3): derivatives, batched loss, LM and GD training, parameters."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.learners.bp import BPNetwork, BPParams


def smooth_data(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """y = sin(x1) + 0.3 x2^2 on [-2, 2]^2."""
    x = np.random.default_rng(seed).uniform(-2.0, 2.0, (n, 2))
    return x, np.sin(x[:, 0]) + 0.3 * x[:, 1] ** 2


@pytest.fixture(params=[("tanh", "linear"), ("sigmoid", "tanh")])
def net(request: pytest.FixtureRequest) -> BPNetwork:
    hidden, output = request.param
    return BPNetwork(2, {"hidden": 4, "hidden_activation": hidden, "output_activation": output})


def central_differences(f, p: np.ndarray, step: float = 1e-6) -> np.ndarray:
    cols = []
    for i in range(p.size):
        e = np.zeros_like(p)
        e[i] = step
        cols.append((np.asarray(f(p + e)) - np.asarray(f(p - e))) / (2 * step))
    return np.stack(cols, axis=-1)


def test_gradient_matches_finite_differences(net: BPNetwork) -> None:
    rng = np.random.default_rng(3)
    x, t = rng.uniform(-1, 1, (40, 2)), rng.uniform(-1, 1, 40)
    p = rng.normal(0, 0.8, net.n_params)
    _, grad = net.loss_and_grad(p, x, t)
    numeric = central_differences(lambda q: net.loss_and_grad(q, x, t)[0], p)
    assert np.linalg.norm(grad - numeric) <= 1e-6 * np.linalg.norm(numeric)


def test_jacobian_matches_finite_differences(net: BPNetwork) -> None:
    rng = np.random.default_rng(4)
    x = rng.uniform(-1, 1, (30, 2))
    p = rng.normal(0, 0.8, net.n_params)
    jac = net.jacobian(p, x)
    assert jac.shape == (30, net.n_params)
    numeric = central_differences(lambda q: net.forward(q, x)[1], p)
    assert np.linalg.norm(jac - numeric) <= 1e-6 * np.linalg.norm(numeric)


def test_n_params_of_the_paper_network() -> None:
    assert BPNetwork(2).n_params == 41


def test_loss_batch_equals_single_evaluations() -> None:
    x, y = smooth_data(200, 0)
    net = BPNetwork(2)
    rows = net.initial_params(np.random.default_rng(1))[None, :] + np.random.default_rng(2).normal(0, 1, (7, 41))
    batch = net.loss_batch(rows, x, y)
    xs, ts = net._scaled(x, y)
    single = [net.loss_and_grad(r, xs, ts)[0] for r in rows]
    np.testing.assert_allclose(batch, single, rtol=1e-12)


def test_loss_batch_chunks_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    from tcbench.learners import bp

    x, y = smooth_data(50, 0)
    net = BPNetwork(2)
    rows = np.random.default_rng(5).normal(0, 1, (9, 41))
    whole = net.loss_batch(rows, x, y)
    monkeypatch.setattr(bp, "CHUNK_FLOATS", 2 * 50 * 10)  # two candidates per chunk
    np.testing.assert_allclose(net.loss_batch(rows, x, y), whole, rtol=1e-14)


def test_loss_batch_by_hand_on_a_1_2_1_network() -> None:
    net = BPNetwork(1, {"hidden": 2})
    # inputs 0, 1, 2 and targets 0, 1, 3 normalise to x = -1, 0, 1 and t = -1, -1/3, 1
    x, y = np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.0, 3.0])
    w1, b1, w2, b2 = [0.5, -1.0], [0.1, 0.2], [1.5, -0.7], 0.3
    p = np.array([*w1, *b1, *w2, b2])
    xs, ts = np.array([-1.0, 0.0, 1.0]), np.array([-1.0, -1.0 / 3.0, 1.0])
    out = [sum(w2[i] * np.tanh(w1[i] * xi + b1[i]) for i in range(2)) + b2 for xi in xs]
    expected = sum((o - ti) ** 2 for o, ti in zip(out, ts, strict=True)) / (2 * 3)
    got = net.loss_batch(np.vstack([p, 2 * p]), x, y)
    assert got[0] == pytest.approx(expected, rel=1e-12)
    assert got.shape == (2,)


def test_loss_batch_non_finite_is_inf() -> None:
    x, y = smooth_data(20, 0)
    net = BPNetwork(2)
    rows = np.vstack([np.zeros(41), np.full(41, np.nan), np.full(41, 1e308)])
    got = net.loss_batch(rows, x, y)
    assert np.isfinite(got[0]) and np.isinf(got[1:]).all()


def test_lm_fits_a_smooth_function() -> None:
    x, y = smooth_data(500, 0)
    xt, yt = smooth_data(500, 1)
    net = BPNetwork(2, {"training": "lm", "epochs": 300}, rng=np.random.default_rng(0))
    history = net.fit(x, y)
    rmse = np.sqrt(np.mean((net.predict(xt) - yt) ** 2))
    assert rmse < 1e-3 * np.ptp(yt)
    assert history.iterations > 0 and history.stopped in ("converged", "max_epochs")
    assert history.loss[-1] < history.loss[0] and history.seconds > 0


def test_gd_decreases_the_loss() -> None:
    x, y = smooth_data(500, 0)
    net = BPNetwork(2, {"epochs": 500}, rng=np.random.default_rng(0))
    history = net.fit(x, y)
    assert history.stopped == "max_epochs" and history.iterations == 500
    assert len(history.loss) == 501
    assert history.loss[-1] < history.loss[0] / 10
    assert min(history.loss) == pytest.approx(history.loss[-1], rel=0.2)


def test_goal_stops_training() -> None:
    x, y = smooth_data(200, 0)
    for training in ("gd", "lm"):
        history = BPNetwork(2, {"training": training, "goal": 1e-2}).fit(x, y)
        assert history.stopped == "goal" and history.loss[-1] <= 1e-2


def test_get_set_params_round_trip() -> None:
    net = BPNetwork(2)
    p = np.arange(41.0)
    net.set_params(p)
    got = net.get_params()
    np.testing.assert_array_equal(got, p)
    got[0] = -1
    assert net.get_params()[0] == 0  # a copy
    with pytest.raises(ValueError, match="expected 41 parameters"):
        net.set_params(np.zeros(40))


def test_same_rng_same_result() -> None:
    x, y = smooth_data(200, 0)
    runs = []
    for _ in range(2):
        net = BPNetwork(2, {"training": "lm", "epochs": 100}, rng=np.random.default_rng(7))
        runs.append((net.fit(x, y).loss, net.predict(x)))
    assert runs[0][0] == runs[1][0]
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    init = np.random.default_rng(9).uniform(-1, 1, 41)
    a, b = BPNetwork(2, {"epochs": 50}), BPNetwork(2, {"epochs": 50})
    a.fit(x, y, init=init)
    b.fit(x, y, init=init)
    np.testing.assert_array_equal(a.get_params(), b.get_params())


@pytest.mark.parametrize("field, value", [
    ("hidden", 0), ("epochs", 0), ("learning_rate", 0.0), ("momentum", 1.0), ("momentum", -0.1),
    ("goal", -1.0), ("hidden_activation", "relu"), ("output_activation", "sigmoid"),
    ("training", "adam"), ("lm_tolerance", 0.0),
])
def test_invalid_parameters(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=field):
        BPNetwork(2, {field: value})
    with pytest.raises(ValueError, match=field):
        BPParams(**{field: value})


def test_wrong_types_and_unknown_names() -> None:
    with pytest.raises(ValueError, match="hidden"):
        BPNetwork(2, {"hidden": "ten"})
    with pytest.raises(ValueError, match="hiden"):
        BPNetwork(2, {"hiden": 10})


def test_nan_inputs_name_the_row() -> None:
    x, y = smooth_data(20, 0)
    x[5, 1] = np.nan
    with pytest.raises(ValueError, match="row 5"):
        BPNetwork(2).fit(x, y)
    x, y = smooth_data(20, 0)
    y[3] = np.inf
    with pytest.raises(ValueError, match="row 3"):
        BPNetwork(2).fit(x, y)


def test_diverging_gd_keeps_finite_parameters() -> None:
    x, y = smooth_data(200, 0)
    net = BPNetwork(2, {"learning_rate": 1e6, "epochs": 2000})
    history = net.fit(x, y)
    assert history.stopped == "diverged"
    assert np.isfinite(history.loss).all() and np.isfinite(net.get_params()).all()
    assert np.isfinite(net.predict(x)).all()


def test_checkpoints_are_the_shorter_trainings_of_the_same_trajectory() -> None:
    """A GD training with checkpoints keeps the weights after those epochs; each equals a training
    stopped there, and the task scores them beside the final weights."""
    import gymnasium as gym

    import tcbench  # noqa: F401 - registers the envs

    def env(**params):  # type: ignore[no-untyped-def]
        e = gym.make("tcbench/MSRA-FullTemp-v0", learner="bp", learner_params={"training": "gd", **params}).unwrapped
        e.reset(seed=2)
        return e

    init = env(epochs=60).learner.initial_params(np.random.default_rng(5))
    long_score, history = env(epochs=60, checkpoints=[10, 30]).score(init)
    assert sorted(history.snapshots) == [10, 30] and len(history.loss) == 61
    short = env(epochs=30)
    short_score, _ = short.score(init)
    np.testing.assert_array_equal(history.snapshots[30], short.learner.get_params())
    at30 = long_score.extra["checkpoints"][30]
    assert at30 == short_score.summary()
    assert long_score.summary() != at30
    with pytest.raises(ValueError, match="checkpoints must be null or, with training gd"):
        env(training="lm", checkpoints=[10])
    with pytest.raises(ValueError, match="checkpoints must be null or, with training gd"):
        env(epochs=20, checkpoints=[30])


def test_matlab_preset_gd_steps_at_lr_001_on_mse_without_momentum() -> None:
    """``preset=matlab`` with ``gd`` is ``traingd``: ``dX = -lr d mse/dp`` with lr 0.01 and
    ``mse = 2 C``, so each step is ``-0.02 dC/dp`` of the rows it trains on, with no momentum."""
    x, y = smooth_data(200, 0)
    net = BPNetwork(2, {"training": "gd", "preset": "matlab", "epochs": 2}, rng=np.random.default_rng(3))
    p0 = np.random.default_rng(7).uniform(-1.0, 1.0, net.n_params)
    history = net.fit(x, y, init=p0)
    assert history.best_epoch == 2 and len(history.val_loss) == 3  # the kept weights are the last epoch's
    held = np.sort(np.random.default_rng(3).permutation(200)[:30])  # 15 % of 200, drawn as the learner draws
    train = np.setdiff1d(np.arange(200), held)
    xs, ts = net._scaled(x[train], y[train])
    g0 = net.loss_and_grad(p0, xs, ts)[1]
    p1 = p0 - 0.01 * (2.0 * g0)
    p2 = p1 - 0.01 * (2.0 * net.loss_and_grad(p1, xs, ts)[1])
    np.testing.assert_allclose(net.get_params(), p2, rtol=0, atol=1e-12)
    assert net.params.learning_rate == 0.02 and net.params.momentum == 0.0 and net.params.max_epochs == 2


def test_matlab_preset_sets_its_keys_and_refuses_them_given() -> None:
    gd, lm = BPParams(preset="matlab"), BPParams(training="lm", preset="matlab")
    assert (gd.validation_fraction, gd.max_fail, gd.min_grad, gd.max_epochs) == (0.15, 6, 1e-5, 1000)
    assert (lm.min_grad, lm.max_epochs) == (1e-7, 1000)
    assert (BPParams().learning_rate, BPParams().momentum, BPParams().validation_fraction) == (0.1, 0.9, 0.0)
    import dataclasses

    assert dataclasses.replace(gd, epochs=5).learning_rate == 0.02  # resolved params copy as they are
    with pytest.raises(ValueError, match="leave learning_rate=0.05 out"):
        BPParams(preset="matlab", learning_rate=0.05)
    with pytest.raises(ValueError, match="preset must be null or one of matlab"):
        BPParams(preset="keras")


def noisy_data(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A smooth function under noise of 0.5: a 30-hidden network fitted by LM overfits 40 rows."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-2.0, 2.0, (n, 2))
    return x, np.sin(x[:, 0]) + 0.3 * x[:, 1] ** 2 + 0.5 * rng.normal(size=n)


def test_lm_validation_stop_keeps_the_best_held_out_weights() -> None:
    x, y = noisy_data(40, 0)
    params = {"training": "lm", "hidden": 30, "epochs": 200, "validation_fraction": 0.25, "max_fail": 6}
    net = BPNetwork(2, params, rng=np.random.default_rng(4))
    history = net.fit(x, y)
    assert history.stopped == "validation" and history.iterations < 200
    assert history.best_epoch == history.iterations - 6  # six steps in a row without a new best
    assert len(history.val_loss) == history.iterations + 1
    assert history.loss[-1] < history.loss[history.best_epoch]  # training error still fell: overfitting
    rng = np.random.default_rng(4)
    rng.uniform(-1.0, 1.0, net.n_params)  # the start the learner drew before its split
    held = np.sort(rng.permutation(40)[:10])
    # the kept weights' eq. 3 error on the held-out rows, in the [-1, 1] units of the targets
    kept = 0.5 * np.mean((net.predict(x[held]) - y[held]) ** 2) / (0.5 * np.ptp(y)) ** 2
    assert kept == pytest.approx(min(history.val_loss), rel=1e-9)
    again = BPNetwork(2, params, rng=np.random.default_rng(4))
    assert again.fit(x, y).val_loss == history.val_loss
    np.testing.assert_array_equal(again.get_params(), net.get_params())
    full = BPNetwork(2, {**params, "validation_fraction": 0.0}, rng=np.random.default_rng(4))
    assert full.fit(x, y).iterations > history.iterations  # without the split it trains on


def test_gd_validation_stop_keeps_the_best_held_out_weights() -> None:
    x, y = noisy_data(40, 0)
    net = BPNetwork(2, {"hidden": 30, "epochs": 3000, "validation_fraction": 0.25, "max_fail": 20},
                    rng=np.random.default_rng(4))
    history = net.fit(x, y)
    assert history.stopped == "validation" and history.best_epoch == history.iterations - 20
    assert min(history.val_loss) == history.val_loss[history.best_epoch]


def test_the_matlab_preset_has_its_own_method_name() -> None:
    from tcbench.runner.kinds.compensation import compensation_label

    assert compensation_label({"name": "bp", "training": "gd", "preset": "matlab"}, {"name": "ifa"}) == "IFA-BP-gd-matlab"
    assert compensation_label({"name": "bp", "training": "lm", "preset": None}, {"name": "none"}) == "random-BP-lm"


def test_a_learner_let_to_extrapolate_has_its_own_method_name() -> None:
    """task.clamp_inputs=false names the fitted learners' rows apart from the default's clamped ones;
    the baselines, which take no learner inputs, keep their names."""
    from tcbench.runner.kinds.compensation import compensation_label

    free = {"name": "msra_zerobias", "clamp_inputs": False}
    held = {"name": "msra_zerobias", "clamp_inputs": True}
    assert compensation_label({"name": "bp", "training": "gd"}, {"name": "ifa"}, free) == "IFA-BP-gd-unclamped"
    assert compensation_label({"name": "bp", "training": "gd"}, {"name": "ifa"}, held) == "IFA-BP-gd"
    assert compensation_label({"name": "poly", "offsets": "per_run"}, {"name": "none"}, free) == "poly3_runs-unclamped"
    assert compensation_label({"name": "memoriser"}, {"name": "none"}, free) == "memoriser"
    assert compensation_label({"name": "lagpoly"}, {"name": "none"}, free) == "lagpoly"
