"""Registries fed by entry-point groups: the built-ins and plugin packages are found the same way.

A package declares classes under a group in its ``pyproject.toml``::

    [project.entry-points."tcbench.optimisers"]
    de = "my_package.de:DifferentialEvolution"

A name is imported when it is first asked for (:meth:`PluginRegistry.get`), so a run of FA does
not import every installed plugin's libraries; :meth:`PluginRegistry.available` loads them all.
An entry point that fails to load (or names the wrong kind of class) is recorded as broken with
its error and skipped; the others still work.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from typing import Any, Generic, TypeVar

log = logging.getLogger(__name__)
T = TypeVar("T")


class UnknownPluginError(KeyError):
    """No class of that name is registered in the group."""

    def __str__(self) -> str:
        return str(self.args[0])


@dataclass(frozen=True)
class Entry(Generic[T]):
    """A registered class and the distribution that provides it."""

    cls: type[T]
    package: str


class PluginRegistry(Generic[T]):
    """Classes of kind ``base`` registered under the entry-point group ``group``."""

    def __init__(self, group: str, base: type[T], kind: str,
                 unknown_error: type[UnknownPluginError] = UnknownPluginError) -> None:
        self.group, self.base, self.kind, self.unknown_error = group, base, kind, unknown_error
        self._points: dict[str, EntryPoint] | None = None
        self._entries: dict[str, Entry[T]] = {}
        self._broken: dict[str, str] = {}

    def _entry_points(self) -> dict[str, EntryPoint]:
        """The group's entry points by name, not yet imported (a later duplicate name wins)."""
        if self._points is None:
            self._points = {ep.name: ep for ep in entry_points(group=self.group)}
        return self._points

    def _load_one(self, name: str) -> Entry[T] | None:
        """Import the entry point ``name`` once; ``None`` if there is none or it is broken."""
        if name in self._entries:
            return self._entries[name]
        ep = self._entry_points().get(name)
        if ep is None or name in self._broken:
            return None
        package = ep.dist.name if ep.dist is not None else "?"
        try:
            cls = ep.load()
            self.check_class(name, cls)
        except Exception as exc:  # a broken plugin must not take the others down
            self._broken[name] = f"{type(exc).__name__}: {exc}"
            log.warning("%s plugin %r from %s skipped: %s", self.kind, name, package, exc)
            return None
        self._entries[name] = Entry(cls, package)
        return self._entries[name]

    def _load_all(self) -> dict[str, Entry[T]]:
        for name in self._entry_points():
            self._load_one(name)
        return self._entries

    def check_class(self, name: str, cls: Any) -> None:
        """Raise ``TypeError`` unless ``cls`` is a subclass of the registry's base."""
        if not (isinstance(cls, type) and issubclass(cls, self.base)):
            raise TypeError(f"{name!r} does not name a {self.base.__module__}.{self.base.__name__} subclass")

    def register(self, name: str, cls: type[T], package: str = "__main__") -> None:
        """Register ``cls`` under ``name`` for this process (entry points are the lasting way)."""
        self.check_class(name, cls)
        self._entries[name] = Entry(cls, package)
        self._broken.pop(name, None)

    def names(self) -> list[str]:
        """Every registered name, without importing any plugin (broken ones included)."""
        return sorted(set(self._entry_points()) | set(self._entries))

    def available(self) -> dict[str, Entry[T]]:
        """Registered classes by name (imports every plugin of the group)."""
        return dict(sorted(self._load_all().items()))

    def broken(self) -> dict[str, str]:
        """Entry points that failed to load, with their error (imports every plugin of the group)."""
        self._load_all()
        return dict(self._broken)

    def get(self, name: str) -> type[T]:
        """The class registered as ``name``; :class:`UnknownPluginError` naming the known ones."""
        entry = self._load_one(name)
        if entry is None:
            from tcbench.errors import unknown_name

            known = [n for n in self.names() if n not in self._broken]
            hint = f" (plugin failed to load: {self._broken[name]})" if name in self._broken else ""
            raise self.unknown_error(unknown_name(self.kind, name, known, hint, self.aliases()))
        return entry.cls

    def aliases(self) -> dict[str, str]:
        """The longer names the registered names go by, from their classes' names (``firefly`` for
        ``fa``), for "did you mean" (no plugin imported)."""
        from tcbench.errors import class_aliases

        paths = {name: ep.value for name, ep in self._entry_points().items()}
        paths.update({name: f"{e.cls.__module__}:{e.cls.__name__}" for name, e in self._entries.items()})
        return class_aliases(paths)


def group_aliases(group: str) -> dict[str, str]:
    """:meth:`PluginRegistry.aliases` of the entry-point group ``group`` (``tcbench.optimisers``)."""
    from tcbench.errors import class_aliases

    return class_aliases({ep.name: ep.value for ep in entry_points(group=group)})
