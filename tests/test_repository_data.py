"""The repository carries the real recordings it uses: ``data/real/<name>/`` with provenance and
licence, each file under 5 MB, and no code, config or document reads a path outside the clone."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import REAL_FILES

from tcbench.data_paths import REAL_DATA, real_file
from tcbench.datasets.real import TOFUPILOT_CSV, tofupilot_gyro
from tcbench.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
SCANNED = ("tests", "experiments", "tcbench", "benchmarks", "conf", "plugins", "examples", "hydra_plugins",
           ".ci", "docs", "README.md", "Makefile", "mkdocs.yml", "pyproject.toml")
TEXT_SUFFIXES = {".py", ".sh", ".md", ".yaml", ".yml", ".toml", ".cfg", ".ini", ".txt", ""}
GENERATED = {"__pycache__", "runs", "outputs", "multirun", "mlruns", "mlartifacts", "ioh-analyzer",
             "leaderboards"}  # docs/leaderboards/: the site's board pages, made at every build
OUTSIDE = ("../shared", '"shared" /', "'shared' /", "TCBENCH_REAL_DATA",
           "PHYSICS.md", "DESIGN.md")  # documents that are not in the repository: docs/concepts/ is its own
MAX_FILE_BYTES = 5_000_000
# Path(__file__).resolve().parents[k]: outside the repository when k reaches past its root
PARENTS = re.compile(r"__file__\)\.resolve\(\)\.parents\[(\d+)\]")
DATA_PATH = re.compile(r"(?<![\w$/.])data/real/[\w./-]*[\w/]")


def scanned_files() -> list[Path]:
    """The text files of the code, configs and documents (this file aside: it names the patterns)."""
    files: list[Path] = []
    for name in SCANNED:
        top = ROOT / name
        for path in [top] if top.is_file() else sorted(top.rglob("*")):
            rel = path.relative_to(ROOT)
            if (path.is_file() and path.suffix in TEXT_SUFFIXES and path != Path(__file__).resolve()
                    and not GENERATED & set(rel.parts) and not any(p.startswith("smoke") for p in rel.parts)):
                files.append(path)
    return files


def test_nothing_refers_to_a_path_outside_the_repository() -> None:
    files = scanned_files()
    assert len(files) > 300  # the walk found the tree
    found = []
    for path in files:
        rel = path.relative_to(ROOT)
        for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            found += [f"{rel}:{number}: {word}" for word in OUTSIDE if word in line]
            found += [f"{rel}:{number}: parents[{k}]" for k in map(int, PARENTS.findall(line))
                      if k >= len(rel.parts)]
    assert not found, "\n".join(found)


def test_the_location_is_defined_once() -> None:
    """Code and tests take ``data/real/`` from :mod:`tcbench.data_paths` (the tests through conftest)."""
    defining = sorted(path.relative_to(ROOT).as_posix() for path in scanned_files()
                      if re.search(r"""["']data["'] / ["']real["']""", path.read_text(encoding="utf-8", errors="replace")))
    assert defining == ["tcbench/data_paths.py"]


def test_every_data_real_path_named_exists() -> None:
    """Every ``data/real/...`` path a script, test or document names is in the repository."""
    named = {m for path in scanned_files() for m in DATA_PATH.findall(path.read_text(encoding="utf-8",
                                                                                   errors="replace"))}
    assert {"data/real/pan_lsm6dsm_tvac_cooling/pan_lsm6dsm_tvac_cooling.csv",
            "data/real/tofupilot_imu_chamber/imu_raw_data.csv",
            "data/real/px4_ulog_samples/sample_log_small.ulg"} <= named  # the documented commands (README, docs)
    assert not sorted(p for p in named if not (ROOT / p).exists())


def test_each_recording_has_provenance_and_licence_and_small_files() -> None:
    folders = sorted(p for p in REAL_DATA.iterdir() if p.is_dir())
    assert [f.name for f in folders] == ["imu_utils_allan_curves", "pan_lsm6dsm_tvac_cooling", "px4_ulog_samples",
                                         "tofupilot_imu_chamber"]
    for folder in folders:
        assert (folder / "PROVENANCE.md").is_file(), folder
        assert any(p.is_file() for p in folder.glob("LICENSE*")), folder
    sizes = {p.relative_to(REAL_DATA).as_posix(): p.stat().st_size for p in REAL_DATA.rglob("*") if p.is_file()}
    assert len(sizes) > 10 and not {p: s for p, s in sizes.items() if s >= MAX_FILE_BYTES}


def test_the_data_the_tests_read_is_in_the_repository() -> None:
    assert REAL_DATA == ROOT / "data" / "real"
    for path in REAL_FILES:
        assert path.is_file() and path.is_relative_to(REAL_DATA), path
    assert real_file("tofupilot_imu_chamber/imu_raw_data.csv") == TOFUPILOT_CSV
    assert tofupilot_gyro("z").time_s.size > 8000  # the default record is the repository's


def test_a_missing_recording_is_one_line_naming_it() -> None:
    with pytest.raises(ConfigError) as caught:
        real_file("tofupilot_imu_chamber/no_such_file.csv")
    message = str(caught.value)
    assert "\n" not in message and str(REAL_DATA / "tofupilot_imu_chamber" / "no_such_file.csv") in message
    assert "data/real/README.md" in message
    with pytest.raises(ConfigError, match="not found"):
        real_file("tofupilot_imu_chamber")  # a folder is not a recording
