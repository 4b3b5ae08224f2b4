"""Task kinds as specs: what a task *is*, in one place.

A :class:`TaskSpec` names a task's config name, gymnasium id and entry point, config schema,
the job kind that runs it (``optimisation`` or ``compensation``), its compensation protocol,
its leaderboard key and what ``tcbench list`` prints. Everything else (validation, the job
runner, the leaderboards, the sweep launcher, ``tcbench list``, gymnasium registration) asks
:func:`task_spec`, so a new task or sensor is one spec here plus its env module and config.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from tcbench.tasks.functions import FUNCTIONS
from tcbench.tasks.ids import ACCEL_CHAMBER_ID, BBOB_ID, GYRO_DRIFTNOISE_ID, GYRO_VMDTUNING_ID, MSRA_ENV_IDS, env_id
from tcbench.tasks.multiobjective import PROBLEMS
from tcbench.tasks.schemas import BBOBTaskConfig, GyroTaskConfig, GyroTuningTaskConfig, MSRATaskConfig, TaskConfig


class UnknownTaskError(KeyError):
    """A task name no spec has."""

    def __str__(self) -> str:
        return str(self.args[0])


def function_key(task: dict[str, Any]) -> str:
    """``rastrigin-2d``, ``rastrigin-10d-shifted``, ``sphere-2d-domain-1_1``."""
    key = f"{task['name']}-{task.get('dim', 2)}d"
    if task.get("shift"):
        key += "-shifted"
    if task.get("lower") is not None or task.get("upper") is not None:
        key += f"-domain{task.get('lower')}_{task.get('upper')}"
    return key


def bbob_key(task: dict[str, Any]) -> str:
    """``bbob-f03-5d``: BBOB function 3 in 5-D (its instances play the part of seeds)."""
    return f"bbob-f{task.get('function')!s:0>2}-{task.get('dim')}d"


def device_key(task: dict[str, Any]) -> str:
    """``msra_fulltemp-dev0``, whatever the draw of its runs (a board pairs every run with its limits on the
    run's own draw, :mod:`tcbench.leaderboard.paired`); ``-<effect>.<param>=<v>`` for
    changed effects; ``<task>-files-<hash>`` on the user's recordings, the hash of their content,
    training files then test files (:func:`tcbench.sensors.data_hash.content_hash`), so runs on
    other data never share a key). :class:`~tcbench.sensors.data_hash.DataHashError` when a file
    cannot be read."""
    if task.get("train_files"):
        from tcbench.sensors.data_hash import content_hash

        return f"{task['name']}-files-{content_hash(task['train_files'], task.get('test_files') or [])}"
    key = f"{task['name']}-dev{task.get('device_seed', 0)}"
    for effect, params in sorted((task.get("effects") or {}).items()):
        key += "-" + "-".join(f"{effect}.{p}={v:g}" for p, v in sorted(params.items()))
    return key


def gyro_pipeline(task: dict[str, Any]) -> str:
    """The front of a gyro method's name: ``MOVMD-TFPF`` (VMD tuned), ``VMD-TFPF``, ``EMD-WTD``,
    ``WTD`` ... from the task's decomposition and denoiser."""
    decomposition = task.get("decomposition", "vmd")
    tuned = task.get("k") is None or task.get("alpha") is None
    front = {"vmd": "MOVMD" if tuned else "VMD", "emd": "EMD", "none": ""}[decomposition]
    denoise = {"tfpf": "TFPF", "wavelet": "WTD", "none": ""}[task.get("denoise", "tfpf")]
    if denoise == "WTD" and task.get("wavelet_level") is not None:
        denoise += f"-L{task['wavelet_level']}"
    return "-".join(p for p in (front, denoise) if p)


@dataclass(frozen=True)
class TaskSpec:
    """One task: see the module docstring. ``key_arg`` is the keyword gymnasium passes the
    task's name as (``function=rastrigin``), None for none; ``sized`` tasks have a ``dim`` the
    memory check reads; ``pipeline`` (compensation) names the processing in front of a learner."""

    name: str
    gym_id: str
    entry_point: str
    schema: type
    job_kind: str
    summary: str
    key: Callable[[dict[str, Any]], str]
    key_arg: str | None = None
    protocol: str | None = None
    sized: bool = False
    multi_objective: bool = False
    pipeline: Callable[[dict[str, Any]], str] | None = None
    family: str = field(default="")

    @property
    def is_compensation(self) -> bool:
        return self.job_kind == "compensation"


