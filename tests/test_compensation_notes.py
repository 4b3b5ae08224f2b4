"""The notes of a compensation board: below the limit only with the interval, the ±0.5 g probe
whatever the bias figure, and where the paper's best-by-training-RMSE pick fails it worse."""

from __future__ import annotations

import numpy as np
import pandas as pd

from tcbench.leaderboard.compensation import summarise


def _runs(method: str, bias_ug: np.ndarray, halfg_ug: np.ndarray, train_rmse: np.ndarray | None = None) -> pd.DataFrame:
    n = bias_ug.size
    return pd.DataFrame({
        "method": method, "status": "FINISHED", "seed": np.arange(n), "bias_variation_ug": bias_ug,
        "raw_bias_variation_ug": 4e4, "sf_variation_ppm": 100.0, "raw_sf_variation_ppm": 2e4,
        "halfg_error_ug": halfg_ug, "train_rmse_ug": np.arange(n, dtype=float) if train_rmse is None else train_rmse,
    })


def test_notes_use_the_interval_and_the_probe() -> None:
    rng = np.random.default_rng(0)
    runs = pd.concat([
        _runs("oracle", np.array([8.95]), np.array([3.0])),
        _runs("wide", np.linspace(5.0, 12.5, 30), np.full(30, 4.0)),          # median below, interval across
        _runs("memoriser", rng.uniform(5.0, 6.0, 30), np.full(30, 5e4)),        # below, and fails the probe
        _runs("honest_fit", rng.uniform(20.0, 22.0, 30), np.full(30, 12.0)),   # above, passes the probe
        # above the limit and failing the probe; its lowest training RMSE (seed 0) fails it worst
        _runs("picked_worse", rng.uniform(30.0, 31.0, 30), np.r_[3e5, np.full(29, 6e4)]),
    ], ignore_index=True)
    table = summarise(runs, "fulltemp").set_index("method")
    wide = float(np.median(runs.loc[runs["method"] == "wide", "bias_variation_ug"]))
    assert wide < 8.95 and table.loc["wide", "note"] == ""
    assert table.loc["memoriser", "note"].startswith("below the physical limit (ci95 up to 5.")
    assert "fails the ±0.5 g probe (5e+04 µg, oracle 3)" in table.loc["memoriser", "note"]
    assert "fails" not in table.loc["wide", "note"] + table.loc["honest_fit", "note"]
    assert table.loc["honest_fit", "note"] == "" and table.loc["oracle", "note"] == ""
    note = table.loc["picked_worse", "note"]
    assert "below" not in note and "fails the ±0.5 g probe" in note and "best-by-train pick fails it worse (3e+05 µg)" in note
    assert "ci_high_primary" not in table.columns


def test_below_a_limit_is_decided_on_the_limits_interval_too() -> None:
    """A limit over 30 run draws has an interval: a method is below it only when its interval ends
    under the limit's; below the thermometer-limited oracle alone is named as such."""
    rng = np.random.default_rng(1)
    runs = pd.concat([
        _runs("oracle", rng.uniform(2.0, 4.0, 30), np.full(30, 3.0)),
        _runs("oracle_thermometer", rng.uniform(6.0, 10.0, 30), np.full(30, 3.0)),
        _runs("inside", rng.uniform(7.5, 8.5, 30), np.full(30, 4.0)),   # under the thermometer's median, not its interval
        _runs("learned_the_run", rng.uniform(5.0, 5.2, 30), np.full(30, 4.0)),
    ], ignore_index=True)
    table = summarise(runs, "fulltemp").set_index("method")
    assert table.loc["inside", "note"] == ""
    assert table.loc["learned_the_run", "note"].startswith("below the thermometer-limited oracle (ci95 up to 5.")
    assert "ci_low_primary" not in table.columns


def test_boards_are_named_by_their_tier() -> None:
    from tcbench.leaderboard.compensation import boards

    frames = []
    for split in ("next_run", "replay"):
        r = _runs("raw", np.full(3, 4e4), np.full(3, 4e4))
        r["split"], r["task"], r["task_name"], r["config_hash"] = split, "msra_fulltemp-dev0", "msra_fulltemp", "h"
        r["run_id"], r["start_time"], r["data_hash"], r["in_sample"] = [f"{split}{i}" for i in range(3)], 0, "", ""
        frames.append(r)
    made = {b.split: b for b in boards(pd.concat(frames, ignore_index=True), {"msra_fulltemp": "fulltemp"})}
    assert set(made) == {"next_run", "replay"}
    assert made["next_run"].stem == "msra_fulltemp-dev0" and made["replay"].stem == "msra_fulltemp-dev0.replay"


def test_a_board_with_no_finished_run_still_writes(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """A board whose only run never finished (stopped before it logged a metric) is written with
    the run listed as failed; its plot has nothing to put on a log axis."""
    from tcbench.leaderboard.compensation import boards, write

    r = _runs("raw", np.full(1, np.nan), np.full(1, np.nan)).assign(status="KILLED")
    r["split"], r["task"], r["task_name"], r["config_hash"] = "next_run", "msra_fulltemp-dev0", "msra_fulltemp", "h"
    r["run_id"], r["start_time"], r["data_hash"], r["in_sample"], r["error_message"] = "k0", 0, "", "", ""
    (board,) = boards(r, {"msra_fulltemp": "fulltemp"})
    paths = write(board, tmp_path, "a test")
    assert paths["png"].stat().st_size > 0 and "KILLED" in paths["md"].read_text()
