"""``tcbench export``: the calibrations of one IMU's axes, each in its slot, as PX4's TC_* and
ArduPilot's INS_TCAL* parameters; applied back as each autopilot applies them, axis by axis,
they give the fitted correction."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import PX4_LOG

from tcbench.cli import main
from tcbench.compensation.ardupilot import ardupilot_correction, ardupilot_parameters
from tcbench.compensation.px4 import OffsetPolynomial, common_range, fit_offset, px4_offset, reexpanded
from tcbench.datasets.real import TOFUPILOT_CSV
from tcbench.sensors.recording import read_recording

AXES = "xyz"


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, list[str]]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err.strip().splitlines()


@pytest.fixture()
def calibrated(workdir: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, Path]:
    """The tofupilot gyro and accelerometer imported axis by axis and calibrated (poly3 only)."""
    folders = {}
    for kind, col, unit in (("gyro", "gyro", "rad/s"), ("accel", "acc", "m/s^2")):
        outputs = ",".join(f"imu.{col}.{a}:{unit}" for a in AXES)
        code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", f"sensor={kind}", "time=timestamp:us",
                           "temperature=imu.temperature:degC", f"output={outputs}", "axes=x,y,z", "out=rec",
                           f"name={kind}", "tracking.enabled=false")
        assert code == 0, err
        for a in AXES:  # each axis from its sidecar (import axes=)
            code, _, err = run(capsys, "calibrate", f"recording=rec/{kind}-imu.{col}.{a}.csv", f"out=cal/{kind}-{a}",
                               "methods=[raw,poly3]", "tracking.enabled=false")
            assert code == 0, err
            folders[f"{kind}-{a}"] = workdir / "cal" / f"{kind}-{a}"
    return folders


def fitted(folder: Path) -> tuple[OffsetPolynomial, dict]:
    about = json.loads((folder / "calibration.json").read_text())
    fit = about["export"]
    return OffsetPolynomial(tuple(fit["x"]), fit["tref_c"], fit["tmin_c"], fit["tmax_c"]), about


def test_px4_parameters_put_every_axis_in_its_slot(calibrated: dict[str, Path], workdir: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    cals = ",".join(f"cal/{k}" for k in calibrated)
    code, out, err = run(capsys, "export", f"calibrations=[{cals}]", "device_id={gyro: 2293768, accel: 2293769}",
                         "px4_instance=1", "out=params")
    assert code == 0, err
    script = (workdir / "params" / "px4_tc_params.txt").read_text().splitlines()
    params = {ln.split()[2]: float(ln.split()[3]) for ln in script}  # as the console reads it
    assert params["TC_G1_ID"] == 2293768 and params["TC_A1_ID"] == 2293769
    assert params["TC_G_ENABLE"] == 1 and params["TC_A_ENABLE"] == 1
    temp = read_recording(workdir / "rec" / "gyro-imu.gyro.x.csv").temperature_c
    probe = np.concatenate([temp, np.linspace(-40.0, 100.0, 141)])  # beyond the range: held at the edge
    for kind, si in (("gyro", np.pi / 180), ("accel", 9.80665)):
        for i, a in enumerate(AXES):
            poly, _ = fitted(calibrated[f"{kind}-{a}"])
            px4 = px4_offset(params, probe, kind, instance=1, axis=i).astype(np.float64)
            want = poly.offset(probe) * si  # the fitted correction of THIS axis, in PX4's unit
            np.testing.assert_allclose(px4, want, atol=2e-6 * np.ptp(want) + 1e-9, err_msg=f"{kind} {a}")
            others = [fitted(calibrated[f"{kind}-{b}"])[0].offset(probe) * si for b in AXES if b != a]
            assert all(np.abs(px4 - o).max() > 100 * np.abs(px4 - want).max() for o in others), f"{kind} {a}"


def test_ardupilot_parameters_give_the_correction_relative_to_the_calibration_temperature(
        calibrated: dict[str, Path], workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cals = ",".join(f"cal/{k}" for k in calibrated)
    code, _, err = run(capsys, "export", f"calibrations=[{cals}]", "formats=[ardupilot]", "ardupilot_imu=2",
                       "out=params")
    assert code == 0, err
    lines = (workdir / "params" / "ardupilot_tcal.parm").read_text().splitlines()
    params = {ln.split()[0]: float(ln.split()[1]) for ln in lines}
    assert params["INS_TCAL2_ENABLE"] == 1 and not (workdir / "params" / "px4_tc_params.txt").exists()
    temp = np.linspace(-30.0, 90.0, 241)
    for kind, si in (("gyro", np.pi / 180), ("accel", 9.80665)):
        for a in AXES:
            poly, _ = fitted(calibrated[f"{kind}-{a}"])
            for cal_temp in (20.0, 35.0, 60.0):
                got = ardupilot_correction(params, temp, cal_temp, kind, imu=2, axis=a).astype(np.float64)
                want = (poly.offset(temp) - poly.offset(np.array([cal_temp]))[0]) * si
                np.testing.assert_allclose(got, want, atol=1e-5 * np.ptp(want) + 1e-8, err_msg=f"{kind} {a} {cal_temp}")


def test_export_refusals_are_one_line(calibrated: dict[str, Path], workdir: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "export", "calibrations=[cal/gyro-x,cal/gyro-y]", "out=p1")
    assert code == 2 and len(err) == 1 and "device_id=" in err[0], err  # PX4 needs the sensor's id
    code, _, err = run(capsys, "export", "calibrations=[cal/gyro-x,cal/gyro-x]", "out=p2", "device_id=1")
    assert code == 2 and len(err) == 1 and "both gyro axis x" in err[0], err
    code, _, err = run(capsys, "export", "calibrations=[cal/nowhere]", "out=p3", "device_id=1")
    assert code == 2 and len(err) == 1 and "no calibration.json" in err[0], err
    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                       "temperature=imu.temperature:degC", "output=imu.gyro.z:rad/s", "out=rec2", "name=noaxis",
                       "tracking.enabled=false")
    assert code == 0, err
    code, _, err = run(capsys, "calibrate", "recording=rec2/noaxis.csv", "out=cal/unknown", "methods=[poly3]",
                       "tracking.enabled=false")
    assert code == 0, err
    code, _, err = run(capsys, "export", "calibrations=[cal/unknown]", "out=p4", "device_id=1")
    assert code == 2 and len(err) == 1 and "axis is unknown" in err[0], err
    code, _, err = run(capsys, "calibrate", "recording=rec2/noaxis.csv", "out=cal/named", "methods=[poly3]",
                       "axis=z", "tracking.enabled=false")  # calibrate axis= names it
    assert code == 0, err
    code, _, err = run(capsys, "export", "calibrations=[cal/named]", "out=p5", "device_id=1")
    assert code == 0, err
    assert not any((workdir / p).exists() for p in ("p1", "p2", "p3", "p4"))


def test_a_px4_log_gives_the_axes_and_the_device_id(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Imported from a PX4 log, each recording knows its axis and the sensor's device id: the
    export needs neither axis= nor device_id=, and the id is the log's."""
    from tcbench.sensors.ulog import read_topic

    code, _, err = run(capsys, "import", f"csv={PX4_LOG}", "sensor=gyro", "out=rec", "name=log", "tracking.enabled=false")
    assert code == 0, err
    for a in AXES:
        code, _, err = run(capsys, "calibrate", f"recording=rec/log-sensor_gyro-0-{a}.csv", f"out=cal/{a}",
                           "methods=[poly3]", "train_branches=[0]", "drift_window_s=5", "tracking.enabled=false")
        assert code == 0, err
    code, _, err = run(capsys, "export", "calibrations=[cal/x,cal/y,cal/z]", "out=params")
    assert code == 0, err
    script = (workdir / "params" / "px4_tc_params.txt").read_text().splitlines()
    logged = read_topic(PX4_LOG, "gyro")[0].device_id
    assert script[0] == f"param set TC_G0_ID {logged}" and logged


