"""What a view shows and from where: the one rule every renderer and the movie orbit use.

Pure numpy (no ``bpy``). Conventions follow :mod:`brainpainter.rendering.views`: RAS
coordinates, ``azimuth`` counter-clockwise from +x seen from above,
``elevation`` above the horizontal plane. The image's up is superior (+z),
except straight from above or below, where it is anterior (+y).

A renderer gets, per view, the parts to draw (:func:`shows`) and an
orthographic :class:`CameraPose` (:func:`frame`); :func:`view_projection`
turns the pose into the 4x4 matrix that maps RAS millimetres to clip space
(OpenGL conventions), so every renderer puts a point on the same pixel.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.rendering.views import View

#: Free space around the framed objects, as a fraction of their extent.
MARGIN = 0.04
_POLE_TOLERANCE = 1e-6
#: Kinds of scene part: cortex of one hemisphere, all subcortical structures, one glass hull, the
#: white-matter tracts of one hemisphere (or the commissural and midline ones: hemi None), the flat
#: map of one hemisphere (drawn unlit, by flat views only), a connectome's nodes and its edges.
PART_KINDS = ("cortex", "subcortical", "glass", "tract", "flat", "node", "edge", "blob")
#: Least depth a camera frames, millimetres: a flat map (no depth) keeps its borders, lifted off it, in view.
MIN_DEPTH = 1.0


#: Kinds of parts that lie inside the cortex (tracts, a connectome's nodes and edges, a volume's blobs):
#: drawn where tracts are.
INSIDE = ("tract", "node", "edge", "blob")
#: A connectome's parts: drawn by every view of a cortex (over it, opaque or glass), a lateral or medial
#: view only its hemisphere's nodes and the edges between them (nilearn's ``l``/``r`` display modes), a
#: view of both hemispheres (dorsal) all, the edges between the hemispheres too (`hemi` None).
CONNECTOME_KINDS = ("node", "edge")


def shows(view: View, kind: str, hemi: str | None, cortex: str = "opaque") -> bool:
    """Whether `view` draws the part of this kind (and hemisphere).

    ``cortex`` views draw the cortex of ``view.hemis``; ``subcortical`` views
    draw every subcortical structure; both draw the glass hulls of ``view.glass``.
    Tracts: ``subcortical`` views draw all of them (inside the glass brain);
    ``cortex`` views draw those of ``view.hemis`` and the commissural ones
    (`hemi` None) when the cortex is drawn as glass or hidden, and none under
    an opaque cortex (it hides them; the other hemisphere's would stand in
    front of a medial wall). A connectome's nodes and edges: ``cortex`` views
    draw those of ``view.hemis`` (over the cortex, see :data:`CONNECTOME_KINDS`),
    and those between hemispheres (`hemi` None) in views of both. ``flat`` views draw the flat maps of
    ``view.hemis`` and nothing else; no other view draws a flat map.

    Parameters
    ----------
    view : View
    kind : {"cortex", "subcortical", "glass", "tract", "flat", "node", "edge", "blob"}
        Nodes and edges: see :data:`CONNECTOME_KINDS`; blobs are drawn as tracts are.
    hemi : {"lh", "rh"} or None
        None for the subcortical part and for commissural tracts.
    cortex : {"opaque", "glass", "hull", "hidden"}
        How cortex views draw the cortex (``RenderSettings.cortex``, resolved:
        :attr:`brainpainter.rendering.geometry.SceneGeometry.cortex`); ``glass``
        draws it (as glass: :meth:`~brainpainter.rendering.geometry.SceneGeometry.visible`),
        ``hull`` draws the glass hulls of ``view.hemis`` instead, ``hidden`` neither.
    """
    if view.content == "flat" or kind == "flat":
        return view.content == "flat" and kind == "flat" and hemi in view.hemis
    if kind == "glass":
        return hemi in view.glass or (cortex == "hull" and view.content == "cortex" and hemi in view.hemis)
    if view.clip and view.content == "cortex" and (kind in INSIDE or kind == "subcortical"):
        return True
    if kind in INSIDE:
        if view.content == "subcortical":
            return True
        if kind in CONNECTOME_KINDS:  # drawn over the cortex; a view of one hemisphere shows its own
            return hemi in view.hemis or (hemi is None and len(view.hemis) > 1)
        return cortex != "opaque" and (hemi is None or hemi in view.hemis)
    if view.content == "subcortical":
        return kind == "subcortical"
    return kind == "cortex" and hemi in view.hemis and cortex not in ("hidden", "hull")


@dataclass(frozen=True)
class CameraPose:
    """Where an orthographic camera sits and what it sees.

    Attributes
    ----------
    location : ndarray of float, shape (3,)
    rotation : ndarray of float, shape (3, 3)
        Columns: image right, image up, and the viewing direction reversed
        (``back``, from the target towards the camera).
    ortho_scale : float
        Width of the visible rectangle in scene units (millimetres).
    clip_start, clip_end : float
        Distances along the viewing direction that bound the drawn depth.
    """

    location: NDArray[Any]
    rotation: NDArray[Any]
    ortho_scale: float
    clip_start: float
    clip_end: float

    @property
    def right(self) -> NDArray[Any]:
        return self.rotation[:, 0]

    @property
    def up(self) -> NDArray[Any]:
        return self.rotation[:, 1]

    @property
    def back(self) -> NDArray[Any]:
        return self.rotation[:, 2]


def view_axes(azimuth: float, elevation: float) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any]]:
    """Camera axes for a viewing direction.

    Parameters
    ----------
    azimuth, elevation : float
        Degrees, as in :class:`~brainpainter.rendering.views.View`.

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


