"""Gymnasium ids of tcbench's tasks, kept apart from the env classes so that registering them
(on ``import tcbench``) imports no simulator, learner or signal-processing code."""

from __future__ import annotations

ENV_VERSION = "v0"
BBOB_ID = "tcbench/BBOB-v0"
GYRO_DRIFTNOISE_ID = "tcbench/Gyro-DriftNoise-v0"
GYRO_VMDTUNING_ID = "tcbench/Gyro-VMDTuning-v0"
GYRO_ENV_IDS = {"gyro_driftnoise": GYRO_DRIFTNOISE_ID, "gyro_vmdtuning": GYRO_VMDTUNING_ID}
ACCEL_CHAMBER_ID = "tcbench/Accel-Chamber-v0"
MSRA_ENV_IDS = {"msra_zerobias": "tcbench/MSRA-ZeroBias-v0", "msra_fulltemp": "tcbench/MSRA-FullTemp-v0"}


def env_id(function_key: str) -> str:
    """Gymnasium id of a function task, e.g. ``tcbench/Rastrigin-v0``."""
    return f"tcbench/{function_key.capitalize()}-{ENV_VERSION}"
