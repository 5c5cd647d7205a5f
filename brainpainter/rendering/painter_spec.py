"""What a worker process needs to build a run's painter: :class:`PainterSpec` (names and small values)."""

from __future__ import annotations

import hashlib
import importlib
import os
import pickle
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from brainpainter.errors import BrainPainterError
from brainpainter.rendering.painter import Painter

if TYPE_CHECKING:
    from brainpainter.rendering.settings import RGB, RenderSettings


@dataclass(frozen=True)
class PainterSpec:
    """How to build a run's :class:`~brainpainter.rendering.painter.Painter` in another process.

    Names and small values only: the worker loads the template itself.

    Attributes
    ----------
    atlas : Atlas or str
    template : str
        A template name or folder (which a remote worker must see at the same path).
    surface : str
    hidden : tuple of str
        ``--hide`` tokens.
    settings : RenderSettings
    renderer : str
        Name in the ``brainpainter.renderers`` registry.
    renderer_target : str or None
        ``"module:Class"`` of the renderer, registered under `renderer` in a
        worker that does not know that name (a renderer registered at run time).
    medial_wall_color : (float, float, float)
    coloring : {"regions", "vertices"}
    contours : Contours, optional
        A second map's iso-lines (its values travel with the spec: about 1.3 MB for both hemispheres).
    layers : tuple of PartsLayer
        Pickled with the spec: the tracts' (their paths and options: each worker reads them and draws
        the same subsample), a connectome's (400 nodes: about 1.3 MB of weights), the blobs (a few
        hundred kB), plugin layers (``--layer``).
    """

    atlas: Any
    template: str
    surface: str
    hidden: tuple[str, ...]
    settings: RenderSettings
    renderer: str
    renderer_target: str | None
    medial_wall_color: RGB
    coloring: str = "regions"
    contours: Any = None
    layers: tuple[Any, ...] = ()

    @classmethod
    def of(cls, painter: Painter, template: Any = None) -> PainterSpec:
        """The spec of a (not yet loaded) painter; `template` is what the caller gave (a name or a folder)."""
        from brainpainter.atlas import registry
        klass = registry.renderers.get(painter.renderer)
        qual = getattr(klass, "__qualname__", "")
        target = (f"{klass.__module__}:{qual}"
                  if isinstance(klass, type) and "<locals>" not in qual else None)
        return cls(
            atlas=painter.atlas,
            # a template name travels as a name (resolved by each worker); a folder as an absolute path
            template=(template if isinstance(template, str) and not os.path.exists(template)
                      else os.path.abspath(painter.scene.template.path)),
            surface=painter.surface, hidden=tuple(str(h) for h in painter.hidden),
            settings=painter.settings, renderer=painter.renderer, renderer_target=target,
            medial_wall_color=tuple(float(c) for c in painter.scene.medial_wall_color),  # type: ignore[arg-type]
            coloring=painter.scene.coloring, contours=painter.scene.contours, layers=tuple(painter.layers),
        )

    @property
    def token(self) -> str:
        """A short digest naming this spec (the Dask worker plugin's name)."""
        return hashlib.sha256(pickle.dumps(self)).hexdigest()[:16]

    def build(self) -> Painter:
        """Build the painter (not loaded), registering the renderer class if this process lacks it."""
        from brainpainter.atlas import registry

        if self.renderer_target is not None:
            module, _, attr = self.renderer_target.partition(":")
            try:
                obj: Any = importlib.import_module(module)
                for part in attr.split("."):
                    obj = getattr(obj, part)
            except (ImportError, AttributeError):
                obj = None  # not importable here: the registry's entry of that name, if any, is used
            try:
                current = registry.renderers.get(self.renderer)
            except BrainPainterError:
                current = None
            if obj is not None and current is not obj:
                registry.renderers.register(self.renderer, lambda: obj, replace=True)
        return Painter(self.atlas, self.template, self.surface, self.hidden, self.settings,
                       self.renderer, self.medial_wall_color, coloring=self.coloring, contours=self.contours,
                       layers=self.layers)
