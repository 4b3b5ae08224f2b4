"""The real-IMU board: one row per record, axis and split, the held-out drift of every
calibration method (RMS over the parts it was not fitted on) against the raw output and against
the white-noise floor of the drift score, the winner with its block-bootstrap interval against
the runner-up (a tie when it reaches 1), best/raw and model/best with theirs, how each learner
was trained, what the model explains but does not compensate, and the diagnosis of the whole
record; the cross-run table (fitted on one run, scored on another: every pair); a plot of the
drift relative to raw.

Usage: python experiments/real-imu/summarise.py --calibrations DIR [DIR ...] [--cross DIR ...]
--recordings DIR --diagnoses DIR --out DIR (``run.sh`` calls it; it reads
``DIR/<axis>/calibration.csv``, ``.md`` and ``.json``, ``RECORDINGS/<axis>.csv`` and
``DIAGNOSES/<axis>/report.json``).
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd

from tcbench.sensors.recording import read_recording
from tcbench.sensors.segments import within_rate_hz
from tcbench.tables import markdown_table

ORDER = ("raw", "poly3", "poly3_rate", "bp", "bp_gd", "elman", "model")


def _ci(v: list[float] | None) -> str:
    """``0.42 [0.31, 0.55]``."""
    return "–" if not v or v[0] != v[0] else f"{v[0]:.3g} [{v[1]:.3g}, {v[2]:.3g}]"


def held_out(calibration: pd.DataFrame) -> pd.Series:
    """Per method, the RMS over the test parts of their drift."""
    drift = next(c for c in calibration.columns if c.startswith("drift_rms_"))
    test = calibration[calibration["role"] == "test"]
    return test.groupby("method")[drift].apply(lambda x: float(np.sqrt(np.mean(np.square(x)))))


def noise_floor(recording: Path, window_s: float) -> float:
    """The drift score of white noise alone: the output's per-sample sigma (from first
    differences, robust) over the square root of the samples in one drift window."""
    rec = read_recording(recording)
    d = np.diff(rec.output)
    sigma = 1.4826 * float(np.median(np.abs(d - np.median(d)))) / np.sqrt(2.0)
    return sigma / np.sqrt(max(1.0, window_s * within_rate_hz(rec.time_s)))


def board(calibrations: list[Path], recordings: Path, diagnoses: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The long table (axis, split, method, drift, ratio to raw) and the wide board."""
    long_rows, wide_rows = [], []
    folders = [p for c in calibrations for p in sorted(c.iterdir()) if (p / "calibration.csv").is_file()]
    for folder in folders:
        cal = pd.read_csv(folder / "calibration.csv")
        window_s = float(re.search(r"residual's ([0-9.]+)-s running mean", (folder / "calibration.md").read_text())[1])
        floor = noise_floor(recordings / f"{folder.name}.csv", window_s)
        unit = next(c for c in cal.columns if c.startswith("drift_rms_")).removeprefix("drift_rms_")
        scores = held_out(cal)
        raw = scores["raw"]
        fitted = sorted(set(cal.loc[cal["role"] == "train", "branch"]))
        tested = sorted(set(cal.loc[cal["role"] == "test", "branch"]))
        restarts = int(cal["restarts"].max()) if "restarts" in cal else 1
        split = f"{','.join(map(str, fitted))} → {','.join(map(str, tested))}"
        for method, value in scores.items():
            long_rows.append({"record": folder.name, "split": split, "method": method, "held_out_drift": value,
                              "unit": unit, "noise_floor": floor, "ratio_to_floor": value / floor,
                              "ratio_to_raw": value / raw, "restarts": int(cal.loc[cal["method"] == method,
                                                                                    "restarts"].max())})
        about = json.loads((folder / "calibration.json").read_text())
        best = about["best"]
        report = diagnoses / folder.name / "report.json"
        verdict = json.loads(report.read_text())["verdict"] if report.is_file() else "–"
        runner = f"{about['next']} {_ci([1 / about['ratio_to_next'], 1 / about['ratio_hi'], 1 / about['ratio_lo']])}" \
            if "next" in about else "–"
        wide_rows.append({"record": folder.name, "unit": unit.replace("_per_", "/"),
                          "fit on → scored on": split, "noise floor": floor,
                          **{m: scores.get(m, np.nan) for m in ORDER}, "best": best,
                          "runner-up / best": runner,
                          "verdict": f"tie ({', '.join(about['tied'])})" if about.get("tied") else "win",
                          "best / raw": _ci(about["x_raw"].get(best)), "best / floor": scores[best] / floor,
                          "model / best": _ci(about["x_best"].get("model")),
                          "screened": about["screening"]["total"] - about["screening"]["kept"],
                          "networks": restarts, "diagnosis of the whole record": verdict,
                          "training": about.get("training", {})})
    return pd.DataFrame(long_rows), pd.DataFrame(wide_rows)


