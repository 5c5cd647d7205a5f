"""Read-only, lazy plugin registries fed by entry points.

Three groups exist: ``brainpainter.atlases``, ``brainpainter.renderers`` and
``brainpainter.templates``. Built-in atlases, the Blender renderer and the
default template register through the same entry points a third-party
distribution would use. An entry is imported only when first asked for; a
plugin that fails to import is recorded and reported, never fatal.

Several names pointing at the same ``module:attr`` target are aliases of one
entry (``dkt`` and ``tourville``); the first name in sorted order that is not
listed as an alias by the object itself is the canonical one.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

from brainpainter.atlas import installed
from brainpainter.atlas.config import read_atlas_config
from brainpainter.atlas.model import Atlas, combine_atlases, load_atlas_dir
from brainpainter.errors import BrainPainterError, PluginError, choice_error

CONFIG_FILE = "atlas.toml"
GROUPS = ("brainpainter.atlases", "brainpainter.renderers", "brainpainter.templates", "brainpainter.layers",
          "brainpainter.readers")

# The optional distributions of this repository (plugins/atlases/<distribution>) and the atlases
# each provides (its "brainpainter.atlases" entry points).
KNOWN_ATLAS_PLUGINS: Mapping[str, tuple[str, ...]] = MappingProxyType({
    "brainpainter-atlas-mouse": ("mouse",),
    "brainpainter-atlas-yeo7": ("yeo7",),
    "brainpainter-atlas-schaefer-yeo": (
        *(f"schaefer{n}_{k}n" for n in range(100, 1001, 100) for k in (7, 17)), "yeo17"),
})


def install_hint(name: str, distribution: str) -> str:
    """What to do when `name` is asked for and its `distribution` is not installed."""
    return (f"{name!r} is provided by the {distribution} package, which is not installed: "
            f"pip install {distribution} (from a checkout of brainpainter: "
            f"pip install plugins/atlases/{distribution}).")


# Names a user may know that live in optional distributions: name -> pip hint.
KNOWN_ELSEWHERE: Mapping[str, Mapping[str, str]] = MappingProxyType({
    "brainpainter.renderers": MappingProxyType({}),
    "brainpainter.atlases": MappingProxyType({
        name: install_hint(name, dist) for dist, names in KNOWN_ATLAS_PLUGINS.items() for name in names}),
    "brainpainter.templates": MappingProxyType({}),
    "brainpainter.layers": MappingProxyType({}),
    "brainpainter.readers": MappingProxyType({}),
})


@dataclass(frozen=True)
class Entry:
    """One registered plugin entry (not yet imported)."""

    name: str
    target: str  # "module:attr"
    distribution: str
    aliases: tuple[str, ...] = ()


@dataclass
class Registry:
    """Lazy mapping from plugin name to the object its entry point names.

    Parameters
    ----------
    group : str
        Entry-point group, e.g. ``"brainpainter.atlases"``.
    kind : str
        Human word for error messages, e.g. ``"atlas"``.
    validate : callable, optional
        ``validate(name, obj) -> obj`` checks the plugin contract and may
        normalise the object (e.g. call a factory); raises PluginError.
    local_source : callable, optional
        ``local_source() -> {name: (location, factory)}``: entries kept in a
        folder rather than installed (user atlases); listed with distribution
        ``"user"``. An installed entry of the same name wins and the local one
        is reported in :meth:`errors`.
    """

    group: str
    kind: str
    validate: Callable[[str, Any], Any] | None = None
    local_source: Callable[[], Mapping[str, tuple[str, Callable[[], Any]]]] | None = None
    _local: dict[str, Callable[[], Any]] = field(default_factory=dict, repr=False)
    _entries: dict[str, Entry] | None = field(default=None, repr=False)
    _alias: dict[str, str] = field(default_factory=dict, repr=False)
    _loaded: dict[str, Any] = field(default_factory=dict, repr=False)
    _errors: dict[str, str] = field(default_factory=dict, repr=False)
    _extra: dict[str, Callable[[], Any]] = field(default_factory=dict, repr=False)

    # -- discovery -------------------------------------------------------
    def _discover(self) -> dict[str, Entry]:
        if self._entries is not None:
            return self._entries
        by_target: dict[tuple[str, str], list[tuple[str, str]]] = {}
        clashes: dict[str, list[str]] = {}
        seen: dict[str, str] = {}
        for ep_name, value, dist in installed.entry_points(self.group, GROUPS):  # cached per environment
            if ep_name in seen and seen[ep_name] != value:
                clashes.setdefault(ep_name, [seen[ep_name]]).append(value)
                continue
            seen[ep_name] = value
            by_target.setdefault((value, dist), []).append((ep_name, dist))
        entries: dict[str, Entry] = {}
        for (target, dist), named in by_target.items():
            names = sorted({n for n, _ in named})
            canonical, aliases = names[0], tuple(names[1:])
            # Prefer the shortest name that is not an English word alias like
            # "tourville": keep sorted order but let the target's attr win.
            attr = target.rpartition(":")[2]
            if attr in names:
                canonical = attr
                aliases = tuple(n for n in names if n != attr)
            entries[canonical] = Entry(canonical, target, dist, aliases)
            for a in aliases:
                self._alias[a] = canonical
        for name, targets in clashes.items():
            self._errors[name] = (
                f"two plugins register the {self.kind} name {name!r} "
                f"({', '.join(targets)}); uninstall one of them"
            )
            entries.pop(name, None)
        self._local = {}
        if self.local_source is not None:
            taken = {n.lower(): n for n in (*entries, *self._alias)}
            for name, (where, factory) in sorted(self.local_source().items()):
                if name.lower() in taken:
                    self._errors[f"{name} (user)"] = (
                        f"the user {self.kind} {name!r} in {where} has the name of an installed "
                        f"{self.kind} and is ignored; remove it (brainpainter {self.kind} remove {name}) "
                        "and add it again under another name"
                    )
                    continue
                entries[name] = Entry(name, where, "user")
                self._local[name] = factory
        self._entries = entries
        return entries

    def names(self) -> list[str]:
        """Canonical names of all registered entries, sorted (no import)."""
        return sorted({*self._discover(), *self._extra})

    def entries(self) -> list[Entry]:
        """All entry-point entries, sorted by name (no import)."""
        return [self._discover()[n] for n in sorted(self._discover())]

    def errors(self) -> dict[str, str]:
        """Names whose import or validation failed, with the reason."""
        self._discover()
        return dict(self._errors)

    def canonical(self, name: str) -> str:
        """Resolve an alias or different case to the canonical name."""
        entries = self._discover()
        key = str(name).strip().lower()
        for n in (*entries, *self._extra):
            if n.lower() == key:
                return n
        for a, n in self._alias.items():
            if a.lower() == key:
                return n
        # Names the objects themselves declare (an atlas.json's "aliases"): only on a miss, as
        # it imports every entry; a broken one is skipped here and reported by errors().
        for n in (*entries, *self._extra):
            try:
                declared = getattr(self.get(n), "aliases", ())
            except BrainPainterError:
                continue
            if key in {str(a).lower() for a in declared}:
                self._alias[key] = n
                return n
        allowed = [*entries, *self._extra, *self._alias]
        hint = KNOWN_ELSEWHERE.get(self.group, {}).get(key, "")
        if not hint:
            hint = f"Run 'brainpainter {self.kind} list' to see what is installed."
        raise choice_error(f"'{self.kind}'", name, allowed, hint)

    def register(self, name: str, factory: Callable[[], Any], *, replace: bool = False) -> None:
        """Register an in-process entry (tests, user atlases). Duplicates refused."""
        if not replace and (name in self._discover() or name in self._extra):
            raise BrainPainterError(
                f"a {self.kind} named {name!r} is already registered; "
                "choose another name or pass replace=True"
            )
        self._extra[name] = factory
        self._loaded.pop(name, None)

    def unregister(self, name: str) -> None:
        self._extra.pop(name, None)
        self._loaded.pop(name, None)

    # -- loading ----------------------------------------------------------
    def get(self, name: str) -> Any:
        """Import (once) and return the object registered under `name`."""
        canonical = self.canonical(name)
        if canonical in self._loaded:
            return self._loaded[canonical]
        try:
            if canonical in self._extra:
                obj = self._extra[canonical]()
            elif canonical in self._local:
                obj = self._local[canonical]()
            else:
                entry = self._discover()[canonical]
                obj = load_target(entry.target)
            if self.validate is not None:
                obj = self.validate(canonical, obj)
        except BrainPainterError as exc:
            self._errors[canonical] = str(exc)
            raise
        except Exception as exc:  # a broken plugin must not crash the caller
            found = self._discover().get(canonical)
            where = f" from {found.distribution} ({found.target})" if found else ""
            msg = f"the {self.kind} plugin {canonical!r}{where} failed to load: {type(exc).__name__}: {exc}"
            self._errors[canonical] = msg
            raise PluginError(msg + "; reinstall or uninstall that plugin") from exc
        self._loaded[canonical] = obj
        return obj

    def load_all(self) -> dict[str, Any]:
        """Load every entry, collecting failures in :meth:`errors`."""
        out = {}
        for name in self.names():
            try:
                out[name] = self.get(name)
            except BrainPainterError:
                pass
        return out

    def reset(self) -> None:
        """Forget discovery and loaded objects (after installing a plugin)."""
        installed.forget()
        self._entries = None
        self._alias.clear()
        self._loaded.clear()
        self._errors.clear()


def load_target(target: str) -> Any:
    """Import ``"package.module:attr.sub"`` and return the attribute."""
    module_name, _, attr = target.partition(":")
    obj: Any = importlib.import_module(module_name)
    for part in filter(None, attr.split(".")):
        obj = getattr(obj, part)
    return obj


def _validate_atlas(name: str, obj: Any) -> Any:
    if callable(obj) and not isinstance(obj, Atlas):
        obj = obj()
    if not isinstance(obj, Atlas):
        raise PluginError(
            f"the atlas plugin {name!r} gave a {type(obj).__name__}, not a brainpainter.atlas.model.Atlas"
        )
    if not obj.regions:
        raise PluginError(f"the atlas plugin {name!r} defines no regions")
    return obj


def _validate_renderer(name: str, obj: Any) -> Any:
    for method in ("render",):
        if not callable(getattr(obj, method, None)):
            raise PluginError(f"the renderer plugin {name!r} has no {method}() method")
    return obj


def _validate_template(name: str, obj: Any) -> Any:
    if callable(obj):
        obj = obj()
    path = Path(obj)
    if not (path / "manifest.json").is_file():
        raise PluginError(f"the template plugin {name!r} points at {path}, which has no manifest.json")
    return path


def _validate_reader(name: str, obj: Any) -> Any:
    for attribute in ("kind", "suffixes", "magic", "claims", "load"):
        if not hasattr(obj, attribute):
            raise PluginError(f"the reader plugin {name!r} gave a {type(obj).__name__}, not a "
                              "brainpainter.layers.readers.Reader")
    return obj


def _validate_layer_kind(name: str, obj: Any) -> Any:
    for attribute in ("name", "description", "options", "open"):
        if not hasattr(obj, attribute):
            raise PluginError(f"the layer plugin {name!r} gave a {type(obj).__name__}, not a "
                              "brainpainter.layers.kinds.LayerKind")
    return obj


# -- looking atlases up --------------------------------------------------------------------
def get_atlas(name: str) -> Atlas:
    """The registered atlas called `name` (or one of its aliases).

    ``"A+B+..."`` combines a cortical atlas with volumetric ones
    (:func:`brainpainter.atlas.model.combine_atlases`), e.g. ``"schaefer400_7n+tian_s2"``.
    """
    if "+" in str(name):
        return combine_atlases([atlases.get(part.strip()) for part in str(name).split("+")])
    atlas: Atlas = atlases.get(name)
    return atlas


def list_atlases() -> list[str]:
    """Names of installed atlases (no plugin is imported)."""
    return atlases.names()


def load_atlas_config(path: str | Path, name: str | None = None) -> Atlas:
    """The atlas a region-group TOML file defines, its base atlas looked up in :data:`atlases`.

    See :func:`brainpainter.atlas.config.read_atlas_config`.
    """
    return read_atlas_config(path, name, get_base=get_atlas)


# -- user atlases: folders in the user's data folder (brainpainter atlas add) --------------
def atlases_dir() -> Path:
    """Folder of the user's atlases (it may not exist yet)."""
    import platformdirs

    return Path(platformdirs.user_data_dir("brainpainter", appauthor=False)) / "atlases"


