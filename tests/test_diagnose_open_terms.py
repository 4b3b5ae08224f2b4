"""Open-world terms: detectors on cases worked by hand, the terms in a diagnosis, and simulate
(each term's columns against the simulator's effect: tests/test_diagnose_terms.py)."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.datasets.concealed import concealed_recording, minimal_columns, unexplained
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.findings import check_finding
from tcbench.diagnose.model_file import parse_model, to_sensor_model
from tcbench.diagnose.terms.detectors import bump_centres, line_periods, line_window, step_times
from tcbench.diagnose.terms.open_base import step_range
from tcbench.sensors.effects import make_effect
from tcbench.sensors.recording import make_recording


def test_step_detector_finds_a_hand_made_jump_to_the_sample() -> None:
    rng = np.random.default_rng(1)
    t = np.arange(20_000.0)
    r = rng.standard_normal(t.size) + np.where(t >= 12_345.0, 0.4, 0.0)
    assert any(abs(s - 12_345.0) <= 30.0 for s in step_times(t, r))


def test_step_detector_proposes_the_sample_after_a_gap() -> None:
    rng = np.random.default_rng(2)
    t = np.concatenate([np.arange(5000.0), np.arange(6800.0, 12_000.0)])
    assert 6800.0 in step_times(t, rng.standard_normal(t.size))


def test_line_detector_finds_a_hand_made_period_also_with_gaps() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(36_000.0)
    keep = (t % 3600.0) < 2400.0  # bursts: a third of every hour lost
    t = t[keep]
    r = rng.standard_normal(t.size) + 0.3 * np.sin(2 * np.pi * t / 1500.0)
    best = line_periods(t, r)[0]
    assert abs(best / 1500.0 - 1.0) < 0.02


def test_line_window_finds_where_a_cycle_runs() -> None:
    rng = np.random.default_rng(5)
    t = np.arange(36_000.0)
    on = (t >= 12_000.0) & (t < 24_000.0)
    r = rng.standard_normal(t.size) + on * 0.5 * np.sign(np.sin(2 * np.pi * t / 1200.0))
    start, end = line_window(t, r, 1200.0)
    assert abs(start - 12_000.0) < 1500.0 and abs(end - 24_000.0) < 1500.0


def test_bump_detector_finds_a_hand_made_bump_in_temperature() -> None:
    rng = np.random.default_rng(4)
    temp = np.linspace(-20.0, 60.0, 30_000)
    r = rng.standard_normal(temp.size) + 0.5 * np.exp(-0.5 * ((temp - 31.0) / 3.0) ** 2)
    centre, width = bump_centres(temp, r)[0]
    assert abs(centre - 31.0) < 1.5 and 1.0 <= width <= 6.0


def test_steps_are_only_testable_with_two_folds_on_each_side() -> None:
    t = np.arange(10_000.0)
    fold = (np.floor(t / 900.0) % 5).astype(np.int64)
    assert step_range(t, fold) == (900.0, 9899.0)


def _hidden_step(seed: int, at: tuple[float, ...] = (0.55,), sizes: tuple[float, ...] = (1.0,)) -> tuple[object, float, float]:
    """A concealed gyro control with steps at fractions ``at`` of its span (relative ``sizes``),
    together 0.8 sigma the minimal model cannot absorb; the first step's time and sigma."""
    rec, truth = concealed_recording("gyro", None, seed)
    t = rec.time_s
    t0 = at[0] * float(t[-1])
    h = sum(size * (t >= f * float(t[-1])) for f, size in zip(at, sizes, strict=True)).astype(float)
    left = float(np.sqrt(np.mean(unexplained(h, minimal_columns(rec.temperature_c, None)) ** 2)))
    h *= 0.8 * truth.white_sigma / left
    out = make_recording(t, rec.temperature_c, rec.input, rec.output + h, sensor="gyro", sample_rate_hz=1.0,
                         device_id="hidden-step")
    return out, t0, truth.white_sigma


