"""``tcbench list``: the registered tasks, optimisers, learners, sensor kinds and diagnosis terms. Its jobs run in
the command line's process (:attr:`~tcbench.commands.registry.CommandSpec.runs_here`)."""

from __future__ import annotations

import re

from tcbench.commands.schemas import LISTS, ListConfig
from tcbench.errors import ConfigError, unknown_name


def check(cfg: ListConfig) -> None:
    """A ConfigError for a ``what`` that is none of :data:`~tcbench.commands.schemas.LISTS`."""
    if cfg.what not in LISTS:
        raise ConfigError(f"what={cfg.what}: {unknown_name('list', cfg.what, LISTS)}")


def work(cfg: ListConfig) -> int:
    """Print the registered tasks, optimisers, learners, sensor kinds and terms (``what``: one of them, or all)."""
    what = cfg.what
    if what in {"all", "tasks"}:
        from tcbench.tasks import TASKS

        for family in dict.fromkeys(spec.family for spec in TASKS.values()):
            print(f"tasks ({family}):")
            for spec in (s for s in TASKS.values() if s.family == family):
                print(f"  {spec.gym_id:26s} task={spec.name:{14 if spec.is_compensation else 11}s} {spec.summary}")
    if what in {"all", "optimisers"}:
        from tcbench.optimisers import registry

        print("optimisers:")
        for name, entry in registry.available().items():
            kinds = "+".join(k for k, ok in (("single", entry.cls.single_objective),
                                             ("multi", entry.cls.multi_objective)) if ok)
            print(f"  {name:10s} {entry.cls.__module__}.{entry.cls.__name__}  (from {entry.package}; {kinds}-objective)")
        for name, err in registry.broken().items():
            print(f"  {name:10s} BROKEN: {err}")
    if what in {"all", "learners"}:
        from tcbench.learners import registry as learners

        print("learners:")
        for name, lentry in learners.available().items():
            kind = "initial weights searchable" if lentry.cls.searchable else "closed form"
            print(f"  {name:10s} {lentry.cls.__module__}.{lentry.cls.__name__}  (from {lentry.package}; {kind})")
        for name, err in learners.broken().items():
            print(f"  {name:10s} BROKEN: {err}")
        print("  raw, memoriser, oracle, oracle_thermometer, lagpoly, model  baselines: no compensation; the training "
              "runs' mean output at the same time (no physics); the simulator's truth (the physical limit); its model "
              "fed the thermometer (the limit of what a compensator reads); the lag-aware polynomial; the models "
              "tcbench diagnose fits to the training runs (the board row diagnosed)")
    if what in {"all", "sensors"}:
        from tcbench.sensors import kinds as sensor_kinds

        print("sensors:")
        for kind in sensor_kinds.registry().values():
            units = f"{kind.input_unit} in, {kind.output_unit} out"
            print(f"  {kind.name:10s} {kind.title}; {units}; protocols: {', '.join(kind.protocols)}"
                  + (f"; PX4 {kind.ulog_topic}" if kind.ulog_topic else ""))
    if what in {"all", "terms"}:
        _list_terms()
    return 0


def _list_terms() -> None:
    """The diagnosis's terms (built-in and installed), the library's then the open world's, with
    their shape and a line each, then the broken term and effect plugins with their error."""
    from tcbench.diagnose.terms import broken_terms, term_source, terms
    from tcbench.sensors.effects import PLUGINS as EFFECT_PLUGINS

    print("terms:")
    for t in (*terms(), *terms(open=True)):
        doc = " ".join((type(t).__doc__ or "").strip().split("\n\n")[0].split())
        doc = re.sub(r" \(:\w+:`[^)]*\)", "", doc.split(". ")[0].rstrip(".")).replace("``", "")
        world = "open world, " if t.open_world else ""
        print(f"  {t.id:24s} {t.shape:22s} {doc}  ({world}from {term_source(t.id)})")
    for name, err in broken_terms().items():
        print(f"  {name:24s} BROKEN: {err}")
    for name, err in EFFECT_PLUGINS.broken().items():
        print(f"  {name:24s} BROKEN effect: {err}")
