"""Config schemas of the task kinds: the keys a ``task:`` config may hold, with their types and
defaults (checked by :func:`tcbench.runner.config.checked_task`)."""

from __future__ import annotations

from dataclasses import dataclass

MISSING = "???"  # omegaconf.MISSING, without importing omegaconf on `import tcbench`


@dataclass
class TaskConfig:
    """Which function task to solve and how (see :class:`tcbench.tasks.FunctionEnv`)."""

    name: str = MISSING
    dim: int = 2
    shift: bool = False
    target_precision: float = 1e-8
    lower: float | None = None
    upper: float | None = None


@dataclass
class BBOBTaskConfig:
    """A BBOB function from ioh (see :class:`tcbench.tasks.bbob_env.BBOBEnv`)."""

    name: str = MISSING
    function: int = 1
    dim: int = 5
    instance: int = 1
    target_precision: float = 1e-8
    stop_at_target: bool = True


@dataclass
class MSRATaskConfig:
    """An MSRA compensation task (see :class:`tcbench.tasks.MSRACompensationEnv`)."""

    name: str = MISSING
    device_seed: int = 0
    recordings_seed: int | None = None  # restart i on draw i
    n_train: int | None = None
    n_test: int | None = None
    train_files: list | None = None
    test_files: list | None = None
    train_on: str = "positions"
    rate_window_s: float = 120.0
    bias_form: str = "plus"
    split: str = "next_run"
    clamp_inputs: bool = True


@dataclass
class GyroTuningTaskConfig:
    """VMD tuning on a gyro oven record (see :class:`tcbench.tasks.GyroVMDTuningEnv`)."""

    name: str = MISSING
    device_seed: int = 0
    recordings_seed: int = 0
    train_files: list | None = None
    sample_rate_hz: float = 10.0
    hold_s: float = 3600.0
    tuning_samples: int = 2048
    effects: dict | None = None


@dataclass
class GyroTaskConfig(GyroTuningTaskConfig):
    """The gyro drift/noise task (see :class:`tcbench.tasks.GyroDriftNoiseEnv`); ``tuner``,
    ``tuner_params`` and ``tuning_budget`` set the multi-objective search of VMD's ``[k, alpha]``
    when they are null."""

    recordings_seed: int | None = None  # restart i on draw i
    n_train: int = 1
    n_test: int = 1
    split: str = "next_run"
    test_files: list | None = None
    decomposition: str = "vmd"
    k: int | None = None
    alpha: float | None = None
    tuner: str = "mopso"
    tuner_params: dict | None = None
    tuning_budget: int = 440
    denoise: str = "tfpf"
    tfpf_window: int = 31
    wavelet_level: int | None = None
    noise_above: float = 0.5
    drift_below: float = 0.15
    inputs: str = "t_rate"
    rate_window_s: float = 120.0
    learner_block_s: float = 10.0
    bandwidth_amplitude_dps: float = 0.005
