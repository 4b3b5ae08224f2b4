"""tcbench diagnose on records too short, too coarse or too narrow in temperature for some detectors:
each detector that cannot run says why in report.json (``statistics.not_tested``) and report.md
("Not tested on this record"); a record too small for anything exits 2 with one line (one shorter
than a full diagnosis needs gets the short-record report: tests/test_short_record.py)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from tcbench.cli import main
from tcbench.datasets.concealed import concealed_recording
from tcbench.diagnose.diagnosis import diagnose
from tcbench.diagnose.report.markdown import not_tested_section
from tcbench.diagnose.report.write import write_report
from tcbench.diagnose.select.crossval import block_folds
from tcbench.diagnose.select.design import Designer
from tcbench.diagnose.select.discover import why_untestable
from tcbench.diagnose.select.locate import why_no_allan
from tcbench.diagnose.select.plan import plan_for
from tcbench.diagnose.signals import DiagnosisData, prepare
from tcbench.diagnose.terms import term, terms
from tcbench.diagnose.terms.detectors import why_no_bumps, why_no_lines, why_no_steps
from tcbench.sensors.recording import Recording, make_recording, write_recording

TempFn = Callable[[np.ndarray, np.random.Generator], np.ndarray]


def _record(n: int, dt_s: float, temp: TempFn, seed: int = 0) -> Recording:
    """A gyro record of ``n`` samples every ``dt_s``: a linear temperature response plus white noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt_s
    temp_c = temp(t, rng)
    out = 0.01 * (temp_c - 25.0) + rng.normal(0.0, 0.01, n)
    return make_recording(t, temp_c, np.zeros(n), out, sensor="gyro", sample_rate_hz=1.0 / dt_s, device_id="x")


def _ramp(span_c: float) -> TempFn:
    return lambda t, _: 25.0 + span_c * t / t[-1]


@pytest.fixture(scope="module")
def short_report(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, str]:
    """report.json and report.md of a 40-min record whose temperature ramps by 3 degC."""
    diag = diagnose(_record(2400, 1.0, _ramp(3.0)), name="short.csv")
    out = tmp_path_factory.mktemp("short") / "report"
    written = write_report(diag, out)
    return json.loads(written["report.json"].read_text()), written["report.md"].read_text()


def test_short_record_lists_what_it_cannot_test_in_report_json(short_report: tuple[dict, str]) -> None:
    not_tested = short_report[0]["statistics"]["not_tested"]
    assert "needs a temperature span of 4 degC; this record spans 3 degC" in not_tested["temperature_bump"]
    assert "needs a record of more than 2400 s; this record spans 2399 s" in not_tested["second_node"]
    assert not {"bias_step", "transient", "periodic", "gated_periodic"} & set(not_tested)  # these could run


def test_short_record_lists_what_it_cannot_test_in_report_md(short_report: tuple[dict, str]) -> None:
    md = short_report[1]
    section = md.split("## Not tested on this record", 1)[1]
    assert "- **temperature_bump**: a temperature bump of width 1 degC" in section
    assert "- **second_node**:" in section


def test_normal_record_runs_every_open_world_detector() -> None:
    rec, _ = concealed_recording("gyro", None, 5)  # ~10.7 h, tens of degC
    data = prepare(rec)
    plan = plan_for(data)
    assert why_untestable(Designer(data), block_folds(data.t_s, plan.block_s, plan.k)) == {}
    assert why_no_allan(data.t_s) is None


