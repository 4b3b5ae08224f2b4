"""Differential evolution for tcbench (a plugin package)."""
