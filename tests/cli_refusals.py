"""What the bad-input corpora share: logging as in a fresh process, a digest of a folder, and a
command refused in one line that changes nothing."""

from __future__ import annotations

import hashlib
import logging
from pathlib import Path

import pytest

from tcbench.cli import main


@pytest.fixture(autouse=True)
def fresh_logging(monkeypatch: pytest.MonkeyPatch) -> None:
    """Logging as in a fresh ``tcbench`` process: earlier tests (Hydra runs) can leave handlers
    on streams pytest has since closed, which would add lines to the captured stderr."""
    root = logging.getLogger()
    monkeypatch.setattr(root, "handlers", [])
    monkeypatch.setattr(root, "level", logging.WARNING)


def snapshot(root: Path) -> dict[str, str]:
    """Every file and folder under ``root`` with a digest of its content (a named pipe, a link
    loop ... by what it is, never opened)."""
    def digest(p: Path) -> str:
        if p.is_dir():
            return "dir"
        if p.is_file():
            return hashlib.sha256(p.read_bytes()).hexdigest()
        return f"special {p.lstat().st_mode:o}"

    return {str(p.relative_to(root)): digest(p) for p in sorted(root.rglob("*"))}


def refused(capsys: pytest.CaptureFixture[str], root: Path, args: list[str], *names: str) -> str:
    """Run ``tcbench <args>``; assert exit 2, one ``tcbench: error:`` line naming each of
    ``names``, no traceback and nothing changed under ``root``; the line."""
    before = snapshot(root)
    code = main(args)
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2, (code, captured.err)
    assert len(lines) == 1 and lines[0].startswith("tcbench: error: "), captured.err
    assert "Traceback" not in captured.err + captured.out
    for name in names:
        assert name in lines[0], (name, lines[0])
    assert snapshot(root) == before
    return lines[0]
