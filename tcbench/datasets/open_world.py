"""Recordings with a mismatch hidden that lies outside the effect library (open world).

Each recording is a concealed recording (:mod:`tcbench.datasets.concealed`: the same 1 Hz,
8-12 h heat-and-cool staircase, the same device with every effect removed, so that without
the hidden mismatch it *is* the minimal model plus white noise) with one structure of
docs/concepts/diagnosis-report.md, shapes that no library effect makes. The kinds (:data:`KINDS`), with the ``shape`` and
``where`` the report must state:

- ``step``: a bias jump at one instant (``time_s``);
- ``restart_after_gap``: 5-30 min of data lost and a bias jump across the gap (``time_s`` = the
  first sample after it);
- ``periodic``: a sinusoid of 10-40 min period (``period_s``);
- ``slow_oscillation``: a sinusoid of 2-5 h period (``period_s``);
- ``compressor_cycling``: a bias offset switched on and off with a period of 10-40 min (duty
  30-70 %) while the chamber holds the package more than 1 degC below room temperature, as a
  chamber compressor loading the supply (``period_s``);
- ``transient``: a jump that decays exponentially (tau 10-60 min) from an instant in the middle
  60 % of the record (``time_s`` = onset);
- ``temperature_bump``: a Gaussian of the package temperature, width 2-6 degC, centred inside the
  profile's range (``temperature_c`` = centre -/+ 2 widths);
- ``second_node``: ``coef * (lag(T_pkg, tau2) - T_pkg)``, tau2 20-90 min (no ``where``);
- ``variance_temperature``: white sigma growing exponentially from cold to hot by a factor 2-4
  (``temperature_c`` = the upper half of the range);
- ``saturation``: the output clipped (ceiling or floor) at a level the noise-free output
  reaches only in one temperature band (``level``);
- ``output_quantisation``: the output read on a grid of step q (``level`` = q);
- ``thermometer_steps``: the thermometer read in whole degrees (``level`` = 1.0);
- ``spikes``: 1-5 isolated samples off by 8-20 sigma (``time_s`` = their instants).

Sizing, "what the starting model cannot absorb is 0.5-1 sigma per sample":

- additive kinds (:data:`ADDITIVE`): the noise-free contribution ``d`` is projected out of the
  minimal model's columns (:func:`~tcbench.datasets.concealed.minimal_columns` of the package
  temperature and the acceleration, on the samples kept), and its amplitude is set so that the
  RMS of what is left is ``rho * sigma``, ``rho ~ U(0.5, 1)``, with the white sigma the device's
  own times a log-uniform factor in 1-3 (as for the concealed set's free-amplitude effects);
- ``saturation`` and ``thermometer_steps``: the white sigma stays the device's times the
  factor and the device's *temperature sensitivity* is set instead: the noise-free output is
  split into its part on the columns without temperature (``1``, ``a``) and the part that moves
  with temperature, and the latter is multiplied by ``k`` so that what the minimal model cannot
  absorb is ``rho * sigma`` (params ``tempco_scale``). For ``saturation`` that is the noise-free
  clipped amount; the clipping side is random and the level is the one whose clipped samples (at
  the extreme input on that side) fill one temperature band spanning the drawn 15-40 % of the
  temperature range (as close as the profile allows); the clip acts on output plus noise. For ``thermometer_steps`` it is the output the minimal model *in the read temperature*
  cannot absorb;
- ``output_quantisation``: ``q = sqrt(12) * rho * sigma``, so the rounding error's RMS is
  ``rho * sigma``;
- ``variance_temperature``: cold-end sigma = device sigma times the factor, hot/cold ratio 2-4;
  the truth's ``white_sigma`` is the RMS over samples of the per-sample sigma;
- ``spikes``: sizes 8-20 white sigma, random sign, at least 5 min apart, in the middle 90 %.

Controls have nothing hidden (white sigma = device sigma times the factor). Every random draw
comes from generators spawned from ``np.random.SeedSequence(seed)``, always in the same order,
so one seed gives one profile and one device whatever the kind, and the same recording twice.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tcbench.datasets.concealed import (
    NOISE_FACTOR,
    SAMPLE_RATE_HZ,
    THERMOMETER_NOISE_C,
    THERMOMETER_STEP_C,
    concealed_profile,
    device_without_effects,
    minimal_columns,
    unexplained,
)
from tcbench.errors import unknown_name
from tcbench.sensors import noise
from tcbench.sensors.effects import (
    BiasStep,
    Effect,
    Periodic,
    SecondNode,
    Signals,
    TemperatureBump,
    Transient,
)
from tcbench.sensors.recording import Recording, make_recording
from tcbench.sensors.kinds import get as sensor_kind
from tcbench.sensors.kinds import profile_input

SHAPE: dict[str, str] = {
    "step": "step",
    "restart_after_gap": "step",
    "periodic": "periodic",
    "slow_oscillation": "periodic",
    "compressor_cycling": "periodic",
    "transient": "transient",
    "temperature_bump": "temperature_function",
    "second_node": "temperature_dynamics",
    "variance_temperature": "variance",
    "saturation": "saturation",
    "output_quantisation": "quantisation",
    "thermometer_steps": "quantisation",
    "spikes": "outliers",
}
KINDS: tuple[str, ...] = tuple(SHAPE)
SENSORS = ("msra", "gyro")

RATIO = (0.5, 1.0)
STEP_AT = (0.15, 0.85)  # fraction of the span
GAP_AT = (0.2, 0.8)
GAP_S = (300.0, 1800.0)
PERIOD_S = (600.0, 2400.0)
SLOW_PERIOD_S = (7200.0, 18000.0)
DUTY = (0.3, 0.7)  # share of each compressor cycle it runs
COMPRESSOR_BELOW_C = 1.0  # the compressor runs while the package is this much below room temperature
TRANSIENT_AT = (0.2, 0.8)
TRANSIENT_TAU_S = (600.0, 3600.0)
BUMP_WIDTH_C = (2.0, 6.0)
SECOND_NODE_TAU_S = (1200.0, 5400.0)
VARIANCE_GROWTH = (2.0, 4.0)  # sigma hot / sigma cold
CLIP_BAND = (0.15, 0.4)  # share of the temperature range where the output clips
THERMOMETER_STEPS_C = 1.0
SPIKES = (1, 5)
SPIKE_SIGMA = (8.0, 20.0)
SPIKE_SEPARATION_S = 600.0


@dataclass(frozen=True)
class OpenWorld:
    """What was hidden: ``kind`` (``None`` for a control), the ``shape`` and ``where`` a report
    must state (keys of :data:`tcbench.diagnose.findings.WHERE_KEYS`), the kind's parameters
    (output units, s, degC), ``ratio`` (RMS the minimal model cannot absorb / white sigma; NaN
    where it does not apply), the white sigma (output unit; the RMS of the per-sample sigma for
    ``variance_temperature``), the recording's time span (s) and the seed."""

    sensor: str
    kind: str | None
    shape: str | None
    where: dict[str, Any]
    params: dict[str, float]
    ratio: float
    white_sigma: float
    span_s: float
    seed: int

    @property
    def deterministic(self) -> bool:
        """Whether a model term can take the hidden structure out (the refit target applies)."""
        return self.kind in DETERMINISTIC


