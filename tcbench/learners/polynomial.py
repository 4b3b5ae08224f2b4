"""Polynomial temperature model: the compensation flight stacks ship, fitted in closed form.

Two forms, chosen by the task (``form="auto"`` is a placeholder the task must resolve):

- ``inverse``: inputs ``[output, temperature]``, target the applied input (g for the MSRA). The
  sensor is modelled as ``output = b(T) + K(T) * target`` with a bias ``b`` and a scale factor
  ``K``, both polynomials of ``degree`` in ``T``; one linear least-squares solve fits both, and
  the prediction inverts the model, ``target = (output - b(T)) / K(T)``.
- ``bias``: ``target = b(x0)``, a polynomial of ``degree`` in the first input column (the
  temperature); any other input column (e.g. the temperature rate) is ignored.
- ``bias_rate``: inputs ``[T, dT/dt]``, ``target = b(T) + r(T) dT/dt`` with ``b`` of ``degree``
  and ``r`` of ``degree - 1`` in ``T``: the first-order expansion of a bias seen through a thermal
  lag (``b(T - tau dT/dt) ~ b(T) - tau b'(T) dT/dt``, so ``r`` has the degree of ``b'``) plus a
  gradient term constant in ``T``.

``offsets="per_run"`` fits the temperature polynomials *within* runs: each training run gets
its own constant term (its turn-on bias, docs/concepts/split-tiers.md), and the model keeps their mean. Pooled
over power-ons at different ambients, a shared constant lets the run-to-run offsets bend the
polynomial (a cubic then extrapolates them into the next run); the task passes the run of each
training row (``fit(..., runs=)``).

Everything is solved in the normalised [-1, 1] units of :class:`~tcbench.learners.base.Scaler`
(an affine change of units keeps both model forms), so the temperature is on [-1, 1] over the
training data and the polynomials are Chebyshev series there, which keeps the solve well
conditioned up to degree 6.

**Flat parameter vector** (:meth:`PolynomialModel.get_params`), Chebyshev coefficients of
increasing order in normalised units: ``inverse``: ``b_0..b_d`` then ``K_0..K_d``
(``2 (d + 1)`` values); ``bias``: ``b_0..b_d`` (``d + 1`` values); ``bias_rate``: ``b_0..b_d`` then
``r_0..r_{d-1}`` (``2 d + 1`` values, ``r`` in normalised rate units). It exists only after
:meth:`PolynomialModel.fit`, which also fixes the normalisation it refers to.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, ClassVar, cast

import numpy as np
from numpy.polynomial import chebyshev

from tcbench.learners.base import FitHistory, Learner, LearnerParams

FORMS = ("auto", "inverse", "bias", "bias_rate")
OFFSETS = ("shared", "per_run")
MAX_DEGREE = 6
AUTO_ERROR = "poly: form 'auto' must be resolved by the task; set form=inverse or form=bias"


@dataclass(frozen=True)
class PolynomialParams(LearnerParams):
    """Polynomial model parameters.

    degree: degree of the temperature polynomials b(T) and K(T), 1..6.
    form: "inverse" (inputs [output, temperature] -> applied input), "bias" (temperature ->
        output bias), "bias_rate" ([temperature, rate] -> bias) or "auto" (the task chooses;
        fitting with "auto" is an error).
    offsets: "shared" (one constant term over every training row) or "per_run" (a constant per
        training run, the temperature shape fitted within runs; the model keeps their mean).
    """

    degree: int = 3
    form: str = "auto"
    offsets: str = "shared"

    def __post_init__(self) -> None:
        if isinstance(self.degree, bool) or not isinstance(self.degree, (int, np.integer)) \
                or not 1 <= self.degree <= MAX_DEGREE:
            raise ValueError(f"poly: degree must be an integer in 1..{MAX_DEGREE}, got {self.degree!r}")
        if self.form not in FORMS:
            raise ValueError(f"poly: form must be one of {', '.join(FORMS)}, got {self.form!r}")
        if self.offsets not in OFFSETS:
            raise ValueError(f"poly: offsets must be one of {', '.join(OFFSETS)}, got {self.offsets!r}")


class PolynomialModel(Learner):
    """Bias and scale factor polynomial in temperature, least squares in one solve."""

    name: ClassVar[str] = "poly"
    Params: ClassVar[type[LearnerParams]] = PolynomialParams
    searchable: ClassVar[bool] = False

    def __init__(self, n_inputs: int, params: LearnerParams | dict[str, Any] | None = None,
                 rng: np.random.Generator | None = None) -> None:
        super().__init__(n_inputs, params, rng)
        self.settings = cast(PolynomialParams, self.params)
        if self.settings.form == "inverse" and self.n_inputs != 2:
            raise ValueError(f"poly: form 'inverse' takes 2 inputs [output, temperature], got {self.n_inputs}")
        self._coef: np.ndarray | None = None
        self._form: str | None = None  # the form the coefficients belong to

    @property
    def uses_runs(self) -> bool:
        """Whether :meth:`fit` needs the run of each training row (``offsets="per_run"``)."""
        return self.settings.offsets == "per_run"

    # -- the flat parameter vector -------------------------------------------------------
    def _fitted(self) -> np.ndarray:
        if self._coef is None:
            raise RuntimeError("poly: the coefficients exist only after fit() (closed-form solve)")
        return self._coef

    @property
    def n_params(self) -> int:
        return int(self._fitted().size)

    def get_params(self) -> np.ndarray:
        return self._fitted().copy()

    def set_params(self, params: np.ndarray) -> None:
        self._fitted()
        self._coef = self._check_vector(params)

    # -- fit and predict -----------------------------------------------------------------
    def _form_checked(self) -> str:
        form = self.settings.form
        if form == "auto":
            raise ValueError(AUTO_ERROR)
        if form in ("inverse", "bias_rate") and self.n_inputs != 2:
            raise ValueError(f"poly: form {form!r} takes 2 inputs, got {self.n_inputs}")
        return form

    def _basis(self, temp_scaled: np.ndarray) -> np.ndarray:
        """Chebyshev basis T_0..T_d of the normalised temperature, shape (n, d + 1)."""
        return chebyshev.chebvander(temp_scaled, self.settings.degree)

    def _design(self, x: np.ndarray, form: str) -> np.ndarray:
        """Least-squares design of the bias forms: ``b`` basis, then ``rate x`` the ``r`` basis."""
        basis = self._basis(x[:, 0])
        if form == "bias":
            return basis
        return np.hstack([basis, basis[:, :-1] * x[:, 1:2]])

    def fit(self, inputs: np.ndarray, targets: np.ndarray, init: np.ndarray | None = None,
            runs: np.ndarray | None = None) -> FitHistory:
        """One least-squares solve in normalised units; ``init`` is ignored (closed form);
        ``runs`` is each row's training run (needed by ``offsets="per_run"``, else ignored).
        Raises ``ValueError`` if the data cannot determine the coefficients (e.g. form
        ``inverse`` with a target that does not vary at the training temperatures)."""
        start = time.perf_counter()
        form = self._form_checked()
        x, y = self._scaled(inputs, targets)
        assert y is not None
        if form == "inverse":
            basis = self._basis(x[:, 1])
            design = np.hstack([basis, basis * y[:, None]])
            rhs = x[:, 0]
        else:
            design = self._design(x, form)
            rhs = y
        onehot = self._run_columns(runs, len(rhs))
        if onehot is not None:  # a constant per run in place of the shared one (Chebyshev T_0 = 1)
            design = np.hstack([onehot, design[:, 1:]])
        coef, _, rank, _ = np.linalg.lstsq(design, rhs, rcond=None)
        if onehot is not None:
            coef = np.concatenate([[coef[:onehot.shape[1]].mean()], coef[onehot.shape[1]:]])
        if rank < design.shape[1]:
            why = ("the target must vary at each temperature" if form == "inverse"
                   else "need more distinct temperatures than the degree"
                   + (" and a temperature rate that varies" if form == "bias_rate" else ""))
            raise ValueError(f"poly: form {form!r} of degree {self.settings.degree} is not determined "
                             f"by the training data ({why})")
        self._coef, self._form = coef, form
        loss = float(0.5 * np.mean((self._predict_scaled(x) - y) ** 2))
        return FitHistory(loss=[loss], iterations=1, stopped="closed_form",
                          seconds=time.perf_counter() - start)

    def _run_columns(self, runs: np.ndarray | None, n_rows: int) -> np.ndarray | None:
        """One indicator column per training run (``offsets="per_run"`` with two runs or more)."""
        if not self.uses_runs:
            return None
        if runs is None:
            raise ValueError("poly: offsets 'per_run' needs the run of each training row (fit(..., runs=))")
        runs = np.asarray(runs).reshape(-1)
        if runs.size != n_rows:
            raise ValueError(f"poly: runs has {runs.size} entries for {n_rows} training rows")
        labels, index = np.unique(runs, return_inverse=True)
        return None if labels.size < 2 else np.eye(labels.size)[index]

    def _predict_scaled(self, x: np.ndarray) -> np.ndarray:
        coef = self._fitted()
        if self._form == "inverse":
            basis = self._basis(x[:, 1])
            half = coef.size // 2
            return (x[:, 0] - basis @ coef[:half]) / (basis @ coef[half:])
        return self._design(x, self._form) @ coef

    def predict(self, inputs: np.ndarray) -> np.ndarray:
        self._fitted()
        x, _ = self._scaled(inputs)
        assert self.y_scaler is not None
        return self.y_scaler.inverse(self._predict_scaled(x))

    def describe(self) -> dict[str, Any]:
        """Name and parameters, with the fitted form when there is one."""
        out = super().describe()
        if self._form is not None:
            out["fitted_form"] = self._form
        return out