def extent(points: NDArray[Any], azimuth: float, elevation: float, aspect: float) -> float:
    """Width the camera must see to hold `points` from this direction (before margin and zoom).

    Parameters
    ----------
    points : ndarray of float, shape (n, 3)
    azimuth, elevation : float
        Degrees.
    aspect : float
        Image width / height.
    """
    right, up, _ = view_axes(azimuth, elevation)
    pts = np.asarray(points, dtype=float)
    u, v = pts @ right, pts @ up
    return max(float(np.ptp(u)), 1e-6, float(np.ptp(v)) * aspect)


def views_aspect(points: NDArray[Any], views: list[tuple[float, float]], lo: float = 0.75,
                 hi: float = 2.0) -> float:
    """Image width / height that frames `points` from these directions: the geometric mean of each
    direction's (width / height) of the points, between `lo` and `hi`.

    Parameters
    ----------
    points : ndarray of float, shape (n, 3)
        RAS millimetres.
    views : list of (float, float)
        Azimuth and elevation of each view, degrees.
    """
    pts = np.asarray(points, dtype=float)
    shapes = []
    for azimuth, elevation in views:
        right, up, _ = view_axes(azimuth, elevation)
        shapes.append(max(float(np.ptp(pts @ right)), 1e-6) / max(float(np.ptp(pts @ up)), 1e-6))
    return float(np.clip(np.exp(np.mean(np.log(shapes))), lo, hi)) if shapes else 4 / 3


def _along(points: NDArray[Any], axis: NDArray[Any]) -> NDArray[Any]:
    """``points @ axis`` element-wise, shape (n,): a BLAS product wakes OpenBLAS's worker thread, which
    then spins a core for a while (more CPU than the product itself, for each view a figure frames)."""
    out: NDArray[Any] = points[:, 0] * axis[0] + points[:, 1] * axis[1] + points[:, 2] * axis[2]
    return out


def frame(points: NDArray[Any], azimuth: float, elevation: float, zoom: float,
          aspect: float, margin: float = MARGIN) -> CameraPose:
    """Frame `points` tightly in an orthographic view.

    Parameters
    ----------
    points : ndarray of float, shape (n, 3)
        Vertices (or convex-hull vertices) of the visible parts.
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
    u, v, w = (_along(pts, axis) for axis in (right, up, back))
    (u0, u1), (v0, v1), (w0, w1) = (u.min(), u.max()), (v.min(), v.max()), (w.min(), w.max())
    width = max(u1 - u0, 1e-6) * (1 + 2 * margin)
    height = max(v1 - v0, 1e-6) * (1 + 2 * margin)
    scale = max(width, height * aspect) / zoom
    depth = max(w1 - w0, MIN_DEPTH)
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


def view_projection(pose: CameraPose, aspect: float) -> NDArray[Any]:
    """The 4x4 matrix from RAS millimetres to OpenGL clip space for `pose`.

    x_clip = -1 is the image's left edge, y_clip = +1 its top edge, and depth
    runs from -1 (``clip_start``) to +1 (``clip_end``).

    Parameters
    ----------
    pose : CameraPose
    aspect : float
        Image width / height.

    Returns
    -------
    ndarray of float64, shape (4, 4)
        Row-major; apply as ``M @ [x, y, z, 1]``.
    """
    view = np.eye(4)
    view[:3, :3] = pose.rotation.T
    view[:3, 3] = -pose.rotation.T @ pose.location
    half_w = pose.ortho_scale / 2.0
    half_h = half_w / aspect
    near, far = pose.clip_start, pose.clip_end
    proj = np.diag([1.0 / half_w, 1.0 / half_h, -2.0 / (far - near), 1.0])
    proj[2, 3] = -(far + near) / (far - near)
    return proj @ view


def to_pixels(points: NDArray[Any], pose: CameraPose, width: int, height: int) -> NDArray[Any]:
    """Pixel coordinates ``(column, row)`` of RAS points, row 0 at the top.

    Parameters
    ----------
    points : ndarray of float, shape (n, 3)
    pose : CameraPose
    width, height : int

    Returns
    -------
    ndarray of float, shape (n, 2)
    """
    m = view_projection(pose, width / height)
    pts = np.asarray(points, dtype=float)
    clip = pts @ m[:3, :3].T + m[:3, 3]
    col = (clip[:, 0] + 1.0) / 2.0 * width
    row = (1.0 - clip[:, 1]) / 2.0 * height
    return np.column_stack([col, row])
