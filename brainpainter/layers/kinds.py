"""What a layer kind is (:class:`LayerKind`), what a plugin's layer draws (:class:`DrawnLayer`), and
the generic ``--layer KIND:FILE`` / ``--layer-opt KIND.NAME=VALUE`` options that reach it.

Every kind is registered in the ``brainpainter.layers`` entry-point group: brainpainter's own
(regions, map, tracts, connectome, contour, outline, blobs; :mod:`.builtin_kinds`) with the flags
that draw them, and a plugin's (e.g. ``foci`` from ``plugins/layers/brainpainter-layer-foci``) with
an :attr:`LayerKind.open` that reads its file into a :class:`DrawnLayer`. docs/architecture.md,
"Adding a layer kind", walks through one.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from brainpainter.atlas.registry import layer_kinds, load_target
from brainpainter.errors import BrainPainterError, choice_error

RGB = tuple[float, float, float]


class PartsLayer(Protocol):
    """What adds its own parts to the scene (the tracts, a connectome, the blobs, a plugin's layer): what
    a :class:`~brainpainter.rendering.painter.Painter` takes (``layers=``), in the order they are drawn.

    It travels to every worker (``--jobs``, Dask) with the painter, so it pickles. One that reads its
    data for the scene's template (the tracts: placed in its coordinates) has ``for_template(template)``,
    which returns the layer read (:func:`for_template`).
    """

    @property
    def kind(self) -> str:
        """Its kind's name (``tracts``, ``connectome``, ``foci``): its key in the manifest."""

    def parts(self, template: Any, slots_for: Callable[..., Any]) -> list[Any]:
        """Its :class:`~brainpainter.rendering.parts.PartGeometry` in `template`'s coordinates;
        ``slots_for(keys, default_rgb, frozenset())`` gives the palette slot of each colour key."""

    def summary(self) -> dict[str, Any]:
        """What was drawn, for the manifest and ``check`` (JSON types)."""


class DrawnLayer(PartsLayer, Protocol):
    """A layer read from its file that adds its parts and colours them itself (the blobs, a plugin's)."""

    def colors(self, row: int) -> dict[str, RGB]:
        """The sRGB colour of each of its palette keys in image (row) `row`."""

    def layer(self) -> Any:
        """Its :class:`~brainpainter.rendering.layers.Layer` (colour scale, opacity, label): its
        colour bar in figures and its entry in the manifest."""


def for_template(layer: PartsLayer, template: Any) -> PartsLayer:
    """`layer` with its data read for `template` where it reads any there (its optional
    ``for_template``, as the tracts have); else `layer` itself."""
    read = getattr(layer, "for_template", None)
    return layer if read is None else read(template)


@dataclass(frozen=True)
class LayerKind:
    """One kind of layer, as ``brainpainter layers`` lists it.

    Attributes
    ----------
    name : str
    description : str
        One line.
    options : mapping of str to str
        Its options (``--layer-opt KIND.NAME=VALUE``, ``Scene.add(..., NAME=VALUE)``) and their help.
    flags : tuple of str
        A built-in kind's command-line flags (it is drawn by them, not by ``--layer``).
    open : str, optional
        ``"module:function"``: ``function(path, options) -> DrawnLayer`` (`options`: the
        ``--layer-opt`` values given, as strings or the keywords' values); None for a built-in kind.
    """

    name: str
    description: str
    options: Mapping[str, str] = field(default_factory=dict)
    flags: tuple[str, ...] = ()
    open: str | None = None

    def read(self, path: str | Path, options: Mapping[str, Any]) -> DrawnLayer:
        """The layer of `path` with `options` (each checked against :attr:`options`)."""
        if self.open is None:
            raise BrainPainterError(f"--layer {self.name}:FILE: the {self.name} layer is drawn by its own "
                                    f"options ({', '.join(self.flags)}); give it with those.")
        for name in options:
            if name not in self.options:
                raise choice_error(f"--layer-opt {self.name}.NAME", name, list(self.options),
                                   f"Give one of the {self.name} layer's options.")
        if not Path(path).is_file():
            raise BrainPainterError(f"--layer {self.name}:{path}: no such file; give the path of a "
                                    f"{self.name} file.")
        opener: Callable[[str | Path, Mapping[str, Any]], DrawnLayer] = load_target(self.open)
        return opener(path, dict(options))


def kind_of(name: str) -> LayerKind:
    """The registered layer kind `name`."""
    kind: LayerKind = layer_kinds.get(name)
    return kind


def parse_layer(given: str) -> tuple[str, str]:
    """``"KIND:FILE"`` to ``(kind, file)``."""
    kind, sep, path = str(given).partition(":")
    if not sep or not kind or not path:
        raise BrainPainterError(f"--layer takes KIND:FILE (e.g. foci:peaks.csv); {given!r} was given. "
                                "'brainpainter layers' lists the kinds.")
    return kind.strip(), path


def parse_layer_opts(given: Iterable[str]) -> dict[str, dict[str, str]]:
    """``"KIND.NAME=VALUE"`` options to ``{kind: {name: value}}``."""
    out: dict[str, dict[str, str]] = {}
    for text in given:
        key, sep, value = str(text).partition("=")
        kind, dot, name = key.partition(".")
        if not sep or not dot or not kind or not name:
            raise BrainPainterError(f"--layer-opt takes KIND.NAME=VALUE (e.g. foci.cmap=magma); {text!r} "
                                    "was given.")
        out.setdefault(kind.strip(), {})[name.strip()] = value.strip()
    return out


def open_layers(layers: Iterable[str], layer_opts: Iterable[str]) -> tuple[DrawnLayer, ...]:
    """The plugin layers of ``--layer KIND:FILE`` (in order) with their ``--layer-opt`` values.

    Raises
    ------
    BrainPainterError
        A kind not installed, a built-in kind (drawn by its own flags), an option the kind does not
        take, an option of a kind not given, a file that is not there.
    """
    specs = [parse_layer(g) for g in layers]
    opts = parse_layer_opts(layer_opts)
    names = layer_kinds.names()
    for kind, _ in specs:
        if kind not in names:
            raise choice_error("--layer KIND", kind, names,
                               "'brainpainter layers' lists the installed kinds.")
    for kind in opts:
        if kind not in {k for k, _ in specs}:
            raise BrainPainterError(f"--layer-opt {kind}.*: no --layer {kind}:FILE was given; give the "
                                    "layer, or leave its options out.")
    return tuple(kind_of(kind).read(path, opts.get(kind, {})) for kind, path in specs)
