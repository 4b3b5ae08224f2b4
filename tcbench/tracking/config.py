"""The ``tracking`` group of a config (where and how runs are recorded in MLflow): a leaf module, so
that the sensor commands share it without importing the job config and everything it checks."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class TrackingConfig:
    """Where and how runs are recorded in MLflow."""

    enabled: bool = True
    uri: str | None = None  # None: $MLFLOW_TRACKING_URI, else sqlite:///mlflow.db in the cwd
    experiment: str = "tcbench"
    sweep_id: str | None = None  # None: derived from the multirun sweep directory
    plots: bool | None = None  # None: for single runs and compensation runs, not optimisation sweeps
    resume: bool = False  # skip jobs whose config and seed already FINISHED in this experiment
    ioh_dir: str | None = None  # also write each run in IOHprofiler's format under this folder