@dataclass
class _Draw:
    """Intermediate arrays of one recording (all full length before ``keep``)."""

    t_s: np.ndarray
    temp_c: np.ndarray
    accel: np.ndarray | None
    base: np.ndarray
    keep: np.ndarray
    room_c: float
    params: dict[str, float] = field(default_factory=dict)
    where: dict[str, Any] = field(default_factory=dict)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x * x)))


def _left(d: np.ndarray, draw: _Draw, temp_c: np.ndarray | None = None) -> float:
    """RMS of what the minimal model's columns (of ``temp_c``, default the package temperature)
    cannot absorb of ``d``, on the samples kept."""
    k = draw.keep
    temp = draw.temp_c if temp_c is None else temp_c
    cols = minimal_columns(temp[k], None if draw.accel is None else draw.accel[k])
    return _rms(unexplained(d[k], cols))


def _at(t_s: np.ndarray, frac: tuple[float, float], rng: np.random.Generator) -> int:
    """Index of the first sample at or after a uniform fraction ``frac`` of the span."""
    target = t_s[0] + rng.uniform(*frac) * (t_s[-1] - t_s[0])
    return int(np.searchsorted(t_s, target))


def _term(effect: Effect, draw: _Draw, rng: np.random.Generator) -> np.ndarray:
    """The output term of a library effect (:mod:`tcbench.sensors.effects`) on the draw's clock,
    with the package temperature as the die's."""
    zeros = np.zeros_like(draw.t_s)
    s = Signals(t_s=draw.t_s, dt_s=1.0 / SAMPLE_RATE_HZ, temp_meas_c=draw.temp_c, temp_die_c=draw.temp_c,
                temp_rate_c_per_s=zeros, accel_g=zeros, cross_g=zeros, rate_dps=zeros)
    return effect.term(s, rng)


