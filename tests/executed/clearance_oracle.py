"""Independent signed distances between capsules and boxes, for the clearance checks.

Written from the definitions alone; it shares no code with ``dualarm_qp.geometry`` nor
with coal, and it uses other methods than either:

* **segment to segment**: the distance from the point ``p0 + s d1`` to the segment
  ``[q0, q1]`` is a convex function of ``s`` (the distance to a convex set, along a
  line); its minimum over ``s`` in [0, 1] is found by golden-section search
  (:data:`GOLDEN_ITERATIONS` steps shrink the bracket below 1e-18), the inner distance
  being the exact clamped projection onto ``[q0, q1]``. The search result is then
  refined by two exact 1-D clamped solves (best ``t`` for ``s``, best ``s`` for ``t``)
  and the smallest value kept.
* **segment to box, apart**: the distance from ``p0 + s d1`` to the box (the point
  clamped into the box in the box's frame) is convex in ``s`` too: the same search.
* **box to box, apart**: the closest points of two boxes can always be taken with one
  of them on an edge of one box (vertex-face, edge-edge and face-face contacts all have
  such a pair), so the distance is the smallest segment-to-box distance of the 24 edges.
* **overlapping** (segment or box meets the box): the penetration depth by separating
  axes. The sets are zonotopes (a box, a segment) whose Minkowski difference has facet
  normals the box axes and the cross products of the generators (the segment's
  direction with each box axis; for two boxes the 15 axes of both), so the largest
  separation along those axes is minus the penetration depth.
* **capsule** = segment swept by a ball: the signed distance of the segment minus the
  radius (for capsule pairs, minus both radii), for apart and overlapping shapes alike.

Every function is vectorised over a leading axis of k shapes (arrays (k, 3), (k,)).
Lengths in m. Accuracy at metre scale: within 2e-15 m of exact rational arithmetic
(segments) and of coal (boxes) on the random shapes tried while writing it;
``test_clearance_oracle.py`` asserts known answers to 1e-12 m and agreement with the
library to 1e-9 m.
"""

from __future__ import annotations

import numpy as np

#: Below this distance [m] (rounding of the clamped distance) a segment meets a box.
TOUCH = 1e-12
#: Golden-section steps: the bracket shrinks by 0.618 per step (0.618**90 ~ 1e-19).
GOLDEN_ITERATIONS = 90
_INV_PHI = (np.sqrt(5.0) - 1.0) / 2.0


def _norm(v: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("...i,...i->...", v, v))


def point_segment(P: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Distance from points ``P`` (k, 3) to segments ``[q0, q1]`` (k, 3): exact clamp."""
    d = q1 - q0
    e = np.einsum("ki,ki->k", d, d)
    t = np.einsum("ki,ki->k", P - q0, d) / np.where(e > 0.0, e, 1.0)
    t = np.clip(t, 0.0, 1.0)
    return _norm(P - q0 - t[:, None] * d)


def point_box(P: np.ndarray, centre: np.ndarray, R: np.ndarray,
              half: np.ndarray) -> np.ndarray:
    """Distance from points (k, 3) to boxes (centre (k, 3), axes R (k, 3, 3) as columns,
    half sizes (k, 3)); 0 inside: the point clamped into the box in its own frame."""
    local = np.einsum("kji,kj->ki", R, P - centre)
    return _norm(np.maximum(np.abs(local) - half, 0.0))


def _golden_min(f, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Minimise the convex functions ``f(s)`` (s: (k,) in [0, 1], returns (k,)) jointly.

    Returns the minimising ``s`` and the smallest value seen (ends of [0, 1] included).
    """
    lo, hi = np.zeros(k), np.ones(k)
    x1 = hi - _INV_PHI * (hi - lo)
    x2 = lo + _INV_PHI * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(GOLDEN_ITERATIONS):
        left = f1 <= f2                   # the minimum lies in [lo, x2]
        hi = np.where(left, x2, hi)
        lo = np.where(left, lo, x1)
        nx1 = np.where(left, hi - _INV_PHI * (hi - lo), x2)
        nx2 = np.where(left, x1, lo + _INV_PHI * (hi - lo))
        # One new evaluation per step: reuse the kept inner point's value.
        fnew = f(np.where(left, nx1, nx2))
        f1, f2 = np.where(left, fnew, f2), np.where(left, f1, fnew)
        x1, x2 = nx1, nx2
    s = 0.5 * (lo + hi)
    at_0, at_1, at_s = f(np.zeros(k)), f(np.ones(k)), f(s)
    best = np.minimum.reduce([at_s, at_0, at_1])
    return np.where(at_0 <= best, 0.0, np.where(at_1 <= best, 1.0, s)), best


def segment_segment(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray,
                    q1: np.ndarray) -> np.ndarray:
    """Distance between segments ``[p0, p1]`` and ``[q0, q1]`` (each (k, 3)) [m]."""
    p0, p1, q0, q1 = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (p0, p1, q0, q1))
    d1, d2 = p1 - p0, q1 - q0
    k = p0.shape[0]

    def along(s: np.ndarray) -> np.ndarray:
        return point_segment(p0 + s[:, None] * d1, q0, q1)

    s, best = _golden_min(along, k)
    # Refine: the exact best t for s, then the exact best s for that t (clamped).
    e = np.einsum("ki,ki->k", d2, d2)
    a = np.einsum("ki,ki->k", d1, d1)
    P = p0 + s[:, None] * d1
    t = np.clip(np.einsum("ki,ki->k", P - q0, d2) / np.where(e > 0, e, 1.0), 0.0, 1.0)
    Q = q0 + t[:, None] * d2
    s2 = np.clip(np.einsum("ki,ki->k", Q - p0, d1) / np.where(a > 0, a, 1.0), 0.0, 1.0)
    refined = _norm(p0 + s2[:, None] * d1 - Q)
    return np.minimum(best, refined)


