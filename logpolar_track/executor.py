"""Run independent tasks in this process, in parallel worker processes, or on a Dask cluster.

One mechanism serves ``lptrack run`` over many videos and ``lptrack bench`` over (sequence, tracker) pairs:
:func:`run_tasks` calls a picklable top-level function on each item and yields a :class:`TaskOutcome` per item
as it finishes. A failing item never stops the others: its exception becomes the outcome's one-line ``error``.

Local parallelism uses one fresh process per task (forked from a ``forkserver`` that has imported lptrack
once, so starting one costs milliseconds). That is what makes a dying worker cost only its own task: a process
killed by the OS or by a signal is seen by its exit code and reported as that task's failure, while a shared
pool (``concurrent.futures``) would break and take every other task down with it. It also gives every task the
same clean state (OpenCV's MIL, for one, is only repeatable in a fresh process).

On a Dask cluster (``scheduler=``) the tasks are submitted to an existing ``dask.distributed`` scheduler; the
workers must see the same files at the same paths (a shared file system), as with any Dask file job.
"""

from __future__ import annotations

import gc
import multiprocessing
import os
import signal
import socket
import threading
import time
from collections import deque
from contextlib import contextmanager
from dataclasses import dataclass
from multiprocessing.connection import wait
from typing import Any, Callable, Iterator, Sequence

import cv2

from .errors import LptrackError, UsageError
from .video import keep_frames_off_the_heap

#: Seconds between progress messages a worker process sends (finer updates are dropped).
PROGRESS_INTERVAL_S = 0.25

#: Seconds a worker gets to clean up after SIGTERM before it is killed.
TERMINATE_GRACE_S = 5.0

#: Hint shown when ``scheduler`` is used without the optional Dask extra.
DASK_HINT = "--scheduler needs Dask's distributed scheduler: pip install 'dask[distributed]'"

TaskFunction = Callable[[Any, "Callable[[int], None] | None"], Any]


@dataclass(frozen=True)
class TaskOutcome:
    """How one task ended.

    Attributes
    ----------
    index : int
        Position of the item in the list given to :func:`run_tasks`.
    value : Any
        The function's return value; None if it failed.
    error : str or None
        One line saying why it failed (the message of an :class:`LptrackError`, ``Type: message`` of any other
        exception, or how its worker process died); None on success.
    """

    index: int
    value: Any = None
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None