def _step(draw: _Draw, rng: np.random.Generator, sign: float) -> tuple[np.ndarray, str]:
    t0 = float(draw.t_s[_at(draw.t_s, STEP_AT, rng)])
    draw.params["time_s"], draw.where["time_s"] = t0, t0
    return _term(BiasStep(time_s=t0, size=sign), draw, rng), "jump"


def _restart_after_gap(draw: _Draw, rng: np.random.Generator, sign: float) -> tuple[np.ndarray, str]:
    t = draw.t_s
    start = float(t[_at(t, GAP_AT, rng)])
    gap_s = float(np.round(rng.uniform(*GAP_S)))
    draw.keep = ~((t >= start) & (t < start + gap_s))
    after = float(t[np.searchsorted(t, start + gap_s)])
    draw.params |= {"gap_start_s": start, "gap_s": gap_s, "time_s": after}
    draw.where["time_s"] = after
    return _term(BiasStep(time_s=after, size=sign), draw, rng), "jump"


def _sinusoid(period_range_s: tuple[float, float]) -> Callable[[_Draw, np.random.Generator, float],
                                                                tuple[np.ndarray, str]]:
    """The pattern of a sinusoid whose period is drawn in ``period_range_s``."""

    def pattern(draw: _Draw, rng: np.random.Generator, sign: float) -> tuple[np.ndarray, str]:
        period = float(rng.uniform(*period_range_s))
        phase = float(rng.uniform(0.0, 2.0 * np.pi))
        draw.params |= {"period_s": period, "phase_rad": phase}
        draw.where["period_s"] = period
        return _term(Periodic(period_s=period, amplitude=sign, phase_rad=phase), draw, rng), "amplitude"

    return pattern


def _compressor_cycling(draw: _Draw, rng: np.random.Generator, sign: float) -> tuple[np.ndarray, str]:
    period = float(rng.uniform(*PERIOD_S))
    duty = float(rng.uniform(*DUTY))
    phase = float(rng.uniform(0.0, 1.0))
    below_c = draw.room_c - COMPRESSOR_BELOW_C
    draw.params |= {"period_s": period, "duty": duty, "phase_cycles": phase, "below_c": below_c}
    draw.where["period_s"] = period
    running = (np.mod(draw.t_s / period + phase, 1.0) < duty) & (draw.temp_c < below_c)
    return sign * running.astype(float), "jump"


def _transient(draw: _Draw, rng: np.random.Generator, sign: float) -> tuple[np.ndarray, str]:
    t0 = float(draw.t_s[_at(draw.t_s, TRANSIENT_AT, rng)])
    tau = float(rng.uniform(*TRANSIENT_TAU_S))
    draw.params |= {"time_s": t0, "tau_s": tau}
    draw.where["time_s"] = t0
    return _term(Transient(time_s=t0, tau_s=tau, amplitude=sign), draw, rng), "jump"


def _temperature_bump(draw: _Draw, rng: np.random.Generator, sign: float) -> tuple[np.ndarray, str]:
    width = float(rng.uniform(*BUMP_WIDTH_C))
    lo, hi = float(draw.temp_c.min()), float(draw.temp_c.max())
    centre = float(rng.uniform(lo + width, hi - width))
    draw.params |= {"centre_c": centre, "width_c": width}
    draw.where["temperature_c"] = [centre - 2.0 * width, centre + 2.0 * width]
    return _term(TemperatureBump(centre_c=centre, width_c=width, amplitude=sign), draw, rng), "amplitude"


def _second_node(draw: _Draw, rng: np.random.Generator, sign: float) -> tuple[np.ndarray, str]:
    tau = float(rng.uniform(*SECOND_NODE_TAU_S))
    draw.params["tau_s"] = tau
    return _term(SecondNode(tau_s=tau, coef_per_c=sign), draw, rng), "coef_per_c"


