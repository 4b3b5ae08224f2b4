"""The top-level ``conf/`` is tcbench's config tree in every install mode.

An editable install from a clone reads the clone's ``conf/``; a wheel and a non-editable
``pip install .`` carry it as ``tcbench/conf/``. The slow tests install each into a fresh
virtual environment that borrows this environment's dependencies (not its tcbench) and run
the ``tcbench`` command from a folder outside the repository.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

import tcbench
from tcbench.config_dir import CONFIG_MODULE, CONFIG_NAME, conf_dir

REPO = Path(__file__).resolve().parents[1]
IN_CLONE = (REPO / "pyproject.toml").is_file() and (REPO / "conf" / "config.yaml").is_file()
# What a build reads: the project file, the readme, the licence and the folders that become packages.
SOURCES = ["pyproject.toml", "README.md", "LICENSE", "tcbench", "conf", "hydra_plugins"]
needs_clone = pytest.mark.skipif(not IN_CLONE, reason="needs tcbench's source tree")


def _groups(root: Path) -> list[str]:
    return sorted(p.name for p in root.iterdir() if p.is_dir() and any(p.glob("*.yaml")))


def test_configs_resolve_in_this_install() -> None:
    root = conf_dir()
    assert (root / "config.yaml").is_file()
    assert {"task", "optimiser", "learner", "experiment"} <= set(_groups(root))
    if IN_CLONE and Path(tcbench.__file__).resolve().parent == REPO / "tcbench":
        # an editable install (or a source checkout): the clone's conf/, edits need no reinstall
        assert root.resolve() == (REPO / "conf").resolve()


def test_missing_configs_are_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import tcbench.config_dir as where
    from tcbench.errors import ConfigError

    monkeypatch.setattr(where, "files", lambda _module: tmp_path)  # e.g. a stale tcbench/conf/ folder
    with pytest.raises(ConfigError, match="leftover tcbench/conf/"):
        where.conf_dir()


def test_primary_config_composes() -> None:
    from hydra import compose, initialize_config_module

    from tcbench.runner.config import register_schema

    register_schema()  # the structured schema config.yaml's defaults start from
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        cfg = compose(CONFIG_NAME, overrides=["task=sphere", "optimiser=fa", "learner=bp"])
    assert cfg.task.name == "sphere" and cfg.optimiser.name == "fa" and cfg.learner.name == "bp"
    assert cfg.budget > 0


def _copy_sources(dest: Path) -> Path:
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info")
    dest.mkdir(parents=True)
    for name in SOURCES:
        src = REPO / name
        if src.is_dir():
            shutil.copytree(src, dest / name, ignore=ignore)
        else:
            shutil.copy2(src, dest / name)
    return dest


def _build_wheel(tmp: Path) -> Path:
    src = _copy_sources(tmp / "src")  # a copy: the build's build/ folder stays out of the clone
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "--no-build-isolation",
                    "-q", "-w", str(tmp / "dist")], check=True, capture_output=True, text=True)
    (wheel,) = (tmp / "dist").glob("tcbench-*.whl")
    return wheel


@needs_clone
def test_wheel_holds_the_config_tree_and_every_package(tmp_path: Path) -> None:
    names = set(zipfile.ZipFile(_build_wheel(tmp_path)).namelist())
    assert "tcbench/conf/config.yaml" in names
    assert not any(n.startswith("conf/") for n in names)  # installed under tcbench/, not top level
    for group in _groups(REPO / "conf"):
        assert any(n.startswith(f"tcbench/conf/{group}/") for n in names), group
    yamls = {f"tcbench/conf/{p.relative_to(REPO / 'conf').as_posix()}" for p in (REPO / "conf").rglob("*.yaml")}
    assert yamls <= names, sorted(yamls - names)
    # the packages are listed in pyproject.toml: a new subpackage must be listed there too
    modules = {p.relative_to(REPO).as_posix() for top in ("tcbench", "hydra_plugins")
               for p in (REPO / top).rglob("*.py") if "__pycache__" not in p.parts}
    assert modules <= names, f"missing from the wheel (add to [tool.setuptools] packages): {sorted(modules - names)}"


def _fresh_env(tmp: Path) -> Path:
    """A virtual environment without tcbench that sees this environment's other packages."""
    env = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(env)], check=True)
    here = next(Path(p) for p in sys.path if p.endswith("site-packages") and Path(p, "hydra").is_dir())
    deps = tmp / "deps"  # this environment's site-packages minus tcbench and editable installs
    deps.mkdir()
    for entry in here.iterdir():
        low = entry.name.lower()
        if low.startswith(("tcbench", "__editable__", "_tcbench")) or low.endswith(".pth"):
            continue
        (deps / entry.name).symlink_to(entry)
    (site,) = (env / "lib").glob("python3*/site-packages")
    (site / "_tcbench_test_deps.pth").write_text(f"{deps}\n")
    return env


def _run(cmd: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "MLFLOW_TRACKING_URI", "VIRTUAL_ENV")}
    env.update(MPLBACKEND="Agg", MLFLOW_DISABLE_TELEMETRY="true", PYTHONNOUSERSITE="1")
    out = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, f"{cmd}:\n{out.stdout}\n{out.stderr}"
    return out


def _check_installed(env: Path, tmp: Path) -> None:
    work = tmp / "elsewhere"
    work.mkdir()
    py, cli = env / "bin" / "python", env / "bin" / "tcbench"
    where = _run([str(py), "-c", "import tcbench; from tcbench.config_dir import conf_dir; "
                  "print(tcbench.__file__); print(conf_dir())"], work).stdout.split()
    site = str(next((env / "lib").glob("python3*/site-packages")))
    assert where[0].startswith(site) and where[1] == f"{site}/tcbench/conf", where
    assert "tcbench/Sphere-v0" in _run([str(cli), "list"], work).stdout
    job = _run([str(cli), "run", "task=sphere", "optimiser=fa", "budget=40", "--cfg", "job"], work).stdout
    assert "name: sphere" in job and "name: fa" in job
    helped = _run([str(cli), "run", "--help"], work).stdout
    assert "experiment: " in helped and "quickstart" in helped  # the config groups, read from the install
    _run([str(cli), "run", "task=sphere", "optimiser=fa", "budget=40", "tracking.enabled=false"], work)


@pytest.mark.slow
@needs_clone
def test_wheel_installs_and_runs(tmp_path: Path) -> None:
    wheel = _build_wheel(tmp_path)
    env = _fresh_env(tmp_path)
    _run([str(env / "bin" / "python"), "-m", "pip", "install", "-q", "--no-deps", str(wheel)], tmp_path)
    _check_installed(env, tmp_path)


@pytest.mark.slow
@needs_clone
def test_pip_install_dot_runs(tmp_path: Path) -> None:
    src = _copy_sources(tmp_path / "src")
    env = _fresh_env(tmp_path)
    _run([str(env / "bin" / "python"), "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation", "."], src)
    _check_installed(env, tmp_path)
