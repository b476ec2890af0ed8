"""A run's figures drawn in other processes, while the run goes on (``dualarm-qp run``).

Importing matplotlib takes about as long as a whole 300-sample run, and drawing a
run's figures one after the other about as long again. :class:`FigureProcess` takes
both off the run's path:

1. :meth:`FigureProcess.start`, called as soon as the command's arguments are parsed,
   forks a process that imports matplotlib and the figure code while the command
   imports the rest (NumPy, Pinocchio, Coal, the configuration schema: neither the
   parser nor ``import dualarm_qp`` loads them), builds and runs the experiment;
2. while it waits for its job, it builds the figures' axes (:mod:`.ready`);
3. once the rollout is done, :meth:`FigureProcess.submit` sends it the run's limits,
   title and trace (the columns of ``trajectory.csv``, not read back from the file); it
   draws the figures, split between itself and one process forked from it (one per
   core), each file written atomically, while the command writes ``trajectory.csv``
   and ``config.yaml``;
4. the command then calls the object (in place of
   :func:`~.run_figures.write_run_figures`), waits for the figures, and writes
   ``report.html`` and ``summary.json`` as before. The files, their content and their
   order are the same. Called without :meth:`~FigureProcess.submit`, the object sends
   the limits and title only, and the process reads ``trajectory.csv``.

Where it is not used:

- ``start`` returns None except on Linux with at least two cores, from a process
  with no other thread: a spawned process (macOS, Windows) would import everything
  again, one core gains nothing, and a fork copies a multi-threaded process (a Dask
  worker) with its locks in whatever state. The figures are then drawn in the run's
  own process, as by a library call of
  :func:`~dualarm_qp.experiments.run.run_experiment`, which draws there unless given
  a FigureProcess (only the command line's ``run`` gives it one).
- Should a drawing process die, the figures are drawn in the run's process instead; an
  error while drawing is raised in the run's process, as if it had drawn them.

Signals: the drawing processes form a process group of their own and ignore SIGINT and
SIGTERM, so a Ctrl-C at the terminal reaches the command alone, which stops its rollout
and writes the partial run, figures included, as before. They take one job from a pipe
and end when it ends: when the command ends, however it ends, so do they, a job under
way finished first (each file whole). The command ends them (SIGKILL to the group) as
soon as it no longer needs them, and always before it removes a set it could not finish.
"""

from __future__ import annotations

import os
import pickle
import select
import signal
import sys
import threading
import traceback
from pathlib import Path
from typing import TYPE_CHECKING, Any, BinaryIO

from ..._signals import STOP_SIGNALS

if TYPE_CHECKING:
    from ..setup import Experiment
    from .rundata import PlotLimits, RunData

#: What each figure costs to draw, relative to ``joints.png`` (measured), to share them
#: between the two drawing processes.
COST = {"joints.png": 1.0, "rates.png": 1.25, "grasp.png": 1.0, "tracking.png": 1.5,
        "closure.png": 0.75, "clearance.png": 0.9}


def can_fork() -> bool:
    """Whether :meth:`FigureProcess.start` starts a process here (see the module's notes)."""
    return (sys.platform == "linux" and hasattr(os, "fork")
            and threading.active_count() == 1 and len(os.sched_getaffinity(0)) >= 2)


def share(names: list[str]) -> tuple[list[str], list[str]]:
    """Split the figures ``names`` in two shares of about equal cost (:data:`COST`).

    Of all splits (a run has at most six figures), the one whose costlier share costs
    least; the cheaper share first (the process that draws it also starts the other's).
    Each share keeps the order of ``names``.
    """
    def cost(group: list[str]) -> float:
        return sum(COST.get(n, 1.0) for n in group)

    best: tuple[list[str], list[str]] = (list(names), [])
    for mask in range(1, 2 ** len(names)):
        one = [n for k, n in enumerate(names) if not mask >> k & 1]
        two = [n for k, n in enumerate(names) if mask >> k & 1]
        if max(cost(one), cost(two)) < max(cost(best[0]), cost(best[1])):
            best = (one, two)
    return best if cost(best[0]) <= cost(best[1]) else (best[1], best[0])


