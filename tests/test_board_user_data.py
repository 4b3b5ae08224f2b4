"""Runs on the user's recordings: keyed by the data's content hash on the compensation boards, no
run merged or dropped, training and testing on the same data warned about and marked."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

from tcbench.leaderboard import compensation as board
from tcbench.runner.job import JobFailure, run_job
from tcbench.sensors.data_hash import DataHashError, content_hash, shared_recordings
from tcbench.sensors.recording import write_recording
from tcbench.sensors.simulate import simulate_recording
from tcbench.tasks.specs import protocols
from tcbench.tracking import store as tracking


def _cycle(tmp: Path, name: str, run_seed: int, device_seed: int = 1) -> str:
    """A simulated chamber cycle written as a user's schema-v1 recording (table and sidecar)."""
    path = tmp / f"{name}.csv"
    write_recording(simulate_recording("accel", "chamber", device_seed, run_seed), path)
    return str(path)


def test_content_hash_follows_the_bytes_not_the_names(tmp_path: Path) -> None:
    a, b = _cycle(tmp_path, "a", 0), _cycle(tmp_path, "b", 1)
    copy = tmp_path / "copy.csv"
    shutil.copy(a, copy)
    shutil.copy(tmp_path / "a.json", tmp_path / "copy.json")
    h = content_hash([a])
    assert len(h) == 12 and int(h, 16) >= 0
    assert content_hash([copy]) == h  # another name, the same data
    assert content_hash([b]) != h
    assert content_hash([a, b]) != content_hash([b, a])  # in order
    assert content_hash([a], [b]) != content_hash([a, b], [])  # the groups apart
    (tmp_path / "copy.json").write_text((tmp_path / "copy.json").read_text().replace('"accel"', '"accel" '))
    assert content_hash([copy]) != h  # the sidecar is part of the recording
    (tmp_path / "copy.json").unlink()
    assert content_hash([copy]) != h
    assert shared_recordings([a], [b, str(copy), a]) == [str(copy), a]
    with pytest.raises(DataHashError, match=r"missing.csv: cannot be read"):
        content_hash([tmp_path / "missing.csv"])


def _job(train: list[str], test: list[str], learner: dict, seed: int = 0, **task: object) -> dict:
    """A tracked compensation job on the user's recordings (no figures)."""
    return {
        "task": {"name": "accel_chamber", "device_seed": 0, "recordings_seed": 0, "n_train": None, "n_test": None,
                 "train_files": train, "test_files": test, "train_on": "all", "rate_window_s": 120.0,
                 "bias_form": "plus", **task},
        "learner": learner, "optimiser": {"name": "none"}, "seed": seed, "budget": 1, "progress": False,
        "tracking": {"enabled": True, "uri": None, "experiment": "user", "sweep_id": "s", "plots": False,
                     "resume": False, "ioh_dir": None},
    }


def _boards() -> list[board.CompensationBoard]:
    return board.boards(board.load_runs(tracking.client(), ["user"]), protocols())


POLY = {"name": "poly", "degree": 3, "form": "auto"}


def test_runs_on_other_files_get_boards_of_their_own(workdir: Path) -> None:
    c = [_cycle(workdir, f"c{i}", i) for i in range(4)]
    for train, test in ((c[:1], c[1:2]), (c[2:3], c[3:])):
        assert not isinstance(run_job(_job(train, test, POLY)), JobFailure)
    first, second = _boards()  # the same method and seed: neither dropped
    assert first.task != second.task
    assert {first.task, second.task} == {f"accel_chamber-files-{content_hash(c[:1], c[1:2])}",
                                         f"accel_chamber-files-{content_hash(c[2:3], c[3:])}"}
    for b in (first, second):
        assert b.table["method"].tolist() == ["poly3"] and b.table["runs"].tolist() == [1]
    by_task = {b.task: b for b in (first, second)}
    mine = by_task[f"accel_chamber-files-{content_hash(c[2:3], c[3:])}"]
    md = board.write(mine, workdir / "lb", "test")["md"].read_text()
    assert f"training files {c[2]}; test files {c[3]}." in md and c[0] not in md


