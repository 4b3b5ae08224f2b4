"""The effect library: named, parametric physical effects a sensor model is composed of.

Each effect has an ``id`` (docs/concepts/physics.md, the effect library), parameters, and a form for simulation. Effects act
at one of three stages:

- ``die``: change the die temperature the physics sees (``thermal_lag``);
- ``output``: add a term to the output, in the sensor's output unit (Hz for the MSRA, deg/s
  for the gyroscope);
- ``final``: transform the finished output (``quantisation``, ``saturation``);
- ``thermometer``: transform the thermometer reading a recording carries, not the temperature
  the physics sees (``thermometer_quantisation``).

The same objects serve simulation now and diagnosis later (fitting their parameters to a
residual), so each is a small frozen dataclass whose fields are its parameters.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from tcbench.plugins import PluginRegistry
from tcbench.errors import unknown_name
from tcbench.sensors import noise
from tcbench.sensors.thermal import first_order_lag


@dataclass
class Signals:
    """What effects see: time since power-on, temperatures and the applied input, per sample.

    ``temp_rate_c_per_s`` is the thermometer's rate of change; ``accel_g`` the acceleration
    along the sensitive axis (MSRA) and ``cross_g`` across it; ``rate_dps`` the applied rate.
    """

    t_s: np.ndarray
    dt_s: float
    temp_meas_c: np.ndarray
    temp_die_c: np.ndarray
    temp_rate_c_per_s: np.ndarray
    accel_g: np.ndarray
    cross_g: np.ndarray
    rate_dps: np.ndarray
    ref_c: float = 25.0


@dataclass(frozen=True)
class Effect:
    """Base of all effects; subclasses set ``id`` and ``stage`` and implement one method.
    ``stochastic``: part of the recorded noise (drawn, or the quantisation of what was drawn),
    left out of the deterministic truth; ``rig``: what the test rig does to the output (a
    compressor's, a fan's or a supply's line), not the sensor; ``repeatable``: a model may hold
    further instances of it (``bias_step_2``: a second step, up to :data:`MAX_REPEATS`);
    ``clock_keyed``: it follows the recording's own clock (an instant of the run, the time since
    its power-on), which a shipped compensator cannot know
    (:func:`tcbench.compensation.fitted_model.compensator` leaves it out)."""

    id: ClassVar[str] = ""
    stage: ClassVar[str] = "output"
    stochastic: ClassVar[bool] = False
    rig: ClassVar[bool] = False
    repeatable: ClassVar[bool] = False
    clock_keyed: ClassVar[bool] = False

    def die_temperature(self, s: Signals) -> np.ndarray:
        """Stage ``die``: the die temperature after this effect."""
        raise NotImplementedError

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        """Stage ``output``: the additive output term (output unit)."""
        raise NotImplementedError

    def transform(self, y: np.ndarray) -> np.ndarray:
        """Stage ``final``: the output after this effect."""
        raise NotImplementedError

    def reading(self, temp_c: np.ndarray) -> np.ndarray:
        """Stage ``thermometer``: the thermometer reading after this effect (degC)."""
        raise NotImplementedError

    def params(self) -> dict[str, float]:
        """Parameters by name."""
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class ThermalLag(Effect):
    """The die follows the thermometer: ``dT_die/dt = (T_meas - T_die) / tau_s``."""

    id: ClassVar[str] = "thermal_lag"
    stage: ClassVar[str] = "die"
    tau_s: float = 600.0

    def die_temperature(self, s: Signals) -> np.ndarray:
        return first_order_lag(s.temp_meas_c, s.dt_s, self.tau_s)


@dataclass(frozen=True)
class TemperatureRate(Effect):
    """Thermal-gradient term ``coef * dT_meas/dt`` (output unit per degC/s); zero at rest."""

    id: ClassVar[str] = "temperature_rate"
    coef_per_c_per_s: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return self.coef_per_c_per_s * s.temp_rate_c_per_s


def play_operator(temp_c: np.ndarray, width_c: float, start_state: float = 0.0) -> np.ndarray:
    """Play (backlash) operator of half-width ``width_c``: the state lags the input by at most
    ``width_c`` and only moves when pushed; it starts ``start_state`` half-widths below the input
    (+1: the history before was a heating, -1 a cooling). Sequential by nature, so it runs over the
    thermal samples (1 Hz or slower in the protocols), not over output samples."""
    out = np.empty_like(temp_c)
    y = float(temp_c[0]) - float(np.clip(start_state, -1.0, 1.0)) * width_c
    w = float(width_c)
    values = []
    for x in temp_c.tolist():  # y = min(max(y, x - w), x + w), without two calls per sample
        if y < x - w:
            y = x - w
        elif y > x + w:
            y = x + w
        values.append(y)
    out[:] = values
    return out


@dataclass(frozen=True)
class Hysteresis(Effect):
    """``amplitude * s(t)``, ``s = (T_die - play(T_die)) / width`` in [-1, 1]: +1 after heating,
    -1 after cooling, remembered through a soak; ``start_state`` is where the history before the
    run left it."""

    id: ClassVar[str] = "hysteresis"
    amplitude: float = 0.0
    width_c: float = 2.0
    start_state: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        step = max(1, int(round(1.0 / s.dt_s)))  # the play operator on a <= 1 Hz grid
        coarse = s.temp_die_c[::step]
        state = (coarse - play_operator(coarse, self.width_c, self.start_state)) / self.width_c
        return self.amplitude * np.interp(s.t_s, s.t_s[::step], state)


@dataclass(frozen=True)
class Warmup(Effect):
    """``amplitude * exp(-t / tau_s)`` after power-on (self-heating, stress settling)."""

    id: ClassVar[str] = "warmup"
    clock_keyed: ClassVar[bool] = True
    amplitude: float = 0.0
    tau_s: float = 1200.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return self.amplitude * np.exp(-s.t_s / self.tau_s)


@dataclass(frozen=True)
class AgingDrift(Effect):
    """``rate_per_h * t + relax_amplitude * exp(-t / relax_tau_s)``: drift with time, not
    temperature (linear ageing plus stress relaxation)."""

    id: ClassVar[str] = "aging_drift"
    clock_keyed: ClassVar[bool] = True
    rate_per_h: float = 0.0
    relax_amplitude: float = 0.0
    relax_tau_s: float = 6000.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return self.rate_per_h * s.t_s / 3600.0 + self.relax_amplitude * np.exp(-s.t_s / self.relax_tau_s)


@dataclass(frozen=True)
class TemperatureCubic(Effect):
    """``c3 * (T_die - ref)^3`` beyond a quadratic model (output unit per degC^3)."""

    id: ClassVar[str] = "temperature_cubic"
    c3_per_c3: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        cube = s.temp_die_c - s.ref_c
        cube **= 3
        cube *= self.c3_per_c3
        return cube


@dataclass(frozen=True)
class AccelNonlinearity(Effect):
    """``k2 * a^2`` with ``a`` the acceleration along the sensitive axis (output unit per g^2)."""

    id: ClassVar[str] = "accel_nonlinearity"
    k2_per_g2: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return self.k2_per_g2 * s.accel_g**2


@dataclass(frozen=True)
class BiasInstability(Effect):
    """Flicker bias noise with Allan floor ``0.664 b`` (``b`` in output units)."""

    id: ClassVar[str] = "bias_instability"
    stochastic: ClassVar[bool] = True
    b: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return noise.flicker(s.t_s.size, s.dt_s, self.b, rng)


@dataclass(frozen=True)
class WhiteNoise(Effect):
    """White output noise of density ``density`` (output unit per sqrt(Hz), i.e. the angle or
    velocity random walk); per sample its standard deviation is ``density * sqrt(fs)``."""

    id: ClassVar[str] = "white_noise"
    stochastic: ClassVar[bool] = True
    density: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return noise.white(s.t_s.size, self.density / np.sqrt(s.dt_s), rng)


@dataclass(frozen=True)
class RandomWalk(Effect):
    """Rate random walk, ``k`` in output unit per sqrt(s)."""

    id: ClassVar[str] = "random_walk"
    stochastic: ClassVar[bool] = True
    k_per_sqrt_s: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return noise.random_walk(s.t_s.size, s.dt_s, self.k_per_sqrt_s, rng)


@dataclass(frozen=True)
class Quantisation(Effect):
    """Output rounded to multiples of ``step`` (counter or ADC resolution)."""

    id: ClassVar[str] = "quantisation"
    stage: ClassVar[str] = "final"
    stochastic: ClassVar[bool] = True
    step: float = 0.0

    def transform(self, y: np.ndarray) -> np.ndarray:
        return noise.quantise(y, self.step)


@dataclass(frozen=True)
class BiasStep(Effect):
    """A bias jump of ``size`` at ``time_s`` (mode hop, shock, restart; docs/concepts/diagnosis-report.md, shapes)."""

    id: ClassVar[str] = "bias_step"
    repeatable: ClassVar[bool] = True
    clock_keyed: ClassVar[bool] = True
    time_s: float = 0.0
    size: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return np.where(s.t_s >= self.time_s, self.size, 0.0)


@dataclass(frozen=True)
class Periodic(Effect):
    """``amplitude * sin(2 pi t / period_s + phase_rad)``: environmental cycling (docs/concepts/diagnosis-report.md, shapes)."""

    id: ClassVar[str] = "periodic"
    repeatable: ClassVar[bool] = True
    rig: ClassVar[bool] = True
    period_s: float = 1800.0
    amplitude: float = 0.0
    phase_rad: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return self.amplitude * np.sin(2.0 * np.pi * s.t_s / self.period_s + self.phase_rad)


@dataclass(frozen=True)
class GatedPeriodic(Effect):
    """A cycle of ``period_s`` present only in ``[start_s, end_s)``: a mean ``offset``, the
    fundamental ``sin1 sin(wt) + cos1 cos(wt)`` and the harmonics ``sin2, cos2, sin3, cos3`` (a
    compressor or heater switched on and off in part of the run loads the supply with a duty
    cycle, not a sinusoid); ``amplitude`` (the fundamental's) is informative."""

    id: ClassVar[str] = "gated_periodic"
    repeatable: ClassVar[bool] = True
    rig: ClassVar[bool] = True
    period_s: float = 1800.0
    start_s: float = 0.0
    end_s: float = 0.0
    sin1: float = 0.0
    cos1: float = 0.0
    sin2: float = 0.0
    cos2: float = 0.0
    sin3: float = 0.0
    cos3: float = 0.0
    sin4: float = 0.0
    cos4: float = 0.0
    sin5: float = 0.0
    cos5: float = 0.0
    offset: float = 0.0
    amplitude: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        phase = 2.0 * np.pi * s.t_s / self.period_s
        wave = self.offset + sum(getattr(self, f"sin{k}") * np.sin(k * phase) + getattr(self, f"cos{k}") * np.cos(k * phase)
                                 for k in range(1, 6))
        return np.where((s.t_s >= self.start_s) & (s.t_s < self.end_s), wave, 0.0)


@dataclass(frozen=True)
class DutyCycle(Effect):
    """A load switched on for a share ``duty`` of every ``period_s`` (from ``on_s``), inside
    ``[start_s, end_s)`` only: the bias moves by ``offset`` in the span and by ``size`` more
    while the load is on (a compressor or heater on a thermostat)."""

    id: ClassVar[str] = "duty_cycle"
    repeatable: ClassVar[bool] = True
    rig: ClassVar[bool] = True
    period_s: float = 1800.0
    on_s: float = 0.0
    duty: float = 0.5
    start_s: float = 0.0
    end_s: float = 0.0
    offset: float = 0.0
    size: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        on = np.mod(s.t_s - self.on_s, self.period_s) < self.duty * self.period_s
        return np.where((s.t_s >= self.start_s) & (s.t_s < self.end_s), self.offset + self.size * on, 0.0)


@dataclass(frozen=True)
class Transient(Effect):
    """A jump of ``amplitude`` at ``time_s`` decaying with ``tau_s`` (settling after a handling event)."""

    id: ClassVar[str] = "transient"
    repeatable: ClassVar[bool] = True
    clock_keyed: ClassVar[bool] = True
    time_s: float = 0.0
    tau_s: float = 1800.0
    amplitude: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        age = s.t_s - self.time_s
        return np.where(age >= 0.0, self.amplitude * np.exp(-np.maximum(age, 0.0) / self.tau_s), 0.0)


@dataclass(frozen=True)
class TemperatureBump(Effect):
    """A Gaussian bump of the bias in die temperature, ``amplitude`` at ``centre_c``, width
    ``width_c`` (an activity dip: a mode crossing at one temperature)."""

    id: ClassVar[str] = "temperature_bump"
    repeatable: ClassVar[bool] = True
    centre_c: float = 25.0
    width_c: float = 2.0
    amplitude: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return self.amplitude * np.exp(-0.5 * ((s.temp_die_c - self.centre_c) / self.width_c) ** 2)


@dataclass(frozen=True)
class SecondNode(Effect):
    """``coef_per_c * (lag(T_die, tau_s) - T_die)``: a second thermal node (a mount or board)
    with its own time constant, unseen by the thermometer."""

    id: ClassVar[str] = "second_node"
    repeatable: ClassVar[bool] = True
    tau_s: float = 3600.0
    coef_per_c: float = 0.0

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        return self.coef_per_c * (first_order_lag(s.temp_die_c, s.dt_s, self.tau_s) - s.temp_die_c)


@dataclass(frozen=True)
class Saturation(Effect):
    """Output clipped to ``[lower, upper]`` (output unit): a range limit, ADC clipping or a
    filter's overflow. A side left at its infinite default does not clip (and is not listed
    in :meth:`params`)."""

    id: ClassVar[str] = "saturation"
    stage: ClassVar[str] = "final"
    upper: float = float("inf")
    lower: float = float("-inf")

    def __post_init__(self) -> None:
        if np.isnan(self.upper) or np.isnan(self.lower) or not self.upper > self.lower:
            raise ValueError(f"saturation: upper must be above lower, got upper={self.upper!r}, lower={self.lower!r}")
        if np.isinf(self.upper) and np.isinf(self.lower):
            raise ValueError("saturation: give upper, lower or both (the clip levels, output unit)")

    def transform(self, y: np.ndarray) -> np.ndarray:
        return np.clip(y, self.lower, self.upper)

    def params(self) -> dict[str, float]:
        return {k: v for k, v in dataclasses.asdict(self).items() if np.isfinite(v)}


@dataclass(frozen=True)
class ThermometerQuantisation(Effect):
    """Thermometer reading rounded to multiples of ``step_c`` (degC; a whole-degree register
    gives 1.0); the die temperature the output follows is not rounded."""

    id: ClassVar[str] = "thermometer_quantisation"
    stage: ClassVar[str] = "thermometer"
    step_c: float = 1.0

    def __post_init__(self) -> None:
        if not self.step_c > 0:
            raise ValueError(f"thermometer_quantisation: step_c must be > 0, got {self.step_c!r}")

    def reading(self, temp_c: np.ndarray) -> np.ndarray:
        return noise.quantise(temp_c, self.step_c)


@dataclass(frozen=True)
class NoiseTemperature(Effect):
    """White noise whose level depends on the die temperature: per-sample standard deviation
    ``density * sqrt(fs) * exp(growth_per_c * (T_die - ref_c))`` (``density`` in output unit
    per sqrt(Hz) at ``ref_c``; ``growth_per_c`` the relative growth of sigma per degC)."""

    id: ClassVar[str] = "noise_temperature"
    stochastic: ClassVar[bool] = True
    density: float = 0.0
    growth_per_c: float = 0.0
    ref_c: float = 25.0

    def __post_init__(self) -> None:
        if not self.density >= 0:
            raise ValueError(f"noise_temperature: density must be >= 0, got {self.density!r}")

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        x = noise.white(s.t_s.size, self.density / np.sqrt(s.dt_s), rng)
        x *= np.exp(self.growth_per_c * (s.temp_die_c - self.ref_c))
        return x


@dataclass(frozen=True)
class NoiseTime(Effect):
    """White noise whose level changes with time: per-sample standard deviation
    ``density * sqrt(fs) * exp(growth_per_h * (t - ref_s) / 3600)`` (``density`` in output unit
    per sqrt(Hz) at ``t = ref_s`` on the record's clock; ``growth_per_h`` the relative growth of
    sigma per hour). A reference inside the record keeps the level finite on an epoch clock."""

    id: ClassVar[str] = "noise_time"
    stochastic: ClassVar[bool] = True
    density: float = 0.0
    growth_per_h: float = 0.0
    ref_s: float = 0.0

    def __post_init__(self) -> None:
        if not self.density >= 0:
            raise ValueError(f"noise_time: density must be >= 0, got {self.density!r}")

    def term(self, s: Signals, rng: np.random.Generator) -> np.ndarray:
        x = noise.white(s.t_s.size, self.density / np.sqrt(s.dt_s), rng)
        x *= np.exp(self.growth_per_h * (s.t_s - self.ref_s) / 3600.0)
        return x


EFFECTS: dict[str, type[Effect]] = {
    cls.id: cls
    for cls in (
        ThermalLag, TemperatureRate, Hysteresis, Warmup, AgingDrift, TemperatureCubic,
        AccelNonlinearity, BiasInstability, WhiteNoise, RandomWalk, Quantisation,
        BiasStep, Periodic, GatedPeriodic, DutyCycle, Transient, TemperatureBump, SecondNode,
        Saturation, ThermometerQuantisation, NoiseTemperature, NoiseTime,
    )
}


EFFECTS_GROUP = "tcbench.effects"


class _EffectPlugins(PluginRegistry[Effect]):
    """Effects of installed packages (entry-point group ``tcbench.effects``, ``my_effect =
    "pkg.module:MyEffect"``): the entry point's name is the effect's id, and no built-in id."""

    def check_class(self, name: str, cls: Any) -> None:
        super().check_class(name, cls)
        if cls.id != name:
            raise TypeError(f"entry point {name!r} names effect {cls.id!r}: the name must be the effect's id")
        if name in EFFECTS:
            raise ValueError(f"effect {name!r} is a built-in effect")
        if cls.stage not in STAGES:
            raise ValueError(f"effect {name!r}: stage {cls.stage!r} is none of {', '.join(STAGES)}")


DIE, OUTPUT, FINAL, THERMOMETER = STAGES = ("die", "output", "final", "thermometer")
PLUGINS: PluginRegistry[Effect] = _EffectPlugins(EFFECTS_GROUP, Effect, "effect")


def plugin_effects() -> dict[str, type[Effect]]:
    """The installed plugin effects by id (imports them all; a broken one is in ``PLUGINS.broken()``)."""
    return {name: entry.cls for name, entry in PLUGINS.available().items()}


def known_effects() -> list[str]:
    """Every effect id, built-in and installed (without importing any plugin)."""
    return sorted({*EFFECTS, *(n for n in PLUGINS.names() if n not in EFFECTS)})


MAX_REPEATS = 3  # instances of one repeatable effect in a model: ``bias_step``, ``bias_step_2``, ``bias_step_3``


def effect_class(effect_id: str) -> type[Effect] | None:
    """The effect class of ``effect_id``: an id of :data:`EFFECTS` or an installed plugin effect
    (imported on first use), or a further instance of a ``repeatable`` one of either
    (``bias_step_2``: a second step); None for an unknown id or a broken plugin."""
    cls = _base_effect_class(effect_id)
    if cls is not None:
        return cls
    base, _, k = effect_id.rpartition("_")
    if k.isdigit() and 2 <= int(k) <= MAX_REPEATS:
        cls = _base_effect_class(base)
        return cls if cls is not None and cls.repeatable else None
    return None


def _base_effect_class(effect_id: str) -> type[Effect] | None:
    """The class of a built-in or installed plugin effect named exactly ``effect_id``."""
    if effect_id in EFFECTS:
        return EFFECTS[effect_id]
    if effect_id in PLUGINS.names():
        try:
            return PLUGINS.get(effect_id)
        except KeyError:
            return None
    return None


def repeatable_effects() -> list[str]:
    """The ids of the built-in effects a model may hold more than once."""
    return [i for i, cls in EFFECTS.items() if cls.repeatable]


def make_effect(effect_id: str, **params: Any) -> Effect:
    """Build an effect by id; unknown ids or parameters raise ``ValueError`` naming the known ones."""
    cls = effect_class(effect_id)
    if cls is None:
        broken = PLUGINS.broken().get(effect_id) if effect_id in PLUGINS.names() else None
        if broken:
            raise ValueError(f"effect {effect_id!r}: plugin failed to load: {broken}")
        raise ValueError(unknown_name("effect", effect_id, known_effects()) + f" (and <id>_2 ... _{MAX_REPEATS} for "
                         f"further instances of {', '.join(repeatable_effects())})")
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(params) - known)
    if unknown:
        raise ValueError(f"effect {effect_id!r} has no parameter {', '.join(unknown)}; known: {', '.join(sorted(known))}")
    unbounded = {f.name for f in dataclasses.fields(cls) if isinstance(f.default, float) and np.isinf(f.default)}
    values = {}
    for key, value in params.items():
        try:
            values[key] = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"effect {effect_id!r}: {key} must be a number, got {value!r}") from None
        if np.isnan(values[key]) or (np.isinf(values[key]) and key not in unbounded):  # a limit may be ±inf
            raise ValueError(f"effects.{effect_id}.{key}: {values[key]:g} is not finite")
    return cls(**values)