def _separation(lo_a: np.ndarray, hi_a: np.ndarray, lo_b: np.ndarray,
                hi_b: np.ndarray) -> np.ndarray:
    """Signed gap between intervals [lo_a, hi_a] and [lo_b, hi_b] (negative: overlap)."""
    return np.maximum(lo_b - hi_a, lo_a - hi_b)


def _unit_or_nan(v: np.ndarray) -> np.ndarray:
    n = _norm(v)
    out = np.full_like(v, np.nan)
    ok = n > 1e-9
    out[ok] = v[ok] / n[ok, None]
    return out


def segment_box_sat(p0: np.ndarray, p1: np.ndarray, centre: np.ndarray, R: np.ndarray,
                    half: np.ndarray) -> np.ndarray:
    """Largest separation of segments and boxes over their separating axes [m].

    Equal to the signed distance when they overlap (minus the penetration depth); a
    lower bound of the distance when apart.
    """
    d1 = p1 - p0
    axes = [R[:, :, i] for i in range(3)]
    axes += [_unit_or_nan(np.cross(d1, R[:, :, i])) for i in range(3)]
    best = np.full(p0.shape[0], -np.inf)
    for n in axes:
        ok = np.isfinite(n).all(axis=1)
        m = np.where(ok[:, None], n, 0.0)
        a0 = np.einsum("ki,ki->k", m, p0)
        a1 = np.einsum("ki,ki->k", m, p1)
        c = np.einsum("ki,ki->k", m, centre)
        w = np.einsum("ki,ki->k", np.abs(np.einsum("kji,kj->ki", R, m)), half)
        sep = _separation(np.minimum(a0, a1), np.maximum(a0, a1), c - w, c + w)
        best = np.where(ok, np.maximum(best, sep), best)
    return best


def segment_box(p0: np.ndarray, p1: np.ndarray, centre: np.ndarray, R: np.ndarray,
                half: np.ndarray) -> np.ndarray:
    """Signed distance between segments (k, 3) and boxes [m] (negative: overlap)."""
    p0, p1, centre = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (p0, p1, centre))
    R = np.asarray(R, dtype=float).reshape(-1, 3, 3)
    half = np.atleast_2d(np.asarray(half, dtype=float))
    d1 = p1 - p0

    def along(s: np.ndarray) -> np.ndarray:
        return point_box(p0 + s[:, None] * d1, centre, R, half)

    _, apart = _golden_min(along, p0.shape[0])
    inside = apart <= TOUCH      # meeting (to rounding): the depth by separating axes
    if inside.any():
        idx = np.flatnonzero(inside)
        apart = apart.copy()
        apart[idx] = np.minimum(0.0, segment_box_sat(p0[idx], p1[idx], centre[idx], R[idx],
                                                     half[idx]))
    return apart