def test_two_configs_of_one_method_on_one_file_both_count(workdir: Path) -> None:
    c = [_cycle(workdir, f"c{i}", i) for i in range(2)]
    bp = {"name": "bp", "training": "gd"}
    for epochs in (5, 10, 5):  # the first config twice: a repeated job counts once
        assert not isinstance(run_job(_job(c[:1], c[1:], {**bp, "epochs": epochs})), JobFailure)
    run_job(_job(c[:1], c[1:], {"name": "raw"}))
    (b,) = _boards()
    table = b.table.set_index("method")
    assert sorted(table.index) == ["random-BP-gd [learner.epochs=10]", "random-BP-gd [learner.epochs=5]", "raw"]
    assert table["runs"].tolist() == [1, 1, 1]  # a method with one config keeps its name
    assert set(b.runs["method"]) == set(table.index)  # the runs (plot, failed list) carry the same labels
    five, ten = table.loc[["random-BP-gd [learner.epochs=5]", "random-BP-gd [learner.epochs=10]"], "median_drift_ug"]
    assert five != ten  # two trainings, not one counted twice


def test_training_on_the_test_data_is_refused(workdir: Path) -> None:
    """A task never tests on its own training runs: a test file that is a training file fails the job
    with one line naming it (recorded as failed), and a held-out job runs."""
    c = [_cycle(workdir, f"c{i}", i) for i in range(2)]
    failed = run_job(_job(c, c[1:], POLY))
    assert isinstance(failed, JobFailure)
    assert f"{c[1]} is both a training and a test recording" in failed.error
    assert not isinstance(run_job(_job(c[:1], c[1:], POLY)), JobFailure)  # held out
    (held_out,) = [b for b in _boards() if not b.in_sample]
    assert not held_out.table["note"].str.contains("in-sample").any()


def test_a_copy_of_a_training_file_is_refused_too(workdir: Path) -> None:
    a = _cycle(workdir, "a", 0)
    shutil.copy(a, workdir / "b.csv")
    shutil.copy(workdir / "a.json", workdir / "b.json")
    untracked = _job([a], [str(workdir / "b.csv")], POLY)
    untracked["tracking"]["enabled"] = False
    failed = run_job(untracked)
    assert isinstance(failed, JobFailure) and failed.user and "(the same data)" in failed.error


def test_the_limits_count_once_per_seed_whatever_the_settings_beside_them() -> None:
    def run(method: str, config: str, start: int, drift_ug: float) -> dict:
        return {"run_id": f"{method}{config}{start}", "status": "FINISHED", "task": "accel_chamber-dev0",
                "method": method, "seed": 0, "config_hash": config, "start_time": start, "error_message": "",
                "task_name": "accel_chamber", "params": {"task.rate_window_s": config}, "drift_ug": drift_ug}

    runs = pd.DataFrame([run("oracle", "60", 1, 5.0), run("oracle", "120", 2, 5.0),
                         run("poly3", "60", 3, 40.0), run("poly3", "120", 4, 50.0)])
    (b,) = board.boards(runs, protocols())
    table = b.table.set_index("method")
    assert sorted(table.index) == ["oracle", "poly3 [task.rate_window_s=120]", "poly3 [task.rate_window_s=60]"]
    assert table["runs"].tolist() == [1, 1, 1]
    assert table.loc["poly3 [task.rate_window_s=120]", "x_oracle"] == 10.0  # the limit row still divides


def test_a_run_killed_before_it_sent_its_params_yields_to_its_finished_rerun() -> None:
    """A resumed sweep reruns a killed job; the killed attempt, which never sent its params (so no
    ``task.split``), neither opens a board of its own nor counts beside the rerun."""
    params = {"task.split": "next_run"}

    def run(method: str, seed: int, status: str, start: int, sent: bool, drift_ug: float) -> dict:
        return {"run_id": f"{method}{seed}{start}", "status": status, "task": "accel_chamber-dev0",
                "method": method, "seed": seed, "config_hash": f"h{method}", "start_time": start,
                "error_message": "", "task_name": "accel_chamber", "draw_tag": str(seed),
                "split": board._split_of(params if sent else {}, {}), "params": params if sent else {},
                "drift_ug": drift_ug}

    runs = pd.DataFrame([run("oracle", s, "FINISHED", s, True, 5.0) for s in range(2)]
                        + [run("poly3", 0, "KILLED", 10, False, float("nan")),
                           run("poly3", 0, "FINISHED", 11, True, 40.0), run("poly3", 1, "FINISHED", 12, True, 50.0)])
    (b,) = board.boards(runs, protocols())
    assert b.split == "next_run"
    assert b.table.set_index("method").loc["poly3", ["runs", "failed"]].tolist() == [2, 0]


def test_a_killed_run_takes_its_tier_from_the_tag_set_when_it_opened() -> None:
    assert board._split_of({}, {"tcbench.split": "replay"}) == "replay"
    assert board._split_of({"task.split": "new_device"}, {"tcbench.split": "replay"}) == "new_device"
    assert board._split_of({"seed": "0"}, {}) == "before tiers"
