"""PX4 thermal calibration: a sensor's offset as the 3rd-order polynomial PX4 ships, fitted to
a recording and exported as its ``TC_*`` parameters.

PX4's documented compensation (docs.px4.io, "Thermal Calibration and Compensation"): for sensor
type ``G`` (rate gyro) or ``A`` (accelerometer), instance ``i`` and axis ``a`` (0, 1, 2 = X, Y,
Z in the board frame), the temperature is held to the calibrated range ``[TC_<t><i>_TMIN,
TC_<t><i>_TMAX]``, ``dT = T - TC_<t><i>_TREF``, the offset is ``X0 + X1 dT + X2 dT^2 + X3 dT^3``
with ``Xn = TC_<t><i>_X<n>_<a>``, and it is subtracted from the reading. PX4 keeps the values as
32-bit floats, in its units: rad/s for a gyro, m/s^2 for an accelerometer. ``TC_<t><i>_ID`` names
the sensor (its ``device_id``); ``TC_<t>_ENABLE`` switches the compensation on.

What the offset holds follows PX4's own fit (``Tools/process_sensor_caldata.py``): a gyro's
polynomial is its whole offset (at rest the compensated rate reads 0); an accelerometer's is the
change of its offset with temperature, fitted after the median of the static reading is taken
off each axis, so the static level (gravity and the bias at rest) stays in the reading and
belongs to the ordinary calibration ``CAL_ACCn_*`` (:func:`px4_polynomial`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tcbench.sensors import kinds

ORDER = 3


def px4_type(sensor: str) -> tuple[str, str]:
    """PX4's parameter letter and unit of a sensor kind (``G``, rad/s for a gyro)."""
    covered = {k.name: (k.px4_letter, k.ulog_unit or k.output_unit) for k in kinds.registry().values() if k.px4_letter}
    if sensor not in covered:
        raise ValueError(f"PX4 thermal calibration covers {', '.join(covered)}, not {sensor!r}")
    return covered[sensor]  # type: ignore[return-value]


def px4_covers(sensor: str | None) -> bool:
    """Whether PX4 has thermal-calibration parameters for this kind."""
    return sensor is not None and kinds.known(sensor) and kinds.get(sensor).px4_letter is not None


def px4_factor(sensor: str, unit: str) -> float:
    """The multiplier from ``unit`` (a recording's output unit) to PX4's unit of ``sensor``
    (pi/180 from deg/s to rad/s; 9.80665 from g to m/s^2)."""
    from tcbench.sensors.units import conversion

    return 1.0 / conversion(px4_type(sensor)[1], unit).mul


@dataclass(frozen=True)
class OffsetPolynomial:
    """One axis's offset: ``x[n]`` the coefficient of ``dT**n`` (in the sensor unit), ``dT = T -
    tref_c`` with ``T`` held to ``[tmin_c, tmax_c]``."""

    x: tuple[float, float, float, float]
    tref_c: float
    tmin_c: float
    tmax_c: float

    def offset(self, temp_c: np.ndarray) -> np.ndarray:
        """The offset at ``temp_c`` (°C) by PX4's formula."""
        dt = np.clip(np.asarray(temp_c, dtype=np.float64), self.tmin_c, self.tmax_c) - self.tref_c
        return self.x[0] + dt * (self.x[1] + dt * (self.x[2] + dt * self.x[3]))


def fit_offset(temp_c: np.ndarray, reading: np.ndarray, tref_c: float | None = None) -> OffsetPolynomial:
    """The least-squares cubic offset of ``reading`` over ``temp_c``; ``tref_c`` defaults to the
    middle of the temperatures seen, ``tmin_c``/``tmax_c`` are their extremes (beyond them PX4
    holds the offset at the edge instead of extrapolating a cubic)."""
    t = np.asarray(temp_c, dtype=np.float64)
    y = np.asarray(reading, dtype=np.float64)
    if t.shape != y.shape or t.ndim != 1 or t.size <= ORDER:
        raise ValueError(f"need matching 1-D temperature and reading arrays of more than {ORDER} samples")
    if not (np.isfinite(t).all() and np.isfinite(y).all()):
        raise ValueError("temperature and reading must be finite")
    tmin, tmax = float(t.min()), float(t.max())
    if tmax - tmin <= 0.0:
        raise ValueError("the temperature does not vary: no offset polynomial can be fitted")
    tref = 0.5 * (tmin + tmax) if tref_c is None else float(tref_c)
    coef = np.polynomial.polynomial.polyfit(t - tref, y, ORDER)
    return OffsetPolynomial(tuple(float(c) for c in coef), tref, tmin, tmax)  # type: ignore[arg-type]


AXES = ("x", "y", "z")  # PX4's axis index 0, 1, 2; ArduPilot's _X, _Y, _Z


def reexpanded(poly: OffsetPolynomial, tref_c: float, tmin_c: float, tmax_c: float) -> OffsetPolynomial:
    """The same cubic written about another reference ``tref_c`` (exact: a binomial shift of
    ``dT``), held to the range ``[tmin_c, tmax_c]`` instead of its own."""
    shift = np.polynomial.Polynomial([tref_c - poly.tref_c, 1.0])  # T - tref_old as a polynomial in T - tref_new
    coef = np.zeros(ORDER + 1)
    expanded = np.polynomial.Polynomial(poly.x)(shift).coef
    coef[:expanded.size] = expanded
    return OffsetPolynomial(tuple(float(c) for c in coef), float(tref_c), float(tmin_c), float(tmax_c))  # type: ignore[arg-type]