def _box_edges(centre: np.ndarray, R: np.ndarray,
               half: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """The 12 edges of boxes (k of them) as segments, each (k, 3) endpoints."""
    edges = []
    for axis in range(3):
        others = [i for i in range(3) if i != axis]
        for sa in (-1.0, 1.0):
            for sb in (-1.0, 1.0):
                off = (sa * half[:, others[0], None] * R[:, :, others[0]]
                       + sb * half[:, others[1], None] * R[:, :, others[1]])
                ext = half[:, axis, None] * R[:, :, axis]
                edges.append((centre + off - ext, centre + off + ext))
    return edges


def box_box(ca: np.ndarray, Ra: np.ndarray, ha: np.ndarray, cb: np.ndarray, Rb: np.ndarray,
            hb: np.ndarray) -> np.ndarray:
    """Signed distance between boxes (k of each) [m] (negative: overlap)."""
    ca, cb, ha, hb = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (ca, cb, ha, hb))
    Ra = np.asarray(Ra, dtype=float).reshape(-1, 3, 3)
    Rb = np.asarray(Rb, dtype=float).reshape(-1, 3, 3)
    apart = np.full(ca.shape[0], np.inf)
    for (e0, e1) in _box_edges(ca, Ra, ha):
        apart = np.minimum(apart, segment_box(e0, e1, cb, Rb, hb))
    for (e0, e1) in _box_edges(cb, Rb, hb):
        apart = np.minimum(apart, segment_box(e0, e1, ca, Ra, ha))
    # segment_box is negative when an edge enters the other box; then the boxes overlap
    # (also when one box holds the other: its centre is inside) and only the axes count.
    overlap = (apart <= TOUCH) | (point_box(ca, cb, Rb, hb) <= 0.0)
    if overlap.any():
        idx = np.flatnonzero(overlap)
        axes = [Ra[idx][:, :, i] for i in range(3)] + [Rb[idx][:, :, i] for i in range(3)]
        axes += [_unit_or_nan(np.cross(Ra[idx][:, :, i], Rb[idx][:, :, j]))
                 for i in range(3) for j in range(3)]
        best = np.full(idx.size, -np.inf)
        for n in axes:
            ok = np.isfinite(n).all(axis=1)
            m = np.where(ok[:, None], n, 0.0)
            c_a = np.einsum("ki,ki->k", m, ca[idx])
            c_b = np.einsum("ki,ki->k", m, cb[idx])
            w_a = np.einsum("ki,ki->k", np.abs(np.einsum("kji,kj->ki", Ra[idx], m)), ha[idx])
            w_b = np.einsum("ki,ki->k", np.abs(np.einsum("kji,kj->ki", Rb[idx], m)), hb[idx])
            sep = _separation(c_a - w_a, c_a + w_a, c_b - w_b, c_b + w_b)
            best = np.where(ok, np.maximum(best, sep), best)
        apart = apart.copy()
        apart[idx] = np.minimum(0.0, best)
    return apart


# ---------------------------------------------------------------- placed shapes
class Placed:
    """Shapes placed in the world, k at a time, as plain arrays.

    ``kind`` is ``"capsule"`` (axis ``a``, ``b`` (k, 3) and ``radius`` (k,)) or ``"box"``
    (``centre`` (k, 3), axes ``R`` (k, 3, 3) as columns, ``half`` sizes (k, 3)).
    """

    def __init__(self, kind: str, **arrays: np.ndarray) -> None:
        self.kind = kind
        self.arrays = arrays

    @classmethod
    def concat(cls, shapes: list[Placed]) -> Placed:
        """The shapes of one kind stacked along the first axis (one vectorised call)."""
        kind = shapes[0].kind
        assert all(s.kind == kind for s in shapes)
        return cls(kind, **{key: np.concatenate([s.arrays[key] for s in shapes])
                            for key in shapes[0].arrays})

    def __getattr__(self, name: str) -> np.ndarray:
        try:
            return self.__dict__["arrays"][name]
        except KeyError:
            raise AttributeError(name) from None


def signed_distance(x: Placed, y: Placed) -> np.ndarray:
    """Signed distances (k,) between placed shapes ``x`` and ``y`` (k each) [m]."""
    if x.kind == "capsule" and y.kind == "capsule":
        return segment_segment(x.a, x.b, y.a, y.b) - x.radius - y.radius
    if x.kind == "capsule":
        return segment_box(x.a, x.b, y.centre, y.R, y.half) - x.radius
    if y.kind == "capsule":
        return segment_box(y.a, y.b, x.centre, x.R, x.half) - y.radius
    return box_box(x.centre, x.R, x.half, y.centre, y.R, y.half)