def default_jobs() -> int:
    """Worker processes to use by default: the cores this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


#: OpenCV worker threads while lptrack tracks (``lptrack run`` and ``lptrack bench``; see :func:`opencv_threads`).
TRACKING_OPENCV_THREADS = 1

_threads_lock = threading.Lock()
_threads_users = 0
_threads_before = 0


@contextmanager
def opencv_threads(count: int | None):
    """Run the ``with`` block with OpenCV's parallel loops on ``count`` threads (``cv2.setNumThreads``); None
    leaves the setting alone. The setting before is restored when the last of the blocks running at once (in
    several threads of this process) ends.

    Why tracking runs on one: the trackers' images are small crops, where OpenCV's parallel loops cost more than
    they save (lpcf on one core: 1.28 against 1.40 ms a frame with two threads; no tracker measured faster
    with two), and the video's decoding already runs in a thread of its own. The setting is process-wide, so
    while blocks with different counts overlap, the last one entered holds.
    """
    global _threads_users, _threads_before
    if count is None:
        yield
        return
    if count < 1:
        raise UsageError(f"OpenCV threads must be at least 1, got {count}")
    with _threads_lock:
        if _threads_users == 0:
            _threads_before = cv2.getNumThreads()
        _threads_users += 1
        cv2.setNumThreads(count)
    try:
        yield
    finally:
        with _threads_lock:
            _threads_users -= 1
            if _threads_users == 0:
                cv2.setNumThreads(_threads_before)


def describe_exception(exc: BaseException) -> str:
    """One line for a task's failure: lptrack's own messages as they are, others with their type."""
    if isinstance(exc, LptrackError):
        return str(exc)
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def run_tasks(function: TaskFunction, items: Sequence, *, jobs: int = 1, scheduler=None,
              on_progress: Callable[[int, int], None] | None = None,
              on_worker_death: Callable[[int, int], None] | None = None,
              on_note: Callable[[str], None] | None = None) -> Iterator[TaskOutcome]:
    """Call ``function(item, report)`` for every item; yield a :class:`TaskOutcome` per item as each finishes.

    Parameters
    ----------
    function : callable
        A top-level (picklable) function ``function(item, report)``. ``report`` is None or a callable the
        function may call with its progress so far (e.g. frames done).
    items : sequence
        Picklable work items.
    jobs : int
        1: one after another in this process. More: up to ``jobs`` worker processes at once, one per task.
    scheduler : str or dask.distributed.Client, optional
        Address of a Dask scheduler (``tcp://host:8786``) or a connected client; then ``jobs`` is ignored.
    on_progress : callable, optional
        ``on_progress(index, done)`` with what a task reported (local runs only).
    on_worker_death : callable, optional
        ``on_worker_death(index, pid)`` after a worker process died without finishing its task, e.g. to
        delete its temporary files.
    on_note : callable, optional
        Called with a sentence for the user about the run (a Dask cluster with no workers yet, where the tasks
        wait for one).

    Yields
    ------
    TaskOutcome
        In completion order.

    Raises
    ------
    UsageError
        ``scheduler`` given but Dask is not installed, or not an address.
    LptrackError
        The Dask scheduler cannot be reached.
    KeyboardInterrupt
        On Ctrl-C (or SIGTERM turned into it by the caller), after every worker process has been stopped.
    """
    if scheduler is not None:
        yield from _run_on_dask(function, items, scheduler, on_note)
    elif jobs <= 1 or len(items) <= 1:
        yield from _run_here(function, items, on_progress)
    else:
        yield from _run_in_processes(function, items, jobs, on_progress, on_worker_death)


def _run_here(function, items, on_progress) -> Iterator[TaskOutcome]:
    for index, item in enumerate(items):
        report = None if on_progress is None else (lambda done, i=index: on_progress(i, done))
        try:
            value = function(item, report)
        except (KeyboardInterrupt, SystemExit):
            raise
        except Exception as exc:  # noqa: BLE001 - one failing task must not stop the others
            yield TaskOutcome(index, error=describe_exception(exc))
        else:
            yield TaskOutcome(index, value)


# -- local worker processes ----------------------------------------------------------------------------

def _interrupt(signum, frame):
    # Once: a second signal would interrupt the task's clean-up of its temporary outputs.
    signal.signal(signal.SIGTERM, _ignore)
    signal.signal(signal.SIGINT, _ignore)
    raise KeyboardInterrupt


def _ignore(signum, frame):
    pass  # not SIG_IGN: a signal already pending would then raise "ignored due to race condition"


#: Signals that stop lptrack (Ctrl-C, ``kill``, a closed terminal), held back while a worker process starts.
_STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


@contextmanager
def _stop_signals_held():
    """Hold Ctrl-C, SIGTERM and SIGHUP back for the ``with`` block: one that comes is acted on (its handler
    called) as the block ends.

    One that landed inside ``Process.start()`` (its exchange with the forkserver) left a worker forked but not yet
    among those :func:`_stop` stops: it went on with its task after lptrack had said "interrupted", made its
    output folder, and stopped only at its first progress report after the parent had exited. Python runs signal
    handlers in the main thread whichever thread the signal reaches, so its handlers are swapped (a signal mask
    would hold it back from this thread only, not from lptrack's other threads); elsewhere than in the main
    thread, where handlers cannot be set, nothing is held.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[tuple[int, Any]] = []

    def hold(signum, frame) -> None:
        caught.append((signum, frame))

    previous = {}
    for signum in _STOP_SIGNALS:
        handler = signal.getsignal(signum)
        if handler is not signal.SIG_IGN and handler is not None:  # one ignored (nohup, a background job) stays so
            previous[signum] = signal.signal(signum, hold)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if caught:
            signum, frame = caught[0]
            handler = previous[signum]
            if callable(handler):
                handler(signum, frame)  # lptrack's: raises KeyboardInterrupt, or Terminated
            else:  # SIG_DFL: its default action, now that it is back
                signal.raise_signal(signum)


def _worker_main(connection, function, item) -> None:
    """Body of a worker process: run one task, send ``("progress", n)`` messages then one final message."""
    # SIGTERM from the parent (its Ctrl-C) unwinds like Ctrl-C, so the task deletes its temporary outputs.
    # Ctrl-C itself reaches the whole process group, and the parent answers it with that SIGTERM: a worker
    # acting on both would unwind a second time inside the clean-up of the first (Python then prints
    # "Exception ignored in: <generator ...>" tracebacks), so it leaves SIGINT to the parent.
    signal.signal(signal.SIGINT, _ignore)
    signal.signal(signal.SIGTERM, _interrupt)
    last = 0.0

    def report(done: int) -> None:
        nonlocal last
        now = time.monotonic()
        if now - last >= PROGRESS_INTERVAL_S:
            last = now
            try:
                connection.send(("progress", done))
            except (BrokenPipeError, ConnectionResetError):
                raise KeyboardInterrupt from None  # the parent is gone: stop, deleting temporary outputs

    try:
        # Set-up inside the try: a worker stopped as it starts (Ctrl-C, `| head` gone) ends quietly too.
        keep_frames_off_the_heap()
        message = ("done", function(item, report))
    except KeyboardInterrupt:
        message = ("error", "interrupted")
    except Exception as exc:  # noqa: BLE001 - reported to the parent as this task's failure
        message = ("error", describe_exception(exc))
    try:
        _send(connection, message)
    except Exception as exc:  # noqa: BLE001 - e.g. a result that cannot be pickled
        _send(connection, ("error", f"cannot return the result: {describe_exception(exc)}"))
    connection.close()


def _send(connection, message) -> None:
    """Send to the parent; if it has gone (it was stopped, its end is closed) there is no one to tell."""
    try:
        connection.send(message)
    except (BrokenPipeError, ConnectionResetError, EOFError):
        pass


def _context():
    methods = multiprocessing.get_all_start_methods()
    if "forkserver" in methods:
        context = multiprocessing.get_context("forkserver")
        # Workers fork from a server that imported lptrack once, instead of importing it per task.
        context.set_forkserver_preload(["logpolar_track.batch", "logpolar_track.bench"])
        return context
    return multiprocessing.get_context("spawn")


def _death_reason(exitcode: int | None) -> str:
    if exitcode is not None and exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        return f"worker process was killed ({name}) before it finished"
    return f"worker process exited (code {exitcode}) before it finished"


@dataclass
class _Running:
    index: int
    process: Any
    connection: Any
    result: tuple | None = None


def _run_in_processes(function, items, jobs, on_progress, on_worker_death) -> Iterator[TaskOutcome]:
    context = _context()
    pending = deque(enumerate(items))
    running: list[_Running] = []
    try:
        while pending or running:
            while pending and len(running) < jobs:
                index, item = pending.popleft()
                receiver, sender = context.Pipe(duplex=False)
                process = context.Process(target=_worker_main, args=(sender, function, item),
                                          name=f"lptrack-task-{index}", daemon=True)
                with _stop_signals_held():  # a Ctrl-C now is acted on once the worker is among those to stop
                    try:
                        process.start()
                    except (EOFError, ConnectionError) as exc:
                        # The forkserver that workers fork from died (killed, out of memory) while being asked for
                        # one; multiprocessing starts a new server only on the next request, so one more try.
                        try:
                            process.start()
                        except (EOFError, ConnectionError):
                            sender.close()
                            receiver.close()
                            raise LptrackError(f"cannot start a worker process: multiprocessing's process server "
                                               f"ended ({describe_exception(exc)}); what had not finished was "
                                               f"not done") from exc
                    sender.close()  # the child holds its own end; EOF on ours then means it is gone
                    running.append(_Running(index, process, receiver))
            wait([r.connection for r in running] + [r.process.sentinel for r in running])
            for task in list(running):
                _drain(task, on_progress)
                if task.result is None and task.process.is_alive():
                    continue
                task.process.join()
                _drain(task, on_progress)
                running.remove(task)
                task.connection.close()
                if task.result is None:
                    if on_worker_death is not None:
                        on_worker_death(task.index, task.process.pid)
                    yield TaskOutcome(task.index, error=_death_reason(task.process.exitcode))
                elif task.result[0] == "done":
                    yield TaskOutcome(task.index, task.result[1])
                else:
                    yield TaskOutcome(task.index, error=task.result[1])
    finally:
        _stop(running, on_worker_death)


def _drain(task: _Running, on_progress) -> None:
    """Read every message waiting from ``task``'s worker; keep the final one."""
    try:
        while task.result is None and task.connection.poll():
            kind, payload = task.connection.recv()
            if kind == "progress":
                if on_progress is not None:
                    on_progress(task.index, payload)
            else:
                task.result = (kind, payload)
    except (EOFError, OSError):
        pass  # the worker is gone; its exit code tells why


def _stop(running: list[_Running], on_worker_death) -> None:
    """Stop workers still running (Ctrl-C, or the consumer stopped early): SIGTERM, a grace period, SIGKILL."""
    for task in running:
        if task.process.is_alive():
            task.process.terminate()
    deadline = time.monotonic() + TERMINATE_GRACE_S
    for task in running:
        task.process.join(max(0.0, deadline - time.monotonic()))
        if task.process.is_alive():
            task.process.kill()
            task.process.join()
        task.connection.close()
        if on_worker_death is not None:
            on_worker_death(task.index, task.process.pid)


# -- Dask ----------------------------------------------------------------------------------------------

#: Seconds to wait for a Dask scheduler: for its port to accept a connection, and then for its answer.
SCHEDULER_CONNECT_S, SCHEDULER_ANSWER_S = 5.0, 10.0


def _connect(client_class, scheduler: str):
    """A ``dask.distributed`` client of the scheduler at address ``scheduler``.

    Raises
    ------
    UsageError
        A malformed address ('nonsense', 'tcp://host' without a port).
    LptrackError
        Nothing accepts connections there (refused, or a host that does not resolve: said at once, where Dask
        retried for its whole timeout), something that is not a Dask scheduler does (an HTTP server: Dask waited
        for its handshake for ever), or Dask could not connect (a ``tls://`` address without Dask's TLS settings
        raised a TypeError).

    Notes
    -----
    The first check opens and closes a plain TCP connection, which a scheduler logs as a connection closed before
    its handshake; the host's name lookup is not bounded by :data:`SCHEDULER_CONNECT_S`.
    """
    address = str(scheduler)
    host, _, port = address.split("://", 1)[-1].rpartition(":")
    if "://" not in address or address.startswith("tcp://"):
        if port.isdigit() and host:
            try:
                socket.create_connection((host.strip("[]"), int(port)), timeout=SCHEDULER_CONNECT_S).close()
            except OSError as exc:
                raise LptrackError(f"cannot reach the Dask scheduler '{scheduler}': {describe_exception(exc)}") \
                    from None
    made: dict[str, Any] = {}
    abandoned = threading.Event()

    def make() -> None:
        try:
            client = client_class(scheduler, timeout=f"{SCHEDULER_ANSWER_S:g}s", set_as_default=False)
        except BaseException as exc:  # noqa: BLE001 - handed over to the caller's thread below
            made["error"] = exc
            return
        made["client"] = client
        if abandoned.is_set():  # connected after the caller gave up: nobody will close it
            client.close()

    # In a thread of its own, so that a peer that never answers (Dask waited for its handshake without end) is
    # given up on, and Ctrl-C is heard meanwhile.
    thread = threading.Thread(target=make, name="lptrack-dask-connect", daemon=True)
    thread.start()
    deadline = 1.5 * SCHEDULER_ANSWER_S  # Dask's own timeout first, where it comes
    try:
        thread.join(deadline)
    finally:  # given up on (or Ctrl-C): a client made from here on, or just made, is closed
        if thread.is_alive():
            abandoned.set()
            if "client" in made:
                made["client"].close()
    if thread.is_alive():
        raise LptrackError(f"the Dask scheduler '{scheduler}' did not answer within {deadline:g} s (is it a Dask "
                           f"scheduler's address?)")
    error = made.pop("error", None)
    if error is None:
        return made["client"]
    if not isinstance(error, (ValueError, OSError, TimeoutError, TypeError)):
        raise error  # not a failure to connect (an lptrack bug, MemoryError): as it is
    malformed = isinstance(error, ValueError)  # the address itself
    message = str(error) if malformed else describe_exception(error)
    # A Client that failed half-made lingers in reference cycles (and in the exception's traceback). Left to the
    # end of the interpreter, its __del__ waits 30 s for its event loop, stopped by then; collected now, while the
    # loop runs, it closes at once.
    del error
    gc.collect()
    if malformed:
        raise UsageError(f"--scheduler '{scheduler}' is not a Dask scheduler address ({message}); give one like "
                         f"tcp://10.0.0.5:8786")
    raise LptrackError(f"cannot connect to the Dask scheduler '{scheduler}': {message}")


def _run_on_dask(function, items, scheduler, on_note=None) -> Iterator[TaskOutcome]:
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise UsageError(DASK_HINT) from None
    own_client = not isinstance(scheduler, Client)
    client = _connect(Client, scheduler) if own_client else scheduler
    futures = {}
    try:
        if on_note is not None and items:
            info = client.scheduler_info()
            if not info.get("workers"):
                # The tasks wait for a worker, and nothing else would say so: it looked like a hang.
                address = scheduler if own_client else info.get("address", "")  # as the user gave it, if given
                on_note(f"the Dask scheduler '{address}' has no workers yet; nothing runs until one connects "
                        f"(Ctrl-C to stop)")
        for index, item in enumerate(items):
            futures[client.submit(function, item, None, pure=False)] = index
        for future in as_completed(futures, loop=client.loop):
            index = futures[future]
            if future.status == "finished":
                yield TaskOutcome(index, future.result())
            else:
                exc = future.exception()
                yield TaskOutcome(index, error=describe_exception(exc) if exc is not None else future.status)
    finally:
        client.cancel(list(futures))
        if own_client:
            client.close()
