"""Gyro temperature-drift compensation: VMD, sample-entropy mode classes, TFPF and a learner."""

from tcbench.compensation.gyro.pipeline import (
    ModeClasses,
    ParallelPipeline,
    PipelineConfig,
    PipelineOutput,
    classify_modes,
)

__all__ = ["ModeClasses", "ParallelPipeline", "PipelineConfig", "PipelineOutput", "classify_modes"]
