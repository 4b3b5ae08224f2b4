"""Parallel VMD / sample-entropy / TFPF / learner pipeline for a gyro output (seed 001, §3.5,
Fig. 7, §4), and the serial and EMD variants its rivals use.

The gyro output (deg/s) is decomposed into modes sorted by centre frequency (VMD, seed 001
eq. 1-7, or EMD). Each mode is classed by its sample entropy: *noise* (irregular, high entropy)
modes are dropped, the sum of the *mixed* modes is denoised (TFPF, or a wavelet threshold), and
the sum of the *drift* (regular, entropy near 0) modes is compensated by a learner mapping
``[T (degC), dT/dt (degC/s)]`` (or ``[T]``) to the drift. The result is the denoised mixed part
plus the compensated drift part. With ``decomposition="none"`` the pipeline is serial: the
learner's drift is removed from the whole output, which the denoiser then smooths.

The drift is slow, so the learner works on block means (``learner_block_s``, default 10 s): it
is trained on the block means of its inputs and target, and its block-rate prediction is
linearly interpolated back to every sample. A recurrent learner (Elman) then sees one step per
block, the same on every record whatever its sample rate.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tcbench.compensation.features import temperature_rate_c_per_s
from tcbench.learners.base import FitHistory, Learner
from tcbench.signal.denoise import emd_imfs, wavelet_denoise
from tcbench.signal.entropy import sample_entropy
from tcbench.signal.tfpf import tfpf
from tcbench.signal.vmd import vmd

LABELS = ("noise", "mixed", "drift")


def _vmd_modes(y: np.ndarray, config: PipelineConfig) -> np.ndarray:
    return vmd(y, config.k, config.alpha).modes


def _emd_modes(y: np.ndarray, config: PipelineConfig) -> np.ndarray:
    return emd_imfs(y)[::-1]  # the residue first, then the IMFs from the slowest


# The decompositions of a parallel pipeline: ``(output, config) -> modes (k, n)`` sorted by centre
# frequency ascending; ``none`` (not here) is the serial pipeline, which decomposes nothing.
DECOMPOSERS: dict[str, Callable[[np.ndarray, PipelineConfig], np.ndarray]] = {"vmd": _vmd_modes, "emd": _emd_modes}
DECOMPOSITIONS = (*DECOMPOSERS, "none")
TUNED = ("vmd",)  # the decompositions whose k and alpha a job tunes when the task leaves them unset


def _no_denoise(x: np.ndarray, window: int, fs_hz: float, level: int | None) -> np.ndarray:
    return x.copy()


# The denoisers: ``(x, tfpf window, fs_hz, wavelet level) -> denoised x``.
DENOISERS: dict[str, Callable[[np.ndarray, int, float, int | None], np.ndarray]] = {
    "tfpf": lambda x, window, fs_hz, level: tfpf(x, window, fs_hz=fs_hz),
    "wavelet": lambda x, window, fs_hz, level: wavelet_denoise(x, level=level),
    "none": _no_denoise,
}
INPUTS = ("t_rate", "t")
ENTROPY_WINDOWS = 4  # contiguous windows a mode's sample entropy is averaged over
ENTROPY_SAMPLES = 1250  # samples per window
DEFAULT_NOISE_ABOVE = 0.5
DEFAULT_DRIFT_BELOW = 0.15


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
    """Mean sample entropy of ``mode`` over ``ENTROPY_WINDOWS`` contiguous windows of
    ``ENTROPY_SAMPLES`` samples spread evenly over the record (the whole mode if shorter).

    Contiguous windows keep the mode's own time scale; a strided decimation would alias a slow
    but locally smooth mode into something that looks like white noise."""
    n = mode.size
    size = min(n, ENTROPY_SAMPLES)
    starts = np.unique(np.linspace(0, n - size, ENTROPY_WINDOWS).astype(int))
    values = []
    for s in starts:
        x = mode[s:s + size]
        if float(np.std(x)) == 0.0:
            values.append(0.0)  # a constant (empty) window is perfectly regular
            continue
        se = sample_entropy(x, m=m, r=r)
        values.append(float("inf") if np.isnan(se) else float(se))
    return float(np.mean(values))


def classify_modes(modes: np.ndarray, *, noise_above: float = DEFAULT_NOISE_ABOVE,
                   drift_below: float = DEFAULT_DRIFT_BELOW, m: int = 2, r: float = 0.2) -> ModeClasses:
    """Class each row of ``modes`` (k, n), sorted by centre frequency ascending, by sample entropy.

    The entropy (template length ``m``, tolerance ``r * std`` of the window) is the mean over four
    contiguous windows of 1250 samples spread over the record, so it stays fast on long records.
    Entropy ``>= noise_above`` -> "noise", ``<= drift_below`` -> "drift", otherwise "mixed". A
    constant window has entropy 0; an undefined entropy (no template matches) counts as ``inf``
    (noise). The lowest-frequency mode (row 0) is always "drift", so there is at least one.

    Defaults (``noise_above = 0.5``, ``drift_below = 0.15``), set on the simulated 10 Hz oven
    run of ``tcbench/Gyro-DriftNoise-v0`` (device 0): VMD modes of white noise are narrow-band
    and locally regular, so their entropy is not the ~2.2 of white noise itself but 0.3-0.65
    (k = 8, alpha = 9755: 0.59, 0.54, 0.40, 0.34, 0.43, 0.53, 0.61 above the drift mode's 0.09;
    alpha = 2000: 0.59-0.62 above 0.18). Seed 001 states no values; with these thresholds the
    modes nearest the drift and the highest ones are noise, those between mixed.

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