def test_a_hidden_step_is_named_located_refitted_and_written_to_model_yaml(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from tcbench.diagnose.report.write import write_report

    rec, t0, sigma = _hidden_step(1)
    d = diagnose(rec, sensor="gyro")
    written = write_report(d, tmp_path / "out", with_plots=False)
    assert "bias_step" in written["report.md"].read_text()
    report = d.to_json()
    for entry in report["effects"]:
        check_finding(entry)
    steps = [e for e in report["effects"] if e["shape"] == "step"]
    assert steps and abs(steps[0]["where"]["time_s"] - t0) < 600.0
    assert d.final.rmse_heldout / sigma < 1.05 < d.baseline.rmse_heldout / sigma
    assert "beyond the library: bias_step (step)" in d.verdict
    spec = parse_model(d.model, "model.yaml")
    step = next(e for e in to_sensor_model(spec).effects if e.id == "bias_step")
    assert step.time_s == pytest.approx(steps[0]["where"]["time_s"])


def test_duty_phase_reads_a_switched_load_hand_worked() -> None:
    """A load on for 30 % of every 600 s from phase 120 s, inside [2000, 8000) s, in unit noise."""
    from tcbench.diagnose.terms.detectors import duty_phase

    t = np.arange(10_000.0)
    on = (np.mod(t - 120.0, 600.0) < 180.0) & (t >= 2000.0) & (t < 8000.0)
    r = 0.8 * on + np.random.default_rng(3).standard_normal(t.size)
    on_s, duty = duty_phase(t, r, 600.0, 2000.0, 8000.0)
    assert abs(on_s - 120.0) <= 600.0 / 64 + 1e-9
    assert abs(duty - 0.3) <= 2.0 / 64


def test_a_slow_line_at_the_band_edge_is_proposed_and_windowed() -> None:
    """A line of 1.8 cycles in the record peaks at the periodogram's low edge: it is proposed,
    and its window (demodulated over two periods, longer than the record) stays inside it."""
    t = np.arange(0.0, 32_000.0, 1.0)
    r = 0.6 * np.sin(2.0 * np.pi * t / 17_800.0) + np.random.default_rng(5).standard_normal(t.size)
    periods = line_periods(t, r)
    assert any(abs(p - 17_800.0) < 0.3 * 17_800.0 for p in periods)
    start, end = line_window(t, r, max(periods))
    assert t[0] <= start < end <= t[-1] + 1.0


def test_two_steps_are_two_instances_of_the_term_and_simulate_back(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """A record with a jump at 30 % and a smaller one the same way at 70 % of its span: both are
    found, as ``bias_step`` and ``bias_step_2``, and model.yaml simulates both. (A jump up and
    back down is a box, which the greedy selection can take for a slow line or hysteresis.)"""
    rec, _, sigma = _hidden_step(2, at=(0.3, 0.7), sizes=(1.0, 0.7))
    d = diagnose(rec, sensor="gyro")
    report = d.to_json()
    steps = sorted(e["where"]["time_s"] for e in report["effects"] if e["shape"] == "step")
    span = float(rec.time_s[-1])
    assert len(steps) == 2 and abs(steps[0] - 0.3 * span) < 600.0 and abs(steps[1] - 0.7 * span) < 600.0
    assert {"bias_step", "bias_step_2"} <= {e["id"] for e in report["effects"]}
    assert d.final.rmse_heldout / sigma < 1.05
    effects = to_sensor_model(parse_model(d.model, "model.yaml")).effects
    assert sorted(e.time_s for e in effects if e.id == "bias_step") == pytest.approx(steps)


def test_a_fourth_instance_or_an_unknown_suffix_is_refused() -> None:
    from tcbench.sensors.effects import effect_class

    assert effect_class("bias_step_3") is effect_class("bias_step")
    assert effect_class("bias_step_4") is None and effect_class("hysteresis_2") is None
    with pytest.raises(ValueError, match="unknown effect 'hysteresis_2'"):
        make_effect("hysteresis_2")


def test_a_plugin_effect_repeats_when_its_class_says_so() -> None:
    from dataclasses import dataclass
    from typing import ClassVar

    from tcbench.sensors.effects import PLUGINS, Effect, effect_class

    @dataclass(frozen=True)
    class Knock(Effect):
        id: ClassVar[str] = "knock_test"
        repeatable: ClassVar[bool] = True
        size: float = 0.0

    @dataclass(frozen=True)
    class Hum(Effect):
        id: ClassVar[str] = "hum_test"
        size: float = 0.0

    PLUGINS.register("knock_test", Knock)
    PLUGINS.register("hum_test", Hum)
    try:
        assert effect_class("knock_test_2") is Knock and effect_class("knock_test_3") is Knock
        assert effect_class("knock_test_4") is None
        assert effect_class("hum_test") is Hum and effect_class("hum_test_2") is None
        assert make_effect("knock_test_2", size=1.0) == Knock(size=1.0)
    finally:
        for name in ("knock_test", "hum_test"):
            PLUGINS._entries.pop(name, None)
