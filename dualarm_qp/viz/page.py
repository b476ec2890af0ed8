"""The HTML page of the 3D view: one self-contained file, no network request.

The page inlines MeshCat's viewer bundle (three.js with orbit controls, shipped in the
``meshcat`` wheel), our player script (``player.js`` beside this module) and the scene
and samples as JSON. A Content-Security-Policy forbids every request but the live
view's own event stream, so an animation cannot reach out even by accident. An early
script records uncaught errors, ``console.error`` calls and blocked requests; the
page writes them, the number of requests made, the arms' box on screen and what it
shows of a collision scene (obstacles, collision shapes, the nearest pair) into
``#dualarm-status`` (read by the browser test).
"""

from __future__ import annotations

import html
import json
import re
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import DualArmError

#: Where the MeshCat viewer bundle lies inside the ``meshcat`` package.
_BUNDLE = ("viewer", "dist", "main.min.js")

_ERROR_HOOK = """
window.__dualarm = {errors: []};
(function () {
  const errs = window.__dualarm.errors;
  window.addEventListener("error", (e) => errs.push("error: " + (e.message ||
    (e.target && (e.target.src || e.target.href)) || e.type)), true);
  window.addEventListener("unhandledrejection", (e) => errs.push("rejection: " + e.reason));
  document.addEventListener("securitypolicyviolation",
    (e) => errs.push("blocked: " + e.blockedURI + " (" + e.violatedDirective + ")"));
  const original = console.error;
  console.error = function (...args) {
    errs.push("console: " + args.join(" "));
    original.apply(console, args);
  };
})();
"""

_STYLE = """
html, body { margin: 0; height: 100%; overflow: hidden; font: 13px/1.35 system-ui, sans-serif; }
#view { position: absolute; left: 0; top: 0; right: 0; bottom: 92px; }
#panel { position: absolute; left: 0; right: 0; bottom: 0; height: 92px; box-sizing: border-box;
         padding: 6px 12px; background: #f4f4f4; border-top: 1px solid #ccc; }
#title { font-weight: 600; }
.row { display: flex; gap: 10px; align-items: center; margin-top: 4px; }
#scrub { flex: 1; }
#readout span { font-variant-numeric: tabular-nums; }
#notes { color: #a04000; }
.legend i { display: inline-block; width: 10px; height: 10px; margin: 0 3px 0 8px; }
.legend i.axis { width: 4px; height: 12px; vertical-align: -1px; }
.dg { display: none !important; }
#dualarm-errors { display: none; }
body.collision #view { bottom: 118px; } body.collision #panel { height: 118px; }
#collision-row[hidden] { display: none; }
#near-label { position: absolute; pointer-events: none; padding: 1px 5px; border-radius: 3px;
              background: rgba(255, 255, 255, 0.85); color: #a0005a; font-weight: 600;
              white-space: nowrap; transform: translate(8px, -50%); }
"""

_BODY = """
<div id="view"></div>
<div id="panel">
  <div class="row"><span id="title"></span>
    <span class="legend"><i style="background:#3b6fb6"></i>leader<i style="background:#c9832f">
    </i>follower<i style="background:#2ca02c"></i>grasp range<i style="background:#d62728"></i>
    grasp<i style="background:#7b2cbf"></i>path D(t)<i class="axis" style="background:#333333">
    </i>joint axis:<i class="axis" style="background:#ffb000"></i>near a limit<i class="axis"
    style="background:#e00000"></i>outside its range</span>
    <label title="Off: only the axes of joints near a limit or outside their range">
    <input type="checkbox" id="all-axes"> every joint axis</label>
    <span id="notes"></span></div>
  <div class="row"><button id="play">Pause</button>
    <input id="scrub" type="range" min="0" max="0" step="1" value="0" aria-label="time">
    <label>speed <select id="speed"><option value="0.25">0.25x</option>
      <option value="0.5">0.5x</option><option value="1" selected>1x</option>
      <option value="2">2x</option><option value="4">4x</option></select></label></div>
  <div class="row" id="readout">t <span id="r-t"></span> s | path t <span id="r-path"></span>
    s | grasp <span id="r-grasp"></span> mm | status <span id="r-status"></span> |
    task scale <span id="r-scale"></span> | <span id="r-limits"></span></div>
  <div class="row" id="collision-row" hidden>
    <span class="legend">collision:<i id="legend-obstacle"></i>obstacle<i
    id="legend-nearest"></i>nearest pair within d_i</span>
    <label title="The capsules and boxes the collision check measures, of the links and the
    object"><input type="checkbox" id="shapes"> collision shapes</label>
    <span>| nearest pair <span id="r-clearance"></span></span></div>
</div>
<div id="near-label" hidden></div>
<div id="dualarm-status" hidden></div>
<pre id="dualarm-errors"></pre>
"""


@cache
def viewer_bundle() -> str:
    """Return the MeshCat viewer bundle (JavaScript, about 0.85 MB).

    Raises
    ------
    DualArmError
        meshcat is not installed or its bundle is missing.
    """
    import importlib.util

    spec = importlib.util.find_spec("meshcat")  # found, not imported: no server code runs
    if spec is None or not spec.submodule_search_locations:
        raise DualArmError("the 3D view needs meshcat: pip install meshcat")
    path = Path(next(iter(spec.submodule_search_locations))).joinpath(*_BUNDLE)
    try:
        return path.read_text(encoding="utf-8")
    except OSError as err:
        raise DualArmError(f"meshcat's viewer bundle is missing ({path}: "
                           f"{err.strerror}); reinstall meshcat") from None


@cache
def player_script() -> str:
    """Return our player script (``player.js``)."""
    return (resources.files(__package__) / "player.js").read_text(encoding="utf-8")


def _inline(text: str) -> str:
    """Return ``text`` safe inside a ``<script>`` element (no ``</script`` or ``<!--`` in it)."""
    return re.sub(r"<(/script|!--)", r"<\\\1", text, flags=re.IGNORECASE)


def render_page(data: dict[str, Any], *, title: str, live: bool = False) -> str:
    """Return the whole HTML page.

    Parameters
    ----------
    data : dict
        ``{"scene": ..., "frames": ... or None}`` (:func:`~dualarm_qp.viz.scene.
        describe_scene`, :func:`~dualarm_qp.viz.frames.frame_payload`).
    title : str
        The page title.
    live : bool
        Follow samples streamed from the serving process (the live view).
    """
    connect = "'self'" if live else "'none'"
    policy = ("default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
              f"img-src data: blob:; connect-src {connect}; worker-src blob:")
    payload = json.dumps({**data, "live": live}, separators=(",", ":"), allow_nan=False)
    payload = payload.replace("<", "\\u003c")  # no markup can end the element early
    return "\n".join([
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f'<meta http-equiv="Content-Security-Policy" content="{policy}">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(title)}</title>",
        f"<style>{_STYLE}</style>",
        f"<script>{_ERROR_HOOK}</script>",
        "</head><body>",
        _BODY,
        f"<script>{_inline(viewer_bundle())}</script>",
        f'<script id="dualarm-data" type="application/json">{payload}</script>',
        f"<script>{_inline(player_script())}</script>",
        "</body></html>",
    ])
