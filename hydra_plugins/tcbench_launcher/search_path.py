"""Installed plugins' Hydra configs on tcbench's config search path.

A package that extends tcbench names the package of its configs (``optimiser/<name>.yaml`` ...)
in the entry-point group ``tcbench.configs``; this search-path plugin adds each such package
whenever the application's primary configs are tcbench's, so ``optimiser=cma`` composes and
``tcbench run --help`` lists plugin optimisers beside the built-in ones. Other Hydra
applications in the same environment are left alone.
"""

from importlib.metadata import entry_points

from hydra.core.config_search_path import ConfigSearchPath
from hydra.plugins.search_path_plugin import SearchPathPlugin


def plugin_config_packages() -> list[str]:
    """``pkg://`` search-path entries of installed plugins' configs, in entry-point name order."""
    return [f"pkg://{ep.value}" for ep in sorted(entry_points(group="tcbench.configs"), key=lambda e: e.name)]


def _is_tcbench(search_path: ConfigSearchPath) -> bool:
    return any(e.provider == "main" and e.path is not None and e.path.rstrip("/").endswith(("tcbench/conf", "tcbench.conf"))
               for e in search_path.get_path())


class TcbenchPluginConfigs(SearchPathPlugin):
    """Appends the ``tcbench.configs`` entry points' packages to tcbench's search path."""

    def manipulate_search_path(self, search_path: ConfigSearchPath) -> None:
        if not _is_tcbench(search_path):
            return
        known = {e.path for e in search_path.get_path()}
        for path in plugin_config_packages():
            if path not in known:
                search_path.append(provider="tcbench-plugin", path=path)
