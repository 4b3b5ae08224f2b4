"""The real-IMU board: one row per record, axis and split, the held-out drift of every
calibration method and of the memoriser, a control (RMS over the parts it was not fitted on of
each part's drift), against the raw output and against the white-noise floor of the drift score
(a limit with its interval: a method is at the floor only when the interval of its drift over the
floor reaches 1), the winner with its block-bootstrap interval against the runner-up (a tie when
it reaches 1), best/raw and model/best with theirs, how each learner was trained, what the model
explains but does not compensate, and the diagnosis of the whole record; the cross-part table
(fitted on one part, scored on another: every pair); a plot of the drift relative to raw.

Every split is named for what it is (``split_kind``): the temperature branches of one recording
are "branches of one power-on" (a recording is one power-on: these are), its time blocks "time
blocks of one cooling" (or heating, when every block runs that way), the parts of other
recordings scored with ``test_recordings=`` "runs". Only the last is a cross-run split.

Usage: python experiments/real-imu/summarise.py --calibrations DIR [DIR ...] [--cross DIR ...]
--diagnoses DIR --out DIR (``run.sh`` calls it; it reads ``DIR/<axis>/calibration.csv`` and
``.json`` and ``DIAGNOSES/<axis>/report.json``). It writes ``board.csv`` (one row per record, split
and method), ``splits.csv`` (one per record and split: ``board.md``'s table), ``cross_part.csv``
(every pair), ``cross_part_tally.csv`` (per record and method over the pairs), ``board.md`` and
``board.png``; the README's tables and numbers are read from these CSVs
(:mod:`tcbench.leaderboard.quoted`).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tcbench.tables import markdown_table

ORDER = ("raw", "poly3", "poly3_rate", "bp", "bp_gd", "elman", "model", "memoriser")
BRANCHES = "branches of one power-on"
RUNS = "runs"


def _ci(v: list[float] | None) -> str:
    """``0.42 [0.31, 0.55]``."""
    return "–" if not v or v[0] != v[0] else f"{v[0]:.3g} [{v[1]:.3g}, {v[2]:.3g}]"


def held_out(calibration: pd.DataFrame) -> pd.Series:
    """Per method, the RMS over the test parts of their drift."""
    drift = next(c for c in calibration.columns if c.startswith("drift_rms_"))
    test = calibration[calibration["role"] == "test"]
    return test.groupby("method")[drift].apply(lambda x: float(np.sqrt(np.mean(np.square(x)))))


def split_kind(about: dict[str, Any], cal: pd.DataFrame) -> str:
    """What the held-out parts of a calibration are (``calibration.json`` and ``.csv``): the
    temperature branches of its recording (:data:`BRANCHES`), its time blocks ("time blocks of one
    cooling" when every block cools, "... of one heating", else "time blocks of one power-on"),
    and the parts of other recordings (:data:`RUNS`), joined by " + " when both are held out."""
    own = cal[cal["recording"] == Path(about["recording"]).stem] if "recording" in cal else cal
    kinds = []
    if about.get("held_out_parts"):
        if "time block" in about["parts"]:
            directions = set(own.drop_duplicates("branch")["direction"])
            kinds.append(f"time blocks of one {directions.pop()}" if len(directions) == 1 and
                         directions <= {"cooling", "heating"} else "time blocks of one power-on")
        else:
            kinds.append(BRANCHES)
    if about.get("test_recordings"):
        kinds.append(RUNS)
    return " + ".join(kinds)


def _floor_columns(about: dict[str, Any], method: str) -> dict[str, Any]:
    """The floor with its interval and the method's drift over it with its interval, from
    ``calibration.json`` (``noise_floor``, ``x_floor``: tcbench calibrate's block bootstrap)."""
    floor, x = about["noise_floor"], about["x_floor"][method]
    return {"noise_floor": floor[0], "noise_floor_lo": floor[1], "noise_floor_hi": floor[2],
            "ratio_to_floor": x[0], "ratio_to_floor_lo": x[1], "ratio_to_floor_hi": x[2],
            "at_floor": method in about["at_floor"]}


def _pooled_columns(about: dict[str, Any], method: str) -> dict[str, Any]:
    """The ranking tcbench calibrate made (``calibration.json``): on every held-out sample pooled,
    the method's drift over the best's and over raw's with their block-bootstrap intervals, and
    whether it is the best or tied with it. Named ``pooled_*``: the drifts above are RMS over parts."""
    best, raw = about["x_best"][method], about["x_raw"][method]
    return {"pooled_best": method == about["best"], "pooled_tied": method in about.get("tied", []),
            "pooled_over_best": best[0], "pooled_over_best_lo": best[1], "pooled_over_best_hi": best[2],
            "pooled_over_raw": raw[0], "pooled_over_raw_lo": raw[1], "pooled_over_raw_hi": raw[2]}


def board(calibrations: list[Path], diagnoses: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The long table (axis, split and its kind, method, drift, the floor and the ratios to it and
    to raw) and the wide board."""
    long_rows, wide_rows = [], []
    folders = [p for c in calibrations for p in sorted(c.iterdir()) if (p / "calibration.csv").is_file()]
    for folder in folders:
        cal = pd.read_csv(folder / "calibration.csv")
        about = json.loads((folder / "calibration.json").read_text())
        if "noise_floor" not in about:
            raise SystemExit(f"summarise.py: {folder}/calibration.json has no noise_floor: calibrate it again "
                             "(the floor comes from tcbench calibrate)")
        unit = next(c for c in cal.columns if c.startswith("drift_rms_")).removeprefix("drift_rms_")
        scores = held_out(cal)
        raw = scores["raw"]
        fitted = sorted(set(cal.loc[cal["role"] == "train", "branch"]))
        tested = sorted(set(cal.loc[cal["role"] == "test", "branch"]))
        restarts = int(cal["restarts"].max()) if "restarts" in cal else 1
        split = f"{','.join(map(str, fitted))} → {','.join(map(str, tested))}"
        kind = split_kind(about, cal)
        for method, value in scores.items():
            long_rows.append({"record": folder.name, "split": split, "split_kind": kind, "method": method,
                              "held_out_drift": value, "unit": unit, **_floor_columns(about, method),
                              "ratio_to_raw": value / raw, **_pooled_columns(about, method),
                              "restarts": int(cal.loc[cal["method"] == method, "restarts"].max())})
        best = about["best"]
        floor = about["noise_floor"]
        report = diagnoses / folder.name / "report.json"
        verdict = json.loads(report.read_text())["verdict"] if report.is_file() else "–"
        runner = f"{about['next']} {_ci([1 / about['ratio_to_next'], 1 / about['ratio_hi'], 1 / about['ratio_lo']])}" \
            if "next" in about else "–"
        wide_rows.append({"record": folder.name, "unit": unit.replace("_per_", "/"),
                          "fit on → scored on": split, "split kind": kind, "noise floor": _ci(floor),
                          **{m: scores.get(m, np.nan) for m in ORDER}, "best": best,
                          "best's drift": scores[best], "best's drift / raw": scores[best] / raw,
                          "runner-up / best": runner,
                          "verdict": f"tie ({', '.join(about['tied'])})" if about.get("tied") else "win",
                          "best / raw": _ci(about["x_raw"].get(best)), "best / floor": _ci(about["x_floor"][best]),
                          "at the floor": ", ".join(about["at_floor"]) or "none",
                          "memoriser / best": _ci(about["x_best"].get("memoriser")),
                          "model / best": _ci(about["x_best"].get("model")),
                          "screened": about["screening"]["total"] - about["screening"]["kept"],
                          "networks": restarts, "diagnosis of the whole record": verdict,
                          "training": about.get("training", {})})
    return pd.DataFrame(long_rows), pd.DataFrame(wide_rows)


def cross(folders: list[Path]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Every (fit part, test part) pair of the calibrations fitted on one part, with the kind of
    the split (:func:`split_kind`: the test part's own, "runs" for another recording's): per
    method its drift over raw's with the interval; and per record, kind and method the pairs it
    wins or ties and the median of its ratio to raw."""
    rows = []
    for folder in sorted(f for c in folders for f in c.iterdir() if (f / "calibration.json").is_file()):
        about = json.loads((folder / "calibration.json").read_text())
        if len(about["fitted"]) != 1:
            continue
        record = folder.name.split(".fit")[0]
        cal = pd.read_csv(folder / "calibration.csv")
        own_kind = split_kind(about | {"test_recordings": []}, cal)
        own = Path(about["recording"]).stem
        for part in about["per_part"]:
            source, index = part["part"].rsplit(":", 1)
            kind = own_kind if source == own else RUNS
            for m, x in part["x_raw"].items():
                if m == "raw":
                    continue
                rows.append({"record": record, "split_kind": kind, "fit part": about["fitted"][0],
                             "test part": int(index) if source == own else part["part"],
                             "method": m, "drift / raw": x[0], "lo": x[1], "hi": x[2],
                             "best": m == part["best"], "tied": m in part["tied"], "blocks": part["blocks"]})
    pairs = pd.DataFrame(rows)
    if pairs.empty:
        return pairs, pairs
    tally = pairs.groupby(["record", "split_kind", "method"], sort=False).agg(
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


def kinds_in_words(kinds: list[str]) -> str:
    """What each split kind on the board is, one sentence each."""
    words = {
        BRANCHES: "*branches of one power-on*: the temperature branches (between the thermometer's turning points) "
                  "of one recording, the sensor never switched off between them, so a fit on one branch and the "
                  "score on another share that power-on's turn-on bias and everything keyed to its clock",
        RUNS: "*runs*: separate recordings (a power-off between them), the only split here that is cross-run",
    }
    out = []
    for kind in kinds:
        for part in kind.split(" + "):
            if part in words:
                out.append(words[part])
            elif part.startswith("time blocks of one "):
                out.append(f"*{part}*: one recording cut into blocks of equal duration, every one on the same "
                           f"{part.removeprefix('time blocks of one ')}, so neighbouring blocks share its level and "
                           "trend")
    return "; ".join(dict.fromkeys(out)) + "." if out else ""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calibrations", type=Path, nargs="+", required=True)
    ap.add_argument("--cross", type=Path, nargs="*", default=[])
    ap.add_argument("--diagnoses", type=Path, required=True)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    long, wide = board(args.calibrations, args.diagnoses)
    pairs, tally = cross([*args.calibrations, *args.cross])
    args.out.mkdir(parents=True, exist_ok=True)
    long.to_csv(args.out / "board.csv", index=False)
    pairs.to_csv(args.out / "cross_part.csv", index=False)
    tally.to_csv(args.out / "cross_part_tally.csv", index=False)
    plot(long, args.out / "board.png")
    numbers = wide.drop(columns=["diagnosis of the whole record", "training"])
    numbers.to_csv(args.out / "splits.csv", index=False)
    verdicts = wide[["record", "diagnosis of the whole record"]].drop_duplicates("record")
    training = [(r["record"], r["fit on → scored on"], t["line"]) for _, r in wide.iterrows()
                for t in r["training"].values()]
    lines = "\n".join(f"- {rec} ({split}): {line}" for rec, split, line in training)
    pair_table = pairs.assign(**{"drift / raw [95%]": [_ci([a, b, c]) for a, b, c in
                                                       zip(pairs["drift / raw"], pairs["lo"], pairs["hi"],
                                                           strict=True)]}).drop(
        columns=["drift / raw", "lo", "hi"]) if not pairs.empty else pairs
    pair_kinds = sorted(set(pairs["split_kind"])) if not pairs.empty else []
    board_kinds = sorted(set(wide["split kind"]))
    cross_runs = "" if RUNS in pair_kinds else " None of these pairs is cross-run: no part is a separate recording."
    (args.out / "board.md").write_text(
        "# Real IMU records: calibration board\n\n"
        "Held-out drift: the RMS, over the parts of the record a method was not fitted on, of the RMS of its "
        "residual's running mean (60 s; 5 s, one burst, for PAN), in the record's unit (`board.csv`: "
        "`held_out_drift`). tofupilot: fitted on the first cooling branch (0), scored on the heating (1) and the "
        "second cooling (2), and fitted on both directions (0, 1), scored on the second cooling (2); PAN (a single "
        "cooling): cut into 5 time blocks, fitted on 0, 2, 4, scored on 1, 3.\n\n"
        f"What the splits are (`split kind`): {kinds_in_words(board_kinds)}"
        f"{'' if any(RUNS in k for k in board_kinds) else ' No split on this board is across runs.'}\n\n"
        "Methods: networks (bp: Levenberg-Marquardt when the rows allow it, else gradient descent; bp_gd: gradient "
        "descent, 1000 epochs; elman: Adam, 500 epochs): the median of `networks` restarts, their inputs held to "
        "the box they were trained on. model = the diagnosed physics (tcbench diagnose on the fitted parts) as a "
        "compensator runs it: its temperature terms, without the terms keyed to the calibration run's clock (steps, "
        "transients, warm-up, ageing) or the rig's lines — explained by the diagnosis, not compensated. memoriser = "
        "a control with no physics: the fitted parts' mean offset against the time since their start, subtracted "
        "at the same time since the start of each held-out part; it knows the split's clock and not the "
        "thermometer, and cannot fly (`memoriser / best`: a method that does not beat it has learned nothing from "
        "the temperature that the split's clock does not give). Every fit sees the screened training parts "
        "(`screened`: samples dropped). Intervals: 95 % block bootstrap over the held-out parts (every method on "
        "the same draws); `runner-up / best` is a tie when its interval reaches 1. `best`, `runner-up / best`, "
        "`best / raw`, `memoriser / best` and `model / best` are tcbench calibrate's ranking on every held-out "
        "sample pooled (`board.csv`: `pooled_*`); the drift columns, `best's drift` and `best's drift / raw` are "
        "RMS over the parts, which can order two close methods the other way. This table is `splits.csv`.\n\n"
        "The noise floor is a limit, with its interval: the drift score white noise alone would give on the "
        "held-out parts (the raw residual's sample variance, half that of its first differences, over the samples "
        "in one window), 95 % block bootstrap drawn within each held-out part, jointly with every method's drift; "
        "`best / floor` is the best's drift over it with that interval, and `at the floor` lists the methods whose "
        "interval reaches 1 — a method is at the floor only then (`board.csv`: `noise_floor_lo`/`_hi`, "
        "`ratio_to_floor_lo`/`_hi`, `at_floor`).\n\n"
        f"{markdown_table(numbers)}\n\n![held-out drift relative to raw](board.png)\n\n"
        f"## Training of each learner\n\n{lines}\n\n"
        "## Fitted on one part, scored on another part of the same record\n\n"
        f"Each part fitted alone and scored on every other part of its record. {kinds_in_words(pair_kinds)}"
        f"{cross_runs} tofupilot: its three branches (6 pairs); PAN: its five time blocks (20 pairs). Every pair "
        "(fit part, test part), every method's held-out drift over raw's with its 95 % block-bootstrap interval "
        "(`cross_part.csv`). Per record and method: the pairs it wins (lowest drift), those it ties with the "
        "pair's best (interval against the best reaches 1), the median of its drift over raw's, and the pairs "
        "where it is worse than raw (`cross_part_tally.csv`)."
        f"\n\n{markdown_table(tally)}\n\n### Every pair\n\n{markdown_table(pair_table)}\n\n"
        f"## Diagnosis of each whole record\n\n{markdown_table(verdicts)}\n")
    print(markdown_table(numbers))
    print(markdown_table(tally))


if __name__ == "__main__":
    main()
