"""Seed 001 Fig. 19 beside tcbench's reproduction: the table of every method with the bandwidth it
keeps, the verdict on the paper's claim over the restarts, and the Allan curves on one axis.

Reads the finished gyro runs from MLflow and writes ``fig19.md`` and, per task (device variant),
``fig19_<task>.csv`` and ``fig19_allan_<task>.png`` into ``--out``. Per method: the median over restarts (seeds) and, for the
Allan figure, the curve of the run whose ARW is the median one.

    python experiments/paper_movmd_tfpf/figures.py --experiment paper-movmd-tfpf --sweep ID --out DIR
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.tracking import store as tracking
from tcbench.leaderboard import compensation as board
from tcbench.compensation.gyro.plots import allan_methods_figure
from tcbench.leaderboard.optimisation import markdown_table, one_run_per_job
from tcbench.compensation.data import DEFAULT_TIER
from tcbench.signal.allan import AllanDeviation

PAPER = {"raw": (0.531076, 32.7364), "MOVMD-TFPF+BAS-elman-adam": (5.22502e-3, 0.140403)}  # Fig. 19
PAPER_METHOD = "MOVMD-TFPF+BAS-elman-adam"
COLUMNS = ("arw_1s_deg_per_sqrt_h", "bias_instability_dph", "drift_dph", "rms_error_dph", "bandwidth_hz")


def _table(runs: pd.DataFrame) -> pd.DataFrame:
    rows = []
    for method, g in runs.groupby("method"):
        row: dict[str, object] = {"method": method, "runs": len(g)}
        for c in COLUMNS:
            row[c] = float(g[c].median())
        paper = PAPER.get(str(method))
        row["paper_arw"], row["paper_bi_dph"] = paper if paper else (np.nan, np.nan)
        rows.append(row)
    raw = next(r for r in rows if r["method"] == "raw")
    rows.append({"method": "raw (seed 001, Fig. 19)", "runs": np.nan, "arw_1s_deg_per_sqrt_h": PAPER["raw"][0],
                 "bias_instability_dph": PAPER["raw"][1]})
    rows.append({"method": f"{PAPER_METHOD} (seed 001, Fig. 19)", "runs": np.nan,
                 "arw_1s_deg_per_sqrt_h": PAPER[PAPER_METHOD][0], "bias_instability_dph": PAPER[PAPER_METHOD][1]})
    table = pd.DataFrame(rows)
    table["arw_gain"] = raw["arw_1s_deg_per_sqrt_h"] / table["arw_1s_deg_per_sqrt_h"]
    table["bi_gain"] = raw["bias_instability_dph"] / table["bias_instability_dph"]
    paper_rows = table["method"].str.endswith("(seed 001, Fig. 19)")
    table.loc[paper_rows, "arw_gain"] = PAPER["raw"][0] / table.loc[paper_rows, "arw_1s_deg_per_sqrt_h"]
    table.loc[paper_rows, "bi_gain"] = PAPER["raw"][1] / table.loc[paper_rows, "bias_instability_dph"]
    return table.sort_values("drift_dph", na_position="last").drop(columns=["paper_arw", "paper_bi_dph"])


def _verdict(runs: pd.DataFrame, oracle: pd.Series) -> list[str]:
    mine = runs[runs["method"] == PAPER_METHOD]
    raw = runs[runs["method"] == "raw"].iloc[0]
    if mine.empty:
        return ["The paper's method has no finished run in this sweep: nothing to compare."]
    arw_gain = raw["arw_1s_deg_per_sqrt_h"] / mine["arw_1s_deg_per_sqrt_h"]
    bi_gain = raw["bias_instability_dph"] / mine["bias_instability_dph"]
    paper_arw, paper_bi = PAPER["raw"][0] / PAPER[PAPER_METHOD][0], PAPER["raw"][1] / PAPER[PAPER_METHOD][1]
    n = len(mine)
    lines = [
        f"**Claim (Fig. 19): ARW 0.531 → 5.2e-3 (×{paper_arw:.0f}) and bias stability 32.7 → 0.14 °/h "
        f"(×{paper_bi:.0f}).** Here, with one VMD tuning and one decomposition shared by the {n} restarts "
        f"(they differ only in the BAS-Elman drift learner's start, so the ARW and bias instability are "
        f"in effect one observation): ARW ×{arw_gain.median():.1f} "
        f"(range {arw_gain.min():.1f}–{arw_gain.max():.1f}), bias instability ×{bi_gain.median():.1f} "
        f"(range {bi_gain.min():.1f}–{bi_gain.max():.1f}); the paper's ARW factor is "
        + ("reached" if (arw_gain >= paper_arw).all() else "not reached")
        + " and its bias-stability factor "
        + ("reached" if (bi_gain >= paper_bi).all() else "not reached")
        + " by that one decomposition: "
        + ("**reproduced**." if (arw_gain >= paper_arw).all() and (bi_gain >= paper_bi).all() else
           "**not reproduced** at the paper's size."),
        f"**What the gains are made of.** The oracle — the simulator's true drift removed, the noise "
        f"untouched; medians over its run draws — has ARW {oracle['arw_1s_deg_per_sqrt_h']:.3g} °/√h and bias instability "
        f"{oracle['bias_instability_dph']:.3g} °/h: that is as low as any temperature compensation can go. "
        f"The paper's pipeline reaches a median ARW of {mine['arw_1s_deg_per_sqrt_h'].median():.3g} °/√h and bias "
        f"instability {mine['bias_instability_dph'].median():.3g} °/h by keeping only "
        f"{mine['bandwidth_hz'].median():.3g} Hz of bandwidth (the raw output keeps "
        f"{raw['bandwidth_hz']:.3g} Hz): the ARW and bias-instability gains beyond the oracle's are an "
        "artefact of filtering — a real rate input faster than that bandwidth is removed with the noise.",
        f"**Temperature compensation proper** (residual drift over temperature, std of the soak means): "
        f"raw {raw['drift_dph']:.3g} °/h, oracle {oracle['drift_dph']:.3g} °/h (median over its run draws), "
        "the paper's pipeline "
        f"{mine['drift_dph'].median():.3g} °/h (median; range {mine['drift_dph'].min():.3g}–"
        f"{mine['drift_dph'].max():.3g}).",
    ]
    return lines


def _allan_curves(client, runs: pd.DataFrame, where: Path) -> dict[str, AllanDeviation]:  # type: ignore[no-untyped-def]
    curves: dict[str, AllanDeviation] = {}
    raw_done = False
    for method, g in runs.groupby("method"):
        pick = g.iloc[(g["arw_1s_deg_per_sqrt_h"] - g["arw_1s_deg_per_sqrt_h"].median()).abs().argsort().iloc[0]]
        path = Path(client.download_artifacts(pick["run_id"], "allan_test1.csv", str(where)))
        d = np.loadtxt(path, delimiter=",", skiprows=1)
        if not raw_done:
            curves["raw"] = AllanDeviation(d[:, 0], d[:, 1] / 3600.0, np.zeros(len(d)), np.nan, 0)
            raw_done = True
        if method != "raw":
            curves[str(method)] = AllanDeviation(d[:, 0], d[:, 2] / 3600.0, np.zeros(len(d)), np.nan, 0)
    return curves


def _paper_figures(client, task: str, runs: pd.DataFrame, out: Path) -> list[str]:  # type: ignore[no-untyped-def]
    """Copy the seed's figures (Figs. 11-14, 17-19) of the paper's method's median run (by
    drift) into ``out/<task>/``; markdown lines that show them."""
    mine = runs[runs["method"] == PAPER_METHOD]
    if mine.empty:
        return []
    pick = mine.iloc[(mine["drift_dph"] - mine["drift_dph"].median()).abs().argsort().iloc[0]]
    where = out / task
    where.mkdir(parents=True, exist_ok=True)
    names = sorted(a.path for a in client.list_artifacts(pick["run_id"]) if a.path.startswith("fig"))
    for name in names:
        client.download_artifacts(pick["run_id"], name, str(where))
    return [f"Figures of the paper's method, restart {int(pick['seed'])} (the median by drift): "
            + ", ".join(f"[{n.split('_')[0]}]({task}/{n})" for n in names) + ".", ""]


def _section(client, task: str, runs: pd.DataFrame, out: Path) -> list[str]:  # type: ignore[no-untyped-def]
    oracle = runs[runs["method"] == "oracle"].median(numeric_only=True)  # over its run draws
    table = _table(runs)
    table.to_csv(out / f"fig19_{task}.csv", index=False)
    with tempfile.TemporaryDirectory() as tmp:
        curves = _allan_curves(client, runs, Path(tmp))
    bw = runs.groupby("method")["bandwidth_hz"].median()
    png = out / f"fig19_allan_{task}.png"
    allan_methods_figure(png, curves, f"Fig. 19: Allan deviation of every method (test run)\n{task}",
                         annotations={m: f"bw {bw[m]:.2g} Hz" for m in curves if m in bw})
    return [f"## {task}", "", markdown_table(table), "", *[f"{line}\n" for line in _verdict(runs, oracle)],
            f"![Allan deviation of every method on {task}]({png.name})", "",
            *_paper_figures(client, task, runs, out)]


def _tier_table(runs: pd.DataFrame) -> list[str]:
    """Drift (°/h, median over the runs, with their count) of every method run on more than one
    tier, per task: what the test runs being a replay of the training power-on is worth."""
    shared = runs.groupby("method")["split"].nunique()
    g = runs[runs["method"].isin(shared[shared > 1].index) | runs["method"].str.startswith("oracle")]
    if g.empty or g["split"].nunique() < 2:
        return []
    table = g.groupby(["task", "method", "split"])["drift_dph"].agg(["median", "size"]).reset_index()
    table["drift_dph"] = [f"{m:.3g} ({n})" for m, n in zip(table["median"], table["size"], strict=True)]
    wide = table.pivot_table(index=["task", "method"], columns="split", values="drift_dph", aggfunc="first")
    wide = wide.reset_index().fillna("–")
    return ["## Tiers: next run against a replay", "",
            "Drift (°/h, median, number of runs in brackets) of the rows run on both tiers: `next_run` tests "
            "on new power-ons of the device (the default, every table above), `replay` on new noise over the "
            "training run's power-on (docs/concepts/split-tiers.md). The oracles are drawn over 30 runs of each tier they "
            "were run on; every other row is one draw of the train and test runs.", "", markdown_table(wide), ""]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--experiment", default="paper-movmd-tfpf")
    p.add_argument("--sweep", default=None)
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args()
    client = tracking.client()
    runs = one_run_per_job(board.load_runs(client, [args.experiment], args.sweep), ("task", "split", "method", "seed"))
    runs = runs[runs["status"] == "FINISHED"]
    tiers = runs
    runs = runs[runs["split"] == DEFAULT_TIER]  # Fig. 19 on the default tier; the others in the tier table
    args.out.mkdir(parents=True, exist_ok=True)
    lines = [
        "# Seed 001 Fig. 19 beside tcbench", "",
        "Simulated 14 h oven runs of gyro 0 at 10 Hz (one to train, one to test; `bash "
        "experiments/paper_movmd_tfpf/run.sh`): the device as simulated by default (flicker B ≈ 33 °/h, "
        "experiments/raw-sensors/README.md)" + (", and the same device with 3 °/h of flicker" if runs["task"].nunique() > 1 else "")
        + ". Medians over restarts; ARW = σ(1 s)/60 "
        "in °/√h (seed 001 prints °/h/√Hz for a value that only fits its bias stability as °/√h, "
        "docs/concepts/physics.md, metrics); bias instability = Allan minimum / 0.664 (°/h); drift = std of the 5-min soak "
        "means (°/h); rms = RMS error against the true rate (°/h); bandwidth = −3 dB frequency of the "
        "whole method, measured by injecting a multi-sine rate into the test run (5 Hz = Nyquist: "
        "nothing lost). Gains are raw / method (the paper's rows: its raw / its result).", "",
    ]
    for task, g in runs.groupby("task", sort=True):
        lines += _section(client, str(task), g, args.out)
    lines += _tier_table(tiers)
    (args.out / "fig19.md").write_text("\n".join(lines))
    print(f"wrote {args.out / 'fig19.md'}")


if __name__ == "__main__":
    main()
