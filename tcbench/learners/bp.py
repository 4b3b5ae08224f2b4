"""Three-layer BP (back-propagation) network, seed 000 §2.1 eq. 1-3.

Forward pass (eq. 2) on normalised data ``x`` (n, m)::

    a1 = x W1^T + b1          (n, l)    hidden pre-activation
    h  = sigma(a1)                       hidden output (tanh or logistic sigmoid)
    y  = phi(h w2 + b2)       (n,)      network output (linear or tanh)

The paper uses m = 2 inputs (frequency difference, temperature), l = 10 hidden neurons (eq. 1)
and one output (acceleration). Training minimises the eq. 3 error ``C = 1/(2n) sum (y_bar - y)^2``
either by full-batch gradient descent with momentum (the paper's step (6) of §2.3) or by
Levenberg-Marquardt with MATLAB ``trainlm``'s damping schedule, both with analytic derivatives.

``preset=matlab`` trains as MATLAB's ``train`` does at its documented defaults (``traingd``: lr
0.01, no momentum, 1000 epochs, min_grad 1e-5; ``trainlm``: mu 1e-3 x0.1/x10 up to 1e10, 1000
epochs, min_grad 1e-7; both: max_fail 6 on a random 15 % validation split). MATLAB's ``mse``
performance is ``2 C``, so its lr 0.01 is a step of 0.02 on ``dC/dp`` here, and its min_grad
bounds ``||d mse / dp|| = 2 ||dC/dp||``. Two differences remain: MATLAB also holds out a 15 %
test split that no training step sees (here the task's test recordings play that part, so the
network trains on 85 % of the rows, not 70 %), and its errors are in target units unless
``performParam.normalization`` is set (here, as for every training, in the [-1, 1] units).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.special import expit

from tcbench.learners.base import FitHistory, Learner, LearnerParams

HIDDEN_ACTIVATIONS = ("tanh", "sigmoid")
OUTPUT_ACTIVATIONS = ("linear", "tanh")
TRAININGS = ("gd", "lm")
PRESETS = ("matlab",)
MATLAB_LR = 0.01  # traingd/traingdm net.trainParam.lr, on the mse gradient
MATLAB_MIN_GRAD = {"gd": 1e-5, "lm": 1e-7}  # traingd / trainlm net.trainParam.min_grad
MATLAB_EPOCHS = 1000  # traingd and trainlm net.trainParam.epochs
MATLAB_VALIDATION = 0.15  # dividerand's default valRatio
MATLAB_MAX_FAIL = 6  # net.trainParam.max_fail
CHUNK_FLOATS = 50_000_000  # largest (k, n, hidden) block loss_batch builds at once
GRAD_BLOCK_ROWS = 8192  # samples per block of the gradient (a cache-sized working set)


@dataclass(frozen=True)
class BPParams(LearnerParams):
    """BP network parameters; defaults are the paper's 2-10-1 network (§2.1, eq. 1 with c ~ 8).

    hidden: hidden neurons l (eq. 1), >= 1.
    hidden_activation: sigma of eq. 2, ``tanh`` or ``sigmoid`` (logistic).
    output_activation: phi of eq. 2, ``linear`` or ``tanh``.
    training: ``gd`` (gradient descent with momentum) or ``lm`` (Levenberg-Marquardt).
    epochs: gradient-descent epochs, or LM iterations, >= 1; ``None``: 1000 for GD (the epoch
        limit of MATLAB's ``traingd``/``traingdm``; the paper gives none), 200 for LM (1000 with
        ``preset=matlab``).
    learning_rate: gradient-descent step eta on ``dC/dp``, > 0 (normalised units). The default
        0.1 with momentum 0.9 is tcbench's choice, not MATLAB's: its steady step,
        ``eta / (1 - mu) = 1`` per unit of ``dC/dp``, is 50 times that of ``traingd`` and of
        ``traingdm`` at their defaults (lr 0.01 on ``d mse/dp = 2 dC/dp``).
    momentum: gradient-descent momentum mu in [0, 1): ``v <- mu v - eta grad C``.
    goal: stop once the eq. 3 error (normalised units) is <= goal, >= 0.
    preset: ``matlab`` (see the module doc) or None. The preset sets ``learning_rate`` (0.02 on
        ``dC/dp``), ``momentum`` (0), ``validation_fraction`` (0.15), ``max_fail`` (6),
        ``min_grad`` and the default ``epochs``; those keys must then be left at their defaults.
    validation_fraction: share of the training rows, drawn at random from the learner's
        Generator, held out of training to stop it early, in [0, 0.5); 0: none. Training stops
        once the held-out eq. 3 error has not improved on its best for ``max_fail`` epochs (LM:
        accepted steps) in a row, and every stop keeps the weights of the best held-out error.
    max_fail: epochs without a new best held-out error before the validation stop, >= 1.
    min_grad: stop once ``||d mse / dp|| = 2 ||dC/dp||`` (normalised units) is below it, >= 0;
        0: never.
    lm_tolerance: LM ``ftol``, ``xtol`` and ``gtol``, > machine epsilon.
    checkpoints: gradient-descent epochs (each <= ``epochs``) after which the weights are kept in
        :attr:`FitHistory.snapshots`, so that one long training scores every shorter budget on the
        same trajectory (a task scores them beside the final weights); None: none.
    """

    hidden: int = 10
    hidden_activation: str = "tanh"
    output_activation: str = "linear"
    training: str = "gd"
    epochs: int | None = None
    learning_rate: float = 0.1
    momentum: float = 0.9
    goal: float = 0.0
    lm_tolerance: float = 1e-12
    checkpoints: list | None = None
    preset: str | None = None
    validation_fraction: float = 0.0
    max_fail: int = 6
    min_grad: float = 0.0

    @property
    def max_epochs(self) -> int:
        """The epoch (GD) or iteration (LM) limit in force."""
        if self.epochs is not None:
            return self.epochs
        if self.preset == "matlab":
            return MATLAB_EPOCHS
        return 1000 if self.training == "gd" else 200

    def _apply_preset(self) -> None:
        """Set the keys ``preset`` decides; a ValueError when one of them was also given."""
        if self.preset is None:
            return
        if self.preset not in PRESETS:
            raise ValueError(f"bp: preset must be null or one of {', '.join(PRESETS)}, got {self.preset!r}")
        values = {"learning_rate": 2.0 * MATLAB_LR, "momentum": 0.0, "validation_fraction": MATLAB_VALIDATION,
                  "max_fail": MATLAB_MAX_FAIL, "min_grad": MATLAB_MIN_GRAD.get(self.training, 0.0)}
        defaults = {f.name: f.default for f in dataclasses.fields(self)}
        # a key at its default or already at the preset's value (a copy of resolved params) is fine
        given = [k for k in values if getattr(self, k) not in (defaults[k], values[k])]
        if given:
            raise ValueError(f"bp: preset {self.preset} sets {', '.join(values)}; leave "
                             f"{', '.join(f'{k}={getattr(self, k)!r}' for k in given)} out or drop the preset")
        for key, value in values.items():
            object.__setattr__(self, key, value)  # frozen: the resolved values are what describe() reports

    def __post_init__(self) -> None:
        self._apply_preset()
        checks = [
            ("hidden", self.hidden >= 1, "an integer >= 1"),
            ("hidden_activation", self.hidden_activation in HIDDEN_ACTIVATIONS,
             "one of " + ", ".join(HIDDEN_ACTIVATIONS)),
            ("output_activation", self.output_activation in OUTPUT_ACTIVATIONS,
             "one of " + ", ".join(OUTPUT_ACTIVATIONS)),
            ("training", self.training in TRAININGS, "one of " + ", ".join(TRAININGS)),
            ("epochs", self.epochs is None or self.epochs >= 1, "an integer >= 1 or null"),
            ("learning_rate", self.learning_rate > 0 and np.isfinite(self.learning_rate), "a finite number > 0"),
            ("momentum", 0 <= self.momentum < 1, "in [0, 1)"),
            ("goal", self.goal >= 0, "a number >= 0"),
            ("lm_tolerance", np.finfo(float).eps < self.lm_tolerance < 1, "in (machine epsilon, 1)"),
            ("checkpoints", self.checkpoints is None or (
                self.training == "gd" and all(isinstance(c, int) and 1 <= c <= self.max_epochs for c in self.checkpoints)),
             "null or, with training gd, a list of epochs within 1..epochs"),
            ("validation_fraction", 0 <= self.validation_fraction < 0.5, "in [0, 0.5)"),
            ("max_fail", isinstance(self.max_fail, int) and self.max_fail >= 1, "an integer >= 1"),
            ("min_grad", self.min_grad >= 0 and np.isfinite(self.min_grad), "a finite number >= 0"),
        ]
        for name, ok, allowed in checks:
            if not ok:
                raise ValueError(f"bp: {name} must be {allowed}, got {getattr(self, name)!r}")


def _tanh(a: np.ndarray) -> np.ndarray:
    """tanh as ``1 - 2 / (exp(2a) + 1)``, computed in place over ``a`` (which it overwrites):
    the same values to ~1e-16 absolute, about twice as fast as ``np.tanh`` on float64 arrays."""
    a *= 2.0
    out = np.exp(a, out=a)
    out += 1.0
    np.divide(-2.0, out, out=out)
    out += 1.0
    return out


def _sigma(a: np.ndarray, kind: str) -> np.ndarray:
    """The hidden activation of ``a``, overwriting ``a``."""
    return _tanh(a) if kind == "tanh" else expit(a, out=a)


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
        a1 = x @ w1.T
        a1 += b1
        h = _sigma(a1, self.params.hidden_activation)
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
        """Eq. 3 error C and its analytic gradient dC/dp (back-propagation), normalised data.
        Gradient descent calls it once per epoch, so it works in place over blocks of
        ``GRAD_BLOCK_ROWS`` samples that stay in the CPU cache."""
        _, _, w2, _ = self._split(p)
        nh, m, n = self.params.hidden, self.n_inputs, len(t)
        g_w1, g_b1, g_w2 = np.zeros((nh, m)), np.zeros(nh), np.zeros(nh)
        g_b2 = sse = 0.0
        for s in range(0, n, GRAD_BLOCK_ROWS):
            xb, tb = x[s:s + GRAD_BLOCK_ROWS], t[s:s + GRAD_BLOCK_ROWS]
            h, y = self.forward(p, xb)
            e = y - tb
            sse += float(e @ e)
            r = e / n  # dC/dy
            if self.params.output_activation == "tanh":
                r *= 1.0 - y * y  # dC/da2
            g = h * h if self.params.hidden_activation == "tanh" else h * (h - 1.0)
            if self.params.hidden_activation == "tanh":
                np.subtract(1.0, g, out=g)
            else:
                np.negative(g, out=g)  # h (1 - h)
            g *= w2
            g *= r[:, None]  # dC/da1 (rows, l)
            g_w1 += g.T @ xb
            g_b1 += g.sum(axis=0)
            g_w2 += h.T @ r
            g_b2 += float(r.sum())
        return 0.5 * sse / n, np.concatenate([g_w1.ravel(), g_b1, g_w2, [g_b2]])

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
                k, nh = w1.shape[0], self.params.hidden
                # all candidates' hidden layers side by side: (n, k * l), one 2-D matmul
                a1 = x @ w1.transpose(2, 0, 1).reshape(self.n_inputs, k * nh)
                a1 += b1.reshape(-1)
                h = _sigma(a1, self.params.hidden_activation).reshape(len(x), k, nh)
                y = np.einsum("nkl,kl->kn", h, w2) + b2[:, None]  # (k, n)
                if self.params.output_activation == "tanh":
                    y = np.tanh(y)
                out[s:s + step] = 0.5 * np.mean((y - t) ** 2, axis=1)
        return np.where(np.isfinite(out), out, np.inf)

    # -- training ------------------------------------------------------------------------
    def fit(self, inputs: np.ndarray, targets: np.ndarray, init: np.ndarray | None = None) -> FitHistory:
        """Train from ``init`` (or :meth:`initial_params`) on the eq. 3 error; the final
        parameters are kept (on divergence, the best finite ones seen; with a validation split,
        those of the best held-out error)."""
        start = time.perf_counter()
        x, t = self._scaled(inputs, targets)
        assert t is not None
        p0 = self._check_vector(init) if init is not None else self.initial_params(self.rng)
        held = self._held_out(len(t))
        val = _Validation(self, x[held], t[held], self.params.max_fail) if held.size else None
        if held.size:
            keep = np.ones(len(t), dtype=bool)
            keep[held] = False
            x, t = x[keep], t[keep]
        train = self._fit_gd if self.params.training == "gd" else self._fit_lm
        p, history = train(p0, x, t, val)
        self._p = p
        history.seconds = time.perf_counter() - start
        return history

    def _held_out(self, n: int) -> np.ndarray:
        """Rows held out for the validation stop: ``validation_fraction`` of ``n`` (at least one,
        leaving at least two to train on), drawn from the learner's Generator; none without."""
        fraction = self.params.validation_fraction
        if fraction == 0:
            return np.empty(0, dtype=np.intp)
        k = max(1, int(round(fraction * n)))
        if n - k < 2:
            raise ValueError(f"bp: validation_fraction {fraction} of {n} rows leaves fewer than 2 to train on")
        return np.sort(self.rng.permutation(n)[:k])

    def _small_gradient(self, grad: np.ndarray) -> bool:
        """Whether ``||d mse / dp|| = 2 ||dC/dp||`` is below ``min_grad``."""
        return self.params.min_grad > 0 and 2.0 * float(np.linalg.norm(grad)) < self.params.min_grad

    def _fit_gd(self, p: np.ndarray, x: np.ndarray, t: np.ndarray, val: _Validation | None = None
                ) -> tuple[np.ndarray, FitHistory]:
        """Full-batch gradient descent with momentum: ``v <- mu v - eta dC/dp; p <- p + v``."""
        cfg = self.params
        history = FitHistory()
        v = np.zeros_like(p)
        best, best_loss = p.copy(), np.inf
        marks = set(cfg.checkpoints or ())
        with np.errstate(all="ignore"):
            while True:
                loss, grad = self.loss_and_grad(p, x, t)
                if not (np.isfinite(loss) and np.isfinite(grad).all()):
                    history.stopped = "diverged"
                    return (best if val is None else val.finish(best)), history
                history.loss.append(loss)
                if history.iterations in marks:
                    history.snapshots[history.iterations] = p.copy()
                if loss < best_loss:
                    best, best_loss = p.copy(), loss
                stop = val.check(p, history) if val is not None else ""
                if not stop and self._small_gradient(grad):
                    stop = "min_grad"
                if not stop and (loss <= cfg.goal or history.iterations == cfg.max_epochs):
                    stop = "goal" if loss <= cfg.goal else "max_epochs"
                if stop:
                    history.stopped = stop
                    return (p if val is None else val.finish(p)), history
                v = cfg.momentum * v - cfg.learning_rate * grad
                p = p + v
                history.iterations += 1

    def _fit_lm(self, p0: np.ndarray, x: np.ndarray, t: np.ndarray, val: _Validation | None = None
                ) -> tuple[np.ndarray, FitHistory]:
        """Levenberg-Marquardt on the residuals ``r = y - t`` with the analytic Jacobian J:
        each iteration solves ``(J^T J + mu I) dp = -J^T r`` (41 x 41 for 2-10-1), accepts the
        step if the eq. 3 error falls (then ``mu /= 10``), else retries with ``mu *= 10`` — the
        damping schedule of MATLAB's ``trainlm`` (mu starts at 1e-3, stops above 1e10). Stops
        after ``epochs`` iterations, at ``goal``, when a step changes the error or the
        parameters by less than ``lm_tolerance`` (relative), below ``min_grad``, or at the
        validation stop."""
        cfg = self.params
        history = FitHistory()
        eye = np.eye(self.n_params)
        mu, p = 1e-3, p0

        def done(why: str, q: np.ndarray) -> tuple[np.ndarray, FitHistory]:
            history.stopped = why
            return (q if val is None else val.finish(q)), history

        with np.errstate(all="ignore"):
            h, y = self.forward(p, x)
            r = y - t
            loss = 0.5 * float(np.mean(r * r))
            if not np.isfinite(loss):
                return p0, FitHistory(loss=[np.inf], stopped="diverged")
            history.loss.append(loss)
            while True:
                if val is not None and (why := val.check(p, history)):
                    return done(why, p)
                if loss <= cfg.goal:
                    return done("goal", p)
                if history.iterations == cfg.max_epochs:
                    return done("max_epochs", p)
                jac = self.jacobian(p, x, (h, y))
                hess, grad = jac.T @ jac, jac.T @ r
                if self._small_gradient(grad / len(t)):
                    return done("min_grad", p)
                while True:
                    try:
                        step = np.linalg.solve(hess + mu * eye, -grad)
                    except np.linalg.LinAlgError:
                        step = np.full_like(p, np.nan)
                    trial = p + step
                    ht, yt = self.forward(trial, x)
                    rt = yt - t
                    trial_loss = 0.5 * float(np.mean(rt * rt))
                    if np.isfinite(trial_loss) and trial_loss < loss:
                        mu = max(mu * 0.1, 1e-20)
                        break
                    mu *= 10.0
                    if mu > 1e10:
                        return done("converged", p)
                change = loss - trial_loss
                small = change <= cfg.lm_tolerance * loss or np.max(np.abs(step)) <= cfg.lm_tolerance * (
                    1.0 + np.max(np.abs(p)))
                p, h, y, r, loss = trial, ht, yt, rt, trial_loss
                history.loss.append(loss)
                history.iterations += 1
                if small:
                    if val is not None:
                        val.check(p, history)  # the last step's held-out error counts too
                    return done("converged", p)

    # -- prediction ----------------------------------------------------------------------
    def predict(self, inputs: np.ndarray) -> np.ndarray:
        """Eq. 2 output in target units (the target normalisation inverted)."""
        x, _ = self._scaled(inputs)
        assert self.y_scaler is not None
        return self.y_scaler.inverse(self.forward(self._p, x)[1])



class _Validation:
    """The validation stop (MATLAB's ``max_fail``): the held-out eq. 3 error after each epoch,
    the weights of its best so far, and the epochs since that best."""

    def __init__(self, net: BPNetwork, x: np.ndarray, t: np.ndarray, max_fail: int) -> None:
        self.net, self.x, self.t, self.max_fail = net, x, t, max_fail
        self.best: np.ndarray | None = None
        self.best_loss, self.fails = np.inf, 0

    def check(self, p: np.ndarray, history: FitHistory) -> str:
        """Score ``p`` on the held-out rows; ``"validation"`` once ``max_fail`` epochs in a row
        have not improved on the best, else ``""``."""
        with np.errstate(all="ignore"):
            e = self.net.forward(p, self.x)[1] - self.t
            loss = 0.5 * float(np.mean(e * e))
        history.val_loss.append(loss)
        if loss < self.best_loss:
            self.best, self.best_loss, self.fails = p.copy(), loss, 0
            history.best_epoch = history.iterations
        else:
            self.fails += 1
        return "validation" if self.fails >= self.max_fail else ""

    def finish(self, p: np.ndarray) -> np.ndarray:
        """The weights to keep: those of the best held-out error (``p`` if none was finite)."""
        return p if self.best is None else self.best
