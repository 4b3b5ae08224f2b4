"""The statistics of a diagnosis as one DiagnoseSettings (tcbench.diagnose.settings): conf/diagnose.yaml
mirrors it key for key, a bad setting is one line naming its key (through the API and through
``tcbench diagnose``), the command's schema and ``--help`` carry every setting, and a setting
reaches the stage it belongs to."""

from __future__ import annotations

import dataclasses
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from tcbench.cli import help as cli_help
from tcbench.cli import main
from tcbench.commands.registry import SPECS
from tcbench.commands.schemas import DiagnoseConfig
from tcbench.diagnose.screens.outliers import find_outliers
from tcbench.diagnose.select.locate import locate
from tcbench.diagnose.settings import (
    DEFAULTS,
    DiagnoseSettings,
    LocateSettings,
    OutlierSettings,
    SettingsError,
    differing,
    documented,
    from_mapping,
    report_mapping,
    to_mapping,
    yaml_lines,
)
from tcbench.sensors.recording import make_recording, write_recording

CONF = Path(__file__).resolve().parents[1] / "conf" / "diagnose.yaml"


def _leaves(mapping: dict, prefix: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    for k, v in mapping.items():
        out |= _leaves(v, f"{prefix}{k}.") if isinstance(v, dict) else {f"{prefix}{k}": v}
    return out


def test_conf_diagnose_yaml_settings_are_the_defaults_field_for_field() -> None:
    given = yaml.safe_load(CONF.read_text(encoding="utf-8"))["settings"]
    assert from_mapping(given) == DiagnoseSettings()
    conf, defaults = _leaves(given), _leaves(to_mapping(DiagnoseSettings()))
    assert list(conf) == list(defaults)  # every section and key, in the dataclasses' order
    for key, value in defaults.items():
        assert conf[key] == value and type(conf[key]) is type(value), key  # 10.0 stays a float, 5 an int


def test_every_setting_in_conf_has_its_reason_and_unit_above_it() -> None:
    lines = CONF.read_text(encoding="utf-8").split("\nsettings:", 1)[1].splitlines()
    keyed = [i for i, ln in enumerate(lines) if ln.strip() and not ln.strip().startswith("#")
             and not ln.rstrip().endswith(":") and "#" not in ln]
    assert len(keyed) == len(documented())
    for i in keyed:
        assert lines[i - 1].strip().startswith("#"), lines[i]
    assert "# [s] longest CV block and cluster" in "\n".join(lines)
    assert "\n".join(yaml_lines()) in CONF.read_text(encoding="utf-8")  # the block as yaml_lines writes it


def test_every_setting_has_a_reason_a_check_and_the_defaults_pass_it() -> None:
    keys = [k for k, _, _ in documented()]
    assert len(keys) == len(set(keys)) > 80
    for key, default, doc in documented():
        assert doc and default is not None, key
    assert DEFAULTS == DiagnoseSettings() and differing(DEFAULTS) == {}
    assert from_mapping(to_mapping(DEFAULTS)) == DEFAULTS


@pytest.mark.parametrize(("given", "words"), [
    ({"selection": {"wald": 3}}, "settings.selection.wald: no such setting"),
    ({"colour": {}}, "settings.colour: no such setting"),
    ({"selection": {"wald_threshold": -1}}, "settings.selection.wald_threshold: must be a number > 0"),
    ({"selection": {"detection_threshold_sigma2": 0}}, "settings.selection.detection_threshold_sigma2: must be a number > 0"),
    ({"surrogate": {"level": 1.0}}, "settings.surrogate.level: must be a probability in (0, 1)"),
    ({"screens": {"outliers": {"alpha": 0.0}}}, "settings.screens.outliers.alpha: must be a probability in (0, 1)"),
    ({"plan": {"folds": 2.5}}, "settings.plan.folds: must be a whole number"),
    ({"plan": {"folds": "5"}}, "settings.plan.folds: must be a whole number"),
    ({"plan": {"folds": True}}, "settings.plan.folds: must be a whole number"),
    ({"detectors": {"bump_widths_c": []}}, "settings.detectors.bump_widths_c: give at least one value"),
    ({"detectors": {"bump_widths_c": [1.0, -2.0]}}, "settings.detectors.bump_widths_c: must be a number > 0"),
    ({"screens": {"outliers": {"window_samples": 30}}}, "settings.screens.outliers.window_samples: must be an odd"),
    ({"plan": 3}, "settings.plan: a section"),
])
def test_a_bad_setting_names_its_key(given: dict, words: str) -> None:
    with pytest.raises(SettingsError) as err:
        from_mapping(given)
    assert str(err.value).startswith(words), str(err.value)


def test_a_setting_given_is_typed_and_the_rest_stay_defaults() -> None:
    made = from_mapping({"plan": {"folds": 4.0}, "detectors": {"bump_widths_c": [2, 3]}})
    assert made.plan.folds == 4 and isinstance(made.plan.folds, int)
    assert made.detectors.bump_widths_c == (2.0, 3.0)
    assert differing(made) == {"plan.folds": 4, "detectors.bump_widths_c": (2.0, 3.0)}
    with pytest.raises(SettingsError, match="settings.selection.wald_threshold"):
        DiagnoseSettings(selection=replace(DEFAULTS.selection, wald_threshold=0.0))  # checked when made


def test_the_command_schema_and_help_carry_every_setting() -> None:
    assert dataclasses.asdict(DiagnoseConfig().settings) == to_mapping(DEFAULTS)
    text = cli_help.usage("diagnose")
    meanings = SPECS["diagnose"].meanings()
    for key, default, _ in documented():
        assert f"  {key}=" in text and key in meanings, key
    assert "  settings.selection.wald_threshold=25.0 " in text and "[probability]" in meanings[
        "settings.surrogate.level"]


def _recording(path: Path) -> Path:
    t = np.arange(0.0, 3600.0)
    temp = 20.0 + 10.0 * np.sin(t / 600.0)
    out = 0.01 * temp + np.random.default_rng(0).normal(0.0, 0.01, t.size)
    write_recording(make_recording(t, temp, np.zeros(t.size), out, sensor="gyro", sample_rate_hz=1.0,
                                   device_id="d"), path)
    return path


@pytest.mark.parametrize(("setting", "words"), [
    ("settings.selection.wald_threshold=-1", "settings.selection.wald_threshold: must be a number > 0"),
    ("settings.surrogate.level=1.5", "settings.surrogate.level: must be a probability in (0, 1)"),
    ("settings.locate.false_alarm=0", "settings.locate.false_alarm: must be a probability in (0, 1)"),
    ("settings.selection.wald=3", "settings.selection.wald: no such config key"),
    ("settings.plan.folds=abc", "settings.plan.folds: Value 'abc'"),
])
def test_tcbench_diagnose_refuses_a_bad_setting_in_one_line_and_writes_nothing(
        setting: str, words: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    rec = _recording(tmp_path / "rec.csv")
    before = sorted(tmp_path.iterdir())
    assert main(["diagnose", f"recording={rec}", "out=diag", setting]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tcbench: error: ") and words in err[0], err
    assert sorted(tmp_path.iterdir()) == before  # no report folder, no MLflow store


def test_a_setting_reaches_its_stage() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(5000.0)
    r = rng.standard_normal(t.size)
    r[2500] = 6.0  # above the default bound for 5000 samples (5.35), below a stricter one
    loose = find_outliers(t, r, 1.0)
    strict = find_outliers(t, r, 1.0, settings=OutlierSettings(alpha=1e-6))
    assert 2500 in loose.index and 2500 not in strict.index
    assert strict.bound > loose.bound and strict.settings.alpha == 1e-6
    assert loose.finding("g").evidence["false_alarm"] == 0.01
    temp = np.linspace(20.0, 40.0, t.size)
    drift = rng.standard_normal(t.size) + 0.12 * (t > 2500)
    assert any(m.what.startswith("time span") for m in locate(t, temp, drift, 1.0, LocateSettings(false_alarm=0.5)))
    assert not any(m.what.startswith("time span") for m in locate(t, temp, drift, 1.0,
                                                                  LocateSettings(false_alarm=1e-9)))


def test_a_diagnosis_runs_with_its_settings_and_its_report_records_them() -> None:
    """The same concealed thermal lag: found at the defaults; with gain thresholds no gain
    reaches it is not kept and its candidate says against what; report.json records every setting
    of the tests (the front stage's rate section is said in native_rate where it averaged) and
    report.md names the ones changed."""
    from tcbench.datasets.concealed import concealed_recording
    from tcbench.diagnose.diagnosis import diagnose
    from tcbench.diagnose.report.markdown import render_markdown

    rec, _ = concealed_recording("msra", "thermal_lag", 1)
    default = diagnose(rec, name="lag")
    strict = DiagnoseSettings(selection=replace(DEFAULTS.selection, detection_threshold_sigma2=1e6,
                                                open_threshold_sigma2=1e6))
    high = diagnose(rec, name="lag", settings=strict)
    assert default.effect_ids == ["thermal_lag"] and "thermal_lag" not in high.effect_ids
    report, high_report = default.to_json(), high.to_json()
    assert report["statistics"]["settings"] == report_mapping(DEFAULTS)
    assert set(to_mapping(DEFAULTS)) - set(report_mapping(DEFAULTS)) == {"rate"}  # said in native_rate when used
    assert high_report["statistics"]["settings"]["selection"]["detection_threshold_sigma2"] == 1e6
    lag = next(c for c in high_report["candidates"] if c["id"] == "thermal_lag")
    assert lag["status"] == "rejected" and lag["threshold_sigma2"] == 1e6
    assert "Settings that differ" not in render_markdown(default, {})
    assert ("`selection.detection_threshold_sigma2 = 1000000.0` (default 10.0)"
            in render_markdown(high, {}))


def test_the_wald_lags_reach_the_selections_robust_wald_test() -> None:
    """settings.selection.wald_lags is robust_wald's default and the scorer of the selection passes
    its own: on noise correlated over many clusters (a random walk) the lags add the clusters'
    covariances to the variance, so the statistic changes with them."""
    from tcbench.diagnose.select.crossval import block_folds, robust_wald
    from tcbench.diagnose.select.design import Designer, Model
    from tcbench.diagnose.select.score import Scorer
    from tcbench.diagnose.signals import DiagnosisData

    rng = np.random.default_rng(5)
    n = 3200
    t = np.arange(n, dtype=float)
    temp = 30.0 + 20.0 * np.sin(2.0 * np.pi * t / 3600.0)
    walk = np.cumsum(rng.standard_normal(n))
    data = DiagnosisData("msra", "Hz", t, temp, temp, np.gradient(temp, t), np.zeros(n), 0.002 * t + walk,
                         np.zeros(n, dtype=int), 1.0, 1.0, 120.0)
    fold, cluster = block_folds(t, 160.0, 5), (t // 100.0).astype(np.int64)
    base, model = Model(), Model().with_effect("aging_drift", None)
    scorers = {lags: Scorer(Designer(data), fold, 5, cluster, replace(DEFAULTS.selection, wald_lags=lags))
               for lags in (0, DEFAULTS.selection.wald_lags)}
    walds = {lags: robust_wald(s.fit(base), s.fit(model), cluster, lags) for lags, s in scorers.items()}
    default = scorers[DEFAULTS.selection.wald_lags]
    assert robust_wald(default.fit(base), default.fit(model), cluster) == walds[DEFAULTS.selection.wald_lags]
    assert walds[0] != pytest.approx(walds[DEFAULTS.selection.wald_lags], rel=0.05)
    for lags, scorer in scorers.items():
        assert scorer.wald(base, model) == walds[lags]  # below the known-noise statistic: the robust one decides


def test_the_thermometer_windows_share_and_quantile_reach_the_staircase_screen() -> None:
    """screens.thermometer.max_window_share caps the widened smoothing window at that share of the
    record; fast_quantile picks the |rate| that stands for the ramps (a quantile in the soak reads none)."""
    from tcbench.diagnose.screens.quantisation import thermometer_steps

    rng = np.random.default_rng(24)
    t = np.arange(0.0, 6 * 3600.0)
    rate = 0.1 / 60.0  # degC/s: a whole degree every 600 s
    reading = np.round(10.3 + np.minimum(t, 3 * 3600.0) * rate + 0.02 * rng.standard_normal(t.size))
    thermo = DEFAULTS.screens.thermometer
    default = thermometer_steps(t, reading, 120.0)
    capped = thermometer_steps(t, reading, 120.0, replace(thermo, max_window_share=0.01))
    soak = thermometer_steps(t, reading, 120.0, replace(thermo, fast_quantile=0.3))
    assert default is not None and capped is not None and soak is not None
    assert default.smooth_s == pytest.approx(thermo.periods * 600.0, rel=0.05)
    assert capped.smooth_s == pytest.approx(0.01 * t[-1])
    assert default.rate_c_per_s == pytest.approx(rate, rel=0.05) and soak.rate_c_per_s < 0.5 * rate
