"""Parallel VMD / sample-entropy / TFPF / learner pipeline for a gyro output (seed 001, §3.5,
Fig. 7, §4).

The gyro output (any rate unit, e.g. deg/s) is decomposed by VMD into ``k`` modes sorted by
centre frequency. Each mode is classed by its sample entropy: *noise* (irregular, high entropy)
modes are dropped, the sum of the *mixed* modes is denoised by TFPF, and the sum of the *drift*
(regular, entropy near 0) modes is compensated by a learner mapping ``[T (degC), dT/dt (degC/s)]``
to the drift (output unit). The result is the denoised mixed part plus the compensated drift part.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tcbench.compensation.features import temperature_rate_c_per_s
from tcbench.learners.base import Learner
from tcbench.signal.entropy import sample_entropy
from tcbench.signal.tfpf import tfpf
from tcbench.signal.vmd import vmd

LABELS = ("noise", "mixed", "drift")
ENTROPY_SAMPLES = 5000  # modes are decimated to at most this many samples for the entropy
DEFAULT_NOISE_ABOVE = 1.0
DEFAULT_DRIFT_BELOW = 0.1


@dataclass(frozen=True)
class ModeClasses:
    """Sample entropy (dimensionless, nats) and class label of each mode, with the thresholds."""

    entropy: np.ndarray
    label: tuple[str, ...]
    noise_above: float
    drift_below: float

    def mask(self, label: str) -> np.ndarray:
        """Boolean mask (k,) of the modes with ``label`` ("noise", "mixed" or "drift")."""
        if label not in LABELS:
            raise ValueError(f"label must be one of {', '.join(LABELS)}, got {label!r}")
        return np.array([lab == label for lab in self.label], dtype=bool)


def _check_thresholds(noise_above: float, drift_below: float) -> None:
    if not (np.isfinite(noise_above) and np.isfinite(drift_below) and 0.0 <= drift_below < noise_above):
        raise ValueError(f"need finite 0 <= drift_below < noise_above, got drift_below = {drift_below!r}, "
                         f"noise_above = {noise_above!r}")


def _mode_entropy(mode: np.ndarray, m: int, r: float) -> float:
    """Sample entropy of ``mode`` decimated by an integer stride to at most ``ENTROPY_SAMPLES``."""
    step = max(1, -(-mode.size // ENTROPY_SAMPLES))
    x = mode[::step]
    if float(np.std(x)) == 0.0:
        return 0.0  # a constant (empty) mode is perfectly regular
    se = sample_entropy(x, m=m, r=r)
    return float("inf") if np.isnan(se) else float(se)


def classify_modes(modes: np.ndarray, *, noise_above: float = DEFAULT_NOISE_ABOVE,
                   drift_below: float = DEFAULT_DRIFT_BELOW, m: int = 2, r: float = 0.2) -> ModeClasses:
    """Class each row of ``modes`` (k, n), sorted by centre frequency ascending, by sample entropy.

    The entropy (template length ``m``, tolerance ``r * std``) is computed on each mode decimated
    by an integer stride to at most 5000 samples, so it stays fast on long records. Entropy
    ``>= noise_above`` -> "noise", ``<= drift_below`` -> "drift", otherwise "mixed". A constant
    mode has entropy 0; an undefined entropy (no template matches) counts as ``inf`` (noise).
    The lowest-frequency mode (row 0) is always "drift", so there is at least one drift mode.

    Defaults (``noise_above = 1.0``, ``drift_below = 0.1``): in seed 001 the noise modes have
    entropy well above the mixed ones and the drift modes near 0. On the synthetic 1 Hz, 4 h
    gyro-like record of ``tests/test_gyro_pipeline.py`` (temperature steps through a lag, cubic
    drift in T, white noise; VMD k = 8, alpha = 2000) the lowest mode gives ~0.01, one mode ~0.72
    and the other six 1.04-1.47; with a 10x larger dT/dt term, two drift modes give ~0.01, two
    mixed ones 0.15-0.52 and the top four 1.07-1.64. These thresholds separate both.

    Raises ValueError for ``modes`` not 2-D with at least ``m + 2`` finite samples per row, or
    thresholds not ``0 <= drift_below < noise_above``.
    """
    u = np.asarray(modes, dtype=np.float64)
    if u.ndim != 2 or u.shape[0] < 1 or u.shape[1] < m + 2:
        raise ValueError(f"modes must have shape (k >= 1, n >= {m + 2}), got {u.shape}")
    if not np.isfinite(u).all():
        raise ValueError("modes must be finite")
    _check_thresholds(noise_above, drift_below)
    entropy = np.array([_mode_entropy(row, m, r) for row in u])
    labels = np.where(entropy >= noise_above, "noise", np.where(entropy <= drift_below, "drift", "mixed"))
    labels[0] = "drift"
    return ModeClasses(entropy=entropy, label=tuple(str(s) for s in labels),
                       noise_above=float(noise_above), drift_below=float(drift_below))


@dataclass(frozen=True)
class PipelineConfig:
    """Pipeline settings.

    k: number of VMD modes; alpha: VMD bandwidth penalty; tfpf_window: TFPF lag window
    (odd, samples); noise_above / drift_below: sample-entropy thresholds (:func:`classify_modes`).
    """

    k: int = 8
    alpha: float = 2000.0
    tfpf_window: int = 31
    noise_above: float = DEFAULT_NOISE_ABOVE
    drift_below: float = DEFAULT_DRIFT_BELOW

    def __post_init__(self) -> None:
        if isinstance(self.k, bool) or not isinstance(self.k, (int, np.integer)) or self.k < 1:
            raise ValueError(f"k must be an integer >= 1, got {self.k!r}")
        if not (np.isfinite(self.alpha) and self.alpha > 0):
            raise ValueError(f"alpha must be a finite number > 0, got {self.alpha!r}")
        w = self.tfpf_window
        if isinstance(w, bool) or not isinstance(w, (int, np.integer)) or w < 3 or w % 2 == 0:
            raise ValueError(f"tfpf_window must be an odd integer >= 3 samples, got {w!r}")
        _check_thresholds(self.noise_above, self.drift_below)


@dataclass(frozen=True)
class PipelineOutput:
    """Result of :meth:`ParallelPipeline.apply`; every part has the input length n, in output units.

    modes (k, n); classes; noise_part, mixed_part, drift_part: sums of the modes of each class;
    denoised_mixed: TFPF of mixed_part; predicted_drift: learner output on [T, dT/dt];
    compensated_drift: drift_part - predicted_drift; output: denoised_mixed + compensated_drift.
    """

    modes: np.ndarray
    classes: ModeClasses
    noise_part: np.ndarray
    mixed_part: np.ndarray
    drift_part: np.ndarray
    denoised_mixed: np.ndarray
    predicted_drift: np.ndarray
    compensated_drift: np.ndarray
    output: np.ndarray


def _check_record(t_s: np.ndarray, temp_c: np.ndarray, output: np.ndarray,
                  min_n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The three series as 1-D float64 arrays of one length >= ``min_n``; ValueError otherwise."""
    arrays = []
    for name, a in (("t_s", t_s), ("temp_c", temp_c), ("output", output)):
        x = np.asarray(a, dtype=np.float64)
        if x.ndim != 1:
            raise ValueError(f"{name} must be 1-D, got shape {x.shape}")
        if not np.isfinite(x).all():
            i = int(np.flatnonzero(~np.isfinite(x))[0])
            raise ValueError(f"{name} must be finite: {name}[{i}] = {x[i]}")
        arrays.append(x)
    t, temp, y = arrays
    if not t.size == temp.size == y.size:
        raise ValueError(f"lengths differ: t_s {t.size}, temp_c {temp.size}, output {y.size}")
    if t.size < min_n:
        raise ValueError(f"need at least {min_n} samples, got {t.size}")
    if np.any(np.diff(t) <= 0):
        raise ValueError("t_s must be strictly increasing")
    return t, temp, y


