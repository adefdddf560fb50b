"""Where a benchmark's episodes run: joblib's parallel executors, named here and nowhere else.

* ``loky`` (local processes, the default), ``dask`` (joins ``scheduler`` when given, else starts a local
  cluster of ``workers`` processes; extra ``dask``) and ``ray`` (joins ``scheduler`` when given, else starts
  a local one; extra ``ray``): :data:`EXECUTORS`, :func:`executor_parallel`.
* :func:`local_processes`: loky named outright, for suite generation and suite files, so that a dask or ray
  context opened by a caller does not take them.

joblib calls its executors "backends" (its keyword ``backend=``); this module is the one place that says so.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

EXECUTORS = ("loky", "dask", "ray")


class ExecutorError(ValueError):
    """An unknown executor, a bad worker count or a missing extra."""


def local_processes(workers: int, **options: Any):
    """A joblib Parallel over ``workers`` local processes (loky), whatever joblib context is open."""
    import joblib

    return joblib.Parallel(n_jobs=workers, backend="loky", **options)


def executor_parallel(executor: str, workers: int, scheduler: str | None) -> tuple[Any, Callable[[], None]]:
    """A joblib Parallel yielding results as they finish (ray: a list, chunk by chunk) on ``executor``, and the
    callable that closes what it started."""
    import joblib

    if executor not in EXECUTORS:
        raise ExecutorError(f"unknown executor {executor!r}; use {', '.join(EXECUTORS)}")
    if workers < 1:
        raise ExecutorError(f"workers must be at least 1, got {workers}")
    if executor == "loky":
        return local_processes(workers, return_as="generator_unordered"), lambda: None
    if executor == "dask":
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise ExecutorError("executor dask needs the extra: pip install 'viapath[dask]'") from None
        if scheduler:
            client = Client(scheduler)
            n_jobs = -1
        else:
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
            n_jobs = workers
        context = joblib.parallel_config(backend="dask")
        context.__enter__()
        parallel = joblib.Parallel(n_jobs=n_jobs, return_as="generator_unordered")

        def close():
            context.__exit__(None, None, None)
            client.close()
            if not scheduler:
                cluster.close()

        return parallel, close
    try:
        import ray
        from ray.util.joblib import register_ray
    except ImportError:
        raise ExecutorError("executor ray needs the extra: pip install 'viapath[ray]'") from None
    register_ray()
    if scheduler:
        ray.init(address=scheduler, ignore_reinit_error=True, log_to_driver=False)
    else:
        ray.init(num_cpus=workers, include_dashboard=False, ignore_reinit_error=True, log_to_driver=False)
    context = joblib.parallel_config(backend="ray")
    context.__enter__()
    # Ray's joblib executor returns lists only: the tasks go in chunks, each chunk's rows written when it ends.
    parallel = joblib.Parallel(n_jobs=workers if not scheduler else -1, return_as="list")

    def close():  # type: ignore[no-redef]  # the other executors' close, above
        context.__exit__(None, None, None)
        ray.shutdown()

    return parallel, close


def stop_workers(parallel) -> None:
    """Kill the worker processes now (loky: terminate the executor with kill_workers), rather than
    letting joblib wait for the episodes they are running."""
    running = getattr(parallel, "_backend", None)  # joblib's private handle on its executor
    workers = getattr(running, "_workers", None)
    try:
        if workers is not None and hasattr(workers, "terminate"):
            workers.terminate(kill_workers=True)
        elif running is not None and hasattr(running, "abort_everything"):
            running.abort_everything(ensure_ready=False)
    except Exception:
        pass
