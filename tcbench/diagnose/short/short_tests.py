"""The tests a record too short for a full diagnosis still supports (:mod:`tcbench.diagnose.short.short_record`).

- **temperature slope** (:func:`temperature_slope`): the output's least-squares slope against the
  smoothed thermometer, beside an intercept (and the input, and a significant level step); its
  standard error from the residual's spectrum (:mod:`tcbench.diagnose.select.spectral_se`), so
  correlated samples do not count as independent ones; a two-sided t test and the ``1 - alpha``
  interval. Along a one-way ramp it is also a drift in time: the report says so.
- **level step** (:func:`level_step`): the one step of the output's level, under the same
  temperature slope, that lowers the squared error most, searched at every sample at least
  ``min_side_samples`` (and ``side_share`` of the record) from either end. The search is
  exact and O(n): with ``e`` the residual of the base fit (orthonormal basis ``Q``) and ``H_k``
  the step at sample ``k``, the drop is ``(sum_{i>=k} e_i)^2 / (n - k - |sum_{i>=k} Q_i|^2)``.
  The step found is studentised, ``t^2 = (size / se)^2`` with the spectral standard error, and
  its p-value repeats search and studentisation on phase-randomised surrogates of the base
  fit's residual, step included (:func:`tcbench.diagnose.select.surrogate.phase_surrogates`), so the
  largest step of 100 000 positions is judged against the largest that noise as slow as the
  record's makes. Surrogates of the residual without the step found are quieter than the noise
  (that step takes out its largest slow excursion): on 200 s at 500 Hz of noise correlated over
  0.5 s, they called 2 of 8 records a step at p = 0.005 from raw drops and 1 of 8 studentised;
  these call none. The price is power: a real step's own power is in the surrogates (on the
  tests' record, 100 ug at 0.2 white sigmas is found at p = 0.005, 30 ug at p = 0.18).
  The size's interval is the spectral one at the step found.
- **white noise** (:func:`white_noise`): the white sigma from first differences and the Allan
  deviation of the residual at the taus the record allows (10 samples to a tenth of it) against
  the white line (:func:`tcbench.diagnose.select.locate.allan_excess`).

Each returns a :class:`ShortTest`; a test the record cannot support is ``not run`` with the reason.
The level, the fewest samples and the step's margins are :class:`~tcbench.diagnose.settings.ShortSettings`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tcbench.diagnose.select.locate import allan_excess, why_no_allan
from tcbench.diagnose.select.spectral_se import SpectralError, spectral_error
from tcbench.diagnose.select.surrogate import CHUNK, phase_surrogates
from tcbench.diagnose.settings import DEFAULTS, ShortSettings

SHORT = DEFAULTS.short
SIGNIFICANT, NOT_SIGNIFICANT, NOT_RUN = "significant", "not significant", "not run"
WHITE, NOT_WHITE = "white", "excess over white noise"


@dataclass
class ShortTest:
    """One test of a short record: ``id``, what it tests, its ``status`` (``significant``,
    ``not significant``, ``white``, ``excess over white noise`` or ``not run``), its numbers
    (in the report's output unit, per degC for a slope, s for times) and, when not run, why."""

    id: str
    what: str
    status: str
    values: dict[str, Any] = field(default_factory=dict)
    reason: str = ""

    @property
    def ran(self) -> bool:
        return self.status != NOT_RUN

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"id": self.id, "what": self.what, "status": self.status, **self.values}
        return out | ({"reason": self.reason} if self.reason else {})


def basis(columns: np.ndarray) -> np.ndarray:
    """Orthonormal basis (n, p) of the columns (n, p), scaled first for conditioning."""
    scale = np.sqrt(np.mean(columns * columns, axis=0))
    scale[scale == 0] = 1.0
    return np.linalg.qr(columns / scale)[0]


def _interval(value: float, err: SpectralError, alpha: float) -> dict[str, float]:
    half = err.quantile(alpha) * err.se
    return {"se": err.se, "ci_low": value - half, "ci_high": value + half, "ci_level": 1.0 - alpha, "dof": err.dof}


def temperature_slope(temp_c: np.ndarray, y: np.ndarray, others: np.ndarray,
                      settings: ShortSettings = SHORT) -> ShortTest:
    """The slope of ``y`` against ``temp_c`` beside the columns ``others`` (n, p), at ``settings.alpha``."""
    what = "slope of the output against temperature (standard error from the residual's spectrum)"
    n, alpha = y.size, settings.alpha
    if n < settings.min_fit_samples:
        return ShortTest("temperature_slope", what, NOT_RUN,
                         reason=f"needs at least {settings.min_fit_samples} samples; this record has {n}")
    q = basis(others)
    x = temp_c - q @ (q.T @ temp_c)
    sxx = float(x @ x)
    slope = float(x @ y) / sxx
    residual = y - q @ (q.T @ y) - slope * x
    err = spectral_error(x, residual)
    p = err.p_value(slope)
    values = {"slope_per_c": slope, **_interval(slope, err, alpha), "t": slope / err.se if err.se > 0 else float("inf"),
              "p_value": p, "se_white_noise_formula": err.se_white, "effective_samples": err.n_effective,
              "samples": n}
    return ShortTest("temperature_slope", what, SIGNIFICANT if p <= alpha else NOT_SIGNIFICANT, values)


def _side(n: int, settings: ShortSettings) -> int:
    return max(settings.min_side_samples, int(np.ceil(settings.side_share * n)))


