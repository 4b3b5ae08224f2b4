"""A significance test for recordings too short for the cluster-robust Wald test.

Null hypothesis: the candidate effect is absent and what it seems to explain is noise as slow
as the residual the model leaves. The noise model is the candidate model's own in-sample
residual: surrogates with exactly its power spectrum and random phases (phase randomisation,
Theiler et al. 1992; a Gaussian noise with the residual's autocovariance, all time scales kept,
flicker and any structure still unexplained included, which makes the test conservative).
Each surrogate is added to the starting model's fit and the whole search is repeated on it:
the statistic is the largest in-sample drop of squared error over every candidate value of the
effect's nonlinear parameter, exactly as for the recording. The p-value is
``(1 + #{surrogate >= observed}) / (1 + draws)``; the draws stop as soon as the p-value is sure
to exceed the test's level (then it is estimated from the draws made); the draws and the level
are the :class:`~tcbench.diagnose.settings.SurrogateSettings` given.

Everything is linear least squares on fixed design matrices, so all surrogates are scored at
once through the QR factor of each design (O(n p draws)). Time is the sample index (bursts are
joined end to end); every draw comes from the ``numpy.random.Generator`` passed in.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tcbench.diagnose.settings import DEFAULTS, SurrogateSettings

CHUNK = 64  # surrogates scored together (memory n x CHUNK)


def phase_surrogates(r: np.ndarray, draws: int, rng: np.random.Generator) -> np.ndarray:
    """``draws`` series (n, draws) with the periodogram of ``r`` (mean removed) and uniform
    random phases."""
    n = r.size
    spec = np.fft.rfft(r - r.mean())
    phase = rng.uniform(0.0, 2.0 * np.pi, size=(spec.size, draws))
    phase[0] = 0.0
    if n % 2 == 0:
        phase[-1] = 0.0
    return np.fft.irfft(np.abs(spec)[:, None] * np.exp(1j * phase), n=n, axis=0)


def _basis(x: np.ndarray) -> np.ndarray:
    scale = np.sqrt(np.mean(x * x, axis=0))
    scale[scale == 0] = 1.0
    return np.linalg.qr(x / scale)[0]


def surrogate_test(
    base_x: np.ndarray,
    candidate_xs: Sequence[np.ndarray],
    y: np.ndarray,
    noise: np.ndarray,
    rng: np.random.Generator,
    settings: SurrogateSettings = DEFAULTS.surrogate,
) -> tuple[float, float]:
    """``(p_value, observed drop)`` of adding an effect to the model of design ``base_x``
    (n, p), the effect searched over the designs ``candidate_xs`` (one per value of its
    nonlinear parameter); ``noise`` is the null model's residual (output unit), ``y`` the
    output. The drop is the largest in-sample SSE reduction, in output unit squared; at most
    ``settings.draws`` surrogates, stopped once the p-value is sure to exceed ``settings.level``."""
    qb = _basis(base_x)
    qall = np.ascontiguousarray(np.hstack([qb, *(_basis(x) for x in candidate_xs)]).T)  # (P, n)
    starts = np.cumsum([0, qb.shape[1], *(x.shape[1] for x in candidate_xs)])[:-1]

    def drops(ys: np.ndarray) -> np.ndarray:
        """Largest SSE(base) - SSE(candidate) = |Q_c' y|^2 - |Q_b' y|^2 per column of ``ys``."""
        proj = qall @ ys
        per = np.add.reduceat(proj * proj, starts, axis=0)  # (1 + candidates, m)
        return np.max(per[1:] - per[0], axis=0)

    observed = float(drops(y[:, None])[0])
    fitted = qb @ (qb.T @ y)  # the starting model's fit: the null's deterministic part
    draws, level = settings.draws, settings.level
    exceed = 0
    done = 0
    while done < draws:
        m = min(CHUNK, draws - done)
        ys = np.ascontiguousarray(fitted[:, None] + phase_surrogates(noise, m, rng))
        exceed += int(np.sum(drops(ys) >= observed))
        done += m
        if (1.0 + exceed) / (1.0 + draws) > level:
            break  # the verdict is settled; the p-value below is estimated from the draws made
    return (1.0 + exceed) / (1.0 + done), observed
