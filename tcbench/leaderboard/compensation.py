"""Compensation leaderboards: per task and method, the paper's metrics over restarts.

Per method: runs (one per seed), failed runs, for each metric the median over restarts with a
bootstrap 95 % interval, the value of the run with the smallest training RMSE ("best of N by
training RMSE", the paper's selection) and the improvement over the raw output (median over runs of raw ÷ the method, on each run's own test runs).
Rows are ordered by the median of the task's primary metric (bias variation for full
temperature, zero-start stability for zero bias); where that ties (median "failed"), by the smaller
share of failed runs, then the median of the finished runs, a method without a finished run last. Every median and interval counts a failed run as
worse than any finished one (:func:`tcbench.stats.with_failures`; "failed" where it falls on
them), so a method cannot rank, nor show a tight interval, on the few restarts it finished; raw
and the oracle are deterministic, one run.
``p_vs_next``: Wilcoxon signed-rank p-value of the primary metric against the next row, paired
by seed (NaN below 6 shared seeds). ``note`` flags a method whose median is below the oracle's,
the physical limit: it cannot be compensating the sensor better than its own noise allows.

Runs on the user's recordings are keyed by the content hash of their data (``accel_chamber-files-
<hash>``, :func:`tcbench.tasks.specs.device_key`): each set of files has its own board, which names
them, and a board whose test files are among its training files says its scores are in-sample.
One run per job is kept: the newest finished per (task, method, config, seed), so two configs of
one method both count and :func:`label_configs` names them apart; the limits (oracle,
oracle_thermometer), the simulator's truth whatever the pipeline or learner settings beside them,
one per (task, method, seed).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.papers import SEED_000, SEED_001
from tcbench.leaderboard.files import (
    FAILED_RULE,
    failed_as_text,
    failed_lines,
    one_run_per_job,
    search_runs,
    write_board_files,
)
from tcbench.tables import markdown_table
from tcbench.compensation.data import DEFAULT_TIER
from tcbench.compensation.scoring import FLAGS, METRIC_NAMES, PRIMARY, TRAIN_RMSE
from tcbench.stats import TIE_BREAK_KEYS, bootstrap_median_ci, failure_tie_break, paired_p_value, with_failures
from tcbench.leaderboard.paired import (
    draw_column, limit_by_draw, n_draws, paired_gain, paired_ratios, pairing_index, ratio_summary,
)
from tcbench.leaderboard.labels import FLAG_SHORT, SHORT
from tcbench.leaderboard.labels import METRICS as METRIC_LABELS

METRICS = METRIC_NAMES
NO_GAIN = ("halfg_error_ug", "bandwidth_hz")  # no raw value (probe), or not a figure to improve
HIGHER_IS_BETTER = ("bandwidth_hz",)  # a failed run counts as the lowest value here, the highest elsewhere


@dataclass
class CompensationBoard:
    """Leaderboard of one compensation task."""

    task: str
    protocol: str
    table: pd.DataFrame
    runs: pd.DataFrame
    data: str = ""  # the user's recordings the runs trained and tested on (empty: simulated)
    in_sample: str = ""  # the test files that are training files too
    split: str = ""  # the tier the simulated test runs were drawn on (tcbench.compensation.data.SPLITS)

    @property
    def named_tier(self) -> str:
        """The tier a board names (in its file stem and plot title): empty for the default ``next_run``."""
        return "" if self.split in ("", DEFAULT_TIER) else self.split

    @property
    def stem(self) -> str:
        """File stem: the task, with the tier after it unless it is the default ``next_run``."""
        return f"{self.task}.{self.named_tier}" if self.named_tier else self.task


def load_runs(client, experiments: list[str], sweep: str | None = None) -> pd.DataFrame:  # type: ignore[no-untyped-def]
    """One row per compensation run with its status, tags and every metric."""
    rows = []
    for r in search_runs(client, experiments, "compensation", sweep):
        t = r.data.tags
        rows.append({
            "run_id": r.info.run_id, "status": r.info.status, "task": t.get("tcbench.task"),
            "method": t.get("tcbench.method"), "seed": int(t.get("tcbench.seed", -1)),
            "sweep": t.get("tcbench.sweep_id"), "config_hash": t.get("tcbench.config_hash"),
            "start_time": r.info.start_time, "error_message": t.get("tcbench.error", ""),
            "task_name": t.get("tcbench.task_name"), "data_hash": t.get("tcbench.data_hash", ""),
            "train_files": t.get("tcbench.train_files", ""), "test_files": t.get("tcbench.test_files", ""),
            "in_sample": t.get("tcbench.in_sample", ""), "split": _split_of(dict(r.data.params), t),
            "draw_tag": t.get("tcbench.draw", ""),
            "params": dict(r.data.params), **r.data.metrics,
        })
    return pd.DataFrame(rows)


def _split_of(params: dict[str, str], tags: Mapping[str, str]) -> str:
    """The tier of a run's simulated test runs: ``task.split``; ``files`` for the user's recordings;
    ``before tiers`` for a run made before tiers existed (its runs differed in noise alone). A run
    killed before it sent its params has its tier from the ``tcbench.split`` tag set when it opened
    (empty for runs opened before that tag existed)."""
    if not params:
        return tags.get("tcbench.split", "")
    if params.get("task.train_files", "None") not in ("None", "", "null"):
        return "files"
    return params.get("task.split", "before tiers")


def summarise(runs: pd.DataFrame, protocol: str) -> pd.DataFrame:
    """Leaderboard table of one task's compensation runs."""
    metrics, primary = METRICS[protocol], PRIMARY[protocol]
    if "draw" not in runs:
        runs = runs.assign(draw=draw_column(runs))
    limits = {column: limit_by_draw(runs, limit, primary) for column, limit in LIMITS.items()}
    rows, values = [], {}
    for method, g in runs.groupby("method", sort=True):
        ok = g[g["status"] == "FINISHED"]
        failed = int(len(g) - len(ok))
        row: dict[str, object] = {"method": method, "runs": len(g), "draws": n_draws(g), "failed": failed}
        train = TRAIN_RMSE[protocol]
        best = ok.loc[ok[train].idxmin()] if train in ok and ok[train].notna().any() else None
        for m in metrics:
            x = with_failures(ok[m].to_numpy(float) if m in ok else np.array([]), failed, m in HIGHER_IS_BETTER)
            low, high = bootstrap_median_ci(x)
            s = SHORT[m]
            median = row[f"median_{s}"] = float(np.median(x)) if x.size else np.nan
            row[f"ci95_{s}"] = _interval(low, high)
            if m == primary:
                row["ci_high_primary"], row["ci_low_primary"] = high, low
            row[f"best_by_train_{s}"] = float(best[m]) if best is not None else np.nan
            if m not in NO_GAIN:
                row[f"gain_{s}"] = paired_gain(ok, m, failed)
        for flag in FLAGS.get(protocol, ()):
            row[FLAG_SHORT[flag]] = float(ok[flag].mean()) if flag in ok else np.nan
        trained = with_failures(ok[train].to_numpy(float), failed) if train in ok else np.array([])
        row[f"median_{train}"] = float(np.median(trained)) if trained.size else np.nan
        for column, limit in limits.items():
            ratio, low, high = ratio_summary(paired_ratios(g, limit, primary))
            row[column], row[f"ci95_{column}"], row[f"_high_{column}"] = ratio, _interval(low, high), high
        row["_rank"] = row[f"median_{SHORT[primary]}"]
        finished = ok[primary].to_numpy(float) if primary in ok else np.array([])
        row.update(failure_tie_break(finished, failed, primary in HIGHER_IS_BETTER))
        rows.append(row)
        values[method] = pd.Series(ok[primary].to_numpy(float), index=pairing_index(ok)) if primary in ok else pd.Series(dtype=float)
    table = pd.DataFrame(rows)
    if table.empty:
        return table
    keys = ["_no_finished", "_rank", *TIE_BREAK_KEYS, f"median_{SHORT[primary]}"]
    table = table.sort_values(keys, na_position="last", kind="stable").reset_index(drop=True)
    table = table.drop(columns=["_rank", "_no_finished", *TIE_BREAK_KEYS])
    table.insert(0, "rank", np.arange(1, len(table) + 1))
    names = table["method"].tolist()
    table["p_vs_next"] = [paired_p_value(values[a], values[b]) for a, b in zip(names, names[1:], strict=False)] + [np.nan]
    table = table[[c for c in table.columns if not c.startswith(("x_", "ci95_x_", "_high_x_"))]
                  + [c for column in LIMITS for c in (column, f"ci95_{column}", f"_high_{column}")]]
    table["note"] = _notes(table, protocol)
    return table.drop(columns=["ci_high_primary", "ci_low_primary", *(f"_high_{c}" for c in LIMITS)])


