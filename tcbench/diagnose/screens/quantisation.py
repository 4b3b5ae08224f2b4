"""Quantisation: the output, or the thermometer, read on a grid.

**Output.** A converter or counter of resolution ``q`` puts every output sample on a lattice
``offset + k q``. :func:`lattice_step` finds ``q`` from the values themselves, with or without
noise to dither them:

1. the smallest non-zero jump between consecutive samples is the candidate step ``q0`` (a
   noisy output jumps by one step often; a noise-free staircase does at every level change);
2. every non-zero jump must be an integer multiple of ``q0`` to ``tolerance_steps`` of a step,
   and ``q`` is refined as the median of jump / multiple;
3. **not chance**: the values' phases ``2 pi (y - y0) / q`` must line up, mean resultant
   length ``R`` at least ``min_resultant`` (1 on an exact lattice; about ``1/sqrt(n)`` for
   values off it, so a record of 200 samples or more cannot reach it by chance);
4. a lattice finer than ``min_step_sigma`` of the white noise (float storage, a CSV's
   last decimal) is real but harmless, and is not reported.

**Thermometer.** A thermometer that reads whole degrees (a Bosch IMU's register) or 1/16 degC
puts the same staircase on the temperature the model is driven by. With enough noise to dither
it (the reading's spread about its smoothed value at least ``dither_spread_steps`` of a step), the
staircase averages out in the diagnosis' smoothing; without it, a window shorter than a few
staircase periods ``q / |dT/dt|`` follows the steps, up to ``q / 2`` off. :func:`thermometer_steps`
then reports the staircase (id ``thermometer_quantisation``) and widens the smoothing window to
``periods`` staircase periods at the record's typical ramp rate (capped at ``max_window_share``,
a quarter, of the record). Measured on a 0-40 degC triangle read in whole degrees with 0.02 degC
of noise, the smoothed temperature's RMS error: 0.26 degC with the 120 s window at 0.1 degC/min, 0.020 with
3 periods (1800 s), and 0.22 vs 0.029 at 0.3 degC/min; wider windows lose at the ramps' corners.
Through a soak at a temperature between two steps the undithered reading stays up to ``q / 2``
off for the whole soak, which no window recovers: on the concealed MSRA profile (soaks of 35-50
min at levels such as 9.7 and 20.2 degC) read in whole degrees the smoothed temperature is
0.23 degC RMS off with 120 s and still 0.21 degC with the adapted 493 s.

The numbers are :class:`~tcbench.diagnose.settings.QuantisationSettings` (the lattice, the output)
and :class:`~tcbench.diagnose.settings.ThermometerSettings` (the staircase).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tcbench.diagnose.findings import Finding
from tcbench.diagnose.settings import (
    DEFAULTS,
    QuantisationSettings,
    ThermometerSettings,
)
from tcbench.diagnose.signals import local_linear

JUMP_FLOOR = 1e-9  # relative to the largest |value|: a smaller jump is float rounding, not a step of the lattice

OUTPUT_EXPLANATION = ("the output sits on a grid: the resolution of the converter or frequency counter, or a "
                      "fixed-point register; below about one step of noise the grid adds q^2/12 of variance and, "
                      "without dither, a staircase the model cannot follow")
OUTPUT_CONFIRM = ("the register width and scaling in the datasheet (LSB size), or a record at a finer output "
                  "resolution setting")
THERMO_EXPLANATION = ("the thermometer reads on a coarse grid with too little noise to dither it (a Bosch IMU "
                      "reads whole degrees): between steps the model sees a constant temperature, so its "
                      "temperature terms lag and jump; the diagnosis widened its thermometer smoothing to "
                      "average the staircase over several steps on the ramps, but through a soak the reading "
                      "stays up to half a step off the true temperature, which no smoothing recovers")
THERMO_CONFIRM = ("the temperature register's resolution in the datasheet, or a reference thermometer of finer "
                  "resolution logged alongside")


def lattice_step(values: np.ndarray, settings: QuantisationSettings = DEFAULTS.screens.quantisation
                 ) -> tuple[float, float] | None:
    """The step ``q`` of the lattice ``values`` lie on and the phases' resultant length ``R``,
    or None when they are not clearly on one (see the module doc)."""
    y = np.asarray(values, dtype=float)
    y = y[np.isfinite(y)]
    if y.size < 2:
        return None
    floor = JUMP_FLOOR * max(float(np.max(np.abs(y))), 1e-300)
    jumps = np.abs(np.diff(y))
    jumps = jumps[jumps > floor]
    if jumps.size < settings.min_jumps:
        return None
    q0 = float(jumps.min())
    multiple = np.round(jumps / q0)
    on = np.abs(jumps / q0 - multiple) <= settings.tolerance_steps
    if on.mean() < settings.min_fraction:
        return None
    q = float(np.median(jumps[on] / multiple[on]))
    phase = 2.0 * np.pi * ((y - y[0]) / q)
    resultant = float(np.hypot(np.cos(phase).mean(), np.sin(phase).mean()))
    return (q, resultant) if resultant >= settings.min_resultant else None


@dataclass(frozen=True)
class OutputQuantisation:
    """The output's lattice step ``step`` (output unit) and the phase alignment behind it."""

    step: float
    resultant: float
    white_sigma: float
    levels: int
    settings: QuantisationSettings = field(default=DEFAULTS.screens.quantisation, repr=False)

    def finding(self, unit: str) -> Finding:
        """The report.json ``effects`` entry (``quantisation``, written to model.yaml as the
        library's ``quantisation: {step}``)."""
        return Finding(
            id="quantisation", shape="quantisation", library=False,
            params={"step": self.step},
            where={"level": self.step},
            evidence={"resultant": round(self.resultant, 6), "min_resultant": self.settings.min_resultant,
                      "step_over_sigma": round(self.step / self.white_sigma, 4), "levels": self.levels,
                      "test": "every non-zero sample-to-sample jump an integer multiple of the step and every "
                              "value's phase on the lattice (mean resultant length)"},
            explanation=f"the output is on a grid of {self.step:.4g} {unit} "
                        f"({self.step / self.white_sigma:.3g} white sigma, {self.levels} levels used): "
                        + OUTPUT_EXPLANATION,
            confirm_with=OUTPUT_CONFIRM,
        )


