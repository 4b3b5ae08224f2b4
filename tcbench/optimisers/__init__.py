"""Optimisers on the ask/tell protocol and their entry-point registry."""

from tcbench.optimisers.protocol import Best, Optimiser, OptimiserParams, ProtocolError
from tcbench.optimisers.registry import UnknownOptimiserError, available, create, get, register

__all__ = [
    "Best",
    "Optimiser",
    "OptimiserParams",
    "ProtocolError",
    "UnknownOptimiserError",
    "available",
    "create",
    "get",
    "register",
]
