"""PX4 thermal-calibration parameters (``TC_G*``): fitted on the real tofupilot chamber cycle's
first cooling branch, exported, and evaluated back by PX4's documented formula alone."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tcbench.compensation.px4 import OffsetPolynomial, fit_offset, px4_offset, px4_parameters, write_parameters
from tcbench.datasets.real import tofupilot_gyro


@pytest.fixture(scope="module")
def cooling() -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Temperature and the three gyro axes (deg/s) of the first cooling branch (start to the coldest sample)."""
    recs = {a: tofupilot_gyro(a) for a in "xyz"}
    temp = recs["x"].temperature_c
    end = int(np.argmin(temp)) + 1
    return temp[:end], {a: r.output[:end] for a, r in recs.items()}


def test_exported_parameters_reproduce_the_fitted_correction(cooling: tuple[np.ndarray, dict[str, np.ndarray]],
                                                             tmp_path: Path) -> None:
    temp, rates = cooling
    polys = [fit_offset(temp, rates[a]) for a in "xyz"]
    params = px4_parameters(dict(zip("xyz", polys, strict=True)), "gyro", instance=1, device_id=2424842,
                            to_px4_unit=np.pi / 180)
    assert params["TC_G1_ID"] == 2424842 and len(params) == 1 + 12 + 3
    assert params["TC_G1_TMIN"] == pytest.approx(temp.min(), abs=1e-5)
    assert params["TC_G1_TMAX"] == pytest.approx(temp.max(), abs=1e-5)
    probe = np.linspace(-40.0, 90.0, 1301)  # beyond the calibrated range too: PX4 holds the edge value
    for axis, poly in enumerate(polys):
        fitted_dps = poly.offset(probe)
        px4_dps = np.degrees(px4_offset(params, probe, "gyro", instance=1, axis=axis).astype(np.float64))
        np.testing.assert_allclose(px4_dps, fitted_dps, atol=1e-5 * np.ptp(fitted_dps) + 1e-9)
        assert px4_dps[probe > temp.max() + 1].std() < 1e-6  # held at TMAX, no cubic extrapolation
        corrected = rates["xyz"[axis]] - np.degrees(px4_offset(params, temp, "gyro", 1, axis).astype(np.float64))
        assert corrected.std() < 0.3 * rates["xyz"[axis]].std()  # the correction takes out most of the drift
    script = write_parameters(params, tmp_path / "tc.txt", "gyro").read_text().splitlines()
    assert script[0] == "param set TC_G1_ID 2424842" and script[-1] == "param set TC_G_ENABLE 1"
    assert {ln.split()[2] for ln in script[:-1]} == set(params)
    read_back = {ln.split()[2]: float(ln.split()[3]) for ln in script[:-1]}
    for k, v in params.items():
        assert np.float32(read_back[k]) == np.float32(v), k  # 9 digits: the float32 value exactly


def test_bad_fits_and_parameters_are_refused() -> None:
    t = np.linspace(0.0, 10.0, 50)
    with pytest.raises(ValueError, match="does not vary"):
        fit_offset(np.full(50, 25.0), t)
    with pytest.raises(ValueError, match="finite"):
        fit_offset(t, np.where(t > 5, np.nan, t))
    a = fit_offset(t, t ** 2)
    b = OffsetPolynomial(a.x, a.tref_c + 1.0, a.tmin_c, a.tmax_c)
    shared = px4_parameters({"x": a, "y": b})  # two references: both written about one, values kept
    assert shared["TC_G0_TREF"] == pytest.approx(0.5 * (a.tmin_c + a.tmax_c))
    with pytest.raises(TypeError, match="mapping of axis name"):
        px4_parameters([a])  # type: ignore[arg-type]  # a list would put the first axis in x's slot
    with pytest.raises(ValueError, match="not 'baro'"):
        px4_parameters({"x": a}, sensor="baro")
