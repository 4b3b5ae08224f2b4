"""ArduPilot thermal calibration: a sensor's offset cubic as its ``INS_TCALn_*`` parameters.

ArduPilot's IMU temperature calibration (``AP_InertialSensor_tempcal``, the form its
``tempcal_IMU.py`` writes): for IMU ``n`` (1..3) one temperature range ``INS_TCALn_TMIN``..``TMAX``
shared by the accelerometer and the gyro, and per axis a cubic *without* its constant term about
35 °C, its coefficients multiplied by 1e6 so that they read well in a parameter editor:
``p(u) = (C1 u + C2 u^2 + C3 u^3) * 1e-6`` with ``u = T - 35``, ``Ck`` =
``INS_TCALn_ACCk_<X|Y|Z>`` (m/s^2) or ``INS_TCALn_GYRk_<X|Y|Z>`` (rad/s). The firmware holds the
temperature ``T`` and the temperature of the sensor's ordinary calibration (``INS_ACCn_CALTEMP``,
``INS_GYRn_CALTEMP``) to the range and corrects a reading ``v`` as ``v - p(T) + p(T_cal)``: the
ordinary calibration owns the offset at ``T_cal``, this one the change with temperature. So the
constant of the fitted cubic does not travel, and what comes back is ``offset(T) - offset(T_cal)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from tcbench.compensation.px4 import AXES, ORDER, OffsetPolynomial, reexpanded
from tcbench.sensors import kinds

TEMP_REFERENCE_C = 35.0
SCALE = 1.0e6


def _letters(sensor: str) -> str:
    """The letters of ``sensor``'s ``INS_TCALn_*`` parameters (its kind's ``ardupilot_letters``)."""
    covered = {k.name: k.ardupilot_letters for k in kinds.registry().values() if k.ardupilot_letters}
    if sensor not in covered:
        raise ValueError(f"ArduPilot's temperature calibration covers {', '.join(sorted(covered))}, not {sensor!r}")
    return covered[sensor]  # type: ignore[return-value]


def ardupilot_parameters(sensors: Mapping[str, Mapping[str, OffsetPolynomial]], imu: int = 1,
                         to_si: Mapping[str, float] | None = None) -> dict[str, float | int]:
    """The ``INS_TCAL<imu>_*`` parameters of one IMU: ``sensors`` maps ``accel``/``gyro`` to its
    axes' offsets (``x``/``y``/``z``; an axis not given gets zero coefficients), ``to_si`` each
    sensor's factor from the fit's unit to ArduPilot's (m/s^2, rad/s). The accelerometer and the gyro
    share one range (the intersection of theirs, :func:`~tcbench.compensation.px4.common_range`)."""
    if not 1 <= imu <= 3:
        raise ValueError("imu 1..3")
    if not sensors:
        raise ValueError("no sensor to export")
    for sensor in sensors:
        _letters(sensor)  # a kind ArduPilot calibrates, or one line
    every = [p for axes in sensors.values() for p in axes.values()]
    if not every:
        raise ValueError("no axis to export")
    lo, hi = max(p.tmin_c for p in every), min(p.tmax_c for p in every)
    if not hi > lo:
        raise ValueError("the fitted temperature ranges do not overlap: calibrate the sensors on one record")
    head = f"INS_TCAL{imu}"
    params: dict[str, float | int] = {f"{head}_ENABLE": 1, f"{head}_TMIN": float(np.float32(lo)),
                                      f"{head}_TMAX": float(np.float32(hi))}
    for sensor, axes in sensors.items():
        letters, factor = _letters(sensor), (to_si or {}).get(sensor, 1.0)
        if bad := [a for a in axes if a not in AXES]:
            raise ValueError(f"axis {bad[0]!r}: the axes are x, y and z")
        about35 = {a: reexpanded(p, TEMP_REFERENCE_C, lo, hi) for a, p in axes.items()}
        for k in range(1, ORDER + 1):
            for a in AXES:
                c = about35[a].x[k] if a in about35 else 0.0
                params[f"{head}_{letters}{k}_{a.upper()}"] = float(np.float32(c * factor * SCALE))
    return params


def ardupilot_correction(params: Mapping[str, float | int], temp_c: np.ndarray, cal_temp_c: float, sensor: str,
                         imu: int = 1, axis: str = "x") -> np.ndarray:
    """What ArduPilot subtracts from ``axis`` of ``sensor`` at ``temp_c`` (its unit, 32-bit, from
    the parameters alone): ``p(T) - p(T_cal)``, both temperatures held to ``TMIN..TMAX``."""
    head, f32 = f"INS_TCAL{imu}", np.float32
    tmin, tmax = f32(params[f"{head}_TMIN"]), f32(params[f"{head}_TMAX"])
    c = [f32(params[f"{head}_{_letters(sensor)}{k}_{axis.upper()}"]) for k in range(1, ORDER + 1)]

    def p(t: np.ndarray) -> np.ndarray:
        u = np.clip(np.asarray(t, dtype=f32), tmin, tmax) - f32(TEMP_REFERENCE_C)
        return (c[0] + (c[1] + c[2] * u) * u) * u * f32(1.0 / SCALE)

    return p(np.asarray(temp_c)) - p(np.asarray([cal_temp_c]))[0]


def write_parm(params: Mapping[str, float | int], path: str | Path, comments: Sequence[str] = ()) -> Path:
    """``params`` as an ArduPilot parameter file (``NAME VALUE`` per line), which Mission Planner,
    MAVProxy (``param load``) and QGroundControl load; ``comments`` first, each a ``#`` line."""
    lines = [f"# {c}" for c in comments] + [f"{k} {v:d}" if isinstance(v, int) else f"{k} {v:.9g}" for k, v in params.items()]
    path = Path(path)
    path.write_text("\n".join(lines) + "\n")
    return path
