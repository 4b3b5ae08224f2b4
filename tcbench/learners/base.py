"""The Learner interface: a regression model that an optimiser can initialise.

A learner maps ``inputs`` (n, m) to ``targets`` (n,). Normalisation is inside: inputs and
targets are mapped column-wise to [-1, 1] from the training data (min-max, as MATLAB's
``mapminmax``), the model works in those units, and :meth:`Learner.predict` answers in target
units. Its weights and thresholds are one flat vector (:meth:`get_params` /
:meth:`set_params`), so an optimiser can search the initial values (FA-BP, IFA-BP, BAS-Elman):
:meth:`loss_batch` gives the training error of many candidate vectors in one array operation,
and :meth:`fit` trains from one of them.

The training error is seed 000 eq. 3, ``C = 1/(2n) sum (y_bar - y)^2``, in normalised units.
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from tcbench.params import make_params


@dataclass(frozen=True)
class LearnerParams:
    """Base of learner parameter dataclasses; subclasses validate in ``__post_init__``."""


@dataclass
class FitHistory:
    """How training went: the eq. 3 error (normalised units) per epoch or iteration."""

    loss: list[float] = field(default_factory=list)
    iterations: int = 0
    stopped: str = ""  # why training ended: "max_epochs", "goal", "converged", "closed_form", ...
    seconds: float = 0.0
    snapshots: dict[int, np.ndarray] = field(default_factory=dict)  # parameters after N epochs (checkpoints)
    val_loss: list[float] = field(default_factory=list)  # held-out eq. 3 error per epoch (validation stop)
    best_epoch: int | None = None  # the epoch whose weights the validation stop kept


@dataclass(frozen=True)
class Scaler:
    """Column-wise affine map of data to [-1, 1]; constant columns map to 0."""

    low: np.ndarray
    high: np.ndarray

    @classmethod
    def fit(cls, data: np.ndarray) -> Scaler:
        d = np.asarray(data, dtype=np.float64)
        d = d.reshape(len(d), -1)
        return cls(d.min(axis=0), d.max(axis=0))

    @property
    def span(self) -> np.ndarray:
        """Each column's range (1 where the column is constant)."""
        span = self.high - self.low
        return np.where(span > 0, span, 1.0)

    def forward(self, data: np.ndarray) -> np.ndarray:
        """Data in [-1, 1] units (shape kept)."""
        d = np.asarray(data, dtype=np.float64)
        flat = d.reshape(len(d), -1)
        return (2.0 * (flat - self.low) / self.span - 1.0).reshape(d.shape)

    def inverse(self, scaled: np.ndarray) -> np.ndarray:
        """Back from [-1, 1] units to data units (shape kept)."""
        s = np.asarray(scaled, dtype=np.float64)
        flat = s.reshape(len(s), -1) if s.ndim > 1 else s.reshape(-1, 1)
        return ((flat + 1.0) * 0.5 * self.span + self.low).reshape(s.shape)


def check_data(inputs: np.ndarray, targets: np.ndarray | None, n_inputs: int, who: str) -> tuple[np.ndarray, np.ndarray | None]:
    """``inputs`` as (n, n_inputs) floats and ``targets`` as (n,); ``ValueError`` naming the problem."""
    x = np.asarray(inputs, dtype=np.float64)
    if x.ndim == 1 and n_inputs == 1:
        x = x.reshape(-1, 1)
    if x.ndim != 2 or x.shape[1] != n_inputs:
        raise ValueError(f"{who}: inputs must have shape (n, {n_inputs}), got {x.shape}")
    if x.shape[0] < 2:
        raise ValueError(f"{who}: need at least 2 samples, got {x.shape[0]}")
    bad = ~np.isfinite(x)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise ValueError(f"{who}: inputs row {row}, column {col} is {x[row, col]}")
    if targets is None:
        return x, None
    y = np.asarray(targets, dtype=np.float64).reshape(-1)
    if y.shape[0] != x.shape[0]:
        raise ValueError(f"{who}: {x.shape[0]} input rows but {y.shape[0]} targets")
    if not np.isfinite(y).all():
        row = int(np.flatnonzero(~np.isfinite(y))[0])
        raise ValueError(f"{who}: target row {row} is {y[row]}")
    return x, y


