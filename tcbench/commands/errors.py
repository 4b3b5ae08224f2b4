"""What the commands share: their one-line user error, reading a recording argument, and the
checks of their output folder, file names and tracking store, made before any work."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tcbench.errors import ConfigError
from tcbench.tracking.config import TrackingConfig


class CommandError(ConfigError):
    """A bad argument or input file of a command: reported in one line."""


def writable_folder(path: str | Path) -> Path:
    """``path`` (an ``out=`` argument) as an output folder, checked before any work: a
    :class:`CommandError` if it cannot be made or written."""
    from tcbench.outputs import folder_problem

    if problem := folder_problem(path):
        raise CommandError(f"out={path}: {problem}")
    return Path(path)


def cannot_write(out: str | Path, exc: OSError, what: str = "the recording") -> CommandError:
    """The one-line error for files that could not be written into ``out`` (a full disk, a
    read-only mount, a quota)."""
    from tcbench.outputs import write_problem

    return CommandError(f"out={out}: cannot write {what} ({write_problem(exc)})")


def file_stem(name: str, key: str = "name", suffix: str = "") -> str:
    """``name`` (the ``key=`` argument) checked as the stem of files written inside ``out=``,
    ``suffix`` the longest ending they get."""
    from tcbench.outputs import name_problem

    if problem := name_problem(name, suffix):
        raise CommandError(f"{key}={name!r}: {problem}")
    return name


def overwrite_error(exc: Any) -> CommandError:
    """The one-line error for output that would replace one of the command's inputs."""
    return CommandError(f"the output {exc.target} would overwrite the input {exc.source}; choose another out= "
                        "or name=")


def read_recording_arg(path: str | Path) -> Any:
    """The recording at ``path`` (a command's ``recording=``), read and validated; a
    :class:`CommandError` naming the file when it is malformed or cannot be read."""
    from tcbench.sensors.recording import RecordingError, read_recording

    try:
        return read_recording(path)
    except RecordingError as exc:
        raise CommandError(str(exc)) from None
    except OSError as exc:
        raise CommandError(f"{path}: cannot read the file ({exc.strerror or exc})") from None


def checked_store(track: TrackingConfig) -> None:
    """With tracking on: the experiment has a name and the store can be used, checked before any
    work and without making anything (:func:`tcbench.tracking.store.check_store`); a
    :class:`CommandError` otherwise."""
    if not track.enabled:
        return
    if not str(track.experiment or "").strip():
        raise CommandError("tracking.experiment: give the MLflow experiment a name, or tracking.enabled=false")
    from tcbench.tracking import checks

    try:
        checks.check_store(track.uri, create=True)  # made when the results are logged
    except checks.StoreError as exc:
        raise CommandError(str(exc)) from None
