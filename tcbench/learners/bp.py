"""Three-layer BP (back-propagation) network, seed 000 §2.1 eq. 1-3.

Forward pass (eq. 2) on normalised data ``x`` (n, m)::

    a1 = x W1^T + b1          (n, l)    hidden pre-activation
    h  = sigma(a1)                       hidden output (tanh or logistic sigmoid)
    y  = phi(h w2 + b2)       (n,)      network output (linear or tanh)

The paper uses m = 2 inputs (frequency difference, temperature), l = 10 hidden neurons (eq. 1)
and one output (acceleration). Training minimises the eq. 3 error ``C = 1/(2n) sum (y_bar - y)^2``
either by full-batch gradient descent with momentum (the paper's step (6) of §2.3) or by
Levenberg-Marquardt (MINPACK through :func:`scipy.optimize.least_squares`), both with analytic
derivatives.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import least_squares
from scipy.special import expit

from tcbench.learners.base import FitHistory, Learner, LearnerParams

HIDDEN_ACTIVATIONS = ("tanh", "sigmoid")
OUTPUT_ACTIVATIONS = ("linear", "tanh")
TRAININGS = ("gd", "lm")
CHUNK_FLOATS = 50_000_000  # largest (k, n, hidden) block loss_batch builds at once


@dataclass(frozen=True)
class BPParams(LearnerParams):
    """BP network parameters; defaults are the paper's 2-10-1 network (§2.1, eq. 1 with c ~ 8).

    hidden: hidden neurons l (eq. 1), >= 1.
    hidden_activation: sigma of eq. 2, ``tanh`` or ``sigmoid`` (logistic).
    output_activation: phi of eq. 2, ``linear`` or ``tanh``.
    training: ``gd`` (gradient descent with momentum) or ``lm`` (Levenberg-Marquardt).
    epochs: gradient-descent epochs, or the LM limit on residual evaluations, >= 1.
    learning_rate: gradient-descent step eta, > 0 (normalised units).
    momentum: gradient-descent momentum mu in [0, 1): ``v <- mu v - eta grad C``.
    goal: stop once the eq. 3 error (normalised units) is <= goal, >= 0.
    lm_tolerance: LM ``ftol``, ``xtol`` and ``gtol``, > machine epsilon.
    """

    hidden: int = 10
    hidden_activation: str = "tanh"
    output_activation: str = "linear"
    training: str = "gd"
    epochs: int = 2000
    learning_rate: float = 0.1
    momentum: float = 0.9
    goal: float = 0.0
    lm_tolerance: float = 1e-12

    def __post_init__(self) -> None:
        checks = [
            ("hidden", self.hidden >= 1, "an integer >= 1"),
            ("hidden_activation", self.hidden_activation in HIDDEN_ACTIVATIONS,
             "one of " + ", ".join(HIDDEN_ACTIVATIONS)),
            ("output_activation", self.output_activation in OUTPUT_ACTIVATIONS,
             "one of " + ", ".join(OUTPUT_ACTIVATIONS)),
            ("training", self.training in TRAININGS, "one of " + ", ".join(TRAININGS)),
            ("epochs", self.epochs >= 1, "an integer >= 1"),
            ("learning_rate", self.learning_rate > 0 and np.isfinite(self.learning_rate), "a finite number > 0"),
            ("momentum", 0 <= self.momentum < 1, "in [0, 1)"),
            ("goal", self.goal >= 0, "a number >= 0"),
            ("lm_tolerance", np.finfo(float).eps < self.lm_tolerance < 1, "in (machine epsilon, 1)"),
        ]
        for name, ok, allowed in checks:
            if not ok:
                raise ValueError(f"bp: {name} must be {allowed}, got {getattr(self, name)!r}")


class _Goal(Exception):
    """Raised inside the LM Jacobian callback when the eq. 3 error reaches ``goal``."""

    def __init__(self, params: np.ndarray) -> None:
        super().__init__()
        self.params = params


def _sigma(a: np.ndarray, kind: str) -> np.ndarray:
    return np.tanh(a) if kind == "tanh" else expit(a)


def _sigma_slope(out: np.ndarray, kind: str) -> np.ndarray:
    """d sigma / d a from the activation's output."""
    return 1.0 - out * out if kind == "tanh" else out * (1.0 - out)