def why_no_step(n: int, settings: ShortSettings = SHORT) -> str | None:
    """Why a record of ``n`` samples cannot be searched for a level step, or None."""
    need = 2 * settings.min_side_samples + 1
    if n >= need:
        return None
    return (f"needs at least {need} samples ({settings.min_side_samples} on either side of a step); this record "
            f"has {n}")


def step_drops(q: np.ndarray, e: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """SSE drop (m columns) of a level step starting at each sample ``lo <= k < hi``, for the
    residuals ``e`` (n, m) of a fit on the orthonormal columns ``q`` (n, p); 0 where the step
    lies in their span (a temperature step at the same sample)."""
    n = e.shape[0]
    tail_e = np.cumsum(e[::-1], axis=0)[::-1][lo:hi]
    tail_q = np.cumsum(q[::-1], axis=0)[::-1][lo:hi]
    width = (n - np.arange(lo, hi)).astype(float)
    norm2 = width - np.sum(tail_q * tail_q, axis=1)
    ok = norm2 > 1e-9 * width
    return np.where(ok[:, None], tail_e**2 / np.where(ok, norm2, 1.0)[:, None], 0.0)


@dataclass(frozen=True)
class _Step:
    """The best step of one residual: its first sample, column (orthogonal to the base), size,
    the residual without it, its spectral error and the studentised statistic ``(size / se)^2``."""

    k: int
    column: np.ndarray
    size: float
    residual: np.ndarray
    err: SpectralError

    @property
    def t2(self) -> float:
        return (self.size / self.err.se) ** 2 if self.err.se > 0 else float("inf")


def _best_step(q: np.ndarray, e: np.ndarray, k: int) -> _Step:
    """The step at sample ``k`` of the base fit's residual ``e`` (base basis ``q``)."""
    step = (np.arange(e.size) >= k).astype(float)
    h = step - q @ (q.T @ step)
    size = float(h @ e) / float(h @ h)
    residual = e - size * h
    return _Step(k, h, size, residual, spectral_error(h, residual))


def level_step(t_s: np.ndarray, y: np.ndarray, base: np.ndarray, rng: np.random.Generator, sigma: float,
               settings: ShortSettings = SHORT, draws: int = DEFAULTS.surrogate.draws
               ) -> tuple[ShortTest, np.ndarray | None]:
    """The largest level step of ``y`` beside the columns ``base`` (n, p), its size, interval and
    search-wide p-value (at most ``draws`` surrogates, at ``settings.alpha``); with the step's
    column (n,) when it is significant."""
    what = "one step of the output's level, searched at every sample (surrogate p-value of the search)"
    n, alpha = y.size, settings.alpha
    why = why_no_step(n, settings)
    if why is not None:
        return ShortTest("level_step", what, NOT_RUN, reason=why), None
    side = _side(n, settings)
    q = basis(base)
    e = y - q @ (q.T @ y)
    found = _best_step(q, e, side + int(np.argmax(step_drops(q, e[:, None], side, n - side)[:, 0])))
    exceed, done = 0, 0
    while done < draws:
        m = min(CHUNK, draws - done)
        z = phase_surrogates(e, m, rng)
        z -= q @ (q.T @ z)
        at = side + np.argmax(step_drops(q, z, side, n - side), axis=0)
        exceed += sum(_best_step(q, z[:, j], int(at[j])).t2 >= found.t2 for j in range(m))
        done += m
        if (1.0 + exceed) / (1.0 + draws) > alpha:
            break  # settled: not significant; the p-value is estimated from the draws made
    p = (1.0 + exceed) / (1.0 + done)
    size, err = found.size, found.err
    values = {"time_s": float(t_s[found.k]), "size": size, **_interval(size, err, alpha),
              "size_white_sigmas": size / sigma if sigma > 0 else float("inf"), "p_value": p,
              "surrogates": done, "searched_from_s": float(t_s[side]), "searched_to_s": float(t_s[n - side - 1]),
              "effective_samples": err.n_effective}
    significant = p <= alpha
    column = (np.arange(n) >= found.k).astype(float)
    return ShortTest("level_step", what, SIGNIFICANT if significant else NOT_SIGNIFICANT, values), (
        column if significant else None)


def white_noise(t_s: np.ndarray, residual: np.ndarray, sigma: float, sample_rate_hz: float,
                alpha: float = SHORT.alpha, min_allan_samples: int = DEFAULTS.locate.min_allan_samples) -> ShortTest:
    """The white sigma and density of the output and the residual's Allan deviation against the
    white line at the taus the record allows (from ``min_allan_samples`` samples), at ``alpha``."""
    what = "white-noise level: sigma from first differences, Allan deviation against the white line"
    values: dict[str, Any] = {"white_sigma": sigma, "density_per_sqrt_hz": sigma / float(np.sqrt(sample_rate_hz))}
    why = why_no_allan(t_s, min_allan_samples)
    ex = None if why else allan_excess(t_s, residual, sigma, alpha, estimated=True, min_samples=min_allan_samples)
    if ex is None:
        return ShortTest("white_noise", what, NOT_RUN, values, reason=why or "no Allan deviation on this record")
    values |= {"tau_s": ex.tau_s.tolist(), "allan_deviation": ex.adev.tolist(), "white_line": ex.white.tolist(),
               "bound_ratio": ex.bound.tolist(), "tau_max_s": float(ex.tau_s[-1])}
    if ex.first_over is None:
        return ShortTest("white_noise", what, WHITE, values)
    values["excess_from_tau_s"] = float(ex.tau_s[ex.first_over])
    return ShortTest("white_noise", what, NOT_WHITE, values)
