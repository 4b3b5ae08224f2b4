"""The Hydra applications behind tcbench's commands (``tcbench run`` on ``conf/config.yaml``, the
others on ``conf/<command>.yaml``: each spec's ``config`` in :mod:`tcbench.commands.registry`)
and the checks made before any job starts. Every job of every command runs through :func:`tcbench.runner.job.run_job`."""

from __future__ import annotations

import dataclasses
import itertools
import logging
import math
import os
import re
import shutil
import typing
from decimal import Decimal
from pathlib import Path
from dataclasses import dataclass
from typing import Any

import hydra
from hydra import compose, initialize_config_module
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import ChoiceSweep, Override, RangeSweep
from hydra.errors import HydraException, MissingConfigException
from omegaconf import DictConfig
from omegaconf.errors import ConfigAttributeError, ConfigKeyError, OmegaConfBaseException

from tcbench.cli.flags import VALUE_FLAGS
from tcbench.commands import schemas as command_schemas
from tcbench.commands.registry import by_config
from tcbench.config_dir import CONFIG_MODULE, CONFIG_NAME, SEARCH_PATH, conf_dir
from tcbench.errors import ConfigError, did_you_mean, unknown_name
from tcbench.runner.schema import as_dict, register_schema

SLURM_LAUNCHER = "hydra_plugins.hydra_submitit_launcher.submitit_launcher.SlurmLauncher"
SLURM_COMMANDS = ("sbatch", "srun")  # submitit submits with sbatch, and refuses to start without srun
GROUPED_LAUNCHER = "hydra_plugins.tcbench_launcher.launcher.GroupedLauncher"
JOBLIB_LAUNCHER = "hydra_plugins.hydra_joblib_launcher.joblib_launcher.JoblibLauncher"
MAX_JOBS = 100_000  # the most jobs one command line may sweep, unless $TCBENCH_MAX_JOBS says otherwise
MAX_JOBS_ENV = "TCBENCH_MAX_JOBS"
log = logging.getLogger(__name__)

register_schema()
command_schemas.register()


def _task(cfg: DictConfig) -> None:
    """Hydra task function: one job per call."""
    from tcbench.runner.job import run_job

    run_job(cfg)


def hydra_app(config_name: str = CONFIG_NAME) -> Any:
    """The Hydra application of a primary config (``config`` for ``tcbench run``, ``simulate`` ...)."""
    return hydra.main(version_base="1.3", config_path=SEARCH_PATH, config_name=config_name)(_task)


hydra_main = hydra_app(CONFIG_NAME)


@dataclass
class Plan:
    """What a ``tcbench run`` command line will do, known before any job starts."""

    jobs: int
    tracking_enabled: bool
    resume: bool
    tracking_uri: str | None
    experiment: str
    sweep_id: str
    outs: tuple[str | None, ...] = ()  # each job's out= (None: a job without one)
    swept: tuple[str, ...] = ()  # the keys and groups the sweep varies (the config's own params included)


def sweep_dir(outs: tuple[str | None, ...]) -> str | None:
    """Where Hydra's record of a sweep goes (its ``multirun.yaml`` and each job's ``.hydra/``
    folder): ``multirun/<date>/<time>`` in the folder every job's ``out=`` lies under
    (``out=cal/${stem:recording}``: ``cal/multirun/...``), as an override value; None when a job
    has no ``out=`` or the outputs share no folder but the file system's root (Hydra's default,
    ``multirun/`` in the working folder, then)."""
    from tcbench.commands.schemas import literal

    if not outs or any(not o for o in outs):
        return None
    common = Path(os.path.commonpath([os.path.abspath(str(o)) for o in outs]))
    if common == Path(common.anchor):
        return None
    cwd = Path.cwd()
    shown = common.relative_to(cwd) if common.is_relative_to(cwd) else common
    return hydra_string(literal(str(shown / "multirun")) + "/${now:%Y-%m-%d}/${now:%H-%M-%S}")


def hydra_string(value: str) -> str:
    """``value`` as one quoted string of Hydra's override grammar (backslashes are doubled only
    where they precede a quote or the closing quote, as the grammar reads them)."""
    return "'" + re.sub(r"(\\*)('|$)", lambda m: m.group(1) * 2 + ("\\'" if m.group(2) else ""), value) + "'"


