"""A live 3D view that your own control loop updates, served on 127.0.0.1.

::

    from dualarm_qp.viz import LiveView

    with LiveView(exp.task) as view:          # opens the page in your browser
        for ...:                              # your loop
            state = ...                       # anything with q_l, q_f, sigma (and t)
            view.update(state, status="optimal", scale=1.0)

The view is a small HTTP server in a thread of this process (no other process is
started): ``/`` is the same self-contained page as a run's animation, and ``/events``
streams each update to the page as a server-sent event. :meth:`LiveView.close` (or
leaving the ``with`` block) stops the server and ends every open stream.
"""

from __future__ import annotations

import json
import threading
import webbrowser
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from types import TracebackType
from typing import Any

from ..errors import InvalidInputError
from ..task.scene import DualArmTask
from .frames import sample_nodes
from .page import render_page
from .scene import describe_scene

#: How long a stream waits for an update before checking whether the view closed [s].
_POLL_S = 0.25


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    view: LiveView


class _Handler(BaseHTTPRequestHandler):
    server: _Server

    def log_message(self, format: str, *args: Any) -> None:
        """Log nothing (the default prints every request)."""

    def do_GET(self) -> None:
        """Serve the page at ``/`` and the update stream at ``/events``."""
        view = self.server.view
        if self.path in ("/", "/index.html") or self.path.startswith("/#"):
            body = view.page.encode("utf-8")
            self.send_response(200)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)
        elif self.path == "/events":
            self.send_response(200)
            self.send_header("Content-Type", "text/event-stream")
            self.send_header("Cache-Control", "no-cache")
            self.end_headers()
            view._stream(self.wfile)
        else:
            self.send_error(404)


class LiveView:
    """A browser view of a task that follows the states you give it.

    Parameters
    ----------
    task : DualArmTask
        Arms, object and path to draw (``Experiment.task``).
    port : int, keyword-only
        Port on 127.0.0.1; 0 (default) picks a free one.
    open_browser : bool, keyword-only
        Open the page in the default web browser.
    title : str, keyword-only
        Shown on the page.
    path_span : (float, float), optional, keyword-only
        Path times [s] of ``D(t)`` drawn as a line; default the trajectory's own span.

    Attributes
    ----------
    url : str
        The page's address, ``http://127.0.0.1:PORT/``.
    """

    def __init__(self, task: DualArmTask, *, port: int = 0, open_browser: bool = True,
                 title: str = "dualarm_qp live view",
                 path_span: tuple[float, float] | None = None) -> None:
        self.task = task
        t0, t1 = path_span if path_span is not None else (task.trajectory.t0,
                                                          task.trajectory.tf)
        scene = describe_scene(task, t_start=t0, t_end=t1, title=title)
        self.page = render_page({"scene": scene, "frames": None}, title=title, live=True)
        self._samples: list[str] = []
        self._cond = threading.Condition()
        self._closed = False
        self._server = _Server(("127.0.0.1", port), _Handler)
        self._server.view = self
        self._thread = threading.Thread(target=self._server.serve_forever,
                                        name="dualarm-live-view", daemon=True)
        self._thread.start()
        self.url = f"http://127.0.0.1:{self._server.server_address[1]}/"
        if open_browser:
            webbrowser.open(self.url)

    # ------------------------------------------------------------------ updates
    def update(self, state: Any = None, *, q_l: Any = None, q_f: Any = None,
               grasp: float | None = None, t: float | None = None, status: str = "",
               scale: float | None = None) -> None:
        """Show one more sample.

        Parameters
        ----------
        state : object, optional
            Anything with ``q_l``, ``q_f`` [rad], ``sigma`` [m] and ``t`` [s]
            attributes (a :class:`~dualarm_qp.step.build.DualArmState`); the keywords
            override its values.
        q_l, q_f : array_like, keyword-only
            Leader and follower joints [rad].
        grasp : float, keyword-only
            Follower grasp coordinate [m].
        t : float, keyword-only
            Time of the sample [s] (default: one more than the last sample's).
        status : str, keyword-only
            Shown in the readout (e.g. the step status).
        scale : float, keyword-only
            Task scale shown in the readout.

        Raises
        ------
        InvalidInputError
            Joints or grasp missing or of the wrong size, or the view is closed.
        """
        if self._closed:
            raise InvalidInputError("the live view is closed")
        q_l = q_l if q_l is not None else getattr(state, "q_l", None)
        q_f = q_f if q_f is not None else getattr(state, "q_f", None)
        grasp = grasp if grasp is not None else getattr(state, "sigma", None)
        t = t if t is not None else getattr(state, "t", None)
        if q_l is None or q_f is None or grasp is None:
            raise InvalidInputError("update needs q_l, q_f and grasp (or a state with "
                                    "q_l, q_f and sigma)")
        q_l = self.task.leader.check_q(q_l, "q_l")
        q_f = self.task.follower.check_q(q_f, "q_f")
        if t is None:
            t = float(len(self._samples))
        s = sample_nodes(self.task, q_l, q_f, float(grasp),
                         float(getattr(state, "sigma_leader", 0.0)))
        nodes = [v for arm in s["arms"] for pose in arm for v in pose] + s["object"]
        event = json.dumps({"t": [float(t)], "path_t": [float(t)], "grasp": [float(grasp)],
                            "scale": [None if scale is None else float(scale)],
                            "status": [str(status)], "nodes": nodes,
                            "limits": s["limits"][0] + s["limits"][1],
                            "grasp_local": s["grasp_local"], **_nearest_event(s)},
                           separators=(",", ":"))
        with self._cond:
            self._samples.append(event)
            self._cond.notify_all()

    @property
    def samples(self) -> int:
        """How many samples were given so far."""
        return len(self._samples)

    def _stream(self, wfile: Any) -> None:
        """Send every sample, then each new one, until the view closes or the page goes."""
        sent = 0
        try:
            while True:
                with self._cond:
                    while sent == len(self._samples) and not self._closed:
                        self._cond.wait(_POLL_S)
                    if self._closed:
                        wfile.write(b"event: close\ndata: \n\n")
                        wfile.flush()
                        return
                    fresh = self._samples[sent:]
                for event in fresh:
                    wfile.write(f"data: {event}\n\n".encode())
                wfile.flush()
                sent += len(fresh)
        except (BrokenPipeError, ConnectionResetError):
            return  # the page was closed

    # ------------------------------------------------------------------ lifetime
    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return self._closed

    def close(self) -> None:
        """Stop the server and end the streams (idempotent)."""
        if self._closed:
            return
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        self._server.shutdown()
        self._server.server_close()
        self._thread.join()

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"LiveView({self.url}, {'closed' if self._closed else 'open'})"


def open_live_view(task: DualArmTask, **options: Any) -> LiveView:
    """Open a :class:`LiveView` of ``task`` (the same keywords); close it when done."""
    return LiveView(task, **options)


def _nearest_event(sample: dict[str, Any]) -> dict[str, Any]:
    """Return the nearest pair of a sample as event fields (none without a collision scene)."""
    if "nearest" not in sample:
        return {}
    n = sample["nearest"]
    if n is None:
        return {"near_pair": [-1], "near_distance": [None], "near": [None]}
    return {"near_pair": [n.pair], "near_distance": [n.distance],
            "near": [[*map(float, n.point_a), *map(float, n.point_b)]]}
