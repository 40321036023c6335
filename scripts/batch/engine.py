"""Running cases on Dask distributed: a LocalCluster on this machine (one
single-threaded worker process per core, on 127.0.0.1) or an existing cluster
given by its scheduler's address. Fault handling: a run's answer (fekap's exit
code) is recorded and not retried; a worker that dies under a case or a case
over the timeout is retried up to `retries` times, then recorded as lost."""

from __future__ import annotations

import logging
import os
import sys
import time
from dataclasses import dataclass, field

from . import task as task_module


@dataclass
class Outcome:
    """What became of the cases run this time."""

    records: dict[str, dict] = field(default_factory=dict)
    lost: dict[str, str] = field(default_factory=dict)
    interrupted: bool = False


class Progress:
    """A progress bar on a terminal; one line per case otherwise."""

    def __init__(self, total: int, stream=None, quiet: bool = False):
        self.total = total
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.quiet = quiet
        self.done = self.failed = self.lost = 0
        self.start = time.monotonic()

    def update(self, name: str, label: str, record: dict | None, running: int, error: str = "") -> None:
        if record is not None:
            self.done += 1
            self.failed += record["exit"] != 0
        elif error:
            self.lost += 1
        if self.quiet:
            return
        finished = self.done + self.lost
        if self.tty:
            width = 30
            filled = int(width * finished / max(self.total, 1))
            elapsed = time.monotonic() - self.start
            eta = elapsed / finished * (self.total - finished) if finished else 0.0
            line = (f"\r[{'#' * filled}{'.' * (width - filled)}] {finished}/{self.total} done, "
                    f"{self.failed} failed, {self.lost} lost, {running} running, ETA {eta:5.0f} s ")
            self.stream.write(line)
            if finished == self.total:
                self.stream.write("\n")
        else:
            if record is not None:
                state = f"exit {record['exit']}" + (f": {record['message']}" if record["message"] else "")
                state += f" ({record['seconds']:.2f} s)"
            else:
                state = f"lost: {error}"
            self.stream.write(f"case {finished}/{self.total} {name} [{label}] {state}\n")
        self.stream.flush()

    def note(self, text: str) -> None:
        if self.quiet:
            return
        if self.tty:
            self.stream.write("\r\033[K")
        self.stream.write(text + "\n")
        self.stream.flush()


def start_client(scheduler: str | None, workers: int | None, retries: int):
    """A Dask client on the given scheduler, or on a new LocalCluster; and the cluster."""
    import dask
    from dask.distributed import Client, LocalCluster
    # Worker deaths come back at once as KilledWorker, and the sweep retries them
    # itself (--retries), so that a timeout and a death count alike.
    dask.config.set({"distributed.scheduler.allowed-failures": 0,
                     "distributed.worker.daemon": False})
    if scheduler:
        return Client(scheduler, timeout="30s"), None
    if "DASK_DISTRIBUTED__WORKER__MULTIPROCESSING_METHOD" not in os.environ and sys.platform == "linux":
        # Forked workers start in about half the time of spawned ones (which
        # import Dask afresh): 3.5 s against 7-9 s for a 2-worker sweep here.
        dask.config.set({"distributed.worker.multiprocessing-method": "fork"})
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                           processes=True, host="127.0.0.1", dashboard_address=None,
                           silence_logs=logging.CRITICAL)
    return Client(cluster), cluster


def run_all(tasks: list[dict], labels: dict[str, str], scheduler: str | None, workers: int | None,
            retries: int, progress: Progress) -> Outcome:
    """Run the tasks (run_case's arguments) on Dask and collect the outcome.
    Ctrl-C stops the sweep: finished cases stay, the rest are cancelled."""
    import cloudpickle
    from dask.distributed import as_completed
    cloudpickle.register_pickle_by_value(task_module)
    # Dask tries plain pickle first, which would send run_case by reference (the
    # workers would need scripts/ importable); a lambda goes through cloudpickle,
    # which sends the registered module's code by value.
    run_case = lambda task, run=task_module.run_case: run(task)  # noqa: E731
    outcome = Outcome()
    if not tasks:
        return outcome
    client = cluster = None
    pending: dict[str, tuple[dict, object]] = {}
    try:
        client, cluster = start_client(scheduler, workers, retries)
        nworkers = max(len(client.scheduler_info().get("workers", {})), 1)
        futures = []
        for task in tasks:
            future = client.submit(run_case, task, key=f"{task['name']}-a{task['attempt']}",
                                   pure=False)
            pending[future.key] = (task, future)
            futures.append(future)
        completed = as_completed(futures)
        for future in completed:
            task, _ = pending.pop(future.key)
            name = task["name"]
            running = min(len(pending), nworkers)
            if future.status == "finished":
                record = future.result()
                outcome.records[name] = record
                progress.update(name, labels[name], record, running)
                continue
            error = future.exception()
            reason = f"{type(error).__name__}: {error}"
            if type(error).__name__ == "KilledWorker":
                reason = "its worker died"
            if task["attempt"] <= retries:
                progress.note(f"case {name} [{labels[name]}]: {reason}; retrying "
                              f"({task['attempt']} of {retries} retries)")
                retry = dict(task, attempt=task["attempt"] + 1)
                new = client.submit(run_case, retry, key=f"{name}-a{retry['attempt']}", pure=False)
                pending[new.key] = (retry, new)
                completed.add(new)
            else:
                outcome.lost[name] = f"lost after {task['attempt']} attempts: {reason}"
                progress.update(name, labels[name], None, running, error=outcome.lost[name])
            future.release()
    except KeyboardInterrupt:
        outcome.interrupted = True
        progress.note("fekap-batch: interrupted; finished cases are kept, the others cancelled")
    finally:
        if client is not None:
            try:
                if pending:
                    client.cancel([f for _, f in pending.values()], force=True)
            except Exception:  # shutting down: nothing more to save
                pass
            client.close(timeout=10)
        if cluster is not None:
            cluster.close(timeout=10)
    return outcome