def user_folders() -> dict[str, Path]:
    """``{name: folder}`` of the atlases in :func:`atlases_dir`."""
    root = atlases_dir()
    if not root.is_dir():
        return {}
    out = {}
    for p in sorted(root.iterdir()):
        if p.is_dir() and not p.name.startswith(".") and (
                (p / "atlas.json").is_file() or (p / CONFIG_FILE).is_file()):
            out[p.name] = p
    return out


def load_user_atlas(folder: Path) -> Atlas:
    """Load one user-atlas folder (label-map or group atlas)."""
    if (folder / CONFIG_FILE).is_file():
        return load_atlas_config(folder / CONFIG_FILE, name=folder.name)
    atlas = load_atlas_dir(folder)
    return atlas if atlas.name == folder.name else replace(atlas, name=folder.name)


def local_entries() -> Mapping[str, tuple[str, Callable[[], Any]]]:
    """``{name: (folder, factory)}`` of the user's atlases, for the registry."""
    return {name: (str(p), functools.partial(load_user_atlas, p)) for name, p in user_folders().items()}


atlases = Registry("brainpainter.atlases", "atlas", _validate_atlas, local_source=local_entries)
renderers = Registry("brainpainter.renderers", "renderer", _validate_renderer)
templates = Registry("brainpainter.templates", "template", _validate_template)
#: Layer kinds (:class:`brainpainter.layers.kinds.LayerKind`) and input formats
#: (:class:`brainpainter.layers.readers.Reader`): the built-in ones and plugins'.
layer_kinds = Registry("brainpainter.layers", "layer kind", _validate_layer_kind)
readers = Registry("brainpainter.readers", "reader", _validate_reader)


def reset_all() -> None:
    """Forget every registry's discovery (after installing or removing plugins)."""
    for reg in (atlases, renderers, templates, layer_kinds, readers):
        reg.reset()
