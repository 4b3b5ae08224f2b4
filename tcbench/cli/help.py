"""Usage text of tcbench's commands, generated from each command's spec
(:mod:`tcbench.commands.registry`) and the schema of its primary config (``tcbench run``'s with
its config groups), so the parameters and defaults shown are the ones the command uses. Built
without Hydra, OmegaConf or the tasks' libraries: ``--help`` answers at once."""

from __future__ import annotations

import dataclasses
import textwrap
from typing import Any

from tcbench.cli.flags import KEY_FLAGS
from tcbench.commands.registry import SPECS, by_config

# keys of the shared schema that these commands accept and ignore (``tcbench run`` uses them)
IGNORED = ("tracking.plots", "tracking.ioh_dir")
HIDDEN = ("kind",)  # the job kind the primary config names, not a parameter
# what -m does, by where a command's jobs run (its spec's ``kinds`` or ``runs_here``)
ON_LAUNCHER = ("the jobs run on tcbench run's launcher (hydra.launcher.n_jobs=2 for two workers) and "
               "the sweep is reported at the end; Hydra's log lines go to stderr and its record of the sweep "
               "to multirun/<date>/<time>/ in the folder every job's out= lies in")
IN_TURN = "the jobs run one after another in this process"


def _shown(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return str(value).lower()
    if value == "":
        return "''"
    return str(value)


def parameters(schema: type) -> list[tuple[str, Any]]:
    """``(dotted key, default)`` of every parameter of a dataclass schema, nested dataclasses
    flattened (``tracking.enabled``); a dict- or list-valued field is one entry."""
    out: list[tuple[str, Any]] = []

    def walk(obj: Any, prefix: str) -> None:
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if dataclasses.is_dataclass(value):
                walk(value, f"{prefix}{f.name}.")
            else:
                out.append((f"{prefix}{f.name}", value))

    walk(schema(), "")
    return out


def usage(name: str) -> str:
    """The ``--help`` text of command ``name``."""
    from tcbench.config_dir import CONFIG_NAME

    spec = SPECS[name]
    if spec.config == CONFIG_NAME:
        return run_usage()
    schema = spec.schema_class()
    sweep = (IN_TURN if spec.runs_here else ON_LAUNCHER) + spec.sweep
    first = f" [{spec.positional.upper()}]" if spec.positional else ""
    fields = {f.name for f in dataclasses.fields(schema)}
    flags = {flag: (key, value) for flag, (key, value) in KEY_FLAGS.items() if key in fields}
    shown = "".join(f" [{flag} {value}]" for flag, (_, value) in flags.items())
    lines = [f"usage: tcbench {name}{first} [-m] [key=value ...]{shown} [--cfg job] [-h]", "",
             textwrap.fill(spec.description, width=100), "",
             "parameters (key=value, default after =):"]
    meanings = spec.meanings()
    rows = [(f"{key}={'(required)' if key in spec.required else _shown(default)}", meanings.get(key, ""))
            for key, default in parameters(schema) if key not in IGNORED + HIDDEN]
    width = max(len(left) for left, _ in rows) + 2
    lines += [f"  {left:{width}s}{meaning}" for left, meaning in rows]
    if ignored := [k for k, _ in parameters(schema) if k in IGNORED]:
        lines.append(f"  (also accepted, unused here: {', '.join(ignored)})")
    lines += ["", "options:",
              "  -h, --help   show this help and exit",
              "  --cfg job    print the config composed from the defaults and the given key=value, "
              "and exit without running",
              *textwrap.wrap("sweep (--multirun): one job per combination of comma-separated values or "
                             "range(...), in Hydra's override grammar (quote a path holding , ( ) [ ] { } or "
                             f"quotes: \"recording='run (1).csv'\"); {sweep}", width=98,
                             initial_indent="  -m           ", subsequent_indent=" " * 15),
              *(f"  {flag + ' ' + value:{12}s} {key}={value}" for flag, (key, value) in flags.items()),
              *spec.options,
              "", "examples:", *(f"  {e}" for e in spec.examples),
              "", textwrap.fill(f"output: {spec.output}", width=100, subsequent_indent="  ")]
    return "\n".join(lines)


def _group_defaults(top: dict[str, Any]) -> dict[str, Any]:
    """The config groups of ``config.yaml``'s defaults list and the option each chooses (None for null)."""
    return {k: v for entry in top.get("defaults", []) if isinstance(entry, dict)
            for k, v in entry.items() if not k.startswith("override ")}


def run_usage() -> str:
    """The ``--help`` text of ``tcbench run``: the header and footer of ``conf/config.yaml``'s
    ``hydra.help``, the options of every config group, and every key of
    :class:`~tcbench.runner.schema.JobConfig` with its default (the default task's and
    optimiser's keys as their option files give them)."""
    import yaml

    from tcbench.config_dir import CONFIG_NAME, conf_dir, group_options

    spec = by_config(CONFIG_NAME)
    assert spec is not None, "no command runs conf/config.yaml"
    schema, meanings = spec.schema_class(), spec.params
    root = conf_dir()
    top = yaml.safe_load((root / f"{CONFIG_NAME}.yaml").read_text(encoding="utf-8"))
    text = top["hydra"]["help"]
    groups = _group_defaults(top)
    options = {group: group_options(group) for group in sorted(groups)}
    rows: list[tuple[str, str]] = []
    for key, default in parameters(schema):
        if key in groups:
            choice = groups[key]
            rows.append((f"{key}={_shown(choice)}", meanings[key]))
            if choice is not None:
                values = yaml.safe_load((root / key / f"{choice}.yaml").read_text(encoding="utf-8")) or {}
                rows += [(f"  {key}.{k}={_shown(v)}", "") for k, v in values.items() if k not in {"name", "defaults"}]
        else:
            value = top.get(key, default) if "." not in key else \
                (top.get(key.split(".")[0]) or {}).get(key.split(".", 1)[1], default)
            rows.append((f"{key}={_shown(value)}", meanings.get(key, "")))
    keys = dict(parameters(schema))
    rows += [(f"{g}={_shown(choice)}", meanings.get(g, "")) for g, choice in groups.items() if g not in keys]
    width = max(len(left) for left, meaning in rows if meaning) + 2
    lines = [text["header"].rstrip(), "", "== Configuration groups ==",
             "Compose your configuration from those groups (group=option)", "",
             *(f"{group}: {', '.join(names)}" for group, names in options.items()), "",
             "parameters (key=value, default after =; `tcbench run task=sphere --cfg job` prints a choice's):",
             *(f"  {left:{width}s}{meaning}".rstrip() for left, meaning in rows), "",
             text["footer"].rstrip()]
    return "\n".join(lines)
