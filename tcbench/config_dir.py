"""Where tcbench's Hydra configs are: the one place the rest of the code asks.

The repository's top-level ``conf/`` (``config.yaml`` and the groups ``task/``, ``optimiser/``,
``learner/``, ``experiment/`` ...) is installed as the package ``tcbench.conf``
(``[tool.setuptools.package-dir]`` in pyproject.toml). A wheel or a ``pip install .`` puts it
in site-packages as ``tcbench/conf/``; an editable install (``pip install -e .``) maps
``tcbench.conf`` to the clone's ``conf/``, so edits there take effect without reinstalling.
"""

from __future__ import annotations

from importlib.metadata import entry_points
from importlib.resources import files
from pathlib import Path

from tcbench.errors import ConfigError

CONFIG_MODULE = "tcbench.conf"
SEARCH_PATH = f"pkg://{CONFIG_MODULE}"  # Hydra's config_path / search-path entry for them
CONFIG_NAME = "config"
PLUGIN_CONFIGS = "tcbench.configs"  # entry-point group naming the config packages of plugins


def conf_dir() -> Path:
    """The folder holding ``config.yaml`` and the config groups, as installed; ConfigError
    (one line) when they are not there."""
    root = Path(str(files(CONFIG_MODULE)))
    if not (root / f"{CONFIG_NAME}.yaml").is_file():
        raise ConfigError(
            f"tcbench's configs are not at {root}: reinstall tcbench (pip install -e . in a clone); "
            "a leftover tcbench/conf/ folder from before the configs moved to conf/ can hide them: delete it")
    return root


def plugin_packages() -> list[str]:
    """The config packages installed plugins name in :data:`PLUGIN_CONFIGS`, in entry-point name order."""
    return [ep.value for ep in sorted(entry_points(group=PLUGIN_CONFIGS), key=lambda e: e.name)]


def group_options(group: str) -> list[str]:
    """The options of the config group ``group`` (``optimiser``: fa, ifa, ... and the plugins'), sorted."""
    folders = [conf_dir() / group, *(Path(str(files(p))) / group for p in plugin_packages())]
    return sorted({f.stem for folder in folders if folder.is_dir() for f in folder.glob("*.yaml")})