LIMITS = {"x_oracle": "oracle", "x_thermo": "oracle_thermometer"}  # ratio column -> the limit row it divides by


def _interval(low: float, high: float) -> str:
    """A 95 % interval as the board shows it ("–" without one)."""
    return f"{_shown(low)}–{_shown(high)}" if not np.isnan(low) else "–"


def _shown(value: float) -> str:
    """An end of an interval as the board shows it: "failed" where it falls on failed runs."""
    return "failed" if np.isinf(value) else f"{value:.3g}"


PROBE_FAILS = 10.0  # a ±0.5 g error this many times the oracle's: the method learned the trained levels


def _notes(table: pd.DataFrame, protocol: str) -> list[str]:
    """Flag what a median alone hides, by the notes of ``protocol`` (:data:`NOTES`; the others:
    :func:`_limit_notes`). One draw: a method's runs all met one draw of power-ons, so its interval
    is over restarts only (the only note of a board without its oracle)."""
    if table.loc[table["method"] == "oracle"].empty:
        return [_one_draw(row) for row in table.to_dict("records")]
    return NOTES.get(protocol, _limit_notes)(table)


def _limit_notes(table: pd.DataFrame) -> list[str]:
    """Below the physical limit: the upper end of the 95 % interval of the method's paired ratio
    to the oracle (each run over the oracle on its own draw, :mod:`tcbench.leaderboard.paired`)
    is under 1; below the thermometer-limited oracle likewise. Fails the ±0.5 g probe (fulltemp):
    its error is over :data:`PROBE_FAILS` times the oracle's — a model of the trained acceleration
    levels, not of the sensor, whatever its Table 2 figure. And (fulltemp) when the paper's pick,
    the best of the restarts by training RMSE, fails the probe worse than the median restart."""
    oracle = table.loc[table["method"] == "oracle"]
    probe_limit = float(oracle["median_halfg_ug"].iloc[0]) if "median_halfg_ug" in oracle else np.nan
    notes = []
    for row in table.to_dict("records"):
        if row["method"] in LIMITS.values():
            notes.append("")
            continue
        parts = [_below_limit(row)]
        probe, picked = row.get("median_halfg_ug", np.nan), row.get("best_by_train_halfg_ug", np.nan)
        if probe > PROBE_FAILS * probe_limit:
            parts.append(f"fails the ±0.5 g probe ({probe:.2g} µg, oracle {probe_limit:.2g})")
        if picked > probe > PROBE_FAILS * probe_limit:
            parts.append(f"the best-by-train pick fails it worse ({picked:.2g} µg)")
        notes.append("; ".join(p for p in (*parts, _one_draw(row)) if p))
    return notes