def claim_outputs(paths: list[Path], written: dict[Path, int], job: int) -> None:
    """Record that job ``job`` (0-based) writes ``paths``; ConfigError when an earlier job of the
    sweep writes one of them."""
    for path in paths:
        key = Path(os.path.abspath(path))
        if key in written:
            raise ConfigError(f"jobs {written[key] + 1} and {job + 1} of the sweep would both write "
                              f"{path}; give each its own out=, named after what the sweep varies (e.g. "
                              "'out=results/${stem:recording}', 'out=lb/${experiments}', 'out=cal/${seed}')")
        written[key] = job


def _known_options(group: str) -> list[str]:
    return sorted(p.stem for p in (conf_dir() / group).glob("*.yaml"))


def _no_such_key(key: str, known: Any) -> str:
    """The line for an unknown key, with the known key of the same parent it probably meant."""
    head, _, leaf = key.rpartition(".")
    meant = did_you_mean(leaf, known)
    return f"{key}: no such config key" + (f"; did you mean {'.'.join(p for p in (head, meant) if p)!r}?"
                                           if meant else "")


def _schema_keys(config_name: str) -> list[str]:
    """The top-level keys of a primary config's schema."""
    schema = _schema(config_name)
    return [f.name for f in dataclasses.fields(schema)] if schema is not None else []


def _explain(exc: Exception, config_name: str = CONFIG_NAME) -> str:
    """One line for a Hydra/OmegaConf composition error of the primary config ``config_name``
    (an unknown key or option with the known one it probably meant)."""
    if isinstance(exc, MissingConfigException) and exc.missing_cfg_file and "/" in exc.missing_cfg_file:
        group, name = exc.missing_cfg_file.split("/", 1)
        from tcbench.plugins import group_aliases

        options = exc.options or _known_options(group)
        return unknown_name(group, name, options, aliases=group_aliases(f"tcbench.{group}s"))
    cause = exc.__cause__
    if isinstance(cause, OmegaConfBaseException):
        key = str(getattr(cause, "full_key", None) or "config")
        if isinstance(cause, ConfigAttributeError | ConfigKeyError):
            parent = cause.parent_node
            return _no_such_key(key, [k for k in parent if k != "hydra" or key.startswith("hydra.")]
                                if parent is not None else [])
        return f"{key}: {str(cause).strip().splitlines()[0]}"
    text = str(exc).strip()
    if unmatched := re.match(r"Could not override '([^']+)'\. No match in the defaults list", text):  # a group's name
        return _no_such_key(unmatched[1], _schema_keys(config_name))
    return text.splitlines()[0] if text else type(exc).__name__


def _schema(config_name: str) -> type | None:
    """The structured schema of a primary config (``config``: ``tcbench run``'s job), or None
    for a config no command runs."""
    spec = by_config(config_name)
    return spec.schema_class() if spec is not None else None


def _plain_type(annotation: Any) -> Any:
    """``X`` of ``X | None``; the annotation itself otherwise."""
    args = [a for a in typing.get_args(annotation) if a is not type(None)]
    return args[0] if len(args) == 1 and type(None) in typing.get_args(annotation) else annotation


def _field_type(schema: type | None, key: str) -> Any:
    """The annotation of the dotted ``key`` in a dataclass schema (``tracking.resume``: bool), or
    None where the key is not a field of a dataclass (a free-form dict's, or unknown)."""
    for part in key.split("."):
        if schema is None or not dataclasses.is_dataclass(schema):
            return None
        hints = typing.get_type_hints(schema)
        if part not in hints:
            return None
        annotation = hints[part]
        schema = _plain_type(annotation)
    return annotation


def _searchpath_problem(value: Any) -> str | None:
    """Why a ``hydra.searchpath`` value names a folder that is not there, or None."""
    for entry in value if isinstance(value, list) else [value]:
        entry = str(entry)
        if "${" in entry:
            continue
        path = entry[len("file://"):] if entry.startswith("file://") else None if "://" in entry else entry
        if path is not None and not Path(path).is_dir():
            return f"no folder {path!r} (the entry {entry!r})"
    return None