class FigureProcess:
    """A forked process that draws one run's figures (:meth:`start` makes one).

    Call it as ``figures(out, exp)`` once ``out/trajectory.csv`` is written (or after
    :meth:`submit`): it returns the names of the PNG files written, as
    :func:`~.run_figures.write_run_figures` does. :meth:`close` ends it; use it as a
    context manager to be sure to.
    """

    def __init__(self, pid: int, jobs: BinaryIO, results: BinaryIO) -> None:
        self.pid: int | None = pid
        self._jobs = jobs
        self._results = results
        self._sent: Path | None = None  # the run folder of the job sent (:meth:`submit`)

    @classmethod
    def start(cls) -> FigureProcess | None:
        """Fork the drawing process, which starts importing matplotlib.

        None where it is not used (:func:`can_fork`).
        """
        if not can_fork():
            return None
        jobs_r, jobs_w = os.pipe()
        _widen(jobs_w)
        results_r, results_w = os.pipe()
        # No SIGINT or SIGTERM between the fork and the child's ignoring them: it would
        # run the command's handler in the child.
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
        try:
            pid = os.fork()
            if pid == 0:  # the child: never returns
                _child(jobs_r, results_w, (jobs_w, results_r), mask)
            try:
                os.setpgid(pid, pid)  # also done by the child: whichever comes first
            except OSError:  # it already has (and may have ended)
                pass
            os.close(jobs_r)
            os.close(results_w)
            return cls(pid, os.fdopen(jobs_w, "wb"), os.fdopen(results_r, "rb"))
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)

    def submit(self, out: Path, exp: Experiment, data: RunData) -> None:
        """Send the job of the run in ``out`` with its trace ``data``, without waiting.

        The figures are then drawn while the command writes the run's other files (the
        trace not read back from ``trajectory.csv``); calling the object waits for them.
        Call :meth:`close` before removing files from ``out`` if the reply is not awaited.
        """
        from .rundata import PlotLimits, run_title

        try:
            self._send((Path(out), PlotLimits.from_experiment(exp), run_title(exp), data))
        except BaseException:
            self.close()
            raise
        self._sent = Path(out)

    def __call__(self, out: Path, exp: Experiment) -> list[str]:
        """Draw the figures of the run in ``out`` made with ``exp``; return their names.

        The job :meth:`submit` sent for ``out``, if it did: its reply.
        """
        from .rundata import PlotLimits, run_title

        try:
            if self._sent != Path(out):
                self._send((Path(out), PlotLimits.from_experiment(exp), run_title(exp), None))
            reply = self._reply()
        except BaseException:
            self.close()  # nothing of it may write after this
            raise
        if reply is None:  # it died: draw here
            self.close()
            from .run_figures import write_run_figures

            return write_run_figures(out, exp)
        kind, value = reply
        if kind == "error":
            self.close()
            err, text = value
            raise err from RuntimeError("in the figure process:\n" + text)
        return list(value)

    def _send(self, job: tuple[Path, PlotLimits, str, RunData | None]) -> None:
        """Send the job (nothing when the process is gone: :meth:`_reply` says so)."""
        if self.pid is None:
            return
        try:
            pickle.dump(job, self._jobs)
            self._jobs.flush()
        except OSError:
            pass

    def _reply(self) -> tuple[str, Any] | None:
        """Wait for the reply to the job sent (None when the process is gone)."""
        if self.pid is None:
            return None
        try:
            reply: tuple[str, Any] = pickle.load(self._results)
        except (OSError, EOFError, pickle.UnpicklingError):
            return None
        return reply

    def close(self) -> None:
        """End the drawing processes (any still running) and reap the first."""
        if self.pid is None:
            return
        pid, self.pid = self.pid, None
        for pipe in (self._jobs, self._results):
            try:
                pipe.close()
            except OSError:
                pass
        try:
            os.killpg(pid, signal.SIGKILL)  # before the reaping: the group still exists
        except OSError:
            pass
        try:
            os.waitpid(pid, 0)
        except ChildProcessError:
            pass

    def __enter__(self) -> FigureProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