# The additive kinds: ``(draw, rng, sign) -> (unit-amplitude contribution, amplitude parameter)``;
# each fills ``draw.params``, ``draw.where`` and (for a gap) ``draw.keep``.
PATTERNS: dict[str, Callable[[_Draw, np.random.Generator, float], tuple[np.ndarray, str]]] = {
    "step": _step,
    "restart_after_gap": _restart_after_gap,
    "periodic": _sinusoid(PERIOD_S),
    "slow_oscillation": _sinusoid(SLOW_PERIOD_S),
    "compressor_cycling": _compressor_cycling,
    "transient": _transient,
    "temperature_bump": _temperature_bump,
    "second_node": _second_node,
}
ADDITIVE: tuple[str, ...] = tuple(PATTERNS)
DETERMINISTIC = (*ADDITIVE, "saturation")  # a model term can take them out: the refit target applies


def _pattern(kind: str, draw: _Draw, rng: np.random.Generator) -> tuple[np.ndarray, str, float]:
    """Unit-amplitude contribution of an additive ``kind`` (sign included), the name of its
    amplitude parameter and the sign (:data:`PATTERNS`). Every kind but ``compressor_cycling``
    (gated by the temperature) is the term of the library effect of the same form."""
    sign = float(rng.choice([-1.0, 1.0]))
    d, amp_name = PATTERNS[kind](draw, rng, sign)
    return d, amp_name, sign


def _split(draw: _Draw) -> tuple[np.ndarray, np.ndarray]:
    """The noise-free output as ``fixed + varying``: ``fixed`` its part on the minimal model's
    columns without temperature (``1`` and ``a``), ``varying`` the part that moves with
    temperature (``u``, ``u^2`` and ``a`` times those). The device has no other effect, so the
    two add up to the output (to rounding)."""
    cols = minimal_columns(draw.temp_c, draw.accel)
    coef, *_ = np.linalg.lstsq(cols, draw.base, rcond=None)
    fixed_cols = [0] if draw.accel is None else [0, 3]
    fixed = cols[:, fixed_cols] @ coef[fixed_cols]
    return fixed, draw.base - fixed


def _saturation(
    draw: _Draw, varying: np.ndarray, rng: np.random.Generator
) -> tuple[float, bool, float, np.ndarray, np.ndarray]:
    """Where the output clips, for a unit temperature sensitivity: the band's drawn share of the
    temperature range (:data:`CLIP_BAND`), the clipping side (ceiling or floor, random, the other
    tried when the first makes no band within 0.05 of the share), the threshold on ``varying``,
    the group of samples that can clip (those at the extreme input on that side) and the unit
    clipped amount (``clip(varying) - varying`` on the group, 0 elsewhere). The threshold is the
    quantile of ``varying`` over the group (1-60 % clipped) whose clipped samples fill one
    temperature band closest to the drawn share."""
    first_ceiling = bool(rng.random() < 0.5)
    share = float(rng.uniform(*CLIP_BAND))
    range_c = float(np.ptp(draw.temp_c))
    best: tuple[float, bool, float, np.ndarray] | None = None
    for ceiling in (first_ceiling, not first_ceiling):
        if draw.accel is None:
            group = np.ones(varying.size, dtype=bool)
        else:
            group = draw.accel == (draw.accel.max() if ceiling else draw.accel.min())
        fractions = np.linspace(0.01, 0.6, 60)
        for threshold in np.quantile(varying[group], 1.0 - fractions if ceiling else fractions):
            beyond = group & ((varying > threshold) if ceiling else (varying < threshold))
            if not beyond.any() or not _one_band(draw, beyond, group):
                continue
            miss = abs(float(np.ptp(draw.temp_c[beyond])) / range_c - share)
            if best is None or miss < best[0]:
                best = (miss, ceiling, float(threshold), group)
        if best is not None and best[0] <= 0.05:
            break
    if best is None:  # pragma: no cover - a monotonic side always makes one band
        raise RuntimeError("no clipping threshold makes a single temperature band")
    _, ceiling, threshold, group = best
    beyond = group & ((varying > threshold) if ceiling else (varying < threshold))
    return share, ceiling, threshold, group, np.where(beyond, threshold - varying, 0.0)