def check_override_values(overrides: list[str], config_name: str = CONFIG_NAME) -> None:
    """ConfigError naming the key and value of an override the composition would take but should
    not: a number for a true/false key (``tracking.resume=1``), a ``hydra.searchpath`` folder
    that is not there, an empty ``out=``. What does not parse is left to the composition."""
    try:
        parsed = OverridesParser.create().parse_overrides(overrides)
    except HydraException:
        return
    schema = _schema(config_name)
    for o in parsed:
        if o.is_delete() or o.is_sweep_override():
            continue
        key, value = o.key_or_group, o.value()
        given = o.input_line.lstrip("+")
        if isinstance(value, str) and "${" in value:
            continue  # an interpolation: resolved, and its value checked, with the config
        if key == "hydra.searchpath" and (problem := _searchpath_problem(value)):
            raise ConfigError(f"{given}: {problem}")
        if key == "out" and isinstance(value, str) and not value.strip():
            raise ConfigError(f"{given}: give a folder (out=. for the working directory)")
        if _plain_type(_field_type(schema, key)) is bool and isinstance(value, int | float) and \
                not isinstance(value, bool):  # OmegaConf would take 1 as true (a word it checks itself)
            raise ConfigError(f"{given}: expected true or false")


def _unknown_key(cfg: DictConfig, schema: type, prefix: str = "") -> str | None:
    """The first key of a composed config its dataclass schema does not have (``+unknown_key=1``
    adds one), searched into the fields that are dataclasses themselves; None if all are known."""
    hints = typing.get_type_hints(schema)
    for key in cfg:
        name = str(key)
        if not prefix and name == "hydra":
            continue
        if name not in hints:
            return prefix + name
        sub = _plain_type(hints[name])
        node = cfg._get_node(name)
        if dataclasses.is_dataclass(sub) and isinstance(node, DictConfig) and not node._is_none():
            if found := _unknown_key(node, sub, f"{prefix}{name}."):
                return found
    return None


def compose_job(overrides: list[str], config_name: str = CONFIG_NAME, hydra_cfg: bool = False) -> DictConfig:
    """The composed config of one job (call inside ``initialize_config_module``); ConfigError
    with one line when it does not compose, an override's value would be taken wrongly
    (:func:`check_override_values`), or it adds a key the schema does not have."""
    check_override_values(overrides, config_name)
    try:
        cfg = compose(config_name, overrides=overrides, return_hydra_config=hydra_cfg)
    except (HydraException, OmegaConfBaseException, ValueError) as exc:
        raise ConfigError(_explain(exc, config_name)) from None
    schema = _schema(config_name)
    if schema is not None and (unknown := _unknown_key(cfg, schema)):
        parent = unknown.rpartition(".")[0]
        known = list(typing.get_type_hints(_plain_type(_field_type(schema, parent)) if parent else schema))
        raise ConfigError(_no_such_key(unknown, known))
    return cfg


def _override_positions(args: list[str]) -> list[int]:
    """Indices of the ``key=value`` (or ``~key``) overrides in a Hydra command line: not flags,
    not the value of a flag (``-cn NAME``, ``--cfg job``, ``--info defaults``)."""
    out, skip = [], False
    for i, a in enumerate(args):
        if skip:
            skip = False
        elif a in VALUE_FLAGS:
            skip = True
        elif not a.startswith("-") and ("=" in a or a.startswith("~")):
            out.append(i)
    return out


def overrides_of(args: list[str]) -> list[str]:
    """The ``key=value`` overrides of a Hydra command line (flags and their values dropped)."""
    return [args[i] for i in _override_positions(args)]


def with_overrides(args: list[str], extra: list[str]) -> list[str]:
    """``args`` with the overrides ``extra`` placed right after the user's last override (or at
    the end): Hydra's parser takes one run of overrides, so ``task=sphere --help x=1`` would
    reject ``x=1`` as an unrecognised argument."""
    positions = _override_positions(args)
    at = positions[-1] + 1 if positions else len(args)
    return [*args[:at], *extra, *args[at:]]


def check_job(cfg: DictConfig | dict[str, Any], written: dict[Path, int] | None = None) -> dict[str, Any]:
    """A composed job config, checked by its kind before anything runs (:meth:`JobKind.plan_check`);
    the plain config. ``written`` collects the outputs of a sweep's jobs: a second job writing
    the same file or folder is a ConfigError."""
    from tcbench.commands.inputs import check_inputs_exist
    from tcbench.runner.kinds import kind_of

    c = as_dict(cfg)
    check_inputs_exist(c)  # named before the readers of the inputs are imported
    kind = kind_of(c)
    kind.plan_check(kind.prepare(c))
    if written is not None:
        claim_outputs(kind.outputs(c), written, len(set(written.values())))
    return c


