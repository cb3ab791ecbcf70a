"""Executors: where the points of a sweep run (serial, a thread pool; Dask in sweep/dask.py)."""
from __future__ import annotations

import concurrent.futures as cf
import os
import threading
from typing import Any, Callable, Iterator, Sequence

from .. import _core
from ..flowsheet import Flowsheet

ConfigError = _core.ConfigError
# the status of a sweep row (the executor protocol below)
STATUS_OK = "ok"
STATUS_FAILED = "failed"


class SerialExecutor:
    """Runs the points one after another on one clone of the flowsheet (reference and debugging)."""

    name = "serial"

    def map_unordered(self, evaluate: Callable[[Flowsheet, Any], dict], flowsheet: Flowsheet,
                      items: Sequence[Any]) -> Iterator[dict]:
        fs = flowsheet.clone()
        if hasattr(evaluate, "batch"):  # the points solved in the core, one call
            yield from evaluate.batch([fs], list(items))
            return
        for item in items:
            yield evaluate(fs, item)


class ThreadExecutor:
    """A thread pool; every worker thread owns one ``Flowsheet.clone()`` (flowsheets are not thread-safe,
    clones are independent). The C++ solve releases the GIL, so the solves run in parallel.

    The executor protocol: ``map_unordered(evaluate, flowsheet, items)`` yields ``evaluate(fs, item)`` for every
    item, in any order, where ``fs`` is a flowsheet equal to ``flowsheet`` that no other running task uses.
    ``evaluate`` never raises for a failed point (it returns a row with status "failed") unless the caller asked
    for errors to propagate. An ``evaluate`` with a ``batch(flowsheets, items)`` method (granuflow.sweep.batch)
    solves many items in one call on one thread per flowsheet: executors hand it their items at once.
    """

    name = "threads"

    def __init__(self, workers: int | None = None):
        self.workers = workers

    def map_unordered(self, evaluate, flowsheet, items):
        workers = max(1, min(self.workers or os.cpu_count() or 1, len(items) or 1))
        if hasattr(evaluate, "batch"):  # the core's threads, one clone each, solve all points in one call
            yield from evaluate.batch([flowsheet.clone() for _ in range(workers)], list(items))
            return
        local = threading.local()
        lock = threading.Lock()

        def task(item):
            fs = getattr(local, "fs", None)
            if fs is None:
                with lock:  # clone() reads the template; serialize it
                    fs = local.fs = flowsheet.clone()
            return evaluate(fs, item)

        with cf.ThreadPoolExecutor(max_workers=workers, thread_name_prefix="granuflow-sweep") as pool:
            futures = [pool.submit(task, item) for item in items]
            try:
                for fut in cf.as_completed(futures):
                    yield fut.result()
            except BaseException as e:
                for f in futures:
                    f.cancel()
                if isinstance(e, KeyboardInterrupt):  # the points being solved stop as well (else the pool waits)
                    _core.interrupt()
                raise


EXECUTORS: dict[str, Callable[..., Any]] = {"threads": ThreadExecutor, "serial": lambda workers=None: SerialExecutor()}


def make_executor(executor: str | Any = "threads", workers: int | None = None):
    """An executor by name (``"threads"``, ``"serial"``, or one added to ``EXECUTORS``), a ``distributed.Client``
    (wrapped in :class:`granuflow.sweep.dask.DaskExecutor`) or the object itself."""
    if isinstance(executor, str):
        try:
            return EXECUTORS[executor](workers=workers)
        except KeyError:
            raise ConfigError(f"executor = '{executor}': unknown (allowed: {', '.join(sorted(EXECUTORS))})") from None
    # a dask.distributed Client runs the same sweep on its cluster (sweep/dask.py)
    from .dask import DaskExecutor, is_dask_client

    if is_dask_client(executor):
        return DaskExecutor(executor)
    if not hasattr(executor, "map_unordered"):
        raise ConfigError(f"executor = {executor!r}: expected a name ({', '.join(sorted(EXECUTORS))}) "
                          "or an object with map_unordered(evaluate, flowsheet, items)")
    return executor
