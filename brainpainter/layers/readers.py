"""What an input is, decided in one place: by its name (ending), then by its first bytes.

Every reader is a :class:`Reader` registered in the ``brainpainter.readers`` entry-point group
(the built-in ones in brainpainter's own ``pyproject.toml``, :mod:`.builtin_readers`), so a plugin
adds a file format the way it adds an atlas. :func:`identify` picks the reader of a path:

1. the readers whose name test claims it (the longest ending wins: ``x.dscalar.nii`` is CIFTI,
   not a volume; ``lh.thickness`` is a map by its FreeSurfer name);
2. a name no reader claims: the reader whose magic numbers its first bytes say
   (:func:`brainpainter.io.sniff.what_is`; a curv file named ``thickness_lh`` is a map);
3. else the fallback of the kinds asked for (a region table reads any text).

>>> identify("lh.thickness").name                                           # doctest: +SKIP
'surface-map'
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from brainpainter.atlas.registry import load_target, readers
from brainpainter.errors import PluginError, choice_error


@dataclass(frozen=True)
class Reader:
    """One input format: how it is recognised and what reads it.

    Attributes
    ----------
    name : str
        Its name in the ``brainpainter.readers`` registry (``table``, ``surface-map``, ``cifti``, ...).
    kind : str
        The layer kind its data feeds (``regions``, ``map``, ``tracts``, ``connectome``, ...).
    description : str
        One line for ``brainpainter layers``.
    suffixes : tuple of str
        Lower-case endings it claims (``.dscalar.nii``).
    magic : tuple of str
        :mod:`brainpainter.io.sniff` formats its first bytes may say (``a FreeSurfer curv file``).
    read : str
        ``"module:function"``: ``function(path, **options)`` reads the layer's data.
    names : str, optional
        ``"module:function"``: ``function(lower_name) -> bool``, a name test besides `suffixes`
        (FreeSurfer's ``lh.thickness`` has no ending).
    fallback : bool
        It reads what no reader of its kind claims (a region table: any text).
    """

    name: str
    kind: str
    description: str
    suffixes: tuple[str, ...] = ()
    magic: tuple[str, ...] = ()
    read: str = ""
    names: str | None = None
    fallback: bool = False

    def claims(self, name: str) -> int:
        """How strongly the lower-case file name `name` is this reader's: the length of the ending it
        matches, 1 for a name its name test takes, 0 for none."""
        ending = max((len(s) for s in self.suffixes if name.endswith(s)), default=0)
        if ending:
            return ending
        if self.names is not None and load_target(self.names)(name):
            return 1
        return 0

    def load(self, path: str | Path, **options: Any) -> Any:
        """The layer data of `path` (what :attr:`read` returns)."""
        reader: Callable[..., Any] = load_target(self.read)
        return reader(path, **options)


def all_readers(kinds: Iterable[str] | None = None) -> list[Reader]:
    """The registered readers (of `kinds` only, if given), in name order."""
    wanted = None if kinds is None else set(kinds)
    names = readers.names()
    if "table" not in names:  # an install whose metadata predates the readers' entry points
        raise PluginError("brainpainter's own readers are not registered (entry-point group "
                          "brainpainter.readers): its installed metadata is older than its code; reinstall "
                          "it (pip install -e . in a checkout, else pip install --force-reinstall "
                          "brainpainter).")
    found = [readers.get(name) for name in names]
    return [r for r in found if wanted is None or r.kind in wanted]


def head_of(path: Path) -> bytes:
    """The first bytes of a regular file (:data:`brainpainter.io.sniff.HEAD`); nothing for a folder,
    a pipe or a file that cannot be read (its reader says why)."""
    from brainpainter.io.sniff import HEAD

    try:
        if not path.is_file():
            return b""
        with path.open("rb") as f:
            return f.read(HEAD)
    except OSError:
        return b""


def identify(path: str | Path, kinds: Iterable[str] | None = None) -> Reader:
    """The reader of `path`: by its name's ending, then its first bytes, then the fallback.

    Parameters
    ----------
    path : str or Path
    kinds : iterable of str, optional
        Only readers of these layer kinds (the main INPUT: ``("regions", "map")``).

    Raises
    ------
    BrainPainterError
        No reader of `kinds` reads it.
    """
    from brainpainter.io.sniff import what_is

    candidates = all_readers(kinds)
    name = Path(path).name.lower()
    scored = [(r.claims(name), r) for r in candidates]
    best = max((score for score, _ in scored), default=0)
    if best:
        return next(r for score, r in scored if score == best)
    said = what_is(head_of(Path(path)))
    by_bytes = [r for r in candidates if said is not None and said in r.magic]
    if by_bytes:
        return by_bytes[0]
    fallback = [r for r in candidates if r.fallback]
    if fallback:
        return fallback[0]
    known = sorted({s for r in candidates for s in r.suffixes})
    raise choice_error("input", Path(path).name, known, "Give a file of one of these kinds.")


def is_map_data(data: Any) -> bool:
    """Whether the main INPUT `data` is a map rather than a region table: a path by its reader
    (:func:`identify` among the ``regions`` and ``map`` readers), an object as
    :func:`brainpainter.maps.inputs.is_map_input` says."""
    from brainpainter.maps.inputs import is_map_input

    if isinstance(data, str | Path):  # the table reader takes what no map reader claims
        return identify(data, ("regions", "map")).kind == "map"
    return is_map_input(data)


def first_layer_kind(data: Any, maps_given: bool) -> str:
    """The kind of a run's first layer: ``"map"`` where maps were given as options (`maps_given`:
    ``--lh``/``--rh``/``--volume``) or `data` is one (:func:`is_map_data`), else ``"regions"`` (a region
    table, or an empty one under tracts or a connectome drawn alone)."""
    return "map" if maps_given or is_map_data(data) else "regions"