def check_launcher(launcher: Any) -> None:
    """A ConfigError when the sweep's launcher (``hydra.launcher`` of the composed config) cannot
    run here: no worker process (``n_jobs`` below 1), or submitit's SLURM launcher on a machine
    without SLURM's commands."""
    if launcher is None:
        return
    target, n_jobs = launcher.get("_target_"), launcher.get("n_jobs")
    if target == GROUPED_LAUNCHER and n_jobs is not None and (isinstance(n_jobs, bool) or not isinstance(n_jobs, int)
                                                             or n_jobs < 1):
        raise ConfigError(f"hydra.launcher.n_jobs={n_jobs}: must be a positive whole number of worker processes "
                          "(1 runs the jobs in this process)")
    if target == JOBLIB_LAUNCHER and n_jobs == 0:
        raise ConfigError("hydra.launcher.n_jobs=0: joblib needs a number of processes (-1: one per core)")
    if target != SLURM_LAUNCHER:
        return
    if missing := [c for c in SLURM_COMMANDS if shutil.which(c) is None]:
        raise ConfigError(f"hydra/launcher=submitit_slurm needs SLURM, but {' and '.join(missing)} "
                          f"{'is' if len(missing) == 1 else 'are'} not on PATH here: run the sweep on a SLURM "
                          "login node, or here with hydra/launcher=submitit_local, hydra/launcher=joblib or "
                          "tcbench's launcher (hydra.launcher.n_jobs=2)")


def max_jobs() -> int:
    """The most jobs one command line may sweep: ``$TCBENCH_MAX_JOBS``, else :data:`MAX_JOBS`."""
    given = os.environ.get(MAX_JOBS_ENV, "").strip()
    if not given:
        return MAX_JOBS
    if not given.isdigit() or int(given) < 1:
        raise ConfigError(f"${MAX_JOBS_ENV} must be a positive whole number of jobs, got {given!r}")
    return int(given)


def sweep_length(override: Override) -> int:
    """How many values a sweep override gives, counted without listing them (a ``range()``'s
    length is computed); a ConfigError for a range of step 0 or a sweep of no value."""
    value = override.value()
    if isinstance(value, RangeSweep):
        if not value.step:
            raise ConfigError(f"{override.input_line}: a range's step must not be 0")
        values = value.range()
        if isinstance(values, range):
            n = len(values)
        else:  # Hydra's float range: start, start + step, ... while short of stop
            n = max(0, math.ceil((Decimal(values.stop) - Decimal(values.start)) / Decimal(values.step)))
    elif isinstance(value, ChoiceSweep):
        n = len(value.list)
    elif isinstance(value, list):
        n = len(value)
    else:
        try:
            n = sum(1 for _ in override.sweep_string_iterator())
        except HydraException as exc:
            raise ConfigError(f"{override.input_line}: {str(exc).strip().splitlines()[0]}") from None
    if n == 0:
        raise ConfigError(f"{override.input_line}: the sweep has no value; give at least one")
    return n


def check_sweep_size(lengths: dict[str, int]) -> int:
    """The number of jobs of a sweep, the product of its keys' numbers of values; a ConfigError
    with the count when it is more than :func:`max_jobs`."""
    jobs = math.prod(lengths.values())
    limit = max_jobs()
    if jobs > limit:
        parts = " × ".join(f"{n} {key}" for key, n in lengths.items())
        raise ConfigError(f"a sweep of {jobs} jobs ({parts}) is more than the {limit} one command line may run; "
                          f"split it into smaller sweeps (or set ${MAX_JOBS_ENV})")
    return jobs


def _parsed(args: list[str]) -> list[Override]:
    try:
        return OverridesParser.create().parse_overrides(overrides_of(args))
    except HydraException as exc:
        raise ConfigError(_explain(exc)) from None


def check_command_line_size(args: list[str]) -> int:
    """The number of jobs the sweeps of a command line give, counted from its overrides alone
    (no config composed); a ConfigError for an empty sweep or one over :func:`max_jobs`."""
    return check_sweep_size({o.get_key_element(): sweep_length(o) for o in _parsed(args) if o.is_sweep_override()})


