"""Learners (BP, Elman, polynomial baseline) behind one interface, and their registry."""

from tcbench.learners.base import FitHistory, Learner, LearnerParams, Scaler
from tcbench.learners.registry import (
    UnknownLearnerError,
    available,
    create,
    get,
    register,
)

__all__ = [
    "FitHistory",
    "Learner",
    "LearnerParams",
    "Scaler",
    "UnknownLearnerError",
    "available",
    "create",
    "get",
    "register",
]