def _below_limit(row: dict[str, object]) -> str:
    """The paired verdict against the limits: below the oracle, else below the thermometer-limited
    oracle, when the whole interval of the ratio on the same draws is under 1 (empty otherwise)."""
    for column, what in (("x_oracle", "the physical limit"), ("x_thermo", "the thermometer-limited oracle")):
        high = float(row.get(f"_high_{column}", np.nan))  # type: ignore[arg-type]
        if high < 1.0:  # NaN (no pairs) compares False
            why = "" if column == "x_oracle" else ": it knows this power-on, which no compensator fitted on other runs can"
            return (f"below {what} (paired on its draws: {float(row[column]):.3g}× the limit on the same draw, "  # type: ignore[arg-type]
                    f"ci95 up to {high:.3g} < 1){why}")
    return ""


MIN_RESTARTS = 30  # a claim is reproduced over at least this many restarts; fewer is said on the row


def _one_draw(row: dict[str, object]) -> str:
    """Said of a method restarted on one draw of power-ons (its interval leaves the draws out), and
    of one run fewer than :data:`MIN_RESTARTS` times (its n said on the row)."""
    runs, draws = int(row.get("runs", 0)), int(row.get("draws", 0))  # type: ignore[call-overload]
    parts = []
    if 1 < runs < MIN_RESTARTS:
        parts.append(f"n = {runs} < {MIN_RESTARTS} restarts")
    if draws == 1 and runs > 1:
        parts.append("one draw: restarts on one set of power-ons, the interval leaves out the variation between draws")
    return "; ".join(parts)


