"""Ask/tell over a callback-style optimiser: the library runs in a worker thread.

Libraries such as ``scipy.optimize`` call the objective themselves (``minimise(f, ...)``), while
tcbench's optimisers never evaluate anything: the caller asks for points and tells their values.
:class:`InvertedRun` turns one into the other without touching the library's algorithm:

- the library call runs in a daemon worker thread, started lazily by the first :meth:`ask`;
- the objective it receives (``evaluate``) posts the requested batch of points to the main thread
  and blocks until :meth:`tell` hands back their values; the two threads never run at once, so
  the library's random draws, and hence the points asked, depend only on its seed;
- :meth:`tell` waits for the worker's next message, so once it returns the run knows whether the
  library wants more points, has returned by itself (:attr:`finished`) or has failed;
- an exception raised by the library is re-raised in the main thread by the next :meth:`ask`;
- :meth:`close` (or garbage collection of the :class:`InvertedRun`, i.e. an abandoned run) makes
  the blocked objective raise a private ``BaseException`` that unwinds the library inside the
  worker, which then ends. The worker holds only the two queues, never the run or its owner, so
  an abandoned optimiser can be collected while its worker is blocked.
"""

from __future__ import annotations

import queue
import threading
import weakref
from collections.abc import Callable
from typing import Any

import numpy as np

Evaluate = Callable[[np.ndarray], np.ndarray]
"""Objective handed to the library: points ``(k, d)`` -> values ``(k,)``."""

JOIN_TIMEOUT = 10.0  # seconds to wait for a stopped worker to unwind the library


class _Stop(BaseException):
    """Raised by the objective inside the worker to unwind the library when the run is stopped.

    A ``BaseException`` (like ``GeneratorExit``), so that no ``except Exception`` in the library
    can swallow it."""


_STOP = object()  # sent to the worker instead of values


class _Channel:
    """The worker's only link to the main thread: one queue each way and a stop flag."""

    def __init__(self) -> None:
        self.requests: queue.SimpleQueue[tuple[str, Any]] = queue.SimpleQueue()  # worker -> main
        self.replies: queue.SimpleQueue[Any] = queue.SimpleQueue()  # main -> worker
        self.stopping = threading.Event()

    def evaluate(self, points: np.ndarray) -> np.ndarray:
        """The objective, called by the library in the worker: post the points and wait for
        their values (or for the order to stop)."""
        if self.stopping.is_set():
            raise _Stop
        batch = np.array(points, dtype=np.float64, ndmin=2)
        self.requests.put(("points", batch))
        reply = self.replies.get()
        if reply is _STOP:
            raise _Stop
        return reply

    def stop(self) -> None:
        """Wake a worker blocked in :meth:`evaluate` so that it unwinds; safe from any thread."""
        self.stopping.set()
        self.replies.put(_STOP)


def _work(channel: _Channel, target: Callable[[Evaluate], Any]) -> None:
    """Body of the worker thread: run the library and report how it ended."""
    try:
        result = target(channel.evaluate)
    except _Stop:
        channel.requests.put(("stopped", None))
    except BaseException as exc:  # noqa: BLE001 - every failure goes to the main thread
        channel.requests.put(("error", exc))
    else:
        channel.requests.put(("finished", result))


class InvertedRun:
    """One run of a callback-style library, driven by ask/tell (see the module docstring).

    ``target(evaluate)`` runs the library with ``evaluate`` as its objective and returns its
    result. It must not hold a reference to the object that owns this run (build it from plain
    values, e.g. with ``functools.partial`` over a module-level function), or that owner could
    never be garbage collected while the worker waits.
    """

    def __init__(self, target: Callable[[Evaluate], Any], name: str = "library") -> None:
        self.name = name
        self._target: Callable[[Evaluate], Any] | None = target
        self._channel = _Channel()
        self._thread: threading.Thread | None = None
        self._points: np.ndarray | None = None  # last batch asked, waiting for tell
        self._error: BaseException | None = None
        self._raised: BaseException | None = None
        self.finished = False  # the library returned by itself
        self.closed = False  # the worker has ended or was told to stop
        self.result: Any = None  # what the library returned, once finished
        self._finalizer = weakref.finalize(self, _Channel.stop, self._channel)
        self._finalizer.atexit = False

    @property
    def started(self) -> bool:
        """True once the worker thread has been started (by the first ask)."""
        return self._thread is not None

    @property
    def alive(self) -> bool:
        """True while the worker thread exists."""
        return self._thread is not None and self._thread.is_alive()

    def ask(self) -> np.ndarray:
        """The batch of points ``(k, d)`` the library wants evaluated next.

        Starts the worker on the first call. Re-raises, once, an exception the library raised;
        raises ``RuntimeError`` when the run has finished or was closed."""
        if self._thread is None and not self.closed:
            target, self._target = self._target, None
            self._thread = threading.Thread(
                target=_work, args=(self._channel, target), name=f"inverted-{self.name}", daemon=True
            )
            self._thread.start()
            self._receive()
        if self._error is not None:
            error, self._error = self._error, None
            self._raised = error
            raise error
        if self._points is None:
            state = "finished" if self.finished else "failed" if self._raised else "been stopped"
            raise RuntimeError(f"{self.name}: no points to evaluate, the run has {state}") from self._raised
        return self._points.copy()

    def tell(self, values: np.ndarray) -> None:
        """Values ``(k,)`` of the last batch asked; returns once the library has either asked for
        its next batch, returned, or failed."""
        if self._points is None:
            raise RuntimeError(f"{self.name}: tell() without a pending ask()")
        values = np.array(values, dtype=np.float64).reshape(-1)
        if values.shape[0] != self._points.shape[0]:
            raise ValueError(
                f"{self.name}: {values.shape[0]} values told for {self._points.shape[0]} points"
            )
        self._points = None
        self._channel.replies.put(values)
        self._receive()

    def close(self, timeout: float = JOIN_TIMEOUT) -> None:
        """Stop the library (it unwinds inside the worker without seeing any further value) and
        wait up to ``timeout`` seconds for the worker to end. Idempotent."""
        self._points = None
        if not self.closed:
            self.closed = True
            self._finalizer()  # the stop order, sent at most once
        self._join(timeout)

    def _receive(self) -> None:
        """Wait for the worker's next message: a batch of points, or how it ended."""
        kind, payload = self._channel.requests.get()
        if kind == "points":
            self._points = payload
            return
        self.closed = True
        self._finalizer.detach()  # the worker is gone: nothing to stop
        if kind == "finished":
            self.finished = True
            self.result = payload
        elif kind == "error":
            self._error = payload
        self._join(JOIN_TIMEOUT)

    def _join(self, timeout: float) -> None:
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout)