def cross(folders: list[Path]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Every (fit run, test run) pair of the calibrations fitted on one part: per method its
    drift over raw's with the interval; and per record and method the pairs it wins or ties
    and the median of its ratio to raw."""
    rows = []
    for folder in sorted(f for c in folders for f in c.iterdir() if (f / "calibration.json").is_file()):
        about = json.loads((folder / "calibration.json").read_text())
        if len(about["fitted"]) != 1:
            continue
        record = folder.name.split(".fit")[0]
        for part in about["per_part"]:
            for m, x in part["x_raw"].items():
                if m == "raw":
                    continue
                rows.append({"record": record, "fit run": about["fitted"][0], "test run": int(part["part"].split(":")[1]),
                             "method": m, "drift / raw": x[0], "lo": x[1], "hi": x[2],
                             "best": m == part["best"], "tied": m in part["tied"], "blocks": part["blocks"]})
    pairs = pd.DataFrame(rows)
    if pairs.empty:
        return pairs, pairs
    tally = pairs.groupby(["record", "method"], sort=False).agg(
        pairs=("best", "size"), won=("best", "sum"), tied=("tied", "sum"),
        median_drift_over_raw=("drift / raw", "median"),
        worse_than_raw=("drift / raw", lambda x: int((x > 1).sum()))).reset_index()
    return pairs, tally


def plot(long: pd.DataFrame, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    long = long.assign(label=long["record"].str.replace("tofupilot-imu.", "tofu ") + "\n" + long["split"])
    records = list(dict.fromkeys(long["label"]))
    methods = [m for m in ORDER if m in set(long["method"]) and m != "raw"]
    fig, ax = plt.subplots(figsize=(14, 5), constrained_layout=True)
    width = 0.8 / len(methods)
    for i, m in enumerate(methods):
        ratio = [long[(long["label"] == r) & (long["method"] == m)]["ratio_to_raw"].squeeze() for r in records]
        ax.bar(np.arange(len(records)) + (i - (len(methods) - 1) / 2) * width, ratio, width, label=m)
    ax.set_yscale("log")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(np.arange(len(records)), records, rotation=30, fontsize=7)
    ax.set_ylabel("held-out drift / raw")
    ax.set_title("Real IMU records: drift left on the parts each model was not fitted on (lower is better)")
    ax.legend(ncol=len(methods), fontsize=8)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calibrations", type=Path, nargs="+", required=True)
    ap.add_argument("--cross", type=Path, nargs="*", default=[])
    ap.add_argument("--recordings", type=Path, required=True)
    ap.add_argument("--diagnoses", type=Path, required=True)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    long, wide = board(args.calibrations, args.recordings, args.diagnoses)
    pairs, tally = cross([*args.calibrations, *args.cross])
    args.out.mkdir(parents=True, exist_ok=True)
    long.to_csv(args.out / "board.csv", index=False)
    pairs.to_csv(args.out / "cross_run.csv", index=False)
    plot(long, args.out / "board.png")
    numbers = wide.drop(columns=["diagnosis of the whole record", "training"])
    verdicts = wide[["record", "diagnosis of the whole record"]].drop_duplicates("record")
    training = [(r["record"], r["fit on → scored on"], t["line"]) for _, r in wide.iterrows()
                for t in r["training"].values()]
    lines = "\n".join(f"- {rec} ({split}): {line}" for rec, split, line in training)
    pair_table = pairs.assign(**{"drift / raw [95%]": [_ci([a, b, c]) for a, b, c in
                                                       zip(pairs["drift / raw"], pairs["lo"], pairs["hi"],
                                                           strict=True)]}).drop(
        columns=["drift / raw", "lo", "hi"]) if not pairs.empty else pairs
    (args.out / "board.md").write_text(
        "# Real IMU records: calibration board\n\n"
        "Held-out drift: the RMS, over the parts of the record a method was not fitted on, of the RMS of its "
        "residual's running mean (60 s; 5 s, one burst, for PAN), in the record's unit. tofupilot: fitted on the "
        "first cooling branch (0), scored on the heating (1) and the second cooling (2), and fitted on both "
        "directions (0, 1), scored on the second cooling (2); PAN (a single cooling): cut into 5 time blocks, "
        "fitted on 0, 2, 4, scored on 1, 3. Networks (bp: Levenberg-Marquardt when the rows allow it, else "
        "gradient descent; bp_gd: gradient descent, 1000 epochs; elman: Adam, 500 epochs): the median of "
        "`networks` restarts, their inputs held to the box they were trained on. model = the diagnosed physics "
        "(tcbench diagnose on the fitted parts) as a compensator runs it: its temperature terms, without the terms "
        "keyed to the calibration run's clock (steps, transients, warm-up, ageing) or the rig's lines — explained "
        "by the diagnosis, not compensated. Every fit sees the screened training parts (`screened`: samples "
        "dropped). Intervals: 95 % block bootstrap over the held-out parts (every method on the same draws); "
        "`runner-up / best` is a tie when its interval reaches 1. noise floor = the drift score white noise alone "
        "would give (the output's sample-to-sample sigma over the root of the samples in a window).\n\n"
        f"{markdown_table(numbers)}\n\n![held-out drift relative to raw](board.png)\n\n"
        f"## Training of each learner\n\n{lines}\n\n"
        "## Cross-run: fitted on one run, scored on another\n\n"
        "tofupilot: its three temperature branches as runs; PAN: its five time blocks. Every pair (fit run, test "
        "run), every method's held-out drift over raw's with its 95 % block-bootstrap interval (`cross_run.csv`). "
        "Per record and method: the pairs it wins (lowest drift), those it ties with the pair's best (interval "
        "against the best reaches 1), the median of its drift over raw's, and the pairs where it is worse than raw."
        f"\n\n{markdown_table(tally)}\n\n### Every pair\n\n{markdown_table(pair_table)}\n\n"
        f"## Diagnosis of each whole record\n\n{markdown_table(verdicts)}\n")
    print(markdown_table(numbers))
    print(markdown_table(tally))


if __name__ == "__main__":
    main()