def common_range(axes: Mapping[str, OffsetPolynomial]) -> dict[str, OffsetPolynomial]:
    """The axes of one sensor on one temperature range, as PX4 and ArduPilot keep it per sensor:
    unchanged when they share one; otherwise each re-expanded about the middle of the range every
    axis was fitted over (the intersection, so no axis extrapolates its cubic). ``ValueError`` when
    the ranges do not overlap or an axis is not x, y or z."""
    if not axes:
        raise ValueError("no axis to export")
    if bad := [a for a in axes if a not in AXES]:
        raise ValueError(f"axis {bad[0]!r}: the axes are x, y and z")
    polys = list(axes.values())
    if all((p.tref_c, p.tmin_c, p.tmax_c) == (polys[0].tref_c, polys[0].tmin_c, polys[0].tmax_c) for p in polys):
        return dict(axes)
    lo, hi = max(p.tmin_c for p in polys), min(p.tmax_c for p in polys)
    if not hi > lo:
        raise ValueError("the axes' fitted temperature ranges do not overlap: calibrate them on one record")
    return {a: reexpanded(p, 0.5 * (lo + hi), lo, hi) for a, p in axes.items()}


def keeps_static_level(sensor: str) -> bool:
    """Whether PX4 leaves ``sensor``'s static level to its ordinary calibration (an
    accelerometer: its ``TC_A*`` polynomial is fitted about the median reading), rather than
    taking the whole offset into ``TC_*`` (a gyro)."""
    return px4_type(sensor)[0] == "A"


def px4_polynomial(poly: OffsetPolynomial, sensor: str, static_level: float) -> OffsetPolynomial:
    """``poly`` (a whole-record offset fit) as PX4 takes it for ``sensor``: unchanged for a gyro;
    for an accelerometer less ``static_level`` (the median of the static reading, same unit), so
    that PX4's subtraction leaves that level in the reading."""
    if not keeps_static_level(sensor):
        return poly
    return OffsetPolynomial((poly.x[0] - float(static_level), *poly.x[1:]), poly.tref_c, poly.tmin_c, poly.tmax_c)


def px4_parameters(axes: Mapping[str, OffsetPolynomial], sensor: str = "gyro", instance: int = 0,
                   device_id: int = 0, to_px4_unit: float = 1.0) -> dict[str, float | int]:
    """The ``TC_*`` parameters of one sensor instance, each axis in its own slot (``x`` -> ``_0``,
    ``y`` -> ``_1``, ``z`` -> ``_2``; an axis not given gets zero coefficients, no correction), the
    coefficients multiplied by ``to_px4_unit`` (e.g. pi/180 from deg/s to PX4's rad/s) and
    rounded to 32-bit floats as PX4 stores them. The axes share one ``TREF``/``TMIN``/``TMAX``
    (:func:`common_range`)."""
    if not isinstance(axes, Mapping):
        raise TypeError("axes: a mapping of axis name (x, y, z) to its OffsetPolynomial")
    if not 0 <= instance <= 3:
        raise ValueError("instance 0..3")
    shared = common_range(axes)
    first = next(iter(shared.values()))
    t = px4_type(sensor)[0]
    head = f"TC_{t}{instance}"
    params: dict[str, float | int] = {f"{head}_ID": int(device_id)}
    for n in range(ORDER + 1):
        for a, name in enumerate(AXES):
            c = shared[name].x[n] if name in shared else 0.0
            params[f"{head}_X{n}_{a}"] = float(np.float32(c * to_px4_unit))
    params |= {f"{head}_TREF": float(np.float32(first.tref_c)), f"{head}_TMIN": float(np.float32(first.tmin_c)),
               f"{head}_TMAX": float(np.float32(first.tmax_c))}
    return params


def px4_offset(params: Mapping[str, float | int], temp_c: np.ndarray, sensor: str = "gyro", instance: int = 0,
               axis: int | str = 0) -> np.ndarray:
    """The offset PX4 subtracts from ``axis`` (0, 1, 2 or x, y, z), in PX4's unit, evaluated from
    the parameters alone (32-bit, as on the flight controller)."""
    head = f"TC_{px4_type(sensor)[0]}{instance}"
    axis = AXES.index(axis) if isinstance(axis, str) else axis
    f32 = np.float32
    tmin, tmax, tref = (f32(params[f"{head}_{k}"]) for k in ("TMIN", "TMAX", "TREF"))
    x = [f32(params[f"{head}_X{n}_{axis}"]) for n in range(ORDER + 1)]
    dt = np.clip(np.asarray(temp_c, dtype=f32), tmin, tmax) - tref
    return x[0] + x[1] * dt + x[2] * dt ** 2 + x[3] * dt ** 3


def write_parameters(params: Mapping[str, float | int], path: str | Path, sensors: Sequence[str] | str,
                     comments: Sequence[str] = ()) -> Path:
    """``params`` as a PX4 console script (``param set NAME VALUE`` per line, then the enable
    switch of each of ``sensors``), to paste into the NuttX shell or run from the SD card;
    ``comments`` first, each a ``#`` line the shell skips."""
    lines = [f"# {c}" for c in comments] + [f"param set {k} {v:d}" if isinstance(v, int) else f"param set {k} {v:.9g}" for k, v in params.items()]
    kinds_ = [sensors] if isinstance(sensors, str) else list(sensors)
    lines += [f"param set TC_{px4_type(s)[0]}_ENABLE 1" for s in dict.fromkeys(kinds_)]
    path = Path(path)
    path.write_text("\n".join(lines) + "\n")
    return path
