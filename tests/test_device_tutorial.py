"""The tutorial "Compensate on the device" (docs/tutorials/device-c.md) runs as written: its tcbench
commands, its C host program, its compile lines and its Python comparison, in order, from a folder
that holds only the repository's data; and what it prints is what the page shows."""

from __future__ import annotations

import contextlib
import io
import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

from tcbench.cli import main

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "tutorials" / "device-c.md"


def blocks() -> list[tuple[str, str]]:
    """The page's fenced blocks, in order: (language, text)."""
    return re.findall(r"```(\w+)\n(.*?)```", PAGE.read_text(), re.S)


def test_the_page_holds_the_steps_this_test_runs() -> None:
    kinds = [k for k, _ in blocks()]
    assert kinds == ["bash", "text", "text", "c", "bash", "python", "text"]
    commands = [shlex.split(ln)[1] for ln in blocks()[0][1].splitlines() if ln.strip()]
    assert commands == ["import", "calibrate", "export"]


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) on this machine")
def test_the_device_tutorial_runs(workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (workdir / "data").symlink_to(ROOT / "data")
    said = []
    for kind, text in blocks():
        if kind == "bash":
            for line in (ln for ln in text.splitlines() if ln.strip()):
                if line.startswith("tcbench "):
                    assert main(shlex.split(line)[1:]) == 0, line
                else:
                    subprocess.run(line, shell=True, check=True, cwd=workdir)
        elif kind == "c":
            path = workdir / text.splitlines()[0].removeprefix("/* ").removesuffix(" */")
            path.write_text(text)
        elif kind == "python":
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                exec(compile(text, str(PAGE), "exec"), {})
            said = out.getvalue().splitlines()
    printed = capsys.readouterr().out.splitlines()
    shown = blocks()[1][1].splitlines()
    assert all(line in printed for line in shown), (shown, printed)
    expected = blocks()[-1][1].splitlines()
    assert [s.split(":")[0] for s in said] == ["double", "float"]
    for got, want in zip(said, expected):
        assert got.split("; ", 1)[1] == want.split("; ", 1)[1]  # the state and the ring as the page says
        limit = 1e-9 if got.startswith("double") else 1e-4  # deg/s, on a correction of about 1.4
        assert float(re.search(r"difference (\S+)", got)[1]) <= limit, got
