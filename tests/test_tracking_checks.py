"""A command checks its tracking store before any work without importing MLflow; the checks
stay reachable from :mod:`tcbench.tracking.store` as before."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tcbench.tracking import checks, store


def test_the_store_checks_import_no_mlflow(tmp_path: Path) -> None:
    code = ("import sys; from tcbench.tracking.checks import check_store; "
            f"print(check_store('sqlite:///{tmp_path / 'm.db'}', create=True)); "
            "print('mlflow' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == [f"sqlite:///{tmp_path / 'm.db'}", "False"]


def test_the_checks_are_the_store_s(tmp_path: Path) -> None:
    assert store.check_store is checks.check_store and store.StoreError is checks.StoreError
    (tmp_path / "folder.db").mkdir()
    with pytest.raises(store.StoreError, match="is a folder"):
        store.check_store(f"sqlite:///{tmp_path / 'folder.db'}", create=True)
    with pytest.raises(checks.StoreError, match="no tracking store"):
        checks.check_store(f"sqlite:///{tmp_path / 'none.db'}", create=False)
