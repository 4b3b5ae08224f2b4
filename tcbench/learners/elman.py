"""Elman recurrent network, seed 001 §3.4.3 (eq. 34), trained by truncated BPTT.

**Model.** Eq. 34 has two hidden layers, each with its context nodes. tcbench uses one hidden layer
(the common Elman form; the second layer of eq. 34 repeats the same pattern)::

    c(t) = h(t-1),  c(0) = 0                      (context nodes: I_C(k) = O_I(k-1))
    h(t) = f(W_x x(t) + W_c c(t) + b1)            (O_I = h(W_L2 X + W_L1 I_C - a_i))
    y(t) = g(w2 . h(t) + b2)                      (Y = f(W_L5 O_H - a_k))

so ``W_x = W_L2``, ``W_c = W_L1``, ``b1 = -a_i``, ``w2 = W_L5``, ``b2 = -a_k``. ``f`` is tanh or the
sigmoid of eq. 35; ``g`` is linear or tanh. Inputs and targets are in normalised [-1, 1] units
(:class:`~tcbench.learners.base.Scaler`); rows are one time-ordered sequence.

**Flat parameter vector** (:meth:`ElmanNetwork.get_params`, row-major blocks, in this order):
``W_x`` (hidden x n_inputs), ``W_c`` (hidden x hidden), ``b1`` (hidden), ``w2`` (hidden), ``b2`` (1).
§3.4.4 (BAS-Elman) searches this vector with :meth:`ElmanNetwork.loss_batch`.

**Windowed training loss.** The recurrence is sequential, so the n samples are cut into
``B = ceil(n / T)`` consecutive windows of ``T = min(window, n)`` steps (the last one padded at
its end; padded steps are masked out of the loss and, being later in time, cannot affect real
steps) and all windows run in parallel: the Python loop is over time steps only. Window ``b``
starts from a zero context, then runs a *warm-up* over the T samples of window ``b - 1`` without
loss, and only then over its own samples; window 0 has no predecessor, so its context is reset to
zero after the warm-up (exact: the sequence starts from ``c(0) = 0``). The warm-up replaces the
true context ``h(bT - 1)`` by the state reached from zero after T steps; for a contractive
recurrence the gap shrinks geometrically in T. The loss is eq. 3, ``1/(2n) sum (y_bar - y)^2``
over the n real samples, and the gradient (:meth:`ElmanNetwork.loss_grad`) is its exact gradient,
back-propagated through the 2T steps (truncated BPTT of length 2T, warm-up included).

**Prediction** runs the exact recurrence over the whole sequence (one loop over samples,
~2 us per step), starting from ``c(0) = 0`` at the first row.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from tcbench.learners.base import FitHistory, Learner, LearnerParams

HIDDEN_ACTIVATIONS = ("tanh", "sigmoid")
OUTPUT_ACTIVATIONS = ("linear", "tanh")
TRAININGS = ("gd", "adam")
MAX_FLOATS = 5e7  # memory cap of one loss_batch chunk (floats)
DIVERGED = 1e4  # a loss this many times above max(first loss, 1) means training diverged
ADAM_BETAS, ADAM_EPS = (0.9, 0.999), 1e-8


@dataclass(frozen=True)
class ElmanParams(LearnerParams):
    """Elman network parameters.

    hidden: hidden (and context) nodes, >= 1.
    hidden_activation: f of eq. 34, "tanh" or "sigmoid" (eq. 35).
    output_activation: g of eq. 34, "linear" or "tanh".
    training: "adam" or "gd" (gradient descent with momentum), full batch per epoch.
    epochs: training epochs, >= 1.
    learning_rate: step size (normalised units), > 0.
    momentum: momentum of "gd", in [0, 1).
    window: truncated BPTT window T (samples), >= 1; each window also runs T warm-up steps.
    goal: stop when the eq. 3 training error (normalised units) is <= goal, >= 0.
    """

    hidden: int = 10
    hidden_activation: str = "tanh"
    output_activation: str = "linear"
    training: str = "adam"
    epochs: int = 500
    learning_rate: float = 0.01
    momentum: float = 0.9
    window: int = 32
    goal: float = 0.0

    def __post_init__(self) -> None:
        if self.hidden < 1:
            raise ValueError(f"hidden must be >= 1, got {self.hidden}")
        if self.hidden_activation not in HIDDEN_ACTIVATIONS:
            raise ValueError(f"hidden_activation must be one of {HIDDEN_ACTIVATIONS}, "
                             f"got {self.hidden_activation!r}")
        if self.output_activation not in OUTPUT_ACTIVATIONS:
            raise ValueError(f"output_activation must be one of {OUTPUT_ACTIVATIONS}, "
                             f"got {self.output_activation!r}")
        if self.training not in TRAININGS:
            raise ValueError(f"training must be one of {TRAININGS}, got {self.training!r}")
        if self.epochs < 1:
            raise ValueError(f"epochs must be >= 1, got {self.epochs}")
        if not (math.isfinite(self.learning_rate) and self.learning_rate > 0):
            raise ValueError(f"learning_rate must be finite and > 0, got {self.learning_rate}")
        if not 0 <= self.momentum < 1:
            raise ValueError(f"momentum must be in [0, 1), got {self.momentum}")
        if self.window < 1:
            raise ValueError(f"window must be >= 1, got {self.window}")
        if not (math.isfinite(self.goal) and self.goal >= 0):
            raise ValueError(f"goal must be finite and >= 0, got {self.goal}")


def _sigmoid(a: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Eq. 35, computed as ``(1 + tanh(a/2)) / 2`` (no overflow)."""
    out = np.multiply(a, 0.5, out=out)
    np.tanh(out, out=out)
    out += 1.0
    out *= 0.5
    return out


