"""Recordings with one physical effect hidden under the noise, for testing ``tcbench diagnose``.

``tcbench diagnose`` fits a minimal model (bias and scale factor each quadratic in the
thermometer temperature, plus white noise) and must name the effect that model misses. A
concealed recording is built so that, without the hidden effect, it is exactly that minimal
model:

- profile (:func:`concealed_profile`): 1 Hz, 8-12 h; the chamber starts at room temperature
  (20-28 degC) and steps through one grid of levels up to hot, down to cold and back (to room,
  or to hot and then room), so every level between the extremes is soaked after heating and
  after cooling; soaks of 35-50 min, ramps at 0.5-2 degC/min, levels within -40..70 degC, span
  at least 30 degC. The package (true) temperature lags the set-point through the chamber air
  and the package. MSRA: the acceleration along the sensitive axis cycles +1, 0, -1, 0 g in
  60-120 s dwells through the whole run (ramps included), nothing across it; gyro: at rest.
- device: ``unit(sensor, device_seed)`` with every effect removed (and the MSRA's
  misalignment set to zero), so its noise-free output is quadratic bias plus a scale factor
  at most quadratic in the die temperature, which equals the package temperature.
- hidden effect: physical parameters drawn from docs/concepts/physics.md, the effect library; its noise-free contribution
  ``d`` (output with the effect minus output without it) is projected out of the minimal
  model's columns ``[1, u, u^2, a, a u, a u^2]`` (``u`` the scaled package temperature, ``a``
  the acceleration; no ``a`` columns for the gyro) by least squares; with ``r`` the RMS of
  what is left and ``rho ~ U(0.3, 0.7)``, the per-sample white-noise sigma is ``r / rho``.
  Effects whose size is a free amplitude (all but ``thermal_lag``) have the amplitude set so
  that the white sigma is the device's own times a log-uniform factor in 1-3; ``thermal_lag``
  has no free amplitude, so its white sigma follows from the device's temperature slope.
- controls (no effect): the device's own white noise, ratio 0.
- thermometer: package temperature + N(0, 0.02 degC), quantised to 1/16 degC.

Every random draw comes from generators spawned from ``np.random.SeedSequence(seed)``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tcbench.sensors import noise
from tcbench.errors import unknown_name
from tcbench.sensors.kinds import get as sensor_kind
from tcbench.sensors.kinds import profile_input, unit
from tcbench.sensors.models import MSRA, SensorModel
from tcbench.sensors.protocols import Chamber, Profile, _from_segments
from tcbench.sensors.recording import Recording, make_recording
from tcbench.sensors.thermal import Segment

EFFECTS_BY_SENSOR: dict[str, tuple[str, ...]] = {
    "msra": (
        "thermal_lag", "temperature_rate", "hysteresis", "warmup", "aging_drift",
        "temperature_cubic", "accel_nonlinearity", "bias_instability",
    ),
    "gyro": (
        "thermal_lag", "temperature_rate", "hysteresis", "warmup", "aging_drift",
        "temperature_cubic", "bias_instability",
    ),
}

SAMPLE_RATE_HZ = 1.0
DURATION_S = (8.0 * 3600.0, 12.0 * 3600.0)
SOAK_S = (35.0 * 60.0, 50.0 * 60.0)
RAMP_C_PER_MIN = (0.5, 2.0)
ROOM_C = (20.0, 28.0)
STEP_C = (6.0, 15.0)
LIMITS_C = (-40.0, 70.0)
MIN_SPAN_C = 30.0
PACKAGE_TAU_S = (120.0, 300.0)
DWELL_S = (60.0, 120.0)
ACCEL_CYCLE_G = (1.0, 0.0, -1.0, 0.0)
RATIO = (0.3, 0.7)
NOISE_FACTOR = (1.0, 3.0)  # free-amplitude effects: white sigma / device default, log-uniform
THERMOMETER_NOISE_C = 0.03
THERMOMETER_STEP_C = 1.0 / 16.0
_MAX_DRAWS = 10_000
NOMINAL_DURATION_S = 10.0 * 3600.0  # the middle of DURATION_S: time scales are sized from it
MAX_RAMP_C_PER_MIN = 10.0  # the fastest chamber ramp a sized programme asks for

# Shape parameters drawn from docs/concepts/physics.md, the effect library; the amplitude parameter (if any) is set later.
_AMPLITUDE = {
    "temperature_rate": "coef_per_c_per_s",
    "hysteresis": "amplitude",
    "warmup": "amplitude",
    "aging_drift": "rate_per_h",
    "temperature_cubic": "c3_per_c3",
    "accel_nonlinearity": "k2_per_g2",
    "bias_instability": "b",
}


@dataclass(frozen=True)
class Concealed:
    """What was hidden: the effect (``None`` for a control), its parameters (as for
    ``SensorModel.with_effects``, output units), the drawn ratio of the RMS the minimal model
    cannot absorb to the white sigma, the per-sample white sigma (output unit) and the seed."""

    sensor: str
    effect: str | None
    params: dict[str, float]
    ratio: float
    white_sigma: float
    seed: int


@dataclass(frozen=True)
class _Parts:
    """The pieces of a concealed recording (noise-free output, contribution, noise)."""

    profile: Profile
    model: SensorModel
    base: np.ndarray
    hidden: np.ndarray
    white: np.ndarray
    thermometer_c: np.ndarray
    device_seed: int
    truth: Concealed


def _check_sensor(sensor: str) -> None:
    if sensor not in EFFECTS_BY_SENSOR:
        raise ValueError(unknown_name("sensor", sensor, EFFECTS_BY_SENSOR))


def device_without_effects(sensor: str, device_seed: int, rate_hz: float = SAMPLE_RATE_HZ,
                           ) -> tuple[SensorModel, float]:
    """The unit with every effect removed (MSRA misalignment zero) and its white sigma per
    sample at ``rate_hz`` (density times sqrt(rate))."""
    device = unit(sensor, device_seed).model
    white_fx = device.effect("white_noise")
    sigma = (white_fx.params()["density"] if white_fx else 0.0) * np.sqrt(rate_hz)
    model = dataclasses.replace(device, effects=())
    if isinstance(model, MSRA):
        model = dataclasses.replace(model, misalignment_rad=0.0)
    return model, float(sigma)


@dataclass(frozen=True)
class Sizing:
    """The time and temperature scales of a staircase programme (defaults: the 8-12 h, 1 Hz set).

    :meth:`for_duration` sizes one to another record length."""

    duration_s: tuple[float, float] = DURATION_S
    soak_s: tuple[float, float] = SOAK_S
    ramp_c_per_min: tuple[float, float] = RAMP_C_PER_MIN
    step_c: tuple[float, float] = STEP_C
    min_span_c: float = MIN_SPAN_C
    package_tau_s: tuple[float, float] = PACKAGE_TAU_S
    dwell_s: tuple[float, float] = DWELL_S

    @classmethod
    def for_duration(cls, duration_s: float) -> Sizing:
        """A programme of ``duration_s`` to 1.25 times that: every time scale of the 10 h
        nominal set times ``s = duration_s / 10 h`` (soaks, package lag; acceleration dwells only
        shortened, to >= 10 s), the ramp rate divided by ``s`` but at most
        :data:`MAX_RAMP_C_PER_MIN`; where that cap binds, the temperature steps and span shrink
        by the same factor, so a 10-min record holds a whole small staircase rather than part
        of a 35-min soak."""
        s = float(duration_s) / NOMINAL_DURATION_S
        lo, hi = RAMP_C_PER_MIN[0] / s, RAMP_C_PER_MIN[1] / s
        ramp = (min(lo, MAX_RAMP_C_PER_MIN / 4.0), min(hi, MAX_RAMP_C_PER_MIN))
        shrink = min(1.0, ramp[1] / hi)  # temperature scale kept in proportion to the ramp
        return cls(
            duration_s=(duration_s, 1.25 * duration_s),
            soak_s=(SOAK_S[0] * s, SOAK_S[1] * s),
            ramp_c_per_min=ramp,
            step_c=(STEP_C[0] * shrink, STEP_C[1] * shrink),
            min_span_c=MIN_SPAN_C * shrink,
            package_tau_s=(max(PACKAGE_TAU_S[0] * s, 5.0), max(PACKAGE_TAU_S[1] * s, 10.0)),
            dwell_s=(max(DWELL_S[0] * min(s, 1.0), 10.0), max(DWELL_S[1] * min(s, 1.0), 20.0)),
        )


def _programme(rng: np.random.Generator, sizing: Sizing | None = None,
               ) -> tuple[float, list[float], np.ndarray, Chamber]:
    """Start temperature, soak levels (degC) in order, soak durations (s) and chamber."""
    z = sizing or Sizing()
    for _ in range(_MAX_DRAWS):
        room_c = float(rng.uniform(*ROOM_C))
        step_c = float(rng.uniform(*z.step_c))
        n_up, n_down = (int(n) for n in rng.integers(1, 4, size=2))
        via_hot = bool(rng.random() < 0.5)
        ramp = float(rng.uniform(*z.ramp_c_per_min))
        grid = [room_c + step_c * k for k in range(-n_down, n_up + 1)]  # one grid, exact revisits
        room, hot, cold = n_down, len(grid) - 1, 0
        path = list(range(room, hot + 1)) + list(range(hot - 1, cold - 1, -1))
        if via_hot:
            path += list(range(cold + 1, hot + 1)) + list(range(hot - 1, room - 1, -1))
        else:
            path += list(range(cold + 1, room + 1))
        levels = [grid[i] for i in path]
        soaks_s = np.round(rng.uniform(*z.soak_s, size=len(levels)))
        travel_c = float(np.abs(np.diff(levels)).sum())
        duration_s = float(soaks_s.sum()) + travel_c / (ramp / 60.0)
        ok = (grid[-1] <= LIMITS_C[1] and grid[0] >= LIMITS_C[0] and grid[-1] - grid[0] >= z.min_span_c
              and z.duration_s[0] <= duration_s <= z.duration_s[1])
        if ok:
            chamber = Chamber(ramp_c_per_min=ramp, package_tau_s=float(rng.uniform(*z.package_tau_s)))
            return room_c, levels, soaks_s, chamber
    raise RuntimeError("no temperature programme met the constraints")  # pragma: no cover


def _accel_cycle(t_s: np.ndarray, rng: np.random.Generator,
                 dwell_s: tuple[float, float] = DWELL_S) -> np.ndarray:
    """Acceleration (g) stepping through +1, 0, -1, 0 g with dwells of 60-120 s (whole s)."""
    n_steps = int(np.ceil((t_s[-1] + 1.0) / dwell_s[0])) + 1
    edges = np.cumsum(np.round(rng.uniform(*dwell_s, size=n_steps)))
    step = np.searchsorted(edges, t_s, side="right")
    return np.asarray(ACCEL_CYCLE_G)[step % len(ACCEL_CYCLE_G)]


def concealed_profile(sensor: str, rng: np.random.Generator, sizing: Sizing | None = None,
                      rate_hz: float = SAMPLE_RATE_HZ) -> Profile:
    """A 1 Hz, 8-12 h heat-and-cool staircase (package temperature ``temp_c`` in degC); MSRA
    acceleration cycling +1, 0, -1, 0 g throughout, gyro at rest. ``info`` lists the soak
    levels (``levels_c``) and durations (``soaks_s``) as space-separated numbers. ``sizing``
    and ``rate_hz`` make the same kind of staircase at another length and rate."""
    _check_sensor(sensor)
    z = sizing or Sizing()
    start_c, levels, soaks_s, chamber = _programme(rng, z)
    segments = [Segment(level, float(s), "", 0.0, 0.0) for level, s in zip(levels, soaks_s, strict=True)]
    profile = _from_segments("concealed", sensor, segments, start_c, rate_hz, chamber)
    zeros = np.zeros_like(profile.t_s)
    accel = _accel_cycle(profile.t_s, rng, z.dwell_s) if sensor_kind(sensor).positions else zeros.copy()
    info: dict[str, float | str] = {
        **profile.info, "start_c": start_c, "air_tau_s": chamber.air_tau_s,
        "levels_c": " ".join(f"{x:.6f}" for x in levels), "soaks_s": " ".join(f"{s:.0f}" for s in soaks_s),
    }
    return dataclasses.replace(profile, accel_g=accel, cross_g=zeros, rate_dps=zeros.copy(),
                               position=None, info=info)


def minimal_columns(temp_c: np.ndarray, accel_g: np.ndarray | None) -> np.ndarray:
    """Columns of the minimal model: ``[1, u, u^2]`` and, with ``accel_g``, ``[a, a u, a u^2]``;
    ``u`` is ``temp_c`` centred and scaled to about [-1, 1]."""
    half = max(float(np.ptp(temp_c)) / 2.0, 1e-9)
    u = (temp_c - (float(temp_c.max()) + float(temp_c.min())) / 2.0) / half
    cols = [np.ones_like(u), u, u * u]
    if accel_g is not None:
        cols += [accel_g * c for c in cols]
    return np.column_stack(cols)


def unexplained(d: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """What of ``d`` the columns cannot absorb (least-squares residual)."""
    coef, *_ = np.linalg.lstsq(columns, d, rcond=None)
    return d - columns @ coef


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x * x)))


# The shapes whose parameters are more than a signed unit amplitude: ``(sign, rng) -> params``,
# drawn in this order; every other effect is ``{_AMPLITUDE[effect]: sign}``.
_SHAPES: dict[str, Callable[[float, np.random.Generator], dict[str, float]]] = {
    "thermal_lag": lambda sign, rng: {"tau_s": float(rng.uniform(60.0, 900.0))},
    "warmup": lambda sign, rng: {"amplitude": sign, "tau_s": float(rng.uniform(600.0, 1800.0))},
    "hysteresis": lambda sign, rng: {"amplitude": sign, "width_c": float(rng.uniform(0.5, 3.0))},
    "aging_drift": lambda sign, rng: {"rate_per_h": sign, "relax_amplitude": 0.0},
    "bias_instability": lambda sign, rng: {"b": 1.0},
}


def _shape_params(effect: str, rng: np.random.Generator) -> dict[str, float]:
    """The effect's parameters with a unit amplitude of random sign (``b`` positive)."""
    sign = float(rng.choice([-1.0, 1.0]))
    shape = _SHAPES.get(effect)
    return shape(sign, rng) if shape is not None else {_AMPLITUDE[effect]: sign}