def _int_at_least(value: object, name: str, minimum: int) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")


@dataclass(frozen=True)
class PipelineConfig:
    """Pipeline settings.

    decomposition: "vmd" (seed 001), "emd" (its EMD rival) or "none" (serial: compensate, then
        denoise the whole output).
    k, alpha: VMD modes and bandwidth penalty (vmdpy's alpha convention, see signal.vmd).
    denoise: "tfpf" (seed 001), "wavelet" (universal soft threshold) or "none".
    tfpf_window: TFPF lag window (odd, samples).
    wavelet_level: the wavelet threshold's decomposition depth; None: the deepest the record allows
        (``pywt.dwt_max_level``, 16 for a 14 h record at 10 Hz). What the threshold removes, and so
        its ARW and the bandwidth it keeps, is a function of it (``experiments/paper_movmd_tfpf``).
    noise_above / drift_below: sample-entropy thresholds (:func:`classify_modes`).
    inputs: learner inputs, "t_rate" ([T, dT/dt], seed 001 eq. 28) or "t" ([T]).
    rate_window_s: trailing window of the dT/dt input (s).
    learner_block_s: block length the learner is trained and predicts at (s).
    """

    decomposition: str = "vmd"
    k: int = 8
    alpha: float = 2000.0
    denoise: str = "tfpf"
    tfpf_window: int = 31
    wavelet_level: int | None = None
    noise_above: float = DEFAULT_NOISE_ABOVE
    drift_below: float = DEFAULT_DRIFT_BELOW
    inputs: str = "t_rate"
    rate_window_s: float = 120.0
    learner_block_s: float = 10.0

    def __post_init__(self) -> None:
        for name, value, known in (("decomposition", self.decomposition, DECOMPOSITIONS),
                                   ("denoise", self.denoise, DENOISERS), ("inputs", self.inputs, INPUTS)):
            if value not in known:
                raise ValueError(f"{name} must be one of {', '.join(known)}, got {value!r}")
        _int_at_least(self.k, "k", 1)
        if not (np.isfinite(self.alpha) and self.alpha > 0):
            raise ValueError(f"alpha must be a finite number > 0, got {self.alpha!r}")
        _int_at_least(self.tfpf_window, "tfpf_window", 3)
        if self.tfpf_window % 2 == 0:
            raise ValueError(f"tfpf_window must be an odd integer >= 3 samples, got {self.tfpf_window!r}")
        if self.wavelet_level is not None:
            _int_at_least(self.wavelet_level, "wavelet_level", 1)
        _check_thresholds(self.noise_above, self.drift_below)
        for name, value in (("rate_window_s", self.rate_window_s), ("learner_block_s", self.learner_block_s)):
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number of seconds, got {value!r}")

    @property
    def serial(self) -> bool:
        """Whether the pipeline is serial (``decomposition="none"``: no decomposition)."""
        return self.decomposition not in DECOMPOSERS

    @property
    def n_inputs(self) -> int:
        """Inputs of the drift learner: 2 ([T, dT/dt]) or 1 ([T])."""
        return 2 if self.inputs == "t_rate" else 1