@dataclass
class _Windows:
    """Normalised data cut into windows: ``x`` (S, B, m) time-major with the warm-up steps first,
    ``y`` and ``mask`` (T, B) for the loss steps, ``warm`` warm-up steps (T, or 0 if B = 1)."""

    x: np.ndarray
    y: np.ndarray
    mask: np.ndarray
    warm: int
    n: int


class ElmanNetwork(Learner):
    """One-hidden-layer Elman network (eq. 34); see the module docstring for the windowed loss."""

    name = "elman"
    Params = ElmanParams
    sequential = True
    params: ElmanParams  # type: ignore[assignment]  # make_params builds cls.Params

    def __init__(self, n_inputs: int, params: ElmanParams | dict[str, Any] | None = None,
                 rng: np.random.Generator | None = None) -> None:
        super().__init__(n_inputs, params, rng)
        self._p = np.zeros(self.n_params)

    # -- parameters ------------------------------------------------------------------------
    @property
    def n_params(self) -> int:
        h, m = self.params.hidden, self.n_inputs
        return h * m + h * h + 2 * h + 1

    def get_params(self) -> np.ndarray:
        return self._p.copy()

    def set_params(self, params: np.ndarray) -> None:
        self._p = self._check_vector(params)

    def _unpack(self, P: np.ndarray) -> tuple[np.ndarray, ...]:
        """Rows of P (k, n_params) -> W_x (k, h, m), W_c (k, h, h), b1 (k, h), w2 (k, h), b2 (k,)."""
        h, m, k = self.params.hidden, self.n_inputs, len(P)
        i, j = h * m, h * m + h * h
        return (P[:, :i].reshape(k, h, m), P[:, i:j].reshape(k, h, h), P[:, j:j + h],
                P[:, j + h:j + 2 * h], P[:, -1])

    # -- windowed forward / backward -------------------------------------------------------
    def _windows(self, x: np.ndarray, y: np.ndarray) -> _Windows:
        n, T = len(x), min(self.params.window, len(x))
        B = -(-n // T)
        pad = B * T - n
        xw = np.concatenate([x, np.zeros((pad, x.shape[1]))]).reshape(B, T, -1).transpose(1, 0, 2)
        yw = np.concatenate([y, np.zeros(pad)]).reshape(B, T).T
        mask = (np.arange(B * T) < n).astype(np.float64).reshape(B, T).T
        if B > 1:  # window b warms up on the samples of window b - 1 (window 0 on its own, then reset)
            xw = np.concatenate([xw[:, np.maximum(np.arange(B) - 1, 0)], xw])
        return _Windows(xw, yw, mask, T if B > 1 else 0, n)

    def _forward(self, P: np.ndarray, w: _Windows) -> tuple[np.ndarray, np.ndarray]:
        """Hidden states (S, k, B, h) and outputs (T, k, B) of the k parameter rows of P."""
        Wx, Wc, b1, w2, b2 = self._unpack(P)
        act = np.tanh if self.params.hidden_activation == "tanh" else _sigmoid
        a_in = np.einsum("sbm,khm->skbh", w.x, Wx) + b1[:, None, :]
        WcT = Wc.transpose(0, 2, 1)
        hs = np.empty_like(a_in)
        h = np.zeros(a_in.shape[1:])
        for s in range(len(a_in)):
            if s == w.warm and w.warm:
                h = h.copy()
                h[:, 0] = 0.0  # window 0 has no predecessor: reset after its warm-up
            np.matmul(h, WcT, out=hs[s])
            hs[s] += a_in[s]
            h = act(hs[s], out=hs[s])
        z = np.einsum("tkbh,kh->tkb", hs[w.warm:], w2) + b2[:, None]
        return hs, (np.tanh(z) if self.params.output_activation == "tanh" else z)

    def _loss(self, out: np.ndarray, w: _Windows) -> np.ndarray:
        """Eq. 3 error (k,) of outputs (T, k, B); non-finite -> inf."""
        with np.errstate(over="ignore", invalid="ignore"):
            loss = np.einsum("tkb,tb->k", (out - w.y[:, None]) ** 2, w.mask) / (2 * w.n)
        return np.where(np.isfinite(loss), loss, np.inf)

    def loss_grad(self, P: np.ndarray, w: _Windows) -> tuple[np.ndarray, np.ndarray]:
        """Windowed eq. 3 loss (k,) and its exact gradient (k, n_params) by BPTT over the 2T steps."""
        P = np.atleast_2d(P)
        _, Wc, _, w2, _ = self._unpack(P)
        hs, out = self._forward(P, w)
        T = w.warm
        e = (out - w.y[:, None]) * w.mask[:, None] / w.n  # dL/dy (T, k, B)
        dz = e * (1.0 - out**2) if self.params.output_activation == "tanh" else e
        dact = 1.0 - hs**2 if self.params.hidden_activation == "tanh" else hs * (1.0 - hs)
        da = np.zeros_like(hs)
        da[T:] = dz[..., None] * w2[:, None, :]  # dL/dh(t) through the output, then + context
        carry = np.zeros(hs.shape[1:])
        for s in range(len(hs) - 1, -1, -1):
            da[s] += carry
            da[s] *= dact[s]
            carry = da[s] @ Wc
            if s == T and T:
                carry[:, 0] = 0.0
        ctx = np.concatenate([np.zeros_like(hs[:1]), hs[:-1]])
        if T:
            ctx[T, :, 0] = 0.0
        grads = [np.einsum("skbi,sbm->kim", da, w.x), np.einsum("skbi,skbj->kij", da, ctx),
                 da.sum(axis=(0, 2)), np.einsum("tkb,tkbh->kh", dz, hs[T:]), dz.sum(axis=(0, 2))]
        k = len(P)
        return self._loss(out, w), np.concatenate([g.reshape(k, -1) for g in grads], axis=1)

    def loss_batch(self, params: np.ndarray, inputs: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """Windowed eq. 3 error (normalised units) of each row of ``params`` (k, n_params); chunks
        of k keep each chunk under ``MAX_FLOATS`` floats."""
        P = np.asarray(params, dtype=np.float64)
        P = P.reshape(1, -1) if P.ndim == 1 else P
        if P.ndim != 2 or P.shape[1] != self.n_params:
            raise ValueError(f"{self.name}: params must have shape (k, {self.n_params}), got {P.shape}")
        x, y = self._scaled(inputs, targets)
        assert y is not None
        w = self._windows(x, y)
        chunk = max(1, int(MAX_FLOATS // (2 * w.x.shape[0] * w.x.shape[1] * self.params.hidden)))
        with np.errstate(over="ignore", invalid="ignore"):
            return np.concatenate([self._loss(self._forward(P[i:i + chunk], w)[1], w)
                                   for i in range(0, len(P), chunk)] or [np.empty(0)])

    # -- training and prediction -----------------------------------------------------------
    def fit(self, inputs: np.ndarray, targets: np.ndarray, init: np.ndarray | None = None) -> FitHistory:
        """Full-batch truncated BPTT with Adam or GD + momentum; keeps the best-so-far parameters.
        Stops at ``goal``, after ``epochs``, or "diverged" (non-finite loss or gradient, or a loss
        ``DIVERGED`` times above max(first loss, 1)), the best parameters restored in every case."""
        start = time.perf_counter()
        x, y = self._scaled(inputs, targets)
        assert y is not None
        w, pr = self._windows(x, y), self.params
        p = self._check_vector(init if init is not None else self.initial_params(self.rng))
        hist = FitHistory(stopped="max_epochs")
        best, best_loss = p.copy(), np.inf
        m1, m2 = np.zeros_like(p), np.zeros_like(p)
        for epoch in range(1, pr.epochs + 1):
            with np.errstate(over="ignore", invalid="ignore"):
                loss_k, grad_k = self.loss_grad(p, w)
            loss, grad = float(loss_k[0]), grad_k[0]
            if not (np.isfinite(loss) and np.isfinite(grad).all()) or \
                    (hist.loss and loss > DIVERGED * max(hist.loss[0], 1.0)):
                hist.stopped = "diverged"
                break
            hist.loss.append(loss)
            hist.iterations = epoch
            if loss < best_loss:
                best, best_loss = p.copy(), loss
            if loss <= pr.goal:
                hist.stopped = "goal"
                break
            if pr.training == "adam":
                (b1, b2) = ADAM_BETAS
                m1 = b1 * m1 + (1 - b1) * grad
                m2 = b2 * m2 + (1 - b2) * grad**2
                p = p - pr.learning_rate * (m1 / (1 - b1**epoch)) / (np.sqrt(m2 / (1 - b2**epoch)) + ADAM_EPS)
            else:
                m1 = pr.momentum * m1 - pr.learning_rate * grad
                p = p + m1
        self._p = best
        hist.seconds = time.perf_counter() - start
        return hist

    def predict(self, inputs: np.ndarray) -> np.ndarray:
        """Exact recurrence of eq. 34 over the whole sequence from ``c(0) = 0``, in target units.
        A sigmoid layer runs as ``h = (1 + u) / 2`` with ``u(t) = tanh(a(t) / 2)``, i.e.
        ``u(t) = tanh((W_x x + b1 + W_c 1 / 2) / 2 + (W_c / 4) u(t-1))``, ``u(0) = -1``: one ufunc
        per step."""
        x, _ = self._scaled(inputs)
        assert self.y_scaler is not None
        Wx, Wc, b1, w2, b2 = (v[0] for v in self._unpack(self._p[None]))
        a_in = x @ Wx.T + b1
        sigmoid = self.params.hidden_activation == "sigmoid"
        if sigmoid:
            a_in, Wc = 0.5 * (a_in + 0.5 * Wc.sum(axis=1)), 0.25 * Wc
        hs = np.empty_like(a_in)
        h = np.full(self.params.hidden, -1.0 if sigmoid else 0.0)
        tmp = np.empty_like(h)
        for t in range(len(a_in)):
            np.dot(Wc, h, out=tmp)
            tmp += a_in[t]
            h = np.tanh(tmp, out=hs[t])
        if sigmoid:
            hs = 0.5 * (1.0 + hs)
        z = hs @ w2 + b2
        return self.y_scaler.inverse(np.tanh(z) if self.params.output_activation == "tanh" else z)
