"""Calibration boards: the ``tcbench calibrate`` runs of some MLflow experiments, one board per
recording's content (its name and ``tcbench.data_hash``: two files of one name never merge, one
file calibrated twice under two names stays one board), one row per method and calibration config
(``tcbench.config_hash``: a calibration repeated with the same config counts once, the newest).

A row gives the method's held-out drift (every held-out sample of that calibration pooled), its
drift on the fitted parts, and its ratio to the best of its calibration; a calibration that held
nothing out is marked in-sample and not ranked. Reads the store, never writes to it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.leaderboard.files import failed_lines, one_run_per_job, search_runs, write_board_files
from tcbench.tables import markdown_table

STATS = {"held_out.drift": "held_out_drift", "held_out.rms": "held_out_rms", "fit.drift": "fit_drift"}


@dataclass
class CalibrationBoard:
    """The board of one recording's calibrations."""

    task: str
    recording: str
    data_hash: str
    table: pd.DataFrame
    runs: pd.DataFrame


def load_runs(client, experiments: list[str], sweep: str | None = None) -> pd.DataFrame:  # type: ignore[no-untyped-def]
    """One row per calibration run and method, with its status, tags and held-out scores."""
    rows = []
    for r in search_runs(client, experiments, "calibration", sweep):
        t, m = r.data.tags, r.data.metrics
        base = {"run_id": r.info.run_id, "status": r.info.status, "start_time": r.info.start_time,
                "recording": t.get("tcbench.recording") or t.get("tcbench.task", "").removeprefix("calibrate-"),
                "data_hash": t.get("tcbench.data_hash", ""), "sensor": t.get("tcbench.sensor", ""),
                "unit": t.get("tcbench.unit", ""),
                "config_hash": t.get("tcbench.config_hash", ""), "held_out": t.get("tcbench.held_out") == "true",
                "split": t.get("tcbench.split", ""),
                "error_message": t.get("tcbench.error", ""), "seed": 0}
        methods = sorted({k.split(".", 1)[0] for k in m if k.endswith(tuple(STATS))})
        if not methods:
            rows.append({**base, "method": "(failed)"})
        for method in methods:
            rows.append({**base, "method": method,
                         **{col: m.get(f"{method}.{key}", np.nan) for key, col in STATS.items()}})
    return pd.DataFrame(rows)


def boards(runs: pd.DataFrame) -> list[CalibrationBoard]:
    """One board per recording content, newest run per (method, config)."""
    out = []
    for (recording, data_hash), g in runs.groupby(["recording", "data_hash"], sort=True):
        kept = one_run_per_job(g.assign(task=f"{recording}-{data_hash}"))
        task = f"calibration-{_slug(str(Path(str(recording)).stem))}-{data_hash or 'unhashed'}"
        out.append(CalibrationBoard(task, str(recording), str(data_hash), _table(kept), kept))
    return out


def _table(runs: pd.DataFrame) -> pd.DataFrame:
    ok = runs[(runs["status"] == "FINISHED") & (runs["method"] != "(failed)")].copy()
    if ok.empty:
        return pd.DataFrame()
    configs = sorted(ok["config_hash"].unique())
    ok["config"] = ok["config_hash"].str[:8]
    best = ok.groupby("run_id")["held_out_drift"].transform("min")
    ok["x_best"] = ok["held_out_drift"] / best
    ok["in_sample"] = ~ok["held_out"]
    cols = ["method", *(["config", "split"] if len(configs) > 1 else []), "held_out_drift", "held_out_rms",
            "fit_drift", "x_best", "in_sample"]
    table = ok.sort_values(["in_sample", "held_out_drift", "fit_drift"], na_position="last")[cols]
    table.insert(0, "rank", np.arange(1, len(table) + 1))
    return table.reset_index(drop=True)


def write(board: CalibrationBoard, out: Path, source: str) -> dict[str, Path]:
    """``OUT/<task>.md`` and ``.csv``."""
    out.mkdir(parents=True, exist_ok=True)
    paths = {"md": out / f"{board.task}.md", "csv": out / f"{board.task}.csv"}
    failed = board.runs[board.runs["status"] != "FINISHED"].drop_duplicates("run_id")
    sensor = ", ".join(sorted(set(board.runs["sensor"]) - {""}))
    unit = ", ".join(sorted(set(board.runs["unit"]) - {""})) or "its output unit"
    lines = [f"# Calibrations of {board.recording}", "",
             f"{sensor} recording, content {board.data_hash} (sha256 of the recording and its sidecar); drift in "
             f"{unit}; from {source}. "
             "held_out_drift: the RMS of the residual's running mean over every held-out sample of the calibration; "
             "fit_drift: the same on the fitted parts; x_best: held-out drift over the best of the same calibration. "
             "A calibration that held nothing out is in_sample and not ranked.", ""]
    lines += [markdown_table(board.table) if not board.table.empty else "No finished calibration.", ""]
    lines += failed_lines(failed)
    write_board_files(lines, board.table, paths)
    return paths


def _slug(text: str) -> str:
    return re.sub(r"[^\w\-.]", "_", text)
