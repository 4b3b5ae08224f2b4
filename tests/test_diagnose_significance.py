"""The significance tests as objects (tcbench.diagnose.select.significance): which one the statistics
plan holds for a record, how the robust Wald test hands an effect to the surrogate test, and what
each says in the report, at the settings' thresholds and level."""

from __future__ import annotations

import math
import pickle
from dataclasses import replace

import numpy as np
import pytest

from tcbench.diagnose.select.evidence import not_significant
from tcbench.diagnose.select.plan import plan_for
from tcbench.diagnose.select.significance import (
    ROBUST_WALD,
    SURROGATE,
    RobustWald,
    SpectralSurrogate,
    significance_tests,
)
from tcbench.diagnose.settings import DEFAULTS, DiagnoseSettings, PlanSettings, SelectionSettings, SurrogateSettings
from tcbench.diagnose.signals import DiagnosisData

ROBUST_WALD_TEST, SURROGATE_TEST = significance_tests(DEFAULTS)
LEVEL = DEFAULTS.surrogate.level


def _data(hours: float) -> DiagnosisData:
    t = np.arange(0.0, hours * 3600.0, 1.0)
    n = t.size
    temp = np.linspace(0.0, 40.0, n)
    return DiagnosisData("gyro", "deg/s", t, temp, temp, np.zeros(n), np.zeros(n), np.zeros(n),
                         np.zeros(n, dtype=np.int64), 1.0, 1.0, 120.0)


def test_the_plan_holds_the_test_the_record_supports() -> None:
    long, short = plan_for(_data(10.0)), plan_for(_data(1.0))
    assert long.test == ROBUST_WALD_TEST and long.to_json()["significance_test"] == ROBUST_WALD
    assert short.test == SURROGATE_TEST and short.to_json()["significance_test"] == SURROGATE
    assert ROBUST_WALD_TEST.decided_by(ROBUST_WALD) is ROBUST_WALD_TEST
    assert ROBUST_WALD_TEST.decided_by(SURROGATE) == SURROGATE_TEST and SURROGATE_TEST.decided_by(SURROGATE) is SURROGATE_TEST
    with pytest.raises(KeyError):
        SURROGATE_TEST.decided_by(ROBUST_WALD)
    assert pickle.loads(pickle.dumps(short)).test == SURROGATE_TEST  # a diagnosis run in a worker process


def test_the_plan_and_its_tests_follow_the_settings() -> None:
    settings = DiagnoseSettings(plan=replace(PlanSettings(), min_clusters=200, folds=4),
                                selection=replace(SelectionSettings(), wald_threshold=40.0),
                                surrogate=replace(SurrogateSettings(), level=0.01))
    plan = plan_for(_data(10.0), settings)  # 32 clusters: fewer than 200, the surrogate test decides
    assert plan.k == 4 and plan.n_clusters < 200
    assert plan.test == SpectralSurrogate(settings.surrogate) and plan.test.settings.level == 0.01
    robust, _ = significance_tests(settings)
    assert robust == RobustWald(40.0, SpectralSurrogate(settings.surrogate))
    assert pickle.loads(pickle.dumps(plan)).test.settings.level == 0.01


class _Scorer:
    def __init__(self, removes_most: bool, p: float) -> None:
        self._removes_most, self.p, self.asked = removes_most, p, 0

    def removes_most(self, base: object, model: object) -> bool:
        return self._removes_most

    def surrogate_p(self, base: object, effect: str, value: object, searched: object, settings: object) -> float:
        self.asked += 1
        assert settings == DEFAULTS.surrogate
        return self.p


class _Model:
    def with_effect(self, effect: str, value: object) -> _Model:
        return self


@pytest.mark.parametrize(("wald", "removes_most", "p", "passed", "decided", "asked"), [
    (30.0, True, 0.5, True, ROBUST_WALD, 0),  # above the Wald threshold: the Wald test decides
    (5.0, False, 0.001, False, ROBUST_WALD, 0),  # below it, removing little: rejected without surrogates
    (5.0, True, 0.001, True, SURROGATE, 1),  # below it but removing most: the surrogate test decides
    (5.0, True, 0.5, False, SURROGATE, 1),
])
def test_robust_wald_hands_what_removes_most_to_the_surrogate_test(
    wald: float, removes_most: bool, p: float, passed: bool, decided: str, asked: int,
) -> None:
    scorer = _Scorer(removes_most, p)
    ok, w, p_value, name = ROBUST_WALD_TEST.judge(scorer, _Model(), "warmup", 600.0, wald)
    assert (ok, w, name, scorer.asked) == (passed, wald, decided, asked)
    assert math.isnan(p_value) if decided == ROBUST_WALD else p_value == p


def test_each_test_says_why_it_rejected_and_what_it_reports() -> None:
    assert not_significant(ROBUST_WALD_TEST, SURROGATE, 0.02) == SURROGATE_TEST.why_not(0.02)
    assert f"p = 0.02 above {LEVEL:g}" in not_significant(ROBUST_WALD_TEST, SURROGATE, 0.02)
    assert "robust Wald below the threshold" in not_significant(ROBUST_WALD_TEST, ROBUST_WALD, float("nan"))
    assert ROBUST_WALD_TEST.to_json(31.234, float("nan")) == {"test": ROBUST_WALD, "robust_wald": 31.23}
    assert SURROGATE_TEST.to_json(float("nan"), 0.00123) == {"test": SURROGATE, "p_value": 0.0012, "level": LEVEL}
    stricter = SpectralSurrogate(replace(SurrogateSettings(), level=0.001))
    assert "above 0.001" in stricter.why_not(0.002) and stricter.to_json(float("nan"), 0.002)["level"] == 0.001
