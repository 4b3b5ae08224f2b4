"""The one line each failure to write a command's outputs becomes (:func:`tcbench.commands.errors.writing_errors`)."""

from __future__ import annotations

import errno
from pathlib import Path

import pytest

from tcbench.commands.errors import CommandError, writing_errors
from tcbench.sensors.recording import RecordingError
from tcbench.staging import InputOverwriteError


def _line(exc: Exception, **kwargs: object) -> str:
    with pytest.raises(CommandError) as caught, writing_errors("OUT", **kwargs):  # type: ignore[arg-type]
        raise exc
    assert caught.value.__cause__ is None and caught.value.__suppress_context__
    return str(caught.value)


def test_each_failure_is_its_command_s_line() -> None:
    over = InputOverwriteError(Path("OUT/a.csv"), Path("a.csv"))
    assert _line(over) == "the output OUT/a.csv would overwrite the input a.csv; choose another out= or name="
    assert _line(over, overwrite_hint="out=").endswith("; choose another out=")
    full = OSError(errno.ENOSPC, "No space left on device")
    assert _line(full, what="the report").startswith("out=OUT: cannot write the report (")
    assert _line(RecordingError("a.csv: row 3: time goes back"), said=(RecordingError,)) == \
        "a.csv: row 3: time goes back"


def test_what_is_not_said_passes_through() -> None:
    with pytest.raises(RecordingError), writing_errors("OUT"):
        raise RecordingError("not said here")
    with pytest.raises(CommandError, match="^already one line$"), writing_errors("OUT"):
        raise CommandError("already one line")
    with writing_errors("OUT"):
        pass
