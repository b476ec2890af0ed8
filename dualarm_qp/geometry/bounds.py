"""A shape's bounding capsule, and the distance from a point to a shape."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .shapes import Box, Capsule

FloatArray = NDArray[np.float64]


def bounding_capsule(shape: Capsule | Box) -> tuple[FloatArray, FloatArray, float]:
    """Return a capsule containing ``shape``, in the shape's frame: (a, b, radius)."""
    if isinstance(shape, Capsule):
        return shape.a, shape.b, shape.radius
    h = shape.half_size
    k = int(np.argmax(h))
    axis = shape.pose[:3, k] * h[k]
    c = shape.centre
    return c - axis, c + axis, float(np.sqrt(max(float(h @ h) - h[k] ** 2, 1e-24)))


def distance_to_point(shape: Capsule | Box, point: FloatArray) -> float:
    """Distance [m] from ``point`` to ``shape`` (0 inside)."""
    if isinstance(shape, Capsule):
        ab = shape.b - shape.a
        denom = float(ab @ ab)
        t = 0.0 if denom == 0.0 else min(max(float((point - shape.a) @ ab) / denom, 0.0), 1.0)
        return max(float(np.linalg.norm(point - (shape.a + t * ab))) - shape.radius, 0.0)
    local = shape.pose[:3, :3].T @ (point - shape.pose[:3, 3])
    return float(np.linalg.norm(np.maximum(np.abs(local) - shape.half_size, 0.0)))


__all__ = ["bounding_capsule", "distance_to_point"]
