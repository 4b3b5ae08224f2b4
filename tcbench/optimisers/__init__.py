"""Optimisers on the ask/tell protocol and their entry-point registry."""

from tcbench.optimisers.protocol import Best, Optimiser, OptimiserParams, ParetoSet, ProtocolError
from tcbench.optimisers.registry import UnknownOptimiserError, available, create, get, register

__all__ = [
    "Best",
    "Optimiser",
    "OptimiserParams",
    "ParetoSet",
    "ProtocolError",
    "UnknownOptimiserError",
    "available",
    "create",
    "get",
    "register",
]
