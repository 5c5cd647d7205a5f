"""Orthographic camera placement from a :class:`~brainpainter.views.View`.

Pure numpy (no ``bpy``), so the geometry is testable without Blender.

Conventions follow :mod:`brainpainter.views`: RAS coordinates, ``azimuth``
counter-clockwise from +x seen from above, ``elevation`` above the horizontal
plane. The image's up is superior (+z), except straight from above or below,
where it is anterior (+y). A Blender camera looks down its local -z axis with
local +y as the image's up, so its rotation matrix has the columns
``(right, up, back)``, where ``back`` points from the target to the camera.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Free space around the framed objects, as a fraction of their extent.
MARGIN = 0.04
_POLE_TOLERANCE = 1e-6


@dataclass(frozen=True)
class CameraPose:
    """Where an orthographic camera sits and what it sees.

    Attributes
    ----------
    location : ndarray of float, shape (3,)
    rotation : ndarray of float, shape (3, 3)
        Columns: image right, image up, and the viewing direction reversed.
    ortho_scale : float
        Width of the visible rectangle in scene units (Blender's
        ``ortho_scale`` with ``sensor_fit = "HORIZONTAL"``).
    clip_start, clip_end : float
    """

    location: np.ndarray
    rotation: np.ndarray
    ortho_scale: float
    clip_start: float
    clip_end: float


def view_axes(azimuth: float, elevation: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Camera axes for a viewing direction.

    Parameters
    ----------
    azimuth, elevation : float
        Degrees, as in :class:`~brainpainter.views.View`.

    Returns
    -------
    right, up, back : ndarray of float, shape (3,)
        Orthonormal, right-handed (``right x up = back``); ``back`` points from
        the brain towards the camera.
    """
    az, el = np.radians(azimuth), np.radians(elevation)
    back = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    if abs(np.cos(el)) < _POLE_TOLERANCE:
        hint = np.array([0.0, 1.0, 0.0])
        back = np.array([0.0, 0.0, np.sign(np.sin(el))])
    else:
        hint = np.array([0.0, 0.0, 1.0])
    forward = -back
    right = np.cross(forward, hint)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return right, up, back


def frame(points: np.ndarray, azimuth: float, elevation: float, zoom: float,
          aspect: float, margin: float = MARGIN) -> CameraPose:
    """Frame `points` tightly in an orthographic view.

    Parameters
    ----------
    points : ndarray of float, shape (n, 3)
        Vertices (or bounding-box corners) of the visible objects.
    azimuth, elevation : float
        Degrees.
    zoom : float
        > 1 magnifies (the visible rectangle shrinks by this factor).
    aspect : float
        Image width / height.
    margin : float
        Free space on each side, as a fraction of the framed extent.

    Returns
    -------
    CameraPose
    """
    right, up, back = view_axes(azimuth, elevation)
    pts = np.asarray(points, dtype=float)
    u, v, w = pts @ right, pts @ up, pts @ back
    (u0, u1), (v0, v1), (w0, w1) = (u.min(), u.max()), (v.min(), v.max()), (w.min(), w.max())
    width = max(u1 - u0, 1e-6) * (1 + 2 * margin)
    height = max(v1 - v0, 1e-6) * (1 + 2 * margin)
    scale = max(width, height * aspect) / zoom
    depth = max(w1 - w0, 1e-3)
    centre = right * (u0 + u1) / 2 + up * (v0 + v1) / 2
    # Sit one depth beyond the nearest point so nothing is clipped.
    location = centre + back * (w1 + depth)
    return CameraPose(
        location=location,
        rotation=np.column_stack([right, up, back]),
        ortho_scale=float(scale),
        clip_start=float(depth * 0.5),
        clip_end=float(depth * 3.0),
    )