def _one_band(draw: _Draw, clipped: np.ndarray, group: np.ndarray) -> bool:
    """Whether the ``clipped`` samples fill one temperature interval: no other sample of the
    ``group`` (same input) lies strictly inside their temperature hull."""
    temp = draw.temp_c
    lo, hi = temp[clipped].min(), temp[clipped].max()
    return not bool((group & ~clipped & (temp > lo) & (temp < hi)).any())


@dataclass
class _Mix:
    """One recording while its kind is hidden: the draw, the noise-free output ``base``, the
    white sigma and the drawn ``rho``, the unit white noise, the thermometer ``reading`` before
    its quantisation, and what a kind sets: the ``output``, the ``thermometer`` reading, the
    ``ratio`` and the ``white_sigma`` of the truth; ``rng`` the kind's own stream."""

    draw: _Draw
    base: np.ndarray
    sigma: float
    rho: float
    white: np.ndarray
    reading: np.ndarray
    output: np.ndarray
    thermometer: np.ndarray
    ratio: float
    white_sigma: float
    rng: np.random.Generator


def _additive(kind: str) -> Callable[[_Mix], None]:
    """Hide the additive ``kind`` sized so that what the minimal model cannot absorb is ``rho * sigma``."""

    def hide(m: _Mix) -> None:
        d, amp_name, sign = _pattern(kind, m.draw, m.rng)
        scale = m.rho * m.sigma / _left(d, m.draw)
        m.draw.params[amp_name] = sign * scale
        m.output = m.base + d * scale + m.sigma * m.white
        m.ratio = m.rho

    return hide


def _hide_saturation(m: _Mix) -> None:
    draw, sigma = m.draw, m.sigma
    fixed, varying = _split(draw)
    share, ceiling, threshold, group, amount = _saturation(draw, varying, m.rng)
    k = m.rho * sigma / _left(amount, draw)  # temperature sensitivity that makes the clip rho sigma
    draw.base = fixed + k * varying
    level = float(np.median(fixed[group]) + k * threshold)
    outside = draw.base[~group]
    if outside.size and (outside.max() >= level if ceiling else outside.min() <= level):
        raise RuntimeError("the clip level reaches samples at another input")  # pragma: no cover
    noisy = draw.base + sigma * m.white
    m.output = np.minimum(noisy, level) if ceiling else np.maximum(noisy, level)
    band = draw.temp_c[amount != 0]
    draw.params |= {"level": level, "ceiling": float(ceiling), "band_share": share, "tempco_scale": k,
                    "band_low_c": float(band.min()), "band_high_c": float(band.max())}
    draw.where["level"] = level
    m.ratio = m.rho


def _hide_output_quantisation(m: _Mix) -> None:
    q = float(np.sqrt(12.0) * m.rho * m.sigma)
    m.output = noise.quantise(m.output, q)
    m.draw.params["step"] = q
    m.draw.where["level"] = q
    m.ratio = m.rho


def _hide_thermometer_steps(m: _Mix) -> None:
    draw = m.draw
    m.thermometer = noise.quantise(m.reading, THERMOMETER_STEPS_C)
    fixed, varying = _split(draw)
    k = m.rho * m.sigma / _left(varying, draw, temp_c=m.thermometer)
    draw.base = fixed + k * varying
    m.output = draw.base + m.sigma * m.white
    draw.params |= {"step_c": THERMOMETER_STEPS_C, "tempco_scale": k}
    draw.where["level"] = THERMOMETER_STEPS_C
    m.ratio = m.rho


def _hide_variance_temperature(m: _Mix) -> None:
    draw = m.draw
    growth = float(m.rng.uniform(*VARIANCE_GROWTH))
    lo, hi = float(draw.temp_c.min()), float(draw.temp_c.max())
    sigma_t = m.sigma * growth ** ((draw.temp_c - lo) / (hi - lo))
    m.output = m.base + sigma_t * m.white
    m.white_sigma = _rms(sigma_t)
    draw.params |= {"sigma_cold": m.sigma, "growth": growth}
    draw.where["temperature_c"] = [(lo + hi) / 2.0, hi]


def _hide_spikes(m: _Mix) -> None:
    draw = m.draw
    times, sizes = _spikes(draw.t_s, m.sigma, m.rng)
    idx = np.searchsorted(draw.t_s, times)
    m.output = m.output.copy()
    m.output[idx] += sizes
    draw.params |= {"count": float(times.size), **{f"size_{i}": float(s) for i, s in enumerate(sizes)}}
    draw.where["time_s"] = [float(x) for x in times]


