"""Human labels of the leaderboards' columns, in one place: every metric the compensation tracks
score (:data:`tcbench.compensation.scoring.METRIC_NAMES`, with its unit), the statistics a board
takes of it (``median_``, ``ci95_`` ...: :mod:`tcbench.leaderboard.compensation`), and the columns
of the optimisation boards, the BBOB tables and the real-IMU board. The board pages
(:mod:`tcbench.leaderboard.pages`) show each label beside the raw column key."""

from __future__ import annotations

from tcbench.compensation.scoring import METRIC_NAMES, TRAIN_RMSE

# the board's short column name of each metric and flag (tcbench.leaderboard.compensation)
SHORT = {"sf_variation_ppm": "sf_ppm", "bias_variation_ug": "bias_ug", "halfg_error_ug": "halfg_ug", "zb_after_30min_ug": "zb30_ug",
         "zb_after_20min_ug": "zb20_ug", "zb_zero_start_ug": "zb0_ug", "drift_dph": "drift_dph",
         "arw_1s_deg_per_sqrt_h": "arw_1s", "bias_instability_dph": "bi_dph", "rms_error_dph": "rms_dph",
         "bandwidth_hz": "bw_hz", "drift_ug": "drift_ug", "hysteresis_ug": "hyst_ug",
         "temp_slope_ug_per_c": "slope_ug_per_c"}
FLAG_SHORT = {"allan_min_interior": "bi_is_floor"}  # the share of runs (mean over their test records)

