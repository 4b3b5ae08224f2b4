"""The Hydra applications behind tcbench's commands (``tcbench run`` on ``conf/config.yaml``,
``tcbench simulate|metrics|import|diagnose|leaderboard|list|quickstart`` on ``conf/<command>.yaml``)
and the checks made before any job starts. Every job of every command runs through :func:`tcbench.runner.job.run_job`."""

from __future__ import annotations

import dataclasses
import itertools
import logging
import os
import re
import shutil
from pathlib import Path
from dataclasses import dataclass
from typing import Any

import hydra
from hydra import compose, initialize_config_module
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.errors import HydraException, MissingConfigException
from omegaconf import DictConfig
from omegaconf.errors import ConfigAttributeError, ConfigKeyError, OmegaConfBaseException

from tcbench.cli.flags import VALUE_FLAGS
from tcbench.commands import schemas as command_schemas
from tcbench.config_dir import CONFIG_MODULE, CONFIG_NAME, SEARCH_PATH, conf_dir
from tcbench.errors import ConfigError, did_you_mean
from tcbench.runner.schema import as_dict, register_schema

SLURM_LAUNCHER = "hydra_plugins.hydra_submitit_launcher.submitit_launcher.SlurmLauncher"
SLURM_COMMANDS = ("sbatch", "srun")  # submitit submits with sbatch, and refuses to start without srun
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
    from tcbench.runner.schema import JobConfig

    schema = JobConfig if config_name == CONFIG_NAME else command_schemas.SCHEMAS.get(config_name)
    return [f.name for f in dataclasses.fields(schema)] if schema is not None else []


def _explain(exc: Exception, config_name: str = CONFIG_NAME) -> str:
    """One line for a Hydra/OmegaConf composition error of the primary config ``config_name``
    (an unknown key or option with the known one it probably meant)."""
    if isinstance(exc, MissingConfigException) and exc.missing_cfg_file and "/" in exc.missing_cfg_file:
        group, name = exc.missing_cfg_file.split("/", 1)
        options = exc.options or _known_options(group)
        meant = did_you_mean(name, options)
        return f"unknown {group} {name!r}; known: {', '.join(options)}" + (f"; did you mean {meant!r}?"
                                                                              if meant else "")
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


def compose_job(overrides: list[str], config_name: str = CONFIG_NAME, hydra_cfg: bool = False) -> DictConfig:
    """The composed config of one job (call inside ``initialize_config_module``); ConfigError
    with one line when it does not compose."""
    try:
        return compose(config_name, overrides=overrides, return_hydra_config=hydra_cfg)
    except (HydraException, OmegaConfBaseException, ValueError) as exc:
        raise ConfigError(_explain(exc, config_name)) from None


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
    run here: submitit's SLURM launcher on a machine without SLURM's commands."""
    if launcher is None or launcher.get("_target_") != SLURM_LAUNCHER:
        return
    if missing := [c for c in SLURM_COMMANDS if shutil.which(c) is None]:
        raise ConfigError(f"hydra/launcher=submitit_slurm needs SLURM, but {' and '.join(missing)} "
                          f"{'is' if len(missing) == 1 else 'are'} not on PATH here: run the sweep on a SLURM "
                          "login node, or here with hydra/launcher=submitit_local, hydra/launcher=joblib or "
                          "tcbench's launcher (hydra.launcher.n_jobs=2)")


def _sweep(args: list[str], config_name: str) -> tuple[list[str], dict[str, list[str]], Any]:
    """The fixed overrides of a command line, its swept keys with their values (the config's
    own ``hydra.sweeper.params`` included, the command line winning) and, with ``-m``, the
    ``hydra.launcher`` config that will run them; call inside ``initialize_config_module``."""
    multirun = "-m" in args or "--multirun" in args
    parser = OverridesParser.create()
    try:
        parsed = parser.parse_overrides(overrides_of(args))
    except HydraException as exc:
        raise ConfigError(_explain(exc)) from None
    fixed = [o.input_line for o in parsed if not o.is_sweep_override()]
    sweeps = {o.get_key_element(): list(o.sweep_string_iterator()) for o in parsed if o.is_sweep_override()}
    if sweeps and not multirun:
        key = next(iter(sweeps))
        raise ConfigError(f"{key} has several values; add -m (--multirun) to sweep over them")
    launcher = None
    if multirun:
        first = [f"{k}={v[0]}" for k, v in sweeps.items()]
        base = compose_job(fixed + first, config_name, hydra_cfg=True)
        given = {o.get_key_element() for o in parsed}  # the command line wins over the config's params
        for key, value in (base.hydra.sweeper.get("params") or {}).items():
            if key not in given:
                (o,) = parser.parse_overrides([f"{key}={value}"])
                vals = list(o.sweep_string_iterator()) if o.is_sweep_override() else [o.value()]
                sweeps[key] = [str(v) for v in vals]
        launcher = base.hydra.get("launcher")
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
        for combo in combos:
            chosen = fixed + [f"{k}={v}" for k, v in zip(keys, combo, strict=True)]
            cfg = compose_job(chosen, config_name)
            if not seeds:
                last = check_job(cfg, written)
                continue
            last = check_job(cfg)
            if kind_of(last).outputs(last):  # a kind that writes files: each seed's own (out=x/${seed})
                for s in seeds:
                    check_job(compose_job([*chosen, f"seed={s}"], config_name), written)
        for s in seeds or []:
            if not s.lstrip("-").isdigit() or int(s) < 0:
                raise ConfigError(f"seed must be a non-negative integer, got {s!r}")
    jobs = len(combos) * (len(seeds) if seeds else 1)
    track = last["tracking"]
    return Plan(jobs, track["enabled"], track["resume"], track.get("uri"), track["experiment"],
                str(track["sweep_id"]))

