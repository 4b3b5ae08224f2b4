"""The README runs as written: after its set-up (the two ```` ```bash ```` blocks that create
``.venv``, which CI runs itself), every other ```` ```bash ```` block runs in a fresh folder with
the environment active (:mod:`doc_blocks`), in the README's order, and must exit 0; a block fenced
```` ```{.bash .no-run} ```` is shown and not run. The fast tests check that what the README and
the quickstart tell a new user to type runs after that set-up."""

from __future__ import annotations

import re
import time
from pathlib import Path

import pytest
from doc_blocks import ROOT, blocks, environment, fresh_folder, run_blocks, runnable

README = ROOT / "README.md"
SET_UP = "python3 -m venv .venv"  # the set-up blocks start so
ACTIVATE = "source .venv/bin/activate"


def _after_set_up() -> list[str]:
    return [body for body in runnable(README) if not body.startswith(SET_UP)]


def test_the_readme_sets_up_twice_and_then_runs_its_examples() -> None:
    set_up = [body for body in runnable(README) if body.startswith(SET_UP)]
    assert len(set_up) == 2, "the README's two set-up blocks (CI runs the second) are not both fenced ```bash"
    assert len(_after_set_up()) >= 3, "the README's examples are not fenced ```bash"
    assert {info for info, _ in blocks(README)} <= {"bash", "{.bash .no-run}", "text"}


def test_ci_and_the_docs_home_page_set_up_as_the_readme_says() -> None:
    """``.ci/run`` installs as the README's test command does (quieter) and runs its pytest selection;
    the docs' home page gives the README's two set-up commands word for word."""
    set_up = [body.strip() for body in runnable(README) if body.startswith(SET_UP)]
    install, _, tests = set_up[1].partition(" && .venv/bin/python -m pytest ")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")

    def words(text: str) -> str:
        return " ".join(w for w in text.split() if w != "-q")

    assert tests and words(install) in words(ci), "the README's test command and .ci/run install differently"
    assert f".venv/bin/python -m pytest {tests.replace(' -n 2', '')}" in ci and "-n 2" in ci
    home = [body.strip() for body in runnable(ROOT / "docs" / "index.md") if body.startswith(SET_UP)]
    assert home == set_up


def test_the_readme_activates_the_environment_before_its_commands() -> None:
    """The set-up installs into .venv, not onto the path: the README says to activate it before the
    first block that calls a bare ``tcbench``, and calls nothing else as ``.venv/bin/...`` after it."""
    text = README.read_text(encoding="utf-8")
    first = min(text.index(body) for body in _after_set_up() if re.search(r"^tcbench ", body, re.M))
    assert ACTIVATE in text[:first], "the README calls tcbench before saying to activate .venv"
    last_set_up = max(text.index(body) for body in runnable(README) if body.startswith(SET_UP))
    assert not re.search(r"`\.venv/bin/(mlflow|mkdocs|pip|pytest)\b", text[last_set_up:]), "a .venv/bin/ call after the set-up"


def test_the_quickstart_says_how_to_reach_its_commands(tmp_path: Path) -> None:
    """The quickstart runs as .venv/bin/tcbench; the commands it prints need the environment active."""
    from tcbench.cli.quickstart import NEXT_STEPS, activate_command

    (tmp_path / ".venv" / "bin").mkdir(parents=True)
    assert activate_command(tmp_path / ".venv", tmp_path) == ""  # no activate script: nothing to say
    (tmp_path / ".venv" / "bin" / "activate").write_text("")
    assert activate_command(tmp_path / ".venv", tmp_path) == ACTIVATE
    assert activate_command(tmp_path / ".venv", tmp_path / "elsewhere") == f"source {tmp_path}/.venv/bin/activate"
    assert ".venv/bin/" not in NEXT_STEPS and "environment active" in NEXT_STEPS


def test_the_extras_are_named_where_they_are_needed() -> None:
    """mkdocs comes with the docs extra, pytest with the test extra: each page that runs one says so."""
    readme = README.read_text(encoding="utf-8")
    assert "mkdocs serve" in readme and "pip install -e '.[docs]'" in readme
    for page in ("add-optimiser.md", "add-term.md"):
        text = (ROOT / "docs" / "tutorials" / page).read_text(encoding="utf-8")
        assert "python -m pytest" in text
        assert "pip install -e '.[test]'" in text[:text.index("python -m pytest")], page


@pytest.mark.slow
def test_readme_runs_as_written(tmp_path: Path) -> None:
    work = fresh_folder(tmp_path / "work")
    start = time.monotonic()
    output = run_blocks("README.md", _after_set_up(), work, environment(work))
    text = "\n".join(output)
    assert "(experiment 'tcbench'" in text and "2293768" in (work / "my-imu/params/px4_tc_params.txt").read_text()
    assert (work / "boards").is_dir() and (work / "again").is_dir()
    print(f"README.md: {len(output)} blocks in {time.monotonic() - start:.0f} s")
