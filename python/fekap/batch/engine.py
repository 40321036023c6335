"""Running cases on Dask distributed: a LocalCluster on this machine (one
single-threaded worker process per core, on 127.0.0.1) or an existing cluster
given by its scheduler's address. Fault handling: a run's answer (fekap's exit
code) is recorded and not retried; a worker that dies under a case or a case
over the timeout is retried up to `retries` times, then recorded as lost."""

from __future__ import annotations

import logging
import operator
import os
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from . import task as task_module

#: Most cases run by one Dask task.
CHUNK = 16


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


def start_client(scheduler: str | None, workers: int | None):
    """A Dask client on the given scheduler, or on a new LocalCluster; and the cluster."""
    import dask
    from dask.distributed import Client, LocalCluster
    # Worker deaths come back at once as KilledWorker, and the sweep retries them
    # itself (--retries), so that a timeout and a death count alike.
    dask.config.set({"distributed.scheduler.allowed-failures": 0})
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


def local_processes(client) -> list[int]:
    """The pids of a LocalCluster's worker processes and of their nannies."""
    pids = set()
    for call in (os.getpid, os.getppid):
        pids.update(client.run(call).values())
    pids.discard(os.getpid())
    return sorted(pids)


def descendants(pids: list[int]) -> list[int]:
    """The processes and their descendants as they are now (Linux /proc; only the processes
    themselves elsewhere): a worker that a nanny restarted since the start is found too."""
    found, todo = [], list(pids)
    while todo:
        pid = todo.pop()
        found.append(pid)
        for task in Path(f"/proc/{pid}/task").glob("*"):
            try:
                todo += [int(child) for child in (task / "children").read_text().split()]
            except (OSError, ValueError):
                continue
    return list(dict.fromkeys(found))


def kill(pids: list[int]) -> None:
    """SIGKILL to the processes of our own LocalCluster and everything they started (their
    fekap runs too, which task.py also gives the parent-death signal)."""
    for pid in descendants(pids):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def run_all(tasks: list[dict], labels: dict[str, str], scheduler: str | None, workers: int | None,
            retries: int, progress: Progress) -> Outcome:
    """Run the tasks (run_case's arguments) on Dask and collect the outcome.
    Ctrl-C stops the sweep within a few seconds: finished cases stay, the rest are
    cancelled; a LocalCluster's workers, and the runs on them, are killed rather than
    waited for (a run of minutes would hold a graceful close as long)."""
    import cloudpickle
    from dask.distributed import as_completed
    cloudpickle.register_pickle_by_value(task_module)
    outcome = Outcome()
    if not tasks:
        return outcome
    client = cluster = None
    pids: list[int] = []
    pending: dict[str, tuple[list[dict], object]] = {}
    try:
        client, cluster = start_client(scheduler, workers)
        if cluster is not None:
            pids = local_processes(client)
        nworkers = max(len(client.scheduler_info().get("workers", {})), 1)
        # The case code goes to each worker once, by value (cloudpickle: the
        # workers need not import scripts/), as data that every task calls
        # through operator.call; sent with each task it cost ~2 ms a case.
        code = client.scatter(task_module.run_cases, broadcast=True, hash=False)
        # Dask's own cost is per task: a large sweep runs a few cases per task
        # (at least 8 tasks per worker remain, for balance and progress).
        size = max(1, min(CHUNK, len(tasks) // (8 * nworkers)))

        def submit(chunk: list[dict]):
            future = client.submit(operator.call, code, chunk, pure=False,
                                   key=f"{chunk[0]['name']}-n{len(chunk)}-a{chunk[0]['attempt']}")
            pending[future.key] = (chunk, future)
            return future

        completed = as_completed([submit(tasks[i:i + size]) for i in range(0, len(tasks), size)])
        for future in completed:
            chunk, _ = pending.pop(future.key)
            running = min(len(pending), nworkers)
            if future.status == "finished":
                for record in future.result():
                    outcome.records[record["case"]] = record
                    progress.update(record["case"], labels[record["case"]], record, running)
                future.release()
                continue
            error = future.exception()
            future.release()
            if len(chunk) > 1:
                # Which case failed is not known: each goes again on its own
                # (those that finished return their case.json at once).
                for task in chunk:
                    completed.add(submit([task]))
                continue
            task = chunk[0]
            name = task["name"]
            reason = f"{type(error).__name__}: {error}"
            if type(error).__name__ == "KilledWorker":
                reason = "its worker died"
            if task["attempt"] <= retries:
                progress.note(f"case {name} [{labels[name]}]: {reason}; retrying "
                              f"({task['attempt']} of {retries} retries)")
                completed.add(submit([dict(task, attempt=task["attempt"] + 1)]))
            else:
                outcome.lost[name] = f"lost after {task['attempt']} attempts: {reason}"
                progress.update(name, labels[name], None, running, error=outcome.lost[name])
    except KeyboardInterrupt:
        # A second Ctrl-C while stopping would leave a traceback and the workers running.
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        outcome.interrupted = True
        kill(pids)
        progress.note("fekap-batch: interrupted; finished cases are kept, the others cancelled")
    finally:
        quick = 2 if outcome.interrupted else 10
        if client is not None:
            try:
                if pending and not pids:
                    client.cancel([f for _, f in pending.values()], force=True)
                client.close(timeout=quick)
            except Exception:  # shutting down: nothing more to save
                pass
        if cluster is not None:
            try:
                cluster.close(timeout=quick)
            except Exception:  # its processes are gone already
                pass
        if outcome.interrupted:
            signal.signal(signal.SIGINT, signal.default_int_handler)
    return outcome