def at_stage(effects: Iterable[Effect], stage: str) -> list[Effect]:
    """The effects acting at ``stage`` (one of :data:`STAGES`), in list order."""
    return [effect for effect in effects if effect.stage == stage]


def apply_effects(
    base: np.ndarray, effects: list[Effect], s: Signals, rng: np.random.Generator
) -> np.ndarray:
    """Add the ``output`` terms to ``base`` (in place: pass a fresh array) and apply the ``final``
    stage, in list order, each effect drawing from its own child stream of ``rng``."""
    streams = rng.spawn(len(effects)) if effects else []
    y = base
    for effect, stream in zip(effects, streams, strict=True):
        if effect.stage == OUTPUT:
            y += effect.term(s, stream)
    for effect in at_stage(effects, FINAL):
        y = effect.transform(y)
    return y


def thermometer_reading(effects: list[Effect], temp_c: np.ndarray) -> np.ndarray:
    """The thermometer reading after the ``thermometer`` stage effects (``temp_c`` if none)."""
    for effect in at_stage(effects, THERMOMETER):
        temp_c = effect.reading(temp_c)
    return temp_c


def die_temperature(effects: list[Effect], s: Signals) -> np.ndarray:
    """Die temperature after the ``die`` stage effects (the thermometer's if none)."""
    temp = s.temp_meas_c
    for effect in at_stage(effects, DIE):
        temp = effect.die_temperature(dataclasses.replace(s, temp_meas_c=temp))
    return temp