#: The size [bytes] asked for the job's pipe: a trace of a few thousand samples (about
#: 0.5 kB each) is sent without waiting for the drawing process to read it.
PIPE_SIZE = 1 << 20


def _widen(fd: int) -> None:
    """Ask Linux to give the pipe ``fd`` :data:`PIPE_SIZE` bytes (left as it is if refused)."""
    import fcntl

    try:
        fcntl.fcntl(fd, getattr(fcntl, "F_SETPIPE_SZ", 1031), PIPE_SIZE)
    except OSError:  # over the system's limit for this user: a smaller pipe works too
        pass


def _child(jobs: int, results: int, parents: tuple[int, int], mask: Any) -> None:
    """Run the drawing process (in the forked child); end it without returning."""
    status = 1
    try:
        for sig in STOP_SIGNALS:
            signal.signal(sig, signal.SIG_IGN)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        os.setpgid(0, 0)
        for fd in parents:
            os.close(fd)
        quiet = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):  # nothing of it on the command's terminal or pipes
            os.dup2(quiet, fd)
        _serve(jobs, results)
        status = 0
    finally:
        os._exit(status)  # never the parent's clean-up: it is the parent's


def _serve(jobs: int, results: int) -> None:
    """Import the figure code, take one job, draw it, reply."""
    from .ready import prepare
    from .run_figures import run_figure_names, write_figures  # matplotlib: the slow part
    from .rundata import RunData

    prepare(stop=lambda: bool(select.select([jobs], [], [], 0)[0]))  # until the job comes
    with os.fdopen(jobs, "rb") as pipe:
        try:
            out, limits, title, data = pickle.load(pipe)
        except EOFError:  # the command ended, or has no figures to draw
            return
    reply: tuple[str, Any]
    try:
        if data is None:  # not sent: the trace is in the run folder
            data = RunData.read(out / "trajectory.csv")
        names = run_figure_names(data, limits)
        mine, theirs = share(names)
        if not mine:  # one share: no second process
            mine, theirs = theirs, mine
        helper = (_fork_helper(lambda: write_figures(out, limits, title, theirs, data=data))
                  if theirs else None)
        write_figures(out, limits, title, mine, data=data)
        if helper is not None:
            _join_helper(*helper)
        reply = ("ok", names)
    except BaseException as err:  # every error goes to the command
        reply = ("error", _portable(err))
    with os.fdopen(results, "wb") as pipe:
        pickle.dump(reply, pipe)


def _fork_helper(work: Any) -> tuple[int, int]:
    """Fork a process that runs ``work()``; return its pid and the pipe of its reply."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        status = 1
        try:
            os.close(read)
            try:
                work()
                reply: tuple[str, Any] = ("ok", None)
            except BaseException as err:  # sent to the first process
                reply = ("error", _portable(err))
            with os.fdopen(write, "wb") as pipe:
                pickle.dump(reply, pipe)
            status = 0
        finally:
            os._exit(status)
    os.close(write)
    return pid, read


def _join_helper(pid: int, read: int) -> None:
    """Wait for the helper of :func:`_fork_helper`; raise its error, if any."""
    with os.fdopen(read, "rb") as pipe:
        try:
            kind, value = pickle.load(pipe)
        except EOFError:
            kind, value = "error", _portable(RuntimeError(
                "the second figure process ended without drawing its figures"))
    os.waitpid(pid, 0)
    if kind == "error":
        raise value[0]


def _portable(err: BaseException) -> tuple[BaseException, str]:
    """Return ``err`` and its traceback in the drawing process, as text.

    An error that does not survive pickling is sent as a RuntimeError saying what it was.
    """
    text = "".join(traceback.format_exception(type(err), err, err.__traceback__))
    try:
        return pickle.loads(pickle.dumps(err)), text
    except Exception:  # any failure to pickle: its text instead
        return RuntimeError(f"{type(err).__name__}: {err}"), text


__all__ = ["COST", "FigureProcess", "can_fork", "share"]
