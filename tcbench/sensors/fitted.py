"""A fitted sensor model: polynomial bias and scale factor in the die temperature, plus effects.

The core of :class:`PolynomialModel` serves every sensor kind (:mod:`tcbench.sensors.kinds`)::

    output = sum_j bias[j] u^j + input * sum_j scale_factor[j] u^j,   u = (T_die - centre_c) / half_range_c

with ``input`` the kind's applied input: the acceleration along the sensitive axis in g (MSRA,
output in Hz; accelerometer, output in g) or the applied rate in deg/s (gyroscope, output in deg/s). This is what ``tcbench diagnose`` fits to
a recording and writes as a model file (:mod:`tcbench.diagnose.model_file`); the effects
(lag, warm-up, noise, ...) are the same objects as in the physical models.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.polynomial import polynomial as npoly

from tcbench.sensors import effects as fx
from tcbench.sensors import kinds
from tcbench.sensors.models import SensorModel


@dataclass(frozen=True)
class PolynomialModel(SensorModel):
    """Polynomial core in the normalised die temperature ``u`` (see the module docstring).

    ``bias`` is in the output unit (Hz or deg/s) per power of ``u``; ``scale_factor`` in the
    output unit per input unit (Hz/g or (deg/s)/(deg/s)) per power of ``u``. ``centre_c`` and
    ``half_range_c`` are in degC; ``ref_c`` (the reference of effects such as
    ``temperature_cubic``) is normally ``centre_c``. ``spike_time_s`` (s on the simulation
    clock) and ``spike_size`` (output unit) are isolated outliers found by ``tcbench diagnose``,
    added to the core output at those samples (see :meth:`spikes`).
    """

    sensor: str = "msra"
    centre_c: float = 25.0
    half_range_c: float = 50.0
    bias: tuple[float, ...] = (0.0,)
    scale_factor: tuple[float, ...] = (1.0,)
    spike_time_s: tuple[float, ...] = ()
    spike_size: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        kinds.get(self.sensor)  # a known kind, or one line naming them
        if not np.isfinite(self.centre_c):
            raise ValueError(f"centre_c must be finite, got {self.centre_c!r}")
        if not (np.isfinite(self.half_range_c) and self.half_range_c > 0):
            raise ValueError(f"half_range_c must be a positive number, got {self.half_range_c!r}")
        for name in ("bias", "scale_factor"):
            values = tuple(float(v) for v in np.atleast_1d(getattr(self, name)))
            if not values:
                raise ValueError(f"{name} needs at least one coefficient")
            if not all(np.isfinite(values)):
                raise ValueError(f"{name} coefficients must be finite, got {values!r}")
            object.__setattr__(self, name, values)
        spikes = tuple(tuple(float(v) for v in np.atleast_1d(getattr(self, n))) for n in ("spike_time_s", "spike_size"))
        if len(spikes[0]) != len(spikes[1]) or not np.all(np.isfinite(spikes[0] + spikes[1])):
            raise ValueError("spike_time_s and spike_size must be finite and of equal length")
        object.__setattr__(self, "spike_time_s", spikes[0])
        object.__setattr__(self, "spike_size", spikes[1])
        object.__setattr__(self, "centre_c", float(self.centre_c))
        object.__setattr__(self, "half_range_c", float(self.half_range_c))

    @property
    def kind(self) -> str:  # type: ignore[override]
        """The sensor kind (checked against a protocol's)."""
        return self.sensor

    @property
    def scale_factor_hz_per_g(self) -> float | None:
        """Nominal scale factor at ``centre_c`` (Hz/g) of a kind whose output is in another unit than
        its input (an MSRA's, :attr:`~tcbench.sensors.kinds.SensorKind.scaled`); None for other kinds."""
        return self.scale_factor[0] if kinds.get(self.sensor).scaled else None

    def normalised(self, temp_c: np.ndarray) -> np.ndarray:
        """``u = (T - centre_c) / half_range_c`` (dimensionless)."""
        return (np.asarray(temp_c, dtype=float) - self.centre_c) / self.half_range_c

    def bias_at(self, temp_c: np.ndarray) -> np.ndarray:
        """Zero-input output at die temperature ``temp_c`` (degC), in the output unit."""
        return npoly.polyval(self.normalised(temp_c), self.bias)

    def scale_factor_at(self, temp_c: np.ndarray) -> np.ndarray:
        """Scale factor at die temperature ``temp_c`` (degC), output unit per input unit."""
        return npoly.polyval(self.normalised(temp_c), self.scale_factor)

    def core(self, s: fx.Signals) -> np.ndarray:
        u = self.normalised(s.temp_die_c)
        applied = getattr(s, kinds.get(self.sensor).input_field)
        return npoly.polyval(u, self.bias) + applied * npoly.polyval(u, self.scale_factor) + self.spikes(s.t_s)

    def spikes(self, t_s: np.ndarray) -> np.ndarray:
        """The isolated outliers of the model (output unit) on the clock ``t_s`` (s): each
        ``spike_size`` added to the sample nearest its ``spike_time_s``, if that sample lies
        within half a sample interval of it (spikes outside the clock are dropped)."""
        out = np.zeros(np.shape(t_s))
        if not self.spike_time_s or out.size == 0:
            return out
        times, sizes = np.asarray(self.spike_time_s), np.asarray(self.spike_size)
        dt = float(np.median(np.diff(t_s))) if out.size > 1 else np.inf
        right = np.clip(np.searchsorted(t_s, times), 0, out.size - 1)
        left = np.clip(right - 1, 0, out.size - 1)
        i = np.where(np.abs(t_s[left] - times) <= np.abs(t_s[right] - times), left, right)
        on = np.abs(t_s[i] - times) <= 0.5 * dt
        np.add.at(out, i[on], sizes[on])
        return out

    def describe(self) -> dict[str, Any]:
        core = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name != "effects"}
        return {"model": "polynomial", **core, "effects": {e.id: e.params() for e in self.effects}}