def test_a_partial_sensor_gets_zeros_and_says_so(calibrated: dict[str, Path], workdir: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "export", "calibrations=[cal/gyro-y]", "device_id=5", "out=params")
    assert code == 0, err
    assert "gyro axis x, z: no calibration given" in out
    params = {ln.split()[2]: float(ln.split()[3]) for ln in (workdir / "params" / "px4_tc_params.txt").read_text().splitlines()}
    assert all(params[f"TC_G0_X{n}_{i}"] == 0.0 for n in range(4) for i in (0, 2))
    assert any(params[f"TC_G0_X{n}_1"] != 0.0 for n in range(4))


def test_reexpansion_is_exact_and_the_common_range_is_the_intersection() -> None:
    rng = np.random.default_rng(3)
    t = np.linspace(-10.0, 60.0, 500)
    a = fit_offset(t, 0.1 + 0.02 * t - 3e-4 * t ** 2 + 2e-6 * t ** 3 + rng.normal(0, 1e-3, t.size))
    b = fit_offset(t[100:], 0.3 - 0.01 * t[100:] + rng.normal(0, 1e-3, 400))
    moved = reexpanded(a, 35.0, a.tmin_c, a.tmax_c)
    np.testing.assert_allclose(moved.offset(t), a.offset(t), rtol=1e-12, atol=1e-12)
    shared = common_range({"x": a, "y": b})
    assert {p.tmin_c for p in shared.values()} == {b.tmin_c} and {p.tmax_c for p in shared.values()} == {a.tmax_c}
    inside = t[(t >= b.tmin_c) & (t <= a.tmax_c)]
    np.testing.assert_allclose(shared["x"].offset(inside), a.offset(inside), atol=1e-12)
    with pytest.raises(ValueError, match="x, y and z"):
        common_range({"w": a})
    apart = OffsetPolynomial(b.x, 200.0, 190.0, 210.0)
    with pytest.raises(ValueError, match="do not overlap"):
        ardupilot_parameters({"gyro": {"x": a, "y": apart}})