@pytest.mark.parametrize(("name", "n", "dt_s", "temp", "words"), [
    ("sixty_samples", 60, 60.0, _ramp(3.0), "too short"),
    ("one_temperature", 3600, 1.0, lambda t, _: np.full(t.size, 25.0), "temperature varies by only 0 degC"),
    ("noisy_one_temperature", 3600, 1.0, lambda t, r: 25.0 + r.normal(0.0, 0.1, t.size), "temperature varies by only"),
])
def test_cli_on_a_record_too_small_exits_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, n: int, dt_s: float, temp: TempFn, words: str,
) -> None:
    path = write_recording(_record(n, dt_s, temp), tmp_path / f"{name}.csv")
    code = main(["diagnose", f"recording={path}", f"out={tmp_path / 'out'}"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and f"{name}.csv" in err and words in err
    assert "Traceback" not in err and not (tmp_path / "out").exists()


@pytest.mark.parametrize(("n", "dt_s", "temp", "expected"), [
    (3600, 1.0, lambda t, r: 25.0 + r.normal(0.0, 1.0, t.size), {"temperature_bump"}),  # noise only: no span
    (300, 30.0, lambda t, _: 25.0 + 10.0 * np.sin(t / 1800.0), {"variance"}),  # too few samples for 12 blocks
])
def test_marginal_records_finish_with_the_reasons(n: int, dt_s: float, temp: TempFn, expected: set[str]) -> None:
    not_tested = diagnose(_record(n, dt_s, temp)).statistics.not_tested
    assert expected <= set(not_tested) and all(isinstance(v, str) and v for v in not_tested.values())


def test_detector_requirements_name_the_record_value() -> None:
    t = np.arange(6) * 10.0
    assert why_no_steps(t) == "change points need at least 8 bins of 10 s of the residual; this record has 6"
    assert "this record has 6" in why_no_lines(t)  # type: ignore[operator]
    assert why_no_bumps(np.array([20.0, 22.5])) == (
        "a temperature bump of width 1 degC needs a temperature span of 4 degC; this record spans 2.5 degC")
    assert why_no_allan(np.arange(50.0)) == (
        "the Allan deviation needs clusters of 10 samples at a tenth of the record (100 samples); this record has 50")
    halves = np.concatenate([np.arange(500.0), 1e4 + np.arange(500.0)])
    assert why_no_allan(halves) is None  # tested inside each segment
    bursts = np.concatenate([k * 600.0 + np.arange(15.0) for k in range(40)])
    assert why_no_allan(bursts) == (
        "the Allan deviation needs clusters of 10 samples inside a continuous segment; the longest of this "
        "record's 40 segments (gaps of more than five sample intervals: bursts, or samples given zero weight) "
        "holds 15")
    assert why_no_steps(np.arange(3600.0)) is None and why_no_lines(np.arange(3600.0)) is None


def _data(t_s: np.ndarray, temp_c: np.ndarray) -> DiagnosisData:
    n = t_s.size
    return DiagnosisData("gyro", "deg/s", t_s, temp_c, temp_c, np.gradient(temp_c, t_s), np.zeros(n), np.zeros(n),
                         np.zeros(n, dtype=np.int64), 1.0, 1.0, 0.0)


def test_each_open_world_term_says_why_it_cannot_be_tested() -> None:
    """why_untestable is every open-world term's own reason (OpenTerm.skip), in the registry's order."""
    tiny = _data(np.arange(6) * 10.0, np.full(6, 20.0))
    fold = np.arange(6) % 5
    why = why_untestable(Designer(tiny), fold)
    assert why == {t.id: r for t in terms(open=True) if (r := t.skip(tiny, fold)) is not None}
    assert list(why) == ["bias_step", "transient", "periodic", "gated_periodic", "duty_cycle", "temperature_bump",
                         "second_node"]
    assert why["bias_step"] == why["transient"] == why_no_steps(tiny.t_s)
    assert why["periodic"] == why["gated_periodic"] == why["duty_cycle"] == why_no_lines(tiny.t_s)
    assert why["second_node"] == ("a second thermal node needs what thermal lag needs: the thermometer never moves "
                                  "faster than 0 degC/min; a thermal lag needs ramps of at least 0.05 degC/min")
    t = np.arange(500.0)  # steps testable after the first 50 s block, but under 600 s of record after it
    short = _data(t, 20.0 + 10.0 * t / t[-1])
    fold = (t // 50.0).astype(np.int64) % 5
    assert term("bias_step").skip(short, fold) is None and term("bias_step").skip(short) is None
    assert term("transient").skip(short, fold) == (
        "a transient of time constant 300 s needs 600 s of record after a testable step; this record has 449 s "
        "after the earliest one")
    assert term("transient").skip(short) is None  # folds unknown: only the change points' needs are checked
    assert term("second_node").skip(short, fold) == (
        "a second thermal node of time constant 600 s needs a record of more than 2400 s; this record spans 499 s")
    halves = (t >= 250.0).astype(np.int64)  # two blocks: no time with two folds on each side
    assert term("bias_step").skip(short, halves) == term("transient").skip(short, halves) == (
        "a step needs samples of two cross-validation folds on each side; this record has no such time")


def test_markdown_section_only_when_something_was_not_tested() -> None:
    assert not_tested_section({}) == []
    lines = not_tested_section({"second_node": "too short"})
    assert lines[0] == "## Not tested on this record" and "- **second_node**: too short." in lines