def _build(sensor: str, effect: str | None, seed: int) -> _Parts:
    """Draw everything of one concealed recording from ``SeedSequence(seed)``."""
    _check_sensor(sensor)
    if effect is not None and effect not in EFFECTS_BY_SENSOR[sensor]:
        raise ValueError(unknown_name("effect", effect, EFFECTS_BY_SENSOR[sensor], f" for sensor {sensor!r}"))
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    streams = np.random.SeedSequence(int(seed)).spawn(7)
    r_profile, r_device, r_params, r_effect, r_scale, r_white, r_thermo = (
        np.random.default_rng(s) for s in streams)
    profile = concealed_profile(sensor, r_profile)
    device_seed = int(r_device.integers(0, 10_000))
    model, default_sigma = device_without_effects(sensor, device_seed)
    base = model.simulate(profile, r_effect)
    n = profile.t_s.size
    if effect is None:
        params: dict[str, float] = {}
        ratio, sigma, hidden = 0.0, default_sigma, np.zeros(n)
    else:
        params = _shape_params(effect, r_params)
        hidden = model.with_effects({effect: params}).simulate(profile, r_effect) - base
        accel = profile.accel_g if sensor_kind(sensor).positions else None
        left = _rms(unexplained(hidden, minimal_columns(profile.temp_c, accel)))
        ratio = float(r_scale.uniform(*RATIO))
        if effect in _AMPLITUDE:
            factor = float(np.exp(r_scale.uniform(*np.log(NOISE_FACTOR))))
            sigma = default_sigma * factor
            scale = ratio * sigma / left
            params[_AMPLITUDE[effect]] *= scale
            hidden = hidden * scale
        else:
            sigma = left / ratio
    white = noise.white(n, sigma, r_white)
    reading = profile.temp_c + r_thermo.standard_normal(n) * THERMOMETER_NOISE_C
    thermometer = noise.quantise(reading, THERMOMETER_STEP_C)
    truth = Concealed(sensor, effect, {k: float(v) for k, v in params.items()}, ratio, sigma, int(seed))
    return _Parts(profile, model, base, hidden, white, thermometer, device_seed, truth)


def concealed_recording(sensor: str, effect: str | None, seed: int) -> tuple[Recording, Concealed]:
    """A schema-v1 recording (1 Hz; output in Hz for the MSRA, deg/s for the gyro) with
    ``effect`` hidden at a random ratio of the white noise (``None``: a control), and the truth.

    Raises ``ValueError`` for an unknown sensor, an effect not in
    ``EFFECTS_BY_SENSOR[sensor]`` or a negative seed."""
    parts = _build(sensor, effect, seed)
    truth = parts.truth
    profile = parts.profile
    extra = {
        "concealed": dataclasses.asdict(truth),
        "device_seed": parts.device_seed,
        "profile": dict(profile.info),
    }
    rec = make_recording(
        profile.t_s, parts.thermometer_c, profile_input(profile), parts.base + parts.hidden + parts.white,
        sensor=sensor, sample_rate_hz=SAMPLE_RATE_HZ, device_id=f"concealed-{sensor}-{truth.seed}",
        extra=extra,
    )
    return rec, truth
