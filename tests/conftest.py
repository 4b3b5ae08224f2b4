"""Shared fixtures: every test that touches MLflow or Hydra works in its own directory."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("MLFLOW_DISABLE_TELEMETRY", "true")


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """Run in an empty directory with no tracking server configured."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    return tmp_path