DIAGNOSED_KEY = (
    "diagnosed = the models tcbench diagnose fits to each training run (learner=model), averaged and run "
    "noise-free on the test thermometer without the terms keyed to a training run's clock")
MSRA_KEY = (
    "raw = no compensation; oracle = the simulator's own model at the true die temperature (noise alone: the "
    "physical limit); oracle_thermometer = the device's model (not this power-on's) fed the package temperature its "
    "thermometer's reading implies (smoothed over 60 s): the limit of a compensator that knows the device exactly, "
    "not this power-on, and reads what a real one reads; memoriser = no physics, the training runs' mean output at "
    "the same time since the start (it wins only where the test runs replay the training signal); poly3 = bias and scale "
    "factor cubic in temperature (least squares); poly3_runs = the same fitted within runs (a constant per power-on, "
    "its turn-on bias; learner.offsets=per_run); poly3_rate = the bias cubic plus a cubic times the temperature rate; "
    "lagpoly = the cubic in the thermometer passed through a "
    "first-order lag, the lag and the degree chosen by leave-one-recording-out error; "
    + DIAGNOSED_KEY + " (the input solved from the models' output on the full-temperature task). "
    "x_oracle, x_thermo = the median over runs of the primary metric ÷ the limit's on the run's own draw of power-ons (paired; ci95_x_* its interval; a run on a draw the limit did not meet has none); draws = the draws of power-ons the runs met (restart i trains and tests on draw i; 1: every restart on one draw). p_vs_next = Wilcoxon signed-rank p-value of the primary metric against the next row, paired by draw (by seed when both met one draw).")
FULLTEMP_NOTE = (
    " note: \"below the physical limit\" when even the upper end of the median's 95 % interval is under the "
    "low end of the oracle's (over its run draws); a method below it is not better physics but has learned the "
    "trained acceleration levels (−1, 0, +1 g), which the ±0.5 g probe (halfg: the 0 g samples moved to ±0.5 g) shows; \"fails the ±0.5 g probe\" "
    "when its error is over ten times the oracle's, whatever its bias figure: a network near the limit on Table 2 "
    "that fails it has fitted the three trained levels rather than the sensor, one far from the limit is simply "
    "wrong between them. The paper's selection rule (best of "
    "the restarts by training RMSE) favours such networks: the note says where its pick fails the probe worse "
    "than the median restart.")
