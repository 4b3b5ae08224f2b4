"""The tutorial "Compensate your own IMU" (docs/tutorials/own-imu.md: import, diagnose, calibrate,
export, leaderboard, on the tofupilot and PAN recordings the repository carries) runs as written:
every command of its bash blocks, in order, from a folder that holds only the repository's data,
and gives the files the page describes."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest

from tcbench.cli import main

ROOT = Path(__file__).resolve().parents[1]


def walkthrough() -> list[list[str]]:
    """The commands of the tutorial's bash blocks, in order, continuations joined."""
    text = (ROOT / "docs" / "tutorials" / "own-imu.md").read_text()
    blocks = re.findall(r"```bash\n(.*?)```", text, re.S)
    return [shlex.split(line) for block in blocks for line in block.replace("\\\n", " ").splitlines()
            if line.strip() and not line.lstrip().startswith("#")]


def test_the_tutorial_blocks_are_what_this_test_runs() -> None:
    commands = walkthrough()
    assert [c[1] for c in commands] == ["import", "diagnose", "calibrate", "export", "import", "metrics",
                                        "calibrate", "leaderboard", "calibrate"]
    assert all(c[0] == "tcbench" for c in commands)


@pytest.mark.slow
def test_the_own_imu_tutorial_runs(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (workdir / "data").symlink_to(ROOT / "data")
    for command in walkthrough():
        assert main(command[1:]) == 0, " ".join(command)
    out = capsys.readouterr().out
    mine = workdir / "my-imu"
    script = (mine / "params" / "px4_tc_params.txt").read_text().splitlines()
    px4 = [ln for ln in script if not ln.startswith("# ")]
    assert px4[0] == "param set TC_G0_ID 2293768" and len(px4) == 1 + 12 + 3 + 1
    parm = [ln for ln in (mine / "params" / "ardupilot_tcal.parm").read_text().splitlines() if not ln.startswith("# ")]
    assert parm[0] == "INS_TCAL1_ENABLE 1"
    bests = {a: json.loads((mine / "calibration" / f"imu-imu.gyro.{a}" / "calibration.json").read_text())["best"]
             for a in "xyz"}
    notes = [ln for ln in script if ln.startswith("# tcbench: these are the cubic's coefficients; gyro ")]
    assert [ln.split("; ")[1].split(":")[0] for ln in notes] == [f"gyro {a}" for a in "xyz" if bests[a] != "poly3"]
    pan = json.loads((mine / "calibration" / "pan-x" / "calibration.json").read_text())
    assert pan["held_out_parts"] == [1, 3] and pan["axis"] == "x"
    boards = sorted(p.name for p in (mine / "boards").glob("calibration-*.md"))
    assert len(boards) == 4, boards  # three tofupilot axes and the PAN gyro, one board each
    assert out.count("best held out:") == 5  # the three tofupilot axes, the PAN gyro, gyro y on two branches
