"""Every name a config, a recording or a truth may carry has its entry in the table that
dispatches on it: a kind, protocol, tier, baseline or method added to its list without its
entry would fail here, not with a KeyError in the middle of a run."""

from __future__ import annotations

import numpy as np
import pytest

from tcbench.compensation import calibration, data, methods, scoring
from tcbench.compensation.gyro import pipeline
from tcbench.datasets import concealed, open_world, open_world_scoring
from tcbench.metrics import report
from tcbench.runner.kinds.compensation import FIXED_LABELS, compensation_label
from tcbench.sensors import effects, kinds
from tcbench.tasks import gyro_env, msra_env


def test_the_open_world_tables_cover_every_kind() -> None:
    assert set(open_world.HIDE) == set(open_world.KINDS)
    assert open_world.ADDITIVE == tuple(open_world.PATTERNS)
    assert set(open_world.DETERMINISTIC) <= set(open_world.KINDS)


def test_every_concealed_effect_has_its_shape() -> None:
    """An effect is drawn by its own shape or as a signed unit amplitude of its one parameter."""
    for sensor, names in concealed.EFFECTS_BY_SENSOR.items():
        for effect in names:
            params = concealed._shape_params(effect, np.random.default_rng(0))
            assert set(params) <= {f for f in effects.effect_class(effect).__dataclass_fields__}, (sensor, effect)


def test_the_where_keys_a_truth_states_are_matched() -> None:
    stated = {key for kind in open_world.KINDS for key in open_world.open_world_recording("gyro", kind, 1)[1].where}
    assert stated == set(open_world_scoring.WHERE_MATCHERS)


def test_the_compensation_tables_cover_their_names() -> None:
    assert calibration.METHODS == tuple(calibration.FITTERS)
    assert set(calibration.LEARNERS) <= set(calibration.METHODS)
    assert set(scoring.SCORERS) == set(data.PROTOCOLS)
    assert set(data.TIER_RUNS) == set(data.SPLITS)
    assert set(data.FILE_CHECKS) <= set(data.PROTOCOLS)
    assert set(pipeline.DENOISERS) == {"tfpf", "wavelet", "none"}
    assert set(pipeline.TUNED) <= set(pipeline.DECOMPOSERS) < set(pipeline.DECOMPOSITIONS)


def test_each_baseline_scores_and_is_labelled() -> None:
    assert set(msra_env.BASELINE_SCORES) == set(methods.BASELINES)
    assert set(gyro_env.BASELINES) <= set(methods.BASELINES)
    assert set(methods.BASELINES) <= set(FIXED_LABELS)
    assert compensation_label({"name": "model"}, {"name": "none"}) == "diagnosed"


def test_every_sensor_kind_report_has_its_reporter() -> None:
    assert set(report.REPORTERS) == set(kinds.REPORTS)
    assert kinds.get(kinds.DEFAULT).name == kinds.DEFAULT


@pytest.mark.parametrize("stage", effects.STAGES)
def test_at_stage_keeps_the_effects_of_one_stage_in_order(stage: str) -> None:
    library = [effects.make_effect(name, **({"upper": 1.0} if name == "saturation" else {})) for name in effects.EFFECTS]
    assert {e.stage for e in library} == set(effects.STAGES)  # the library acts at every stage
    picked = effects.at_stage(library, stage)
    assert [e.id for e in picked] == [e.id for e in library if e.stage == stage]


def test_every_board_folder_s_kind_has_its_pages() -> None:
    from tcbench.leaderboard.pages import render
    from tcbench.leaderboard.pages.catalogue import FAMILIES

    assert {f.kind for f in FAMILIES.values()} <= set(render.KIND_PAGES)


def test_a_board_s_notes_are_those_of_a_protocol_it_can_have() -> None:
    from tcbench.leaderboard import compensation as board

    assert set(board.NOTES) <= set(board.KEYS)


def test_calibrate_fits_what_the_library_refuses_once_each() -> None:
    """The methods ``tcbench calibrate`` fits itself are methods the library lists but will not fit,
    and none is a network restarted ``restarts`` times."""
    from tcbench.commands import calibration as command

    assert set(command.OWN_FITS) <= set(calibration.METHODS)
    assert not set(command.OWN_FITS) & set(calibration.LEARNERS)
    for method in command.OWN_FITS:
        with pytest.raises(ValueError, match="tcbench diagnose"):
            calibration.fit(method, [])
