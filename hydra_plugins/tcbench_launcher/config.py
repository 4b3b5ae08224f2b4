"""Configs of tcbench's sweeper and launcher (no ``from __future__ import annotations`` here:
Hydra loads plugin modules without registering them, which string annotations of a dataclass
would need)."""

from dataclasses import dataclass

from hydra._internal.core_plugins.basic_sweeper import BasicSweeperConf
from hydra.core.config_store import ConfigStore


@dataclass
class GroupingSweeperConf(BasicSweeperConf):
    _target_: str = "hydra_plugins.tcbench_launcher.launcher.GroupingSweeper"


@dataclass
class GroupedLauncherConf:
    _target_: str = "hydra_plugins.tcbench_launcher.launcher.GroupedLauncher"
    n_jobs: int = 1  # worker processes; 1 runs the jobs in this process


# Hydra imports every module under hydra_plugins when it looks for plugins; this makes
# ``hydra/sweeper=tcbench`` and ``hydra/launcher=tcbench`` known.
ConfigStore.instance().store(group="hydra/sweeper", name="tcbench", node=GroupingSweeperConf, provider="tcbench")
ConfigStore.instance().store(group="hydra/launcher", name="tcbench", node=GroupedLauncherConf, provider="tcbench")