def find_output_quantisation(output: np.ndarray, white_sigma: float,
                             settings: QuantisationSettings = DEFAULTS.screens.quantisation
                             ) -> OutputQuantisation | None:
    """The output's lattice, when it is clearly one and at least ``min_step_sigma`` of the
    white noise ``white_sigma`` (output unit); None otherwise."""
    found = lattice_step(output, settings)
    if found is None or not found[0] >= settings.min_step_sigma * white_sigma:
        return None
    q, resultant = found
    levels = int(np.unique(np.round((np.asarray(output, dtype=float) - output[0]) / q)).size)
    return OutputQuantisation(q, resultant, float(white_sigma), levels, settings)


@dataclass(frozen=True)
class ThermometerSteps:
    """The thermometer's lattice: ``step_c`` (degC), its spread about the default smoothing in
    steps, the typical ramp rate (degC/s), the staircase period ``step_c / rate`` (s) and the
    smoothing window chosen for it (s); ``staircase`` whether it is coarse and undithered."""

    step_c: float
    spread_steps: float
    rate_c_per_s: float
    period_s: float
    smooth_s: float
    default_smooth_s: float
    staircase: bool
    settings: ThermometerSettings = field(default=DEFAULTS.screens.thermometer, repr=False)

    def finding(self) -> Finding:
        """The report.json ``effects`` entry (``thermometer_quantisation``, shape quantisation)."""
        widened = self.smooth_s > self.default_smooth_s
        return Finding(
            id="thermometer_quantisation", shape="quantisation", library=False,
            params={"step_c": self.step_c, "smooth_s": self.smooth_s},
            where={"level": self.step_c},
            evidence={"spread_steps": round(self.spread_steps, 4), "dither_spread_steps": self.settings.dither_spread_steps,
                      "typical_rate_c_per_min": round(60.0 * self.rate_c_per_s, 4),
                      "staircase_period_s": round(self.period_s, 2),
                      "test": "thermometer values on a lattice; reading spread about its smoothed value below "
                              f"{self.settings.dither_spread_steps} step (not dithered)"},
            explanation=(f"the thermometer reads in steps of {self.step_c:.4g} degC "
                         f"(a step every {self.period_s:.0f} s at the typical {60.0 * self.rate_c_per_s:.3g} "
                         "degC/min): " + THERMO_EXPLANATION
                         + (f" (from {self.default_smooth_s:.0f} s to {self.smooth_s:.0f} s)" if widened
                            else " (the default window already spans enough steps)")),
            confirm_with=THERMO_CONFIRM,
        )


def thermometer_steps(t_s: np.ndarray, temp_c: np.ndarray, default_smooth_s: float,
                      settings: ThermometerSettings = DEFAULTS.screens.thermometer,
                      lattice: QuantisationSettings = DEFAULTS.screens.quantisation) -> ThermometerSteps | None:
    """The thermometer's lattice (found as ``lattice`` says) and the smoothing window it needs,
    or None when the reading is not on a lattice coarser than ``min_step_c`` (see the module doc)."""
    found = lattice_step(temp_c, lattice)
    if found is None or found[0] < settings.min_step_c:
        return None
    q = found[0]
    duration_s = float(t_s[-1] - t_s[0])
    value, _ = local_linear(t_s, temp_c, min(default_smooth_s, duration_s))
    spread = float(np.std(temp_c - value)) / q
    _, slow_rate = local_linear(t_s, temp_c, min(settings.rate_window_s, settings.max_window_share * duration_s))
    speed = np.abs(slow_rate)
    top = float(np.quantile(speed, settings.fast_quantile))
    typical = float(np.median(speed[speed >= settings.moving_share * top])) if top > 0 else 0.0
    period = q / typical if typical > 0 else np.inf
    staircase = spread < settings.dither_spread_steps
    window = default_smooth_s
    if staircase:
        window = float(np.clip(settings.periods * period, default_smooth_s,
                               max(default_smooth_s, settings.max_window_share * duration_s)))
    return ThermometerSteps(q, spread, typical, float(period), window, default_smooth_s, staircase, settings)
