"""Diagnose every gyro axis of the real recordings and hold each final model against the
physics-agnostic reference (issue 23, item 6), in one command.

Records (PROVENANCE.md beside each under the repository's ``data/real/``):
- ``tofupilot``: the 70.7-min chamber cycle, -17.6 -> 74 -> 35 degC at about 2 Hz
  (:func:`tcbench.datasets.real.tofupilot_gyro`);
- ``pan_lsm6dsm``: the 2-h thermal-vacuum cooling run, 25 bursts of 5 s at about 50 Hz
  (``pan_lsm6dsm.convert``).

Each axis's report goes to ``--out/<record>/<axis>/`` (report.json, report.md, model.yaml,
plots); ``--out/summary.md`` holds one row per axis: the starting model's, the final model's
and the reference's held-out RMSE in white sigma, final / reference (target <= 1.25), the test
that decided, the effects named and the seconds taken; then, per axis, its residual plot
(located findings marked), its verdict and every finding with its shape, where, explanation
and the measurement that would confirm it.

    python experiments/diagnose-real/run.py [--out DIR] [--records tofupilot,pan_lsm6dsm]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from pathlib import Path

from pan_lsm6dsm import DATA as PAN_DATA
from pan_lsm6dsm import convert as pan_gyro

from tcbench.datasets.real import TOFUPILOT_CSV, tofupilot_gyro
from tcbench.diagnose.diagnosis import Diagnosis, diagnose
from tcbench.diagnose.report.markdown import format_where
from tcbench.diagnose.report.write import write_report
from tcbench.diagnose.settings import DEFAULTS
from tcbench.sensors.recording import Recording

RECORDS: dict[str, tuple[Callable[[str], Recording], str, Path]] = {
    "tofupilot": (lambda axis: tofupilot_gyro(axis, TOFUPILOT_CSV), "tofupilot chamber cycle gyro {axis}",
                  TOFUPILOT_CSV),
    "pan_lsm6dsm": (lambda axis: pan_gyro(PAN_DATA / "pan_lsm6dsm_tvac_cooling.csv", axis),
                    "PAN LSM6DSM gyro {axis} (cooling, 25 bursts)", PAN_DATA / "pan_lsm6dsm_tvac_cooling.csv"),
}
HEADER = ["| record | axis | baseline held-out | final held-out | reference held-out | final / reference | test "
          "| effects named | s |", "|---|---|---|---|---|---|---|---|---|"]


def _sentence(text: str) -> str:
    """``text`` ending in one full stop."""
    return text.rstrip().rstrip(".") + "."


def axis_section(d: Diagnosis, record: str, axis: str, files: dict[str, Path], out: Path) -> list[str]:
    """The summary's section of one axis: its residual plot (linked relative to ``out``), the
    verdict and every finding with shape, where, explanation and confirm-with."""
    rel = {name: path.relative_to(out).as_posix() for name, path in files.items()}
    t0 = float(d.series.t_s[0])
    lines = [f"### {record} {axis}", "", f"![{record} {axis} residuals]({rel['residuals.png']})", "",
             f"Report: [report.md]({rel['report.md']}); spectrum: [spectrum.png]({rel['spectrum.png']}); "
             f"Allan: [allan.png]({rel['allan.png']}).", "", f"**Verdict:** {d.verdict}", ""]
    if not d.effects:
        lines += ["No finding.", ""]
    for f in d.effects:
        kind = "library" if f.library else "not library"
        where = format_where(f.where, f.params.get("unit", d.unit), t0)
        lines += [f"- **{f.id}** ({f.shape}, {kind}); where: {where}. {_sentence(f.explanation)} "
                  f"*Confirm with:* {_sentence(f.confirm_with)}"]
    return [*lines, ""]


def diagnose_record(record: str, out: Path) -> tuple[list[str], list[str]]:
    """Diagnose the three gyro axes of ``record``, write their reports under ``out/<record>``;
    the summary rows and the per-axis sections."""
    load, title, source = RECORDS[record]
    if not source.exists():
        raise SystemExit(f"run.py: {source} not found (the repository's data/real/, data/real/README.md)")
    rows: list[str] = []
    sections: list[str] = []
    for axis in ("x", "y", "z"):
        t0 = time.perf_counter()
        d = diagnose(load(axis), name=title.format(axis=axis))
        seconds = time.perf_counter() - t0
        files = write_report(d, out / record / axis)
        sections += axis_section(d, record, axis, files, out)
        s = d.noise.white_sigma
        rows.append(f"| {record} | {axis} | {d.baseline.rmse_heldout / s:.2f} sigma | "
                    f"{d.final.rmse_heldout / s:.2f} sigma | {d.reference.rmse_heldout / s:.2f} sigma | "
                    f"{d.reference.final_over_reference:.2f} | {d.statistics.significance_test} | "
                    f"{', '.join(d.effect_ids) or '-'} | {seconds:.1f} |")
        print(f"{record} {axis}: {d.verdict}", flush=True)
    return rows, sections


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("leaderboards/diagnose-real"))
    ap.add_argument("--records", default=",".join(RECORDS), help=f"comma-separated, of {', '.join(RECORDS)}")
    args = ap.parse_args()
    records = [r.strip() for r in args.records.split(",") if r.strip()]
    if unknown := [r for r in records if r not in RECORDS]:
        raise SystemExit(f"run.py: unknown record {unknown[0]!r}; known: {', '.join(RECORDS)}")
    done = [diagnose_record(record, args.out) for record in records]
    rows = [row for r, _ in done for row in r]
    sections = [line for _, sec in done for line in sec]
    head = [f"# Real gyro recordings: final model against the physics-agnostic reference (target <= {DEFAULTS.reference.structure_ratio:g})",
            "", "Held-out RMSE in white sigma (first differences); blocks, folds and the significance test as in "
            "each report.json `statistics`. Command: `python experiments/diagnose-real/run.py`.", ""]
    findings = ["", "## Findings per axis", "",
                ("Each axis: the held-out residual of the starting and the final model against time and temperature "
                 "(located findings marked: dashed lines at instants, strips over temperature bands), the verdict, "
                 "and every finding of report.json `effects` with its shape, where, explanation and the measurement "
                 "that would confirm it."), ""]
    text = "\n".join(head + HEADER + rows + findings + sections).rstrip() + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "summary.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
