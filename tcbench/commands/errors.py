"""What the commands share: their one-line user error, reading a recording argument, and the
checks of their output folder, file names, output files and tracking store, made before any work."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
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


def overwrite_error(exc: Any, hint: str = "out= or name=") -> CommandError:
    """The one-line error for output that would replace one of the command's inputs (``hint``:
    what the user can change)."""
    return CommandError(f"the output {exc.target} would overwrite the input {exc.source}; choose another {hint}")


def refused_output(exc: Any, hint: str = "out=") -> CommandError:
    """The one-line error for output the staging refused (:class:`tcbench.staging.OutputRefusedError`):
    a link out of ``out=``, a file where a folder is, or existing files without ``overwrite=true``
    (``hint``: what else the user can change, ``out=`` or ``out= or name=``)."""
    from tcbench.staging import refusal_line

    return CommandError(refusal_line(exc, hint))


@contextlib.contextmanager
def writing_errors(out: str | Path, what: str = "the recording", hint: str = "out=",
                   overwrite_hint: str = "out= or name=",
                   said: tuple[type[Exception], ...] = ()) -> Iterator[None]:
    """Around the writing of a command's outputs into ``out``: each failure as its one-line
    :class:`CommandError`. Output over an input (:func:`overwrite_error`, ``overwrite_hint``),
    output the staging refused (:func:`refused_output`, ``hint``), files that cannot be written
    (:func:`cannot_write`, ``what``), and the errors ``said`` (their message is the line, e.g. a
    :class:`~tcbench.sensors.recording.RecordingError`)."""
    from tcbench.staging import InputOverwriteError, OutputRefusedError

    try:
        yield
    except said as exc:
        raise CommandError(str(exc)) from None
    except InputOverwriteError as exc:
        raise overwrite_error(exc, overwrite_hint) from None
    except OutputRefusedError as exc:
        raise refused_output(exc, hint) from None
    except OSError as exc:
        raise cannot_write(out, exc, what) from None


def free_outputs(out: str | Path, names: list[str], overwrite: bool, hint: str = "out=",
                 folders: list[str] | None = None) -> None:
    """The files ``names`` (and folders ``folders``) a command will write into ``out``, checked
    before any work as they will be when moved into place (:func:`tcbench.staging.check_targets`):
    a :class:`CommandError` when one exists without ``overwrite``, is a link out of ``out`` or
    is a folder where a file goes (or the reverse)."""
    from tcbench.staging import OutputRefusedError, check_targets

    entries = [(f, True) for f in folders or []] + [(n, False) for n in names]
    try:
        check_targets(out, sorted(entries), overwrite)
    except OutputRefusedError as exc:
        raise refused_output(exc, hint) from None


def say_replaced(replaced: list[Path]) -> None:
    """Print, in one line, the files an ``overwrite=true`` command replaced (none: nothing)."""
    from tcbench.staging import replaced_line

    if replaced:
        print(replaced_line(replaced))


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
