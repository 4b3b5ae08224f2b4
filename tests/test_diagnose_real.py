"""tcbench diagnose on a real record: the tofupilot chamber cycle (70 min, 2 Hz, -17.6..74 degC).

Before the statistics were sized to the recording, every temperature effect was rejected on
gyro y (robust Wald over a handful of 15-min blocks) and ten sigma of structure was called
bias instability."""

from __future__ import annotations

import json

import pytest

from tcbench.datasets.real import tofupilot_gyro
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.report.write import write_report
from tcbench.diagnose.select.plan import SURROGATE
from tcbench.diagnose.terms import terms

TEMPERATURE_EFFECTS = {t.id for t in terms() if t.shape.startswith("temperature_")}  # the library's
WITHIN_REFERENCE = 1.25  # the target: final held-out RMSE within this factor of the reference


@pytest.fixture(scope="module")
def gyro_y():
    return diagnose(tofupilot_gyro("y"), name="tofupilot gyro y")


def test_conversion_drops_the_glitch_and_converts_units() -> None:
    rec = tofupilot_gyro("y")
    assert rec.time_s.size == 8399 and rec.time_s[0] == 0.0
    assert 4200.0 < rec.time_s[-1] < 4300.0
    assert -18.0 < rec.temperature_c.min() < -17.0 and 73.0 < rec.temperature_c.max() < 75.0
    assert 1.0 < abs(rec.output).max() < 5.0  # deg/s: 0.02-0.07 rad/s of bias


def test_short_record_gets_short_blocks_and_the_surrogate_test(gyro_y) -> None:
    st = gyro_y.statistics
    assert st.plan.block_s < 300.0 and st.significance_test == SURROGATE
    assert st.to_json()["cv_block_s"] == st.plan.block_s and st.to_json()["significance_test"] == SURROGATE


def test_temperature_structure_is_kept_not_called_noise(gyro_y) -> None:
    kept = set(gyro_y.effect_ids) & TEMPERATURE_EFFECTS
    assert kept, gyro_y.verdict
    for e in gyro_y.effects:
        if e.id in TEMPERATURE_EFFECTS:
            assert e.evidence["test"] == SURROGATE and e.evidence["p_value"] <= 0.005
    assert gyro_y.effect_ids != ["bias_instability"]
    # deterministic before stochastic: flicker only once the reference finds no more structure
    if "bias_instability" in gyro_y.effect_ids:
        assert not gyro_y.deterministic_remains


def test_final_far_below_baseline_and_near_the_reference(gyro_y) -> None:
    sigma = gyro_y.noise.white_sigma
    base, final = gyro_y.baseline.rmse_heldout, gyro_y.final.rmse_heldout
    ref = gyro_y.reference.rmse_heldout
    assert final < 0.5 * base
    assert final < 2.0 * sigma
    assert final <= WITHIN_REFERENCE * ref
    assert gyro_y.reference.final_over_reference == pytest.approx(final / ref)


def test_report_says_which_test_and_shows_the_reference(gyro_y, tmp_path) -> None:
    write_report(gyro_y, tmp_path)
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["reference"]["rmse_heldout"] > 0 and report["reference"]["terms"]
    assert report["statistics"]["significance_test"] == SURROGATE
    text = (tmp_path / "report.md").read_text()
    assert "reference (no physics)" in text and "surrogate" in text and "Final / reference" in text