CHAMBER_KEY = (
    "raw = no compensation; oracle = the simulator's own model at the true die temperature (noise alone: the "
    "physical limit); oracle_thermometer = the device's model (not this power-on's) fed the package "
    "temperature its thermometer's reading implies (smoothed over 60 s): the limit of a compensator that knows the "
    "device exactly, not this power-on; memoriser = no physics, the training runs' mean output at the same time "
    "since the start; poly3 = bias cubic in the thermometer, as flight stacks ship it (least squares); poly3_rate = the same plus "
    "a cubic times the temperature rate (the inputs the networks get); lagpoly = cubic in the thermometer passed "
    "through a first-order lag, lag and degree by leave-one-recording-out error; "
    + DIAGNOSED_KEY + " (lag, hysteresis, ...). Networks get [T, dT/dt]. "
    "x_oracle, x_thermo = the median over runs of the primary metric ÷ the limit's on the run's own draw of power-ons (paired; ci95_x_* its interval; a run on a draw the limit did not meet has none); draws = the draws of power-ons the runs met (restart i trains and tests on draw i; 1: every restart on one draw). p_vs_next = Wilcoxon signed-rank p-value of the primary metric against the next row, paired by draw (by seed when both met one draw).")
GYRO_KEY = (
    "Methods are named by their pipeline: MOVMD = MOPSO-tuned VMD with sample-entropy classes (noise modes "
    "dropped), TFPF/WTD = denoiser of the mixed part (or of the whole output without a decomposition; WTD = "
    "universal soft threshold at the deepest level the record allows unless named -L<level>), then "
    "the drift learner (BAS-elman = BAS-initialised Elman on [T, dT/dt]; (T) = temperature input only); "
    "raw = the recorded output; oracle = the simulator's true drift removed, noise untouched (the physical "
    "limit); oracle_thermometer = the device's drift model (not this power-on's) fed the package temperature "
    "its thermometer's reading implies (smoothed over 60 s); memoriser = no physics, the training run's mean "
    "output at the same time since the start subtracted; "
    + DIAGNOSED_KEY + ", their bias subtracted (no pipeline); "
    "x_oracle, x_thermo = the median over runs of the primary metric ÷ the limit's on the run's own draw of power-ons (paired; ci95_x_* its interval; a run on a draw the limit did not meet has none); draws = the draws of power-ons the runs met (restart i trains and tests on draw i; 1: every restart on one draw). p_vs_next = Wilcoxon signed-rank p-value of the primary metric against the next row, paired by draw (by seed when both met one draw). note: an ARW below the oracle's is not compensation but filtering — the bandwidth kept (bw_hz) "
    "says how much of a real rate input the method throws away with the noise.")


SPLIT_LINES = {
    "replay": "**Split replay:** the test runs replay the training runs' power-on with new noise: a diagnostic, "
              "not a benchmark (a memoriser of the training signal can win here).",
    "next_run": "**Split next_run:** the test runs are new power-ons of the same device under the same programme "
                "(turn-on bias and scale factor, hysteresis state, chamber timing and the thermometer differ; "
                "docs/concepts/split-tiers.md).",
    "new_profile": "**Split new_profile:** the test runs are new power-ons under a programme the training never "
                   "saw (the holds in reverse order, ramps twice as fast; a room 5 °C warmer for the zero-bias test).",
    "new_device": "**Split new_device:** the training runs are of some units of the population, the test runs of "
                  "others.",
    "before tiers": "**Runs made before split tiers:** simulated runs then differed in their noise alone (what "
                    "`replay` is now); their held-out scores measure a replay of the training signal.",
}
KEYS = {"gyro": GYRO_KEY, "chamber": CHAMBER_KEY, "fulltemp": MSRA_KEY + FULLTEMP_NOTE, "roomtemp": MSRA_KEY}