class BPNetwork(Learner):
    """Three-layer BP network (eq. 2) trained on the eq. 3 error.

    Flat parameter vector (length ``hidden * (n_inputs + 2) + 1``, 41 for 2-10-1):

    ==============  =======================  ==========================================
    slice           shape                    meaning
    ==============  =======================  ==========================================
    W1              (hidden, n_inputs)       input->hidden weights w_mj, row-major
    b1              (hidden,)                hidden thresholds b_j
    w2              (hidden,)                hidden->output weights w_li
    b2              (1,)                     output threshold b_n
    ==============  =======================  ==========================================
    """

    name = "bp"
    Params = BPParams
    params: BPParams  # type: ignore[assignment]  # make_params builds cls.Params

    def __init__(self, n_inputs: int, params: BPParams | dict[str, Any] | None = None,
                 rng: np.random.Generator | None = None) -> None:
        super().__init__(n_inputs, params, rng)
        self._p = np.zeros(self.n_params)

    # -- parameter vector ----------------------------------------------------------------
    @property
    def n_params(self) -> int:
        return self.params.hidden * (self.n_inputs + 2) + 1

    def get_params(self) -> np.ndarray:
        return self._p.copy()

    def set_params(self, params: np.ndarray) -> None:
        self._p = self._check_vector(params)

    def _split(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """W1 (..., l, m), b1 (..., l), w2 (..., l), b2 (...,) of one vector or a (k, P) batch."""
        nh, m = self.params.hidden, self.n_inputs
        lm = nh * m
        w1 = p[..., :lm].reshape(*p.shape[:-1], nh, m)
        return w1, p[..., lm:lm + nh], p[..., lm + nh:lm + 2 * nh], p[..., -1]

    # -- model (normalised units) --------------------------------------------------------
    def forward(self, p: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Hidden outputs h (n, l) and network output y (n,) of eq. 2 for one vector ``p``."""
        w1, b1, w2, b2 = self._split(p)
        h = _sigma(x @ w1.T + b1, self.params.hidden_activation)
        a2 = h @ w2 + b2
        return h, a2 if self.params.output_activation == "linear" else np.tanh(a2)

    def _delta(self, p: np.ndarray, x: np.ndarray, hy: tuple[np.ndarray, np.ndarray] | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """h, y, dy/da2 (n,) and dy/da1 (n, l): the back-propagated sensitivities of eq. 2;
        ``hy`` passes an already computed :meth:`forward` of ``p``."""
        _, _, w2, _ = self._split(p)
        h, y = self.forward(p, x) if hy is None else hy
        out_slope = np.ones_like(y) if self.params.output_activation == "linear" else 1.0 - y * y
        hid = out_slope[:, None] * w2 * _sigma_slope(h, self.params.hidden_activation)
        return h, y, out_slope, hid

    def loss_and_grad(self, p: np.ndarray, x: np.ndarray, t: np.ndarray) -> tuple[float, np.ndarray]:
        """Eq. 3 error C and its analytic gradient dC/dp (back-propagation), normalised data."""
        h, y, out_slope, hid = self._delta(p, x)
        r = (y - t) / len(t)  # dC/dy
        g_hid = hid * r[:, None]
        grad = np.concatenate([(g_hid.T @ x).ravel(), g_hid.sum(axis=0), h.T @ (out_slope * r),
                               [np.dot(out_slope, r)]])
        return 0.5 * float(np.mean((y - t) ** 2)), grad

    def jacobian(self, p: np.ndarray, x: np.ndarray, hy: tuple[np.ndarray, np.ndarray] | None = None
                 ) -> np.ndarray:
        """Analytic Jacobian dy/dp (n, n_params) of the outputs (= of the residuals y - t)."""
        h, _, out_slope, hid = self._delta(p, x, hy)
        n, nh, lm = len(x), self.params.hidden, self.params.hidden * self.n_inputs
        jac = np.empty((n, self.n_params))
        jac[:, :lm] = (hid[:, :, None] * x[:, None, :]).reshape(n, lm)
        jac[:, lm:lm + nh] = hid
        np.multiply(out_slope[:, None], h, out=jac[:, lm + nh:lm + 2 * nh])
        jac[:, -1] = out_slope
        return jac

    def loss_batch(self, params: np.ndarray, inputs: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """Eq. 3 error of each row of ``params`` (k, n_params); ``inf`` where not finite."""
        x, t = self._scaled(inputs, targets)
        assert t is not None
        pk = np.asarray(params, dtype=np.float64)
        pk = pk.reshape(1, -1) if pk.ndim == 1 else pk
        if pk.ndim != 2 or pk.shape[1] != self.n_params:
            raise ValueError(f"bp: params must have shape (k, {self.n_params}), got {pk.shape}")
        step = max(1, CHUNK_FLOATS // (len(x) * self.params.hidden))
        out = np.empty(len(pk))
        with np.errstate(all="ignore"):
            for s in range(0, len(pk), step):
                w1, b1, w2, b2 = self._split(pk[s:s + step])
                a1 = x @ np.swapaxes(w1, 1, 2) + b1[:, None, :]  # (k, n, l), batched matmul
                h = _sigma(a1, self.params.hidden_activation)
                y = (h @ w2[:, :, None])[..., 0] + b2[:, None]
                if self.params.output_activation == "tanh":
                    y = np.tanh(y)
                out[s:s + step] = 0.5 * np.mean((y - t) ** 2, axis=1)
        return np.where(np.isfinite(out), out, np.inf)

    # -- training ------------------------------------------------------------------------
    def fit(self, inputs: np.ndarray, targets: np.ndarray, init: np.ndarray | None = None) -> FitHistory:
        """Train from ``init`` (or :meth:`initial_params`) on the eq. 3 error; the final
        parameters are kept (on divergence, the best finite ones seen)."""
        start = time.perf_counter()
        x, t = self._scaled(inputs, targets)
        assert t is not None
        p0 = self._check_vector(init) if init is not None else self.initial_params(self.rng)
        train = self._fit_gd if self.params.training == "gd" else self._fit_lm
        p, history = train(p0, x, t)
        self._p = p
        history.seconds = time.perf_counter() - start
        return history

    def _fit_gd(self, p: np.ndarray, x: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, FitHistory]:
        """Full-batch gradient descent with momentum: ``v <- mu v - eta dC/dp; p <- p + v``."""
        cfg = self.params
        history = FitHistory()
        v = np.zeros_like(p)
        best, best_loss = p.copy(), np.inf
        with np.errstate(all="ignore"):
            while True:
                loss, grad = self.loss_and_grad(p, x, t)
                if not (np.isfinite(loss) and np.isfinite(grad).all()):
                    history.stopped = "diverged"
                    return best, history
                history.loss.append(loss)
                if loss < best_loss:
                    best, best_loss = p.copy(), loss
                if loss <= cfg.goal or history.iterations == cfg.epochs:
                    history.stopped = "goal" if loss <= cfg.goal else "max_epochs"
                    return p, history
                v = cfg.momentum * v - cfg.learning_rate * grad
                p = p + v
                history.iterations += 1

    def _fit_lm(self, p0: np.ndarray, x: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, FitHistory]:
        """Levenberg-Marquardt on the residuals y - t with the analytic Jacobian; the loss is
        recorded at every Jacobian evaluation (each accepted iterate)."""
        cfg = self.params
        history = FitHistory()
        big = 1e100  # stands in for non-finite residuals of rejected trial steps

        cache: dict[str, np.ndarray] = {}  # the last point evaluated, its h, y and residuals

        def residuals(p: np.ndarray) -> np.ndarray:
            with np.errstate(all="ignore"):
                h, y = self.forward(p, x)
                r = y - t
            if not np.isfinite(r).all():
                r = np.nan_to_num(r, nan=big, posinf=big, neginf=-big)
            cache.update(p=p.copy(), h=h, y=y, r=r)
            return r

        def jac(p: np.ndarray) -> np.ndarray:
            if "p" not in cache or not np.array_equal(p, cache["p"]):
                residuals(p)
            loss = 0.5 * float(np.mean(cache["r"] ** 2))
            history.loss.append(loss)
            if loss <= cfg.goal:
                raise _Goal(p.copy())
            with np.errstate(all="ignore"):
                j = self.jacobian(p, x, (cache["h"], cache["y"]))
            return j if np.isfinite(j).all() else np.nan_to_num(j, nan=0.0, posinf=big, neginf=-big)

        with np.errstate(all="ignore"):
            finite = np.isfinite(self.forward(p0, x)[1]).all()
        if not finite:
            return p0, FitHistory(loss=[np.inf], stopped="diverged")
        tol = cfg.lm_tolerance
        try:
            res = least_squares(residuals, p0, jac=jac, method="lm", ftol=tol, xtol=tol, gtol=tol,
                                max_nfev=cfg.epochs)
        except _Goal as reached:
            history.iterations = len(history.loss) - 1
            history.stopped = "goal"
            return reached.params, history
        final = 0.5 * float(np.mean(res.fun ** 2))
        if not history.loss or history.loss[-1] != final:
            history.loss.append(final)
        history.iterations = int(res.njev) if res.njev is not None else len(history.loss)
        history.stopped = "max_epochs" if res.status == 0 else "converged"
        return res.x, history

    # -- prediction ----------------------------------------------------------------------
    def predict(self, inputs: np.ndarray) -> np.ndarray:
        """Eq. 2 output in target units (the target normalisation inverted)."""
        x, _ = self._scaled(inputs)
        assert self.y_scaler is not None
        return self.y_scaler.inverse(self.forward(self._p, x)[1])