class ParallelPipeline:
    """Seed 001 parallel compensation: VMD, entropy classes, TFPF on mixed, learner on drift."""

    def __init__(self, config: PipelineConfig | None = None) -> None:
        self.config = config if config is not None else PipelineConfig()
        self.learner: Learner | None = None
        self.train_classes: ModeClasses | None = None

    def _min_n(self) -> int:
        return max(2 * self.config.k, self.config.tfpf_window, 8)

    def _decompose(self, y: np.ndarray) -> tuple[np.ndarray, ModeClasses]:
        c = self.config
        modes = vmd(y, c.k, c.alpha).modes
        return modes, classify_modes(modes, noise_above=c.noise_above, drift_below=c.drift_below)

    @staticmethod
    def _features(t: np.ndarray, temp: np.ndarray) -> np.ndarray:
        """Inputs (n, 2): temperature (degC) and causal temperature rate (degC/s)."""
        return np.column_stack((temp, temperature_rate_c_per_s(t, temp)))

    def fit(self, t_s: np.ndarray, temp_c: np.ndarray, output: np.ndarray, learner: Learner) -> ModeClasses:
        """Fit ``learner`` (2 inputs) on a training record: times (s), temperature (degC) and gyro
        output; its target is the sum of the drift modes. Returns the training mode classes."""
        t, temp, y = _check_record(t_s, temp_c, output, self._min_n())
        if not isinstance(learner, Learner) or learner.n_inputs != 2:
            raise ValueError("learner must be a tcbench Learner with n_inputs = 2 ([T, dT/dt])")
        modes, classes = self._decompose(y)
        learner.fit(self._features(t, temp), modes[classes.mask("drift")].sum(axis=0))
        self.learner, self.train_classes = learner, classes
        return classes

    def apply(self, t_s: np.ndarray, temp_c: np.ndarray, output: np.ndarray) -> PipelineOutput:
        """Compensate a record (times s, temperature degC, gyro output) with the fitted learner."""
        if self.learner is None:
            raise RuntimeError("apply() before fit()")
        t, temp, y = _check_record(t_s, temp_c, output, self._min_n())
        modes, classes = self._decompose(y)
        noise = modes[classes.mask("noise")].sum(axis=0)
        mixed = modes[classes.mask("mixed")].sum(axis=0)
        drift = modes[classes.mask("drift")].sum(axis=0)
        fs_hz = 1.0 / float(np.median(np.diff(t)))
        denoised = tfpf(mixed, self.config.tfpf_window, fs_hz=fs_hz)
        predicted = np.asarray(self.learner.predict(self._features(t, temp)), dtype=np.float64).reshape(-1)
        compensated = drift - predicted
        return PipelineOutput(modes=modes, classes=classes, noise_part=noise, mixed_part=mixed,
                              drift_part=drift, denoised_mixed=denoised, predicted_drift=predicted,
                              compensated_drift=compensated, output=denoised + compensated)