def _gyro_notes(table: pd.DataFrame) -> list[str]:
    """Flag a gyro method whose ARW is below the oracle's (noise untouched): it smooths the
    output, and its bandwidth kept says how much of a real rate input it throws away; and one whose
    drift is below the oracle's on the same draws (paired interval under 1)."""
    oracle = table.loc[table["method"] == "oracle"].iloc[0]
    notes = []
    for row in table.to_dict("records"):
        parts = []
        if row["method"] in LIMITS.values():
            notes.append("")
            continue
        filters = row["median_arw_1s"] < 0.9 * oracle["median_arw_1s"]
        if filters:
            parts.append(f"ARW below the physical limit by filtering: bandwidth {row['median_bw_hz']:.3g} Hz")
        if float(row.get("_high_x_oracle", np.nan)) < 1.0:
            why = ("the flicker of the soak means is smoothed too" if filters else
                   "with the noise untouched (no filtering), its fit follows this draw's flicker of the soak means, "
                   "not better physics")
            parts.append(f"drift below the oracle's on the same draws ({row['x_oracle']:.3g}×, ci95 up to "
                         f"{row['_high_x_oracle']:.3g}): {why}")
        notes.append("; ".join(p for p in (*parts, _one_draw(row)) if p))
    return notes


# The notes of a protocol's board whose limits are not the accelerometers' (:func:`_limit_notes`)
NOTES: dict[str, Callable[[pd.DataFrame], list[str]]] = {"gyro": _gyro_notes}


def boards(runs: pd.DataFrame, protocol_of: dict[str, str]) -> list[CompensationBoard]:
    """One board per compensation task in ``runs`` (one run per job: the newest finished per
    task, method, config and seed); ``protocol_of`` maps a task name to its protocol
    (:func:`tcbench.tasks.specs.protocols`)."""
    out = []
    runs = runs.assign(split=runs["split"].fillna("")) if "split" in runs else runs.assign(split="")
    for (task, split), g in _one_run_per_job(runs).groupby(["task", "split"], sort=True):
        g = label_configs(g)
        protocol = protocol_of[str(g["task_name"].iloc[0])]
        table = _mark_in_sample(summarise(g, protocol), g)
        out.append(CompensationBoard(str(task), protocol, table, g, _data_line(g), _tag_values(g, "in_sample"),
                                     str(split)))
    return out


def _one_run_per_job(runs: pd.DataFrame) -> pd.DataFrame:
    """The newest finished run per task, method, config and seed (the config holds the tier, so a
    run killed before it sent its params yields to its finished rerun); per task, tier, method and
    seed for the limits, whose names leave out the settings they do not depend on (the gyro pipeline)."""
    limit = runs["method"].isin(list(LIMITS.values()))
    kept = [one_run_per_job(runs[~limit], ("task", "method", "config_hash", "seed")),
            one_run_per_job(runs[limit], ("task", "split", "method", "seed"))]
    return pd.concat([k for k in kept if not k.empty] or [runs.iloc[:0]]).sort_index()


HIDDEN_KEYS = ("seed", "progress", "tracking.")  # params that are not part of a job's config hash
LABEL_KEYS = 3  # differing config keys named in a label; beyond them the config hash tells them apart
LABEL_VALUE_CHARS = 40


def _config_params(params: object) -> dict[str, str]:
    items = params.items() if isinstance(params, dict) else ()
    return {str(k): str(v) for k, v in items if not str(k).startswith(HIDDEN_KEYS)}


def _short(value: str) -> str:
    return value if len(value) <= LABEL_VALUE_CHARS else value[:LABEL_VALUE_CHARS - 1] + "…"


