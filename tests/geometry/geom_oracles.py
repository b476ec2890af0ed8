"""Independent distance oracles for the geometry tests (no code of the package).

* :func:`segment_distance_exact`: the minimum of ``|p0 + s d1 - q0 - t d2|`` over
  ``[0, 1]^2`` in exact rational arithmetic: the interior stationary point if it lies in
  the square, and the minimum of each of the four edges (a clamped 1-D quadratic).
* :func:`point_box_distance`: clamping a point into the box, in the box frame.
* :func:`segment_box_distance`, :func:`box_box_distance`: bounded least squares over
  the parameters of both sets (the distance when apart, zero when they meet).
* :func:`support_signed_distance`: the signed distance of two convex sets from their
  support functions, ``max over unit n of (-h_b(-n) - h_a(n))`` (the distance when
  apart, minus the penetration depth when overlapping), by dense sampling of the
  sphere and the separating axes of :func:`separating_axes` (where the maximum sits on a
  kink), refined with Nelder-Mead. Any direction gives a lower bound, so the oracle can
  only err low.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from scipy.optimize import lsq_linear, minimize


def segment_distance_exact(p0, p1, q0, q1) -> float:
    P0, P1, Q0, Q1 = ([Fraction(float(x)) for x in v] for v in (p0, p1, q0, q1))
    d1 = [y - x for x, y in zip(P0, P1, strict=True)]
    d2 = [y - x for x, y in zip(Q0, Q1, strict=True)]
    r = [x - y for x, y in zip(P0, Q0, strict=True)]

    def dot(u, v):
        return sum((x * y for x, y in zip(u, v, strict=True)), Fraction(0))

    a, e, b, c, f = dot(d1, d1), dot(d2, d2), dot(d1, d2), dot(d1, r), dot(d2, r)

    def clamp(x):
        return min(max(x, Fraction(0)), Fraction(1))

    def squared(s, t):
        g = [ri + s * x - t * y for ri, x, y in zip(r, d1, d2, strict=True)]
        return dot(g, g)

    candidates = []
    det = a * e - b * b
    if det != 0:  # stationary point: a s - b t = -c, b s - e t = -f
        s, t = (b * f - c * e) / det, (a * f - b * c) / det
        if 0 <= s <= 1 and 0 <= t <= 1:
            candidates.append((s, t))
    for s in (Fraction(0), Fraction(1)):
        candidates.append((s, clamp((b * s + f) / e) if e else Fraction(0)))
    for t in (Fraction(0), Fraction(1)):
        candidates.append((clamp((b * t - c) / a) if a else Fraction(0), t))
    return float(min(squared(s, t) for s, t in candidates)) ** 0.5


def point_segment_distance(p, a, b) -> float:
    d = b - a
    dd = d @ d
    t = 0.0 if dd == 0 else min(max((p - a) @ d / dd, 0.0), 1.0)
    return float(np.linalg.norm(p - (a + t * d)))


def box_local(point, box):
    R, c = box.pose[:3, :3], box.pose[:3, 3]
    return R.T @ (point - c)


def point_box_distance(point, box) -> float:
    """Distance of a point outside (or on) a box; zero inside."""
    x = box_local(point, box)
    return float(np.linalg.norm(x - np.clip(x, -box.half_size, box.half_size)))


def _bounded_least_squares(A, target, lower, upper) -> float:
    res = lsq_linear(A, target, bounds=(lower, upper), method="bvls", tol=1e-14)
    return float(np.linalg.norm(A @ res.x - target))


def segment_box_distance(a, b, box) -> float:
    """min over t in [0, 1] and u in the box of |a + t (b - a) - (c + R u)| (bounded
    least squares): the distance of a segment from a box, zero if they meet."""
    R, c, h = box.pose[:3, :3], box.pose[:3, 3], box.half_size
    A = np.column_stack([b - a, -R])
    return _bounded_least_squares(A, c - a, np.r_[0.0, -h], np.r_[1.0, h])


def box_box_distance(box_a, box_b) -> float:
    """min over u in box a and v in box b of |c_a + R_a u - c_b - R_b v|, zero if they meet."""
    A = np.column_stack([box_a.pose[:3, :3], -box_b.pose[:3, :3]])
    target = box_b.pose[:3, 3] - box_a.pose[:3, 3]
    return _bounded_least_squares(A, target, np.r_[-box_a.half_size, -box_b.half_size],
                                  np.r_[box_a.half_size, box_b.half_size])


def capsule_support(cap):
    def h(n):
        return np.maximum(n @ cap.a, n @ cap.b) + cap.radius
    return h


def box_support(box):
    R, c = box.pose[:3, :3], box.pose[:3, 3]

    def h(n):
        return n @ c + np.abs(n @ R) @ box.half_size
    return h


def _directions(count: int) -> np.ndarray:
    i = np.arange(count) + 0.5
    phi = np.arccos(1.0 - 2.0 * i / count)
    theta = np.pi * (1.0 + 5.0**0.5) * i
    return np.column_stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi),
                            np.cos(phi)])


def separating_axes(*frames_and_axes) -> np.ndarray:
    """Candidate directions where the maximum may sit on a kink of the support functions
    (the separating-axis theorem): the given face normals and edge directions, and the
    cross products of every two of them, both signs."""
    axes = [np.asarray(v, dtype=float) for v in frames_and_axes]
    crosses = [np.cross(u, v) for i, u in enumerate(axes) for v in axes[i + 1:]]
    out = [v / np.linalg.norm(v) for v in axes + crosses if np.linalg.norm(v) > 1e-9]
    return np.array(out + [-v for v in out]).reshape(-1, 3)


def support_signed_distance(h_a, h_b, axes=None) -> float:
    def gap(n):
        return -h_b(-n) - h_a(n)

    dirs = _directions(20_000)
    if axes is not None:
        dirs = np.vstack([dirs, axes])
    values = gap(dirs)
    best = -np.inf
    for j in np.argsort(values)[-6:]:
        n0 = dirs[j]
        x0 = [np.arccos(np.clip(n0[2], -1.0, 1.0)), np.arctan2(n0[1], n0[0])]

        def neg(x):
            n = np.array([np.sin(x[0]) * np.cos(x[1]), np.sin(x[0]) * np.sin(x[1]),
                          np.cos(x[0])])
            return -float(gap(n[None])[0])

        res = minimize(neg, x0, method="Nelder-Mead",
                       options={"xatol": 1e-13, "fatol": 1e-15, "maxiter": 4000})
        best = max(best, -res.fun, values[j])
    return float(best)
