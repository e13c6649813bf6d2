"""The sweep general path: any config, one :func:`~research.experiments.evaluate.evaluate` per point,
serially or on a Dask distributed cluster (a ``LocalCluster`` by default, ``scheduler=ADDRESS`` for a
real one).

Every finished point is written to the store as soon as it arrives (atomic, keyed by the point's
config, the code version and its input files), so an interrupted sweep loses nothing and a re-run
computes only the points that are not there. A point whose evaluation raises is stored as a failure
with its error (``status = "error"``) and the sweep goes on; ``retry_failed`` recomputes those.
Workers return their records and the client writes the store, so a remote cluster needs no shared disk.
"""

from __future__ import annotations

import os
import traceback
from pathlib import Path

from research.experiments.store import ResultStore

#: environment of LocalCluster workers: one point per worker on one core, no BLAS / XLA thread pools
#: competing with the other workers
ONE_THREAD = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"}


def point_task(config_json: dict, base_dir: str) -> dict:
    """Evaluate one point on a worker: ``{"status": "ok", ...record}`` or ``{"status": "error", "error": ...}``.

    Pure function of its arguments (the config as a JSON dictionary, the folder of the config file).
    """
    import research  # noqa: F401  (x64 on the worker)
    from research.experiments.config import validate
    from research.experiments.evaluate import evaluate

    try:
        cfg = validate(config_json, Path(base_dir) / "sweep-point.toml")
        return {"status": "ok"} | evaluate(cfg, base_dir, model_file=False).record
    except Exception as e:  # a failing point is a result, not the end of the sweep
        return {"status": "error", "error": f"{type(e).__name__}: {e}",
                "traceback": traceback.format_exc(limit=6)}


def run_general(tasks: list[tuple[int, str, dict]], base_dir: str | Path, store: ResultStore, *, engine: str,
                scheduler: str | None = None, workers: int | None = None, progress=None) -> dict[int, dict]:
    """Evaluate ``(index, key, config JSON)`` tasks not yet in the store; returns ``{index: record}``.

    Args:
        engine: ``"serial"`` (in this process) or ``"dask"``.
        scheduler: address of a running Dask scheduler (``tcp://host:8786``); ``None`` starts a
            ``LocalCluster`` of ``workers`` single-threaded processes (default: the CPU count).
        progress: callback taking the number of points just finished.
    """
    out = {}
    if not tasks:
        return out
    base_dir = str(base_dir)

    def finish(index, key, rec):
        out[index] = store.put(key, rec).record
        if progress is not None:
            progress(1)

    if engine == "serial":
        for index, key, cfg in tasks:
            finish(index, key, point_task(cfg, base_dir))
        return out
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler is None:
        n = max(1, min(workers or os.cpu_count() or 1, len(tasks)))
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None, env=ONE_THREAD)
    client = Client(scheduler if scheduler is not None else cluster)
    try:
        futures = {client.submit(point_task, cfg, base_dir, pure=False): (index, key) for index, key, cfg in tasks}
        for fut in as_completed(futures):
            index, key = futures[fut]
            try:
                rec = fut.result()
            except Exception as e:  # the worker died: report, do not store (a re-run retries it)
                out[index] = {"status": "error", "error": f"{type(e).__name__}: {e}"}
                if progress is not None:
                    progress(1)
                continue
            finish(index, key, rec)
    finally:
        client.close()
        if cluster is not None:
            # close each worker with time to exit on its own: the cluster's own close gives a nanny 4 s,
            # after which it kills the process (``distributed.nanny - WARNING ... killing``, issue 16) --
            # JAX workers on a loaded machine need longer
            cluster.sync(_close_workers, list(cluster.workers.values()), WORKER_CLOSE_TIMEOUT_S)
            cluster.close()
    return out


#: seconds a LocalCluster worker process is given to exit before its nanny kills it
WORKER_CLOSE_TIMEOUT_S = 60.0


async def _close_workers(nannies, timeout: float) -> None:
    import asyncio

    await asyncio.gather(*(n.close(timeout=timeout) for n in nannies))