def label_configs(runs: pd.DataFrame) -> pd.DataFrame:
    """``runs`` with each method that ran under several configs on the board relabelled by the
    config keys whose values differ between them: ``BP-gd [learner.epochs=50]`` beside ``BP-gd
    [learner.epochs=100]`` (the Hydra overrides that separate them; beyond :data:`LABEL_KEYS` keys,
    or when the params do not tell them apart, the config hash too). A method with one config, and
    a limit, keeps its name."""
    if runs.empty or "config_hash" not in runs:
        return runs
    hashes = runs["config_hash"].fillna("").astype(str)
    method = runs["method"].copy()
    for name, g in runs.groupby("method", sort=False):
        h = hashes[g.index]
        if h.nunique() < 2 or name in LIMITS.values():
            continue
        configs = {c: _config_params(g.loc[h == c, "params"].iloc[0] if "params" in g else None)
                   for c in sorted(h.unique())}
        keys = sorted({k for p in configs.values() for k in p})
        differing = [k for k in keys if len({p.get(k) for p in configs.values()}) > 1]
        labels = {}
        for c, p in configs.items():
            parts = [f"{k}={_short(p.get(k, '–'))}" for k in differing[:LABEL_KEYS]]
            if len(differing) > LABEL_KEYS:
                parts.append(f"+{len(differing) - LABEL_KEYS} keys")
            labels[c] = parts
        unique = len({tuple(v) for v in labels.values()}) == len(labels) and len(differing) <= LABEL_KEYS
        for c, parts in labels.items():
            parts = parts if unique else [*parts, f"config {c[:8] or 'unknown'}"]
            method[h[h == c].index] = f"{name} [{', '.join(parts)}]"
    return runs.assign(method=method)


def _tag_values(runs: pd.DataFrame, column: str) -> str:
    """The distinct non-empty values of a tag column over ``runs``, joined (empty without)."""
    if column not in runs:
        return ""
    values = [str(v) for v in runs[column].dropna().unique() if str(v)]
    return " | ".join(sorted(values))


def _data_line(runs: pd.DataFrame) -> str:
    """What the board's runs trained and tested on, when that is the user's recordings."""
    digest = _tag_values(runs, "data_hash")
    if not digest:
        return ""
    return (f"Data: the user's recordings (content hash {digest} of the training then the test files, tables "
            f"and sidecars): training files {_tag_values(runs, 'train_files')}; test files "
            f"{_tag_values(runs, 'test_files')}.")


IN_SAMPLE_NOTE = "in-sample: tested on training data"


def _mark_in_sample(table: pd.DataFrame, runs: pd.DataFrame) -> pd.DataFrame:
    """The note of every row with a run whose test files are among its training files."""
    if table.empty or "in_sample" not in runs:
        return table
    marked = set(runs.loc[runs["in_sample"].fillna("").astype(str) != "", "method"])
    notes = [f"{IN_SAMPLE_NOTE}; {n}" if m in marked and n else IN_SAMPLE_NOTE if m in marked else n
             for m, n in zip(table["method"], table["note"], strict=True)]
    return table.assign(note=notes)