def _specs() -> dict[str, TaskSpec]:
    out: dict[str, TaskSpec] = {}
    for key, fn in FUNCTIONS.items():
        out[key] = TaskSpec(key, env_id(key), "tcbench.tasks.function_env:FunctionEnv", TaskConfig, "optimisation",
                            f"{fn.title}, domain [{fn.lower:g}, {fn.upper:g}]^d, x*={fn.x_opt:g}", function_key,
                            key_arg="function", sized=True, family="single objective")
    out["bbob"] = TaskSpec("bbob", BBOB_ID, "tcbench.tasks.bbob_env:BBOBEnv", BBOBTaskConfig, "optimisation",
                           "COCO's 24 noiseless BBOB functions through ioh (task.function, task.dim, "
                           "task.instance), domain [-5, 5]^d", bbob_key, sized=True, family="single objective")
    from tcbench.tasks.mo_env import mo_env_id

    for key, p in PROBLEMS.items():
        out[key] = TaskSpec(key, mo_env_id(key), "tcbench.tasks.mo_env:MultiObjectiveEnv", TaskConfig, "optimisation",
                            f"{p.title}, {p.n_objectives} objectives, {p.default_dim} variables in "
                            f"[{p.lower:g}, {p.upper:g}]", function_key, key_arg="function", sized=True,
                            multi_objective=True, family="multi-objective")
    out["gyro_vmdtuning"] = TaskSpec(
        "gyro_vmdtuning", GYRO_VMDTUNING_ID, "tcbench.tasks.gyro_vmd_env:GyroVMDTuningEnv", GyroTuningTaskConfig,
        "optimisation", "VMD [k, alpha] against fuzzy and permutation entropy (2 objectives)", device_key,
        multi_objective=True, family="multi-objective")
    for key, eid in MSRA_ENV_IDS.items():
        full = "full" in key
        out[key] = TaskSpec(
            key, eid, "tcbench.tasks.msra_env:MSRACompensationEnv", MSRATaskConfig, "compensation",
            f"MSRA {'four-position runs -40..60 °C' if full else 'zero-bias runs at room temperature'}",
            device_key, key_arg="task", protocol="fulltemp" if full else "roomtemp", family="compensation")
    out["accel_chamber"] = TaskSpec(
        "accel_chamber", ACCEL_CHAMBER_ID, "tcbench.tasks.msra_env:MSRACompensationEnv", MSRATaskConfig,
        "compensation", "accelerometer (g) at rest through chamber cycles 60 → −20 → 60 → 25 °C", device_key,
        key_arg="task", protocol="chamber", family="compensation")
    out["gyro_driftnoise"] = TaskSpec(
        "gyro_driftnoise", GYRO_DRIFTNOISE_ID, "tcbench.tasks.gyro_env:GyroDriftNoiseEnv", GyroTaskConfig,
        "compensation", "seed 001 parallel model on gyro oven runs (decomposition, denoiser, drift learner; "
        "bandwidth kept)", device_key, protocol="gyro", pipeline=gyro_pipeline, family="compensation")
    return out


TASKS: dict[str, TaskSpec] = _specs()


def task_spec(name: str) -> TaskSpec:
    """The spec of a task by its config name (case-insensitive); :class:`UnknownTaskError`
    naming the known ones otherwise."""
    spec = TASKS.get(str(name).lower())
    if spec is None:
        from tcbench.errors import unknown_name

        raise UnknownTaskError(unknown_name("task", name, sorted(TASKS)))
    return spec


def register_specs() -> None:
    """Register every task with gymnasium under its id (idempotent)."""
    import gymnasium as gym

    for spec in TASKS.values():
        if spec.gym_id not in gym.registry:
            gym.register(id=spec.gym_id, entry_point=spec.entry_point,
                         kwargs={spec.key_arg: spec.name} if spec.key_arg else {}, disable_env_checker=True)


def protocols() -> dict[str, str]:
    """Compensation protocol of every compensation task (``msra_fulltemp`` -> ``fulltemp``)."""
    return {name: str(s.protocol) for name, s in TASKS.items() if s.protocol}