# How each kind is hidden in a recording (its keys are :data:`KINDS`).
HIDE: dict[str, Callable[[_Mix], None]] = {
    **{kind: _additive(kind) for kind in ADDITIVE},
    "saturation": _hide_saturation,
    "output_quantisation": _hide_output_quantisation,
    "thermometer_steps": _hide_thermometer_steps,
    "variance_temperature": _hide_variance_temperature,
    "spikes": _hide_spikes,
}


def open_world_recording(sensor: str, kind: str | None, seed: int) -> tuple[Recording, OpenWorld]:
    """A schema-v1 recording (1 Hz; MSRA output in Hz, gyro in deg/s) with ``kind`` hidden
    (``None``: a control) and its truth. Raises ``ValueError`` for an unknown sensor or kind or
    a negative seed."""
    if sensor not in SENSORS:
        raise ValueError(unknown_name("sensor", sensor, SENSORS))
    if kind is not None and kind not in SHAPE:
        raise ValueError(unknown_name("kind", kind, KINDS))
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    streams = np.random.SeedSequence(int(seed)).spawn(8)  # the eighth is kept for a new kind
    r_profile, r_device, r_kind, r_sim, r_scale, r_white, r_thermo = (
        np.random.default_rng(s) for s in streams[:7])
    profile = concealed_profile(sensor, r_profile)
    device_seed = int(r_device.integers(0, 10_000))
    model, default_sigma = device_without_effects(sensor, device_seed)
    base = model.simulate(profile, r_sim)
    n = profile.t_s.size
    factor = float(np.exp(r_scale.uniform(*np.log(NOISE_FACTOR))))
    rho = float(r_scale.uniform(*RATIO))
    sigma = default_sigma * factor
    draw = _Draw(profile.t_s, profile.temp_c, profile.accel_g if sensor_kind(sensor).positions else None, base,
                 np.ones(n, dtype=bool), float(profile.info["start_c"]))
    white = noise.white(n, 1.0, r_white)  # unit noise, scaled below
    reading = profile.temp_c + r_thermo.standard_normal(n) * THERMOMETER_NOISE_C
    thermometer = noise.quantise(reading, THERMOMETER_STEP_C)
    output = base + sigma * white
    mix = _Mix(draw, base, sigma, rho, white, reading, output, thermometer, float("nan"), sigma, r_kind)
    if kind is not None:
        HIDE[kind](mix)
    draw, output, thermometer, ratio, white_sigma = mix.draw, mix.output, mix.thermometer, mix.ratio, mix.white_sigma
    kept = draw.keep
    t_kept = draw.t_s[kept]
    truth = OpenWorld(sensor, kind, SHAPE.get(kind) if kind else None, dict(draw.where),
                      {key: float(v) for key, v in draw.params.items()}, ratio, float(white_sigma),
                      float(t_kept[-1] - t_kept[0]), int(seed))
    extra = {"open_world": dataclasses.asdict(truth), "device_seed": device_seed, "profile": dict(profile.info)}
    rec = make_recording(t_kept, thermometer[kept], profile_input(profile)[kept], output[kept], sensor=sensor,
                         sample_rate_hz=SAMPLE_RATE_HZ, device_id=f"open-world-{sensor}-{seed}", extra=extra)
    return rec, truth


def _spikes(t_s: np.ndarray, sigma: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Instants (s, on the sample grid, >= 10 min apart, middle 90 % of the span) and sizes."""
    count = int(rng.integers(SPIKES[0], SPIKES[1] + 1))
    span = t_s[-1] - t_s[0]
    lo, hi = t_s[0] + 0.05 * span, t_s[0] + 0.95 * span
    slots = np.arange(lo, hi - SPIKE_SEPARATION_S, SPIKE_SEPARATION_S)  # one spike per 10-min slot at most
    chosen = np.sort(rng.choice(slots.size, size=count, replace=False))
    offsets = rng.uniform(0.0, SPIKE_SEPARATION_S / 2.0, size=count)  # keeps neighbours >= 5 min apart
    times = t_s[np.searchsorted(t_s, slots[chosen] + offsets)]
    sizes = rng.uniform(*SPIKE_SIGMA, size=count) * sigma * rng.choice([-1.0, 1.0], size=count)
    return times, sizes
