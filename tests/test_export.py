"""``tcbench export``: the calibrations of one IMU's axes, each in its slot, as PX4's TC_* and
ArduPilot's INS_TCAL* parameters; applied back as each autopilot applies them, axis by axis,
they give the fitted correction."""

from __future__ import annotations

import json
import shlex
import shutil
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


@pytest.fixture(scope="module")
def calibrated_once(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The tofupilot gyro and accelerometer imported axis by axis and calibrated (poly3 only),
    once for the module: ``rec/`` and ``cal/<kind>-<axis>`` in a folder of their own."""
    folder = tmp_path_factory.mktemp("calibrated")
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(folder)
        patch.delenv("MLFLOW_TRACKING_URI", raising=False)
        for kind, col, unit in (("gyro", "gyro", "rad/s"), ("accel", "acc", "m/s^2")):
            outputs = ",".join(f"imu.{col}.{a}:{unit}" for a in AXES)
            assert main(["import", f"csv={TOFUPILOT_CSV}", f"sensor={kind}", "time=timestamp:us",
                         "temperature=imu.temperature:degC", f"output={outputs}", "axes=x,y,z", "out=rec",
                         f"name={kind}", "tracking.enabled=false"]) == 0
            for a in AXES:  # each axis from its sidecar (import axes=)
                assert main(["calibrate", f"recording=rec/{kind}-imu.{col}.{a}.csv", f"out=cal/{kind}-{a}",
                             "methods=[raw,poly3]", "tracking.enabled=false"]) == 0
    return folder


@pytest.fixture()
def calibrated(calibrated_once: Path, workdir: Path) -> dict[str, Path]:
    """A copy of :func:`calibrated_once`'s ``rec/`` and ``cal/`` in the test's own folder: the
    calibration folders by ``<kind>-<axis>``."""
    for sub in ("rec", "cal"):
        shutil.copytree(calibrated_once / sub, workdir / sub)
    return {f"{kind}-{a}": workdir / "cal" / f"{kind}-{a}" for kind in ("gyro", "accel") for a in AXES}


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
            poly, about = fitted(calibrated[f"{kind}-{a}"])
            px4 = px4_offset(params, probe, kind, instance=1, axis=i).astype(np.float64)
            level = about["export"]["static_level"] if kind == "accel" else 0.0  # PX4 leaves it to CAL_ACCn_*
            want = (poly.offset(probe) - level) * si  # the fitted correction of THIS axis, in PX4's unit
            np.testing.assert_allclose(px4, want, atol=2e-6 * np.ptp(want) + 1e-9, err_msg=f"{kind} {a}")
            others = [(fitted(calibrated[f"{kind}-{b}"])[0].offset(probe) - level) * si for b in AXES if b != a]
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


def test_an_accel_calibration_without_its_static_level_is_refused_for_px4(
        calibrated: dict[str, Path], workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A calibration.json of an accelerometer that does not hold its static level cannot give
    PX4's polynomial (it would carry gravity): one line, nothing written; ArduPilot's has no
    constant and is written."""
    path = calibrated["accel-x"] / "calibration.json"
    about = json.loads(path.read_text())
    del about["export"]["static_level"]
    path.write_text(json.dumps(about))
    code, _, err = run(capsys, "export", "calibrations=[cal/accel-x,cal/accel-y]", "device_id=3", "out=p1")
    assert code == 2 and len(err) == 1 and "cal/accel-x: no static level" in err[0], err
    assert not (workdir / "p1").exists()
    code, _, err = run(capsys, "export", "calibrations=[cal/accel-x,cal/accel-y]", "formats=[ardupilot]", "out=p2")
    assert code == 0, err


def test_a_px4_log_gives_the_axes_and_the_device_id(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Imported from a PX4 log, each recording knows its axis and the sensor's device id: the
    export needs neither axis= nor device_id=, and the id is the log's."""
    from tcbench.sensors.ulog import read_topic

    code, _, err = run(capsys, "import", f"csv={PX4_LOG}", "sensor=gyro", "out=rec", "name=log", "tracking.enabled=false")
    assert code == 0, err
    hints = []
    for a in AXES:
        code, out, err = run(capsys, "calibrate", f"recording=rec/log-sensor_gyro-0-{a}.csv", f"out=cal/{a}",
                             "methods=[poly3]", "train_branches=[0]", "drift_window_s=5", "tracking.enabled=false")
        assert code == 0, err
        hints += [ln for ln in out.splitlines() if ln.startswith("for ")]
    code, _, err = run(capsys, "export", "calibrations=[cal/x,cal/y,cal/z]", "out=params")
    assert code == 0, err
    script = (workdir / "params" / "px4_tc_params.txt").read_text().splitlines()
    logged = read_topic(PX4_LOG, "gyro")[0].device_id
    assert script[0] == f"param set TC_G0_ID {logged}" and logged
    # calibrate's last lines name the export with the log's id, and it runs as printed
    assert hints[0] == f"for PX4/ArduPilot: tcbench export 'calibrations=[cal/x]' device_id={logged}", hints
    assert main(shlex.split(hints[-1].removeprefix("for PX4/ArduPilot: "))[1:]) == 0
    assert (workdir / "export" / "px4_tc_params.txt").read_text().startswith(f"param set TC_G0_ID {logged}")


def test_calibrate_prints_an_export_command_that_runs(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Without a device id from a log, calibrate printed ``tcbench export calibrations=[...]``,
    which exits 2 asking for ``device_id=``: now one command for ArduPilot that runs as printed,
    and PX4's with ``device_id=N`` and where N is found; a recording without its axis is told to
    name it first."""
    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                       "temperature=imu.temperature:degC", "output=imu.gyro.z:rad/s", "axes=z", "out=rec", "name=z",
                       "tracking.enabled=false")
    assert code == 0, err
    code, out, err = run(capsys, "calibrate", "recording=rec/z.csv", "out=cal/z", "methods=[raw,poly3]",
                         "tracking.enabled=false")
    assert code == 0, err
    hints = [ln for ln in out.splitlines() if ln.startswith("for ")]
    assert hints == ["for ArduPilot: tcbench export 'calibrations=[cal/z]' formats=[ardupilot]",
                     "for PX4 too: tcbench export 'calibrations=[cal/z]' device_id=N, N the gyro's device id (its "
                     "CAL_GYRO0_ID parameter on the vehicle, or the log's)"], hints
    assert main(shlex.split(hints[0].removeprefix("for ArduPilot: "))[1:]) == 0
    assert (workdir / "export" / "ardupilot_tcal.parm").is_file()
    px4 = hints[1].removeprefix("for PX4 too: ").split(",")[0].replace("device_id=N", "device_id=2293768")
    assert main([*shlex.split(px4)[1:], "out=px4"]) == 0
    assert (workdir / "px4" / "px4_tc_params.txt").read_text().startswith("param set TC_G0_ID 2293768")
    code, _, err = run(capsys, "import", f"csv={TOFUPILOT_CSV}", "sensor=gyro", "time=timestamp:us",
                       "temperature=imu.temperature:degC", "output=imu.gyro.z:rad/s", "out=rec", "name=noaxis",
                       "tracking.enabled=false")
    assert code == 0, err
    code, out, err = run(capsys, "calibrate", "recording=rec/noaxis.csv", "out=cal/noaxis", "methods=[poly3]",
                         "tracking.enabled=false")
    assert code == 0 and "calibrate again with axis=x|y|z, then tcbench export" in out, out


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


def px4_applied(params: dict, head: str, axis: int, temp_c: np.ndarray, reading: np.ndarray) -> np.ndarray:
    """PX4's compensation from its documented formula, in 32-bit: the offset sum X_k dT^k, with
    dT = clamp(T, TMIN, TMAX) - TREF, subtracted from the reading."""
    f32 = np.float32
    tmin, tmax, tref = (f32(params[f"{head}_{k}"]) for k in ("TMIN", "TMAX", "TREF"))
    dt = np.clip(temp_c.astype(f32), tmin, tmax) - tref
    offset = sum(f32(params[f"{head}_X{k}_{axis}"]) * dt ** k for k in range(4))
    return (reading.astype(f32) - offset).astype(np.float64)


def ardupilot_applied(params: dict, head: str, axis: str, temp_c: np.ndarray, cal_temp_c: float,
                      reading: np.ndarray) -> np.ndarray:
    """ArduPilot's compensation: v - p(T) + p(T_cal), p the constant-free cubic about 35 degC of
    the INS_TCAL coefficients x 1e-6, both temperatures held to TMIN..TMAX, in 32-bit."""
    f32 = np.float32
    lo, hi = f32(params["INS_TCAL1_TMIN"]), f32(params["INS_TCAL1_TMAX"])

    def p(t: np.ndarray) -> np.ndarray:
        u = np.clip(np.asarray(t, dtype=f32), lo, hi) - f32(35.0)
        return sum(f32(params[f"{head}{k}_{axis.upper()}"]) * u ** k for k in (1, 2, 3)) * f32(1e-6)

    return (reading.astype(f32) - p(temp_c) + p(np.array([cal_temp_c]))[0]).astype(np.float64)


def thermal_spread(temp_c: np.ndarray, reading: np.ndarray) -> float:
    """The spread of the reading over temperature: the SD of its means in 2-degC bins."""
    bins = np.floor(temp_c / 2.0).astype(int)
    _, which = np.unique(bins, return_inverse=True)
    return float(np.std(np.bincount(which, reading) / np.bincount(which)))


def test_the_firmware_round_trip_removes_the_drift_and_keeps_the_static_reading(
        calibrated: dict[str, Path], workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The real tofupilot gyro and accelerometer exported, and each file applied to the raw log as
    its firmware applies it: on every axis most of the thermal drift goes, and the static reading
    is what the firmware's ordinary calibration expects. An accelerometer keeps its level (z about
    -9.6 m/s^2: PX4 leaves it to CAL_ACCn_*, ArduPilot to the reading at T_cal); PX4's gyro reads
    its true rate, 0, at rest."""
    import pandas as pd

    cals = ",".join(f"cal/{k}" for k in calibrated)
    code, out, err = run(capsys, "export", f"calibrations=[{cals}]", "device_id={gyro: 1, accel: 2}", "out=params",
                         "formats=[px4,ardupilot]")
    assert code == 0, err
    script = (workdir / "params" / "px4_tc_params.txt").read_text().splitlines()
    px4 = {ln.split()[2]: float(ln.split()[3]) for ln in script}  # as the NuttX console reads it
    parm = (workdir / "params" / "ardupilot_tcal.parm").read_text().splitlines()
    ap = {ln.split()[0]: float(ln.split()[1]) for ln in parm}
    log = pd.read_csv(TOFUPILOT_CSV, sep="\t")  # the firmware's units: rad/s and m/s^2
    temp = log["imu.temperature"].to_numpy()
    cal_temp_c = 35.0
    near_cal = np.abs(temp - cal_temp_c) < 1.0
    for kind, col, px4_head, ap_head in (("gyro", "gyro", "TC_G0", "INS_TCAL1_GYR"),
                                         ("accel", "acc", "TC_A0", "INS_TCAL1_ACC")):
        for i, a in enumerate(AXES):
            raw = log[f"imu.{col}.{a}"].to_numpy()
            spread = thermal_spread(temp, raw)
            by_px4 = px4_applied(px4, px4_head, i, temp, raw)
            by_ap = ardupilot_applied(ap, ap_head, a, temp, cal_temp_c, raw)
            for firmware, corrected in (("px4", by_px4), ("ardupilot", by_ap)):
                assert thermal_spread(temp, corrected) < 0.5 * spread, f"{kind} {a} {firmware}: drift left"
            static = 0.0 if kind == "gyro" else np.median(raw)  # PX4: a gyro's whole offset, an accel's change
            assert abs(np.median(by_px4) - static) < 0.25 * spread, f"{kind} {a} px4: {np.median(by_px4)} not {static}"
            lo, hi = np.percentile(raw[near_cal], [5, 95])  # what the sensor reads at T_cal
            assert lo <= np.median(by_ap) <= hi, f"{kind} {a} ardupilot: {np.median(by_ap)} not in {lo}..{hi}"
    assert abs(px4["TC_A0_X0_2"]) < 0.5  # gravity left to CAL_ACC0_*: z still reads about -9.6 at rest
    assert "accel: TC_A0_X0_* leave out the static level" in out