@dataclass(frozen=True)
class FrontEnd:
    """The learner-independent stages on one record: modes (k, n) and their classes (None for
    the serial pipeline), the parts summed per class and the denoised mixed part (n,)."""

    modes: np.ndarray | None
    classes: ModeClasses | None
    noise_part: np.ndarray
    mixed_part: np.ndarray
    drift_part: np.ndarray
    denoised_mixed: np.ndarray


@dataclass(frozen=True)
class PipelineOutput:
    """Result of :meth:`ParallelPipeline.apply`; every part has the input length n, in output units.

    modes (k, n) and classes (None for the serial pipeline); noise_part, mixed_part, drift_part:
    sums of the modes of each class (serial: zeros, zeros and the whole output); denoised_mixed;
    predicted_drift: learner output interpolated to every sample (zeros without a learner);
    compensated_drift: drift_part - predicted_drift; output: the pipeline's result.
    """

    modes: np.ndarray | None
    classes: ModeClasses | None
    noise_part: np.ndarray
    mixed_part: np.ndarray
    drift_part: np.ndarray
    denoised_mixed: np.ndarray
    predicted_drift: np.ndarray
    compensated_drift: np.ndarray
    output: np.ndarray


def check_record(t_s: np.ndarray, temp_c: np.ndarray, output: np.ndarray,
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


def block_index(t_s: np.ndarray, block_s: float) -> np.ndarray:
    """Block number of each sample: consecutive blocks of ``block_s`` seconds from the first."""
    return ((t_s - t_s[0]) // block_s).astype(np.int64)


def block_means(block: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Mean of ``values`` (n,) or (n, m) over each block of ``block`` (n,), blocks in order."""
    counts = np.bincount(block)
    v = values.reshape(len(values), -1)
    sums = np.stack([np.bincount(block, weights=col, minlength=counts.size) for col in v.T], axis=1)
    means = sums[counts > 0] / counts[counts > 0, None]
    return means.reshape(-1) if values.ndim == 1 else means


def denoise(x: np.ndarray, how: str, window: int, fs_hz: float, level: int | None = None) -> np.ndarray:
    """``x`` through the denoiser ``how`` ("tfpf", "wavelet" at ``level``, or "none")."""
    return DENOISERS.get(how, _no_denoise)(x, window, fs_hz, level)


def decompose(y: np.ndarray, config: PipelineConfig) -> np.ndarray:
    """Modes (k, n) of ``y`` sorted by centre frequency ascending (VMD or EMD; EMD's residue
    first, then its IMFs from the slowest)."""
    return DECOMPOSERS[config.decomposition](y, config)


def front_end(y: np.ndarray, fs_hz: float, config: PipelineConfig) -> FrontEnd:
    """Decomposition, classes and the denoised mixed part of ``y`` (learner-independent)."""
    if config.serial:
        zeros = np.zeros_like(y)
        return FrontEnd(None, None, zeros, zeros, y.copy(), zeros)
    modes = decompose(y, config)
    classes = classify_modes(modes, noise_above=config.noise_above, drift_below=config.drift_below)
    mixed = modes[classes.mask("mixed")].sum(axis=0)
    return FrontEnd(modes, classes, modes[classes.mask("noise")].sum(axis=0), mixed,
                    modes[classes.mask("drift")].sum(axis=0), denoise(mixed, config.denoise, config.tfpf_window, fs_hz,
                                                                        config.wavelet_level))


class ParallelPipeline:
    """Seed 001 parallel compensation: decomposition, entropy classes, denoised mixed part,
    learner on the drift part (or the serial variant, see the module docstring)."""

    def __init__(self, config: PipelineConfig | None = None) -> None:
        self.config = config if config is not None else PipelineConfig()
        self.learner: Learner | None = None
        self.train_classes: ModeClasses | None = None

    def min_samples(self) -> int:
        """Fewest samples a record needs."""
        return max(2 * self.config.k, self.config.tfpf_window, 8)

    def features(self, t: np.ndarray, temp: np.ndarray) -> np.ndarray:
        """Learner inputs (n, 1 or 2): temperature (degC) and its causal rate (degC/s)."""
        if self.config.inputs == "t":
            return temp.reshape(-1, 1)
        return np.column_stack((temp, temperature_rate_c_per_s(t, temp, self.config.rate_window_s)))

    def training_set(self, t_s: np.ndarray, temp_c: np.ndarray, front: FrontEnd) -> tuple[np.ndarray, np.ndarray]:
        """Block means of the learner's inputs (blocks, n_inputs) and of the drift part (blocks,)."""
        block = block_index(np.asarray(t_s, dtype=np.float64), self.config.learner_block_s)
        if np.bincount(block).size < 2 or np.count_nonzero(np.bincount(block)) < 4:
            raise ValueError(f"the record holds fewer than 4 blocks of learner_block_s = "
                             f"{self.config.learner_block_s:g} s")
        return block_means(block, self.features(t_s, temp_c)), block_means(block, front.drift_part)

    def front(self, t_s: np.ndarray, temp_c: np.ndarray, output: np.ndarray) -> FrontEnd:
        """Checked record through the learner-independent stages."""
        t, _, y = check_record(t_s, temp_c, output, self.min_samples())
        return front_end(y, 1.0 / float(np.median(np.diff(t))), self.config)

    def fit(self, t_s: np.ndarray, temp_c: np.ndarray, output: np.ndarray, learner: Learner | None,
            init: np.ndarray | None = None, front: FrontEnd | None = None) -> tuple[ModeClasses | None, FitHistory | None]:
        """Fit ``learner`` on a training record (times s, temperature degC, gyro output) from
        ``init``; its target is the drift part. ``None``: no drift compensation. ``front``
        reuses the record's :meth:`front`. Returns the training classes and the fit history."""
        t, temp, y = check_record(t_s, temp_c, output, self.min_samples())
        front = front if front is not None else front_end(y, 1.0 / float(np.median(np.diff(t))), self.config)
        history = None
        if learner is not None:
            if not isinstance(learner, Learner) or learner.n_inputs != self.config.n_inputs:
                raise ValueError(f"learner must be a tcbench Learner with n_inputs = {self.config.n_inputs} "
                                 f"(inputs {self.config.inputs})")
            history = learner.fit(*self.training_set(t, temp, front), init=init)
        self.learner, self.train_classes = learner, front.classes
        return front.classes, history

    def predict_drift(self, t: np.ndarray, temp: np.ndarray) -> np.ndarray:
        """The learner's drift at every sample (block-rate prediction, linearly interpolated)."""
        if self.learner is None:
            return np.zeros_like(t)
        block = block_index(t, self.config.learner_block_s)
        x = block_means(block, self.features(t, temp))
        centre = block_means(block, t)
        pred = np.asarray(self.learner.predict(x), dtype=np.float64).reshape(-1)
        return np.interp(t, centre, pred)

    def apply(self, t_s: np.ndarray, temp_c: np.ndarray, output: np.ndarray,
              front: FrontEnd | None = None) -> PipelineOutput:
        """Compensate a record (times s, temperature degC, gyro output) with the fitted learner;
        ``front`` reuses the record's :meth:`front`."""
        t, temp, y = check_record(t_s, temp_c, output, self.min_samples())
        fs_hz = 1.0 / float(np.median(np.diff(t)))
        f = front if front is not None else front_end(y, fs_hz, self.config)
        predicted = self.predict_drift(t, temp)
        compensated = f.drift_part - predicted
        if self.config.serial:
            out = denoise(compensated, self.config.denoise, self.config.tfpf_window, fs_hz, self.config.wavelet_level)
        else:
            out = f.denoised_mixed + compensated
        return PipelineOutput(modes=f.modes, classes=f.classes, noise_part=f.noise_part, mixed_part=f.mixed_part,
                              drift_part=f.drift_part, denoised_mixed=f.denoised_mixed, predicted_drift=predicted,
                              compensated_drift=compensated, output=out)