# every metric of METRIC_NAMES and the training RMSEs: what it measures, its unit
METRICS = {
    "sf_variation_ppm": "scale-factor variation over −40…60 °C, ppm",
    "bias_variation_ug": "bias variation over −40…60 °C, µg",
    "halfg_error_ug": "error at ±0.5 g (probe, not in the paper), µg",
    "zb_after_30min_ug": "zero-bias stability from 30 min after power-on, µg",
    "zb_after_20min_ug": "zero-bias stability from 20 min after power-on, µg",
    "zb_zero_start_ug": "zero-bias stability from power-on, µg",
    "drift_ug": "drift over the chamber cycle (1σ of 10 s means), µg",
    "hysteresis_ug": "hysteresis (largest cooling − heating difference), µg",
    "temp_slope_ug_per_c": "slope of the output against the thermometer, µg/°C",
    "drift_dph": "residual drift over temperature (std of soak means), °/h",
    "arw_1s_deg_per_sqrt_h": "angle random walk (Allan deviation at 1 s), °/√h",
    "bias_instability_dph": "bias instability (Allan minimum / 0.664), °/h",
    "rms_error_dph": "RMS error against the true rate, °/h",
    "bandwidth_hz": "bandwidth kept (−3 dB), Hz",
    "train_rmse_ug": "training RMSE, µg",
    "train_rmse_dph": "training RMSE, °/h",
    "allan_min_interior": "share of runs whose bias instability is a floor (Allan minimum inside the curve)",
}
# what a compensation board takes of a metric, by the prefix of its column: {metric} is its label
# ({what} the label without its unit)
STATS = {
    "median_": "median {metric}",
    "ci95_": "95 % interval of the median {metric}",
    "best_by_train_": "{metric} of the restart with the smallest training RMSE",
    "gain_": "gain over raw in {what} (median over runs of raw ÷ the method)",
}
# columns that are no statistic of one metric, on every kind of board
COLUMNS = {
    "rank": "rank",
    "method": "method",
    "runs": "runs (restarts or draws)",
    "failed": "failed runs",
    "seeds": "seeds",
    "p_vs_next": "p-value against the next row (Wilcoxon, paired by draw, by seed on one draw; – under 6 shared pairs, where no "
                 "difference could reach p < 0.05)",
    "draws": "draws of power-ons the runs met",
    "x_oracle": "median over runs of the ratio to the oracle on the same draw (the physical limit)",
    "x_thermo": "median over runs of the ratio to the thermometer-limited oracle on the same draw",
    "ci95_x_oracle": "95 % interval of x_oracle",
    "ci95_x_thermo": "95 % interval of x_thermo",
    "note": "note",
    # optimisation boards (tcbench.leaderboard.optimisation)
    "median_best": "median final best value",
    "median_error": "median final error (best − f*)",
    "ci95_low": "95 % interval of the median error, low end",
    "ci95_high": "95 % interval of the median error, high end",
    "iqr_error": "inter-quartile range of the final error",
    "success_rate": "share of runs reaching the target",
    "ert_evals": "expected evaluations to reach the target (ERT)",
    "median_evals": "median evaluations used",
    "median_hv": "median hypervolume",
    "median_igd": "median inverted generational distance (IGD)",
    # BBOB (leaderboards/bbob)
    "dim": "dimension",
    "function": "BBOB function",
    "budget": "budget, evaluations",
    "missing": "planned runs without a log",
    "median_final_precision": "median final precision (f − f_opt)",
    "success_1e-2": "share of runs reaching 1e-2",
    "ert_1e-2": "ERT to 1e-2, evaluations",
    "success_1e-8": "share of runs reaching 1e-8",
    "ert_1e-8": "ERT to 1e-8, evaluations",
    "solved_1e-2": "functions whose median run reaches 1e-2",
    "solved_1e-8": "functions whose median run reaches 1e-8",
    "runs_1e-2": "share of runs reaching 1e-2",
    "runs_1e-8": "share of runs reaching 1e-8",
    "ecdf_at_budget": "share of (function, instance, target) triples reached",
    # the real-IMU board (leaderboards/real-imu/board.csv)
    "record": "record and axis",
    "split": "fitted on → scored on",
    "split_kind": "what the parts are (branches of one power-on, time blocks of one cooling, runs)",
    "held_out_drift": "held-out drift (RMS over the held-out parts of each part's drift), record's unit",
    "unit": "unit",
    "noise_floor": "noise floor (what white noise alone scores)",
    "noise_floor_lo": "noise floor, 95 % interval low",
    "noise_floor_hi": "noise floor, 95 % interval high",
    "ratio_to_floor": "held-out drift ÷ noise floor",
    "ratio_to_floor_lo": "held-out drift ÷ noise floor, 95 % interval low",
    "ratio_to_floor_hi": "held-out drift ÷ noise floor, 95 % interval high",
    "at_floor": "at the noise floor (the interval of drift ÷ floor reaches 1)",
    "ratio_to_raw": "held-out drift ÷ raw's",
    "pooled_best": "best on every held-out sample pooled (the calibration's ranking)",
    "pooled_tied": "tied with that best (the interval against it reaches 1)",
    "pooled_over_best": "pooled held-out drift ÷ the best's",
    "pooled_over_best_lo": "pooled held-out drift ÷ the best's, 95 % interval low",
    "pooled_over_best_hi": "pooled held-out drift ÷ the best's, 95 % interval high",
    "pooled_over_raw": "pooled held-out drift ÷ raw's",
    "pooled_over_raw_lo": "pooled held-out drift ÷ raw's, 95 % interval low",
    "pooled_over_raw_hi": "pooled held-out drift ÷ raw's, 95 % interval high",
    "restarts": "restarts (their median)",
    # across devices (leaderboards/accel-chamber/devices.csv)
    "device": "device",
    "lag_s": "thermal lag of the device, s",
    "hysteresis_mg": "hysteresis half loop of the device, mg",
    "raw_ug": "raw median drift, µg",
    "thermo_limit_ug": "thermometer-limited oracle's median drift, µg",
    "best": "best method",
    "best_x_thermo": "best method's drift ÷ the thermometer-limited oracle's",
    # seed 000's claims (leaderboards/paper-ifa-bp/claims.csv)
    "tier": "split tier",
    "claim": "the paper's claim",
    "metric": "metric",
    "selection": "which restart",
    "worst-test gain": "gain over raw, worse test dataset",
    "reproduced": "reproduced",
    # the ranking across the compensation boards (tcbench.leaderboard.pages.summary)
    "boards": "boards counted",
    "mean_rank": "mean place over the boards counted",
    "wins": "first places",
    "median_x_thermo": "median over the boards of median ÷ the thermometer-limited oracle's",
    # the list of every board (the summary page)
    "board": "board",
    "study": "study",
    "primary": "primary metric",
    "paper_place": "the paper's method: best place",
    "best_method": "best method",
    "best_x_thermo_board": "best method's median ÷ the thermometer-limited oracle's",
}
_LONG = {short: metric for metric, short in {**SHORT, **FLAG_SHORT}.items()}


def metric_of(column: str) -> str | None:
    """The metric of METRIC_NAMES a compensation board's column is a statistic of
    (``median_zb0_ug`` -> ``zb_zero_start_ug``), or None."""
    for prefix in STATS:
        if column.startswith(prefix):
            rest = column[len(prefix):]
            if rest in _LONG:
                return _LONG[rest]
            if rest in METRICS:  # median_train_rmse_ug: the metric's own name
                return rest
    return _LONG.get(column)


def column_label(column: str) -> str:
    """The human label of a board column (the key itself when none is known)."""
    if column in COLUMNS:
        return COLUMNS[column]
    metric = metric_of(column)
    if metric is None:
        if column.startswith("x_"):  # devices.csv: a method's drift over the thermometer-limited oracle's
            return f"{column[2:]}: median drift ÷ the thermometer-limited oracle's"
        return METRICS.get(column, column)
    form = next((form for prefix, form in STATS.items() if column.startswith(prefix)), "{metric}")
    return form.format(metric=METRICS[metric], what=METRICS[metric].rsplit(", ", 1)[0])


def unlabelled_metrics() -> list[str]:
    """The metrics the compensation tracks score that have no label here (none, when complete)."""
    scored = {m for names in METRIC_NAMES.values() for m in names} | set(TRAIN_RMSE.values()) | set(FLAG_SHORT)
    return sorted(scored - set(METRICS))