class Learner(ABC):
    """Base class of learners. Subclasses set ``name`` and ``Params`` and implement the model."""

    name: ClassVar[str] = ""
    Params: ClassVar[type[LearnerParams]] = LearnerParams
    searchable: ClassVar[bool] = True  # a flat parameter vector an optimiser may initialise
    sequential: ClassVar[bool] = False  # rows form one time-ordered sequence (recurrent models)
    uses_runs: bool = False  # fit() takes runs= (each training row's run), e.g. per-run offsets

    def __init__(self, n_inputs: int, params: LearnerParams | dict[str, Any] | None = None,
                 rng: np.random.Generator | None = None) -> None:
        if int(n_inputs) != n_inputs or n_inputs < 1:
            raise ValueError(f"{self.name}: n_inputs must be a positive integer, got {n_inputs}")
        self.n_inputs = int(n_inputs)
        self.params = make_params(type(self), params)  # type: ignore[arg-type]
        self.rng = rng if rng is not None else np.random.default_rng(0)
        if not isinstance(self.rng, np.random.Generator):
            raise TypeError("rng must be a numpy.random.Generator")
        self.x_scaler: Scaler | None = None
        self.y_scaler: Scaler | None = None

    # -- normalisation -------------------------------------------------------------------
    def scale_to(self, inputs: np.ndarray, targets: np.ndarray) -> None:
        """Fit the input and target normalisation to this (training) data."""
        x, y = check_data(inputs, targets, self.n_inputs, self.name)
        self.x_scaler, self.y_scaler = Scaler.fit(x), Scaler.fit(y)

    def _scaled(self, inputs: np.ndarray, targets: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
        """Normalised inputs (and targets), fitting the normalisation first if it is not set."""
        x, y = check_data(inputs, targets, self.n_inputs, self.name)
        if self.x_scaler is None or self.y_scaler is None:
            if y is None:
                raise RuntimeError(f"{self.name}: predict() before fit()")
            self.scale_to(x, y)
        assert self.x_scaler is not None and self.y_scaler is not None
        return self.x_scaler.forward(x), None if y is None else self.y_scaler.forward(y)

    # -- the flat parameter vector -------------------------------------------------------
    @property
    @abstractmethod
    def n_params(self) -> int:
        """Length of the flat parameter vector (weights and thresholds)."""

    @abstractmethod
    def get_params(self) -> np.ndarray:
        """The current parameters as one flat vector (a copy)."""

    @abstractmethod
    def set_params(self, params: np.ndarray) -> None:
        """Set all parameters from one flat vector of length :attr:`n_params`."""

    def init_bounds(self) -> tuple[float, float]:
        """Box an optimiser searches initial parameters in (normalised units)."""
        return (-1.0, 1.0)

    def initial_params(self, rng: np.random.Generator) -> np.ndarray:
        """A random initial vector: where training starts without an optimiser."""
        low, high = self.init_bounds()
        return rng.uniform(low, high, self.n_params)

    def loss_batch(self, params: np.ndarray, inputs: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """Eq. 3 training error of each row of ``params`` (k, n_params) on the data, without
        training; one array operation over the k candidates. Fits the normalisation if unset."""
        raise TypeError(f"learner {self.name!r} has no parameters to search")

    # -- training and prediction ---------------------------------------------------------
    @abstractmethod
    def fit(self, inputs: np.ndarray, targets: np.ndarray, init: np.ndarray | None = None) -> FitHistory:
        """Train on the data from ``init`` (or :meth:`initial_params`); the normalisation is
        fitted to this data unless :meth:`scale_to` already set it."""

    @abstractmethod
    def predict(self, inputs: np.ndarray) -> np.ndarray:
        """Predictions (n,) in target units."""

    def _check_vector(self, params: np.ndarray) -> np.ndarray:
        p = np.asarray(params, dtype=np.float64).reshape(-1)
        if p.size != self.n_params:
            raise ValueError(f"{self.name}: expected {self.n_params} parameters, got {p.size}")
        return p.copy()

    def describe(self) -> dict[str, Any]:
        """Name and parameters as plain data."""
        return {"name": self.name, **dataclasses.asdict(self.params)}
