"""3D views of the dual-arm task: a run's animation as one offline HTML file, and a live view.

- :func:`write_animation`: the animation of a recorded run (``dualarm-qp run
  --animate``; for a finished run folder, ``dualarm-qp animate RUN_DIR`` and
  :func:`dualarm_qp.experiments.animate.animate_run`);
- :class:`LiveView`: a browser view on ``127.0.0.1`` that your own control loop
  updates every step.

Both draw with three.js from MeshCat's viewer bundle, inlined in the page; nothing is
imported until first used, so ``import dualarm_qp`` stays light.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .animation import animation_html, write_animation
    from .live import LiveView, open_live_view

__all__ = ["LiveView", "animation_html", "open_live_view", "write_animation"]

_WHERE = {"LiveView": "live", "open_live_view": "live",
          "animation_html": "animation", "write_animation": "animation"}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        from importlib import import_module

        return getattr(import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
