"""The real-IMU board: one row per record, axis and split, the held-out drift of every
calibration method (RMS over the parts it was not fitted on) against the raw output and against
the white-noise floor of the drift score, the winner, and the diagnosis of the whole record; a
plot of the drift relative to raw.

Usage: python experiments/real-imu/summarise.py --calibrations DIR [DIR ...] --recordings DIR
--diagnoses DIR --out DIR (``run.sh`` calls it; it reads ``DIR/<axis>/calibration.csv`` and
``.md``, ``RECORDINGS/<axis>.csv`` and ``DIAGNOSES/<axis>/report.json``).
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

ORDER = ("raw", "poly3", "poly3_rate", "bp", "elman", "model")


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
        best = min((m for m in scores.index if m != "raw"), key=lambda m: scores[m])
        report = diagnoses / folder.name / "report.json"
        verdict = json.loads(report.read_text())["verdict"] if report.is_file() else "–"
        wide_rows.append({"record": folder.name, "unit": unit.replace("_per_", "/"),
                          "fit on → scored on": split, "noise floor": floor,
                          **{m: scores.get(m, np.nan) for m in ORDER}, "best": best,
                          "best / raw": scores[best] / raw, "best / floor": scores[best] / floor,
                          "model / best": scores.get("model", np.nan) / scores[best],
                          "networks": restarts, "diagnosis of the whole record": verdict})
    return pd.DataFrame(long_rows), pd.DataFrame(wide_rows)


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
    ap.add_argument("--recordings", type=Path, required=True)
    ap.add_argument("--diagnoses", type=Path, required=True)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    long, wide = board(args.calibrations, args.recordings, args.diagnoses)
    args.out.mkdir(parents=True, exist_ok=True)
    long.to_csv(args.out / "board.csv", index=False)
    plot(long, args.out / "board.png")
    numbers = wide.drop(columns=["diagnosis of the whole record"])
    verdicts = wide[["record", "diagnosis of the whole record"]].drop_duplicates("record")
    (args.out / "board.md").write_text(
        "# Real IMU records: calibration board\n\n"
        "Held-out drift: the RMS, over the parts of the record a method was not fitted on, of the RMS of its "
        "residual's running mean (60 s; 5 s, one burst, for PAN), in the record's unit. tofupilot: fitted on the "
        "first cooling branch (0), scored on the heating (1) and the second cooling (2), and fitted on both "
        "directions (0, 1), scored on the second cooling (2); PAN (a single cooling): cut into 5 time blocks, "
        "fitted on 0, 2, 4, scored on 1, 3. Networks (bp, elman): the median of `networks` restarts. model = the "
        "diagnosed physics (tcbench diagnose on the fitted parts). noise floor = the drift score white noise alone "
        "would give (the output's sample-to-sample sigma over the root of the samples in a window).\n\n"
        f"{markdown_table(numbers)}\n\n![held-out drift relative to raw](board.png)\n\n"
        f"## Diagnosis of each whole record\n\n{markdown_table(verdicts)}\n")
    print(markdown_table(numbers))


if __name__ == "__main__":
    main()