def _sweep(args: list[str], config_name: str) -> tuple[list[str], dict[str, list[str]], Any]:
    """The fixed overrides of a command line, its swept keys with their values (the config's
    own ``hydra.sweeper.params`` included, the command line winning) and, with ``-m``, the
    ``hydra.launcher`` config that will run them; call inside ``initialize_config_module``. The
    jobs are counted before any value is listed (:func:`check_sweep_size`)."""
    multirun = "-m" in args or "--multirun" in args
    parser = OverridesParser.create()
    parsed = _parsed(args)
    fixed = [o.input_line for o in parsed if not o.is_sweep_override()]
    swept = {o.get_key_element(): o for o in parsed if o.is_sweep_override()}
    if swept and not multirun:
        key = next(iter(swept))
        raise ConfigError(f"{key} has several values; add -m (--multirun) to sweep over them")
    lengths = {key: sweep_length(o) for key, o in swept.items()}
    check_sweep_size(lengths)
    launcher = None
    if multirun:
        first = [f"{k}={next(iter(o.sweep_string_iterator()))}" for k, o in swept.items()]
        base = compose_job(fixed + first, config_name, hydra_cfg=True)
        given = {o.get_key_element() for o in parsed}  # the command line wins over the config's params
        for key, value in (base.hydra.sweeper.get("params") or {}).items():
            if key not in given:
                (o,) = parser.parse_overrides([f"{key}={value}"])
                swept[key] = o
                lengths[key] = sweep_length(o) if o.is_sweep_override() else 1
        check_sweep_size(lengths)
        launcher = base.hydra.get("launcher")
    sweeps = {key: [str(v) for v in o.sweep_string_iterator()] if o.is_sweep_override() else [str(o.value())]
              for key, o in swept.items()}
    return fixed, sweeps, launcher


def expand(args: list[str], config_name: str) -> list[tuple[list[str], dict[str, Any]]]:
    """Every job of a command line, composed: its swept ``key=value`` and its plain config."""
    conf_dir()
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        fixed, sweeps, _ = _sweep(args, config_name)  # run here in turn, not on the launcher
        keys = list(sweeps)
        jobs = []
        for combo in itertools.product(*sweeps.values()):
            chosen = [f"{k}={v}" for k, v in zip(keys, combo, strict=True)]
            jobs.append((chosen, as_dict(compose_job(fixed + chosen, config_name))))
    return jobs


def plan(args: list[str], config_name: str = CONFIG_NAME) -> Plan:
    """Compose and check every job of a command line; raise ConfigError (or the kind's one-line
    error) on the first bad one."""
    from tcbench.runner.kinds import kind_of

    conf_dir()  # one line naming the problem when the installed configs are missing
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        fixed, sweeps, launcher = _sweep(args, config_name)
        check_launcher(launcher)
        seeds = sweeps.pop("seed", None)
        keys = list(sweeps)
        combos = list(itertools.product(*sweeps.values())) or [()]
        last: dict[str, Any] = {}
        written: dict[Path, int] = {}
        outs: list[str | None] = []
        for combo in combos:
            chosen = fixed + [f"{k}={v}" for k, v in zip(keys, combo, strict=True)]
            cfg = compose_job(chosen, config_name)
            if not seeds:
                last = check_job(cfg, written)
                outs.append(last.get("out"))
                continue
            last = check_job(cfg)
            outs.append(last.get("out"))
            if kind_of(last).outputs(last):  # a kind that writes files: each seed's own (out=x/${seed})
                for s in seeds:
                    outs.append(check_job(compose_job([*chosen, f"seed={s}"], config_name), written).get("out"))
        for s in seeds or []:
            if not s.lstrip("-").isdigit() or int(s) < 0:
                raise ConfigError(f"seed must be a non-negative integer, got {s!r}")
    jobs = len(combos) * (len(seeds) if seeds else 1)
    track = last["tracking"]
    return Plan(jobs, track["enabled"], track["resume"], track.get("uri"), track["experiment"],
                str(track["sweep_id"]), tuple(outs), (*keys, *(["seed"] if seeds else [])))


def deferred_to_the_jobs(args: list[str], swept: tuple[str, ...]) -> list[str]:
    """``args`` with every plain override of a key inside a swept config group (``task.split=replay``
    beside ``task=msra_zerobias,msra_fulltemp``) given as a sweep of its one value
    (``task.split=choice(replay)``). Hydra composes a multirun's config once before it sweeps, with
    the group at its default (``task: rastrigin``), where the key may not exist ("Could not override
    'task.split'"); a sweep's value is set in each job's config, where the group's choice holds it.
    The jobs are the same."""
    groups = {key for key in swept if "." not in key}
    parser = OverridesParser.create()
    out = list(args)
    for i in _override_positions(args):
        key, eq, value = args[i].partition("=")
        if not (eq and "." in key and key.split(".", 1)[0] in groups and "${" not in value):
            continue
        (o,) = parser.parse_overrides([args[i]])
        if o.is_sweep_override() or o.is_delete() or o.value() is None:  # choice() takes no null
            continue
        out[i] = f"{key}=choice({value})"
    return out