def _plot(board: CompensationBoard, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    primary = PRIMARY[board.protocol]
    done = board.runs[board.runs["status"] == "FINISHED"]
    order = board.table["method"].tolist()
    fig, ax = plt.subplots(figsize=(max(6.0, 0.9 * len(order) + 2), 4.2))
    rng = np.random.default_rng(0)
    for i, method in enumerate(order):
        y = done.loc[done["method"] == method, primary].to_numpy(float)
        ax.scatter(i + rng.uniform(-0.15, 0.15, y.size), y, s=12, alpha=0.7)
        if y.size:
            ax.hlines(np.median(y), i - 0.3, i + 0.3, color="k")
    ax.set_xticks(range(len(order)), order, rotation=30, ha="right")
    values = done[primary].to_numpy(float) if primary in done else np.array([])
    if np.any(np.isfinite(values) & (values > 0)):  # log scale needs a positive value to show
        ax.set_yscale("log")
    what, _, unit = METRIC_LABELS.get(primary, primary).rpartition(", ")
    ax.set_ylabel(f"{what} ({unit})" if what else unit)
    tier = f" ({board.named_tier})" if board.named_tier else ""
    ax.set_title(f"{board.task}{tier}: {what or unit} per restart (line: median)")
    ax.grid(True, which="both", axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def task_line(protocol: str) -> str:
    """The board's task in words: the paper it comes from and the sensor, spelt out."""
    return {
        "roomtemp": f"**Task:** zero-bias stability of a simulated micromachined silicon resonant accelerometer "
                    f"(MSRA) at room temperature, Table 1 of seed 000: {SEED_000.cite()}.",
        "fulltemp": f"**Task:** scale factor and bias of a simulated micromachined silicon resonant accelerometer "
                    f"(MSRA) over -40...60 °C, Table 2 of seed 000: {SEED_000.cite()}.",
        "chamber": "**Task:** the drift of an ordinary capacitive MEMS accelerometer at rest through temperature-"
                   "chamber cycles, the most common real calibration record (no paper).",
        "gyro": f"**Task:** drift and noise of a simulated dual-mass MEMS gyroscope through oven steps, Fig. 19 of "
                f"seed 001: {SEED_001.cite()}.",
    }[protocol]


def write(board: CompensationBoard, out_dir: Path, source: str) -> dict[str, Path]:
    """Write ``<task>.md``, ``<task>.csv`` and ``<task>.png`` into ``out_dir`` (atomically)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {"md": out_dir / f"{board.stem}.md", "csv": out_dir / f"{board.stem}.csv",
             "png": out_dir / f"{board.stem}.png"}
    _plot(board, paths["png"])
    primary = PRIMARY[board.protocol]
    failed = board.runs[board.runs["status"] != "FINISHED"]
    conv = {
        "fulltemp": "sf = scale-factor variation std/mean over the temperature nodes (ppm); bias = bias "
                    "variation std over the nodes (µg), eq. 12 plus form",
        "roomtemp": "zb30/zb20/zb0 = zero-bias stability (1σ of 10 s means) from 30 min, 20 min and 0 min "
                    "after power-on (µg)",
        "chamber": "drift_ug = 1σ of the 10 s means of the output over the whole chamber cycle (µg); hyst_ug = "
                   "largest cooling − heating difference in common 1 °C bins (µg); slope_ug_per_c = |slope| of "
                   "the output against the thermometer (µg/°C)",
        "gyro": "drift_dph = residual drift over temperature, std of the 5-min soak means (°/h); arw_1s = "
                "σ(1 s)/60, the Allan deviation at 1 s (°/√h; IEEE 952's ARW where white noise dominates at 1 s); "
                "bi_dph = Allan minimum / 0.664 (°/h); bi_is_floor = the share of runs whose Allan minimum is "
                "inside the curve (0: the minimum is the curve's end, for a filtered output σ at the first τ, and "
                "bi_dph is no floor); rms_dph = RMS error against the true rate (°/h); bw_hz = bandwidth kept, the "
                "−3 dB frequency of the whole method measured by injecting a multi-sine rate (Nyquist when "
                "nothing is lost); for a nonlinear method (a wavelet threshold, TFPF) it depends on the test "
                "signal, and single sines can give another value (experiments/paper_movmd_tfpf/wtd_levels.py "
                "measures both)",
    }[board.protocol]
    lines = [
        f"# Compensation leaderboard: {board.task}" + (f" — split {board.split}" if board.split else ""), "",
        task_line(board.protocol), "",
        *([SPLIT_LINES.get(board.split, ""), ""] if board.split in SPLIT_LINES else []),
        *([board.data, ""] if board.data else []),
        *([f"**In-sample:** train_files and test_files share {board.in_sample}: the test scores are in-sample, "
           "not held out (the rows are marked in note).", ""] if board.in_sample else []),
        f"Source: {source}. Metrics are means over the test recordings; {conv}.",
        f"Rows are ordered by the median of {primary} over restarts (seeds); ci95 = bootstrap 95 % "
        "interval of that median; best_by_train = the run with the smallest training RMSE (the paper's "
        "\"best of 30\" selection); gain = the median over runs of raw ÷ the method on the run's own test runs. " + FAILED_RULE + " " + KEYS.get(board.protocol, MSRA_KEY), "",
        markdown_table(failed_as_text(board.table)), "", f"![{primary} per restart]({paths['png'].name})", "",
    ]
    write_board_files(lines + failed_lines(failed), board.table, paths)
    return paths
