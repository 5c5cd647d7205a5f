"""Atlas model: a lookup table of regions plus the template labels it uses.

An atlas is data. On disk it is a directory with ``atlas.json`` (metadata)
and ``regions.tsv`` with the columns ``index, name, hemi, kind, color,
aliases``, in the style of BIDS ``dseg.tsv`` look-up tables. Cortical rows
come from FreeSurfer annotation colour tables and subcortical rows from
FreeSurfer's aseg look-up table; nothing is typed by hand in Python.
"""

from __future__ import annotations

import csv
import json
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from brainpainter.errors import BrainPainterError

#: The cortical surfaces of a template (here, not in template.py: option parsing needs them cheaply).
SURFACES = ("pial", "white", "inflated")
#: Coordinate spaces of volumes and tractograms (:mod:`brainpainter.atlas.volumes` maps them onto a template).
SPACES = ("MNI152NLin2009cAsym", "MNI152NLin6Asym", "fsaverage", "template")

HEMIS = ("lh", "rh", "bilateral")
HEMI_PREFIX = {"lh": "Left-", "rh": "Right-", "bilateral": ""}
#: A hemisphere spelled at the start or the end of a name, apart from the rest by ``-``, ``_``, ``.``
#: or spaces: ``Left-Putamen``, ``lh.AF``, ``CnF_l``, ``Lobule_VI_R``, ``Arcuate right``.
_HEMI_IN_NAME = (
    ("lh", re.compile(r"^(?:left|lh|l)[-_. ]+(?P<rest>.+)$", re.IGNORECASE)),
    ("rh", re.compile(r"^(?:right|rh|r)[-_. ]+(?P<rest>.+)$", re.IGNORECASE)),
    ("lh", re.compile(r"^(?P<rest>.+?)[-_. ]+(?:left|lh|l)$", re.IGNORECASE)),
    ("rh", re.compile(r"^(?P<rest>.+?)[-_. ]+(?:right|rh|r)$", re.IGNORECASE)),
)
KINDS = ("cortical", "subcortical")
REGION_COLUMNS = ("index", "name", "hemi", "kind", "color", "aliases")
T = TypeVar("T")


@dataclass(frozen=True)
class Region:
    """One region of an atlas.

    Attributes
    ----------
    index : int
        FreeSurfer look-up-table index (e.g. 1035 for ctx-lh-insula).
    name : str
        Structure name without hemisphere (``"insula"``, ``"Hippocampus"``).
    hemi : {"lh", "rh", "bilateral"}
    kind : {"cortical", "subcortical"}
    color : tuple of int, shape (3,)
        FreeSurfer colour, 0-255.
    aliases : tuple of str
        Other names this region is known by (hemisphere-free or full).
    """

    index: int
    name: str
    hemi: str
    kind: str
    color: tuple[int, int, int]
    aliases: tuple[str, ...] = ()

    @property
    def key(self) -> str:
        """The BrainPainter column name: ``Left-insula``, ``Brain-Stem``."""
        return HEMI_PREFIX[self.hemi] + self.name


def hemisphere_in_name(name: str) -> tuple[str | None, str]:
    """The hemisphere a name spells and the rest of it: ``("lh", "Putamen")`` for ``Left-Putamen``,
    ``Putamen_L`` or ``lh.Putamen``; ``(None, name)`` when it spells none.

    The one rule for the names of volume structures, mesh files and bundles.
    """
    text = name.strip()
    for hemi, pattern in _HEMI_IN_NAME:
        m = pattern.match(text)
        if m:
            return hemi, m.group("rest").strip()
    return None, text


@dataclass(frozen=True)
class Atlas:
    """A parcellation: metadata plus its regions.

    Attributes
    ----------
    name : str
        Registry name (``"dk"``).
    title : str
        Human title (``"Desikan-Killiany"``).
    template_labels : str
        Name of the label set inside a template that carries this atlas's
        cortical regions (``"dk"``); subcortical regions come from the aseg.
    regions : tuple of Region
    description, citation : str
    aliases : tuple of str
        Other names of the atlas itself.
    label_dir : Path or None
        Folder with a label-set overlay (``labels.json``) that carries
        `template_labels` for a template that lacks it (custom and plugin
        atlases); see :meth:`brainpainter.atlas.template.Template.with_label_sets`.
    members : tuple of (str, tuple of str)
        Region groups: ``(key, member keys)`` pairs saying which regions of the
        label set a region of this atlas stands for (``("Left-frontal",
        ("Left-superiorfrontal", ...))``; a BrainGlobe parent and its drawn
        descendants, from ``groups`` in ``atlas.json``). Regions not listed
        stand for themselves. Empty for ordinary atlases.
    volume_dirs : tuple of Path
        Folders of volumetric atlases (``subcortical.npz`` meshes, see
        :mod:`brainpainter.atlas.volumes`) drawn as the template's subcortical part
        instead of its own structures; see
        :meth:`brainpainter.atlas.template.Template.with_volumes`.
    sources : tuple of (str, str)
        For an atlas combined from several (``schaefer400_7n+tian_s2``): each
        region key and the atlas it comes from. Empty otherwise.
    template_dir : Path or None
        A template of the atlas's own (a volume atlas of a brain without
        cortical surfaces, e.g. a mouse), used unless another template is named.
    image_aspect : float or None
        Width / height of the images when the user gives no size (a mouse brain, longer
        than wide, is framed in a square); None: the command's own size (1200 x 900).
        Where set, a run at no size given frames its views instead
        (:func:`brainpainter.rendering.painter.shown_aspect`).
    views : tuple of str
        Default views (``atlas.json``'s ``views``): those its meshes can show (the mouse's
        hemispheres are open on the medial side, so no medial view). Empty: the usual ones.
    """

    name: str
    title: str
    template_labels: str
    regions: tuple[Region, ...]
    description: str = ""
    citation: str = ""
    aliases: tuple[str, ...] = ()
    label_dir: Path | None = None
    members: tuple[tuple[str, tuple[str, ...]], ...] = ()
    volume_dirs: tuple[Path, ...] = ()
    sources: tuple[tuple[str, str], ...] = ()
    template_dir: Path | None = None
    image_aspect: float | None = None
    views: tuple[str, ...] = ()
    _by_key: dict[str, Region] = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        keys: dict[str, Region] = {}
        for r in self.regions:
            if r.key in keys:
                raise BrainPainterError(f"atlas {self.name!r} lists region {r.key!r} twice")
            keys[r.key] = r
        object.__setattr__(self, "_by_key", keys)

    def __iter__(self) -> Iterator[Region]:
        return iter(self.regions)

    def __len__(self) -> int:
        return len(self.regions)

    @property
    def keys(self) -> list[str]:
        """Region keys in table order."""
        return [r.key for r in self.regions]

    def region(self, key: str) -> Region:
        """Region by its key (exact)."""
        return self._by_key[key]

    def cortical(self, hemi: str | None = None) -> list[Region]:
        """Cortical regions, optionally of one hemisphere."""
        return [r for r in self.regions if r.kind == "cortical" and hemi in (None, r.hemi)]

    def subcortical(self) -> list[Region]:
        return [r for r in self.regions if r.kind == "subcortical"]

    def member_keys(self, key: str) -> tuple[str, ...]:
        """Keys of the label-set regions that region `key` is drawn as (itself if no group)."""
        return dict(self.members).get(key, (key,))

    def expand(self, mapping: Mapping[str, T]) -> dict[str, T]:
        """Copy of `mapping` (region key -> anything) with each group's value given to its members.

        A member with a value of its own keeps it; of nested groups (a
        structure tree's ancestors) the smallest wins.
        """
        out = dict(mapping)
        for key, members in sorted(self.members, key=lambda g: -len(g[1])):
            if key in mapping:
                out.update({m: mapping[key] for m in members if m not in mapping})
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description (regions with key, hemi, colour, aliases)."""
        return {
            "name": self.name,
            "title": self.title,
            "template_labels": self.template_labels,
            "description": self.description,
            "citation": self.citation,
            "aliases": list(self.aliases),
            "n_cortical_per_hemisphere": {h: len(self.cortical(h)) for h in ("lh", "rh")},
            "n_subcortical": len(self.subcortical()),
            "label_dir": None if self.label_dir is None else str(self.label_dir),
            "groups": {k: list(m) for k, m in self.members},
            "volume_dirs": [str(p) for p in self.volume_dirs],
            "regions": [
                {
                    "key": r.key,
                    "index": r.index,
                    "name": r.name,
                    "hemi": r.hemi,
                    "kind": r.kind,
                    "color": "#{:02x}{:02x}{:02x}".format(*r.color),
                    "aliases": list(r.aliases),
                }
                for r in self.regions
            ],
        }


def read_regions_tsv(path: str | Path) -> tuple[Region, ...]:
    """Read a ``regions.tsv`` look-up table.

    Parameters
    ----------
    path : path-like
        Tab-separated file with header ``index name hemi kind color aliases``;
        ``color`` is ``#rrggbb``; ``aliases`` is ``|``-separated (may be empty).
    """
    path = Path(path)
    regions = []
    with path.open(newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh, delimiter="\t")
        missing = set(REGION_COLUMNS) - set(reader.fieldnames or ())
        if missing:
            raise BrainPainterError(
                f"{path} lacks the columns {sorted(missing)}; a regions table needs {list(REGION_COLUMNS)}"
            )
        for i, row in enumerate(reader, start=2):
            hemi, kind, color = row["hemi"], row["kind"], row["color"].lstrip("#")
            if hemi not in HEMIS or kind not in KINDS or len(color) != 6:
                raise BrainPainterError(
                    f"{path} line {i}: hemi must be one of {list(HEMIS)}, kind one of "
                    f"{list(KINDS)} and color #rrggbb; got {hemi!r}, {kind!r}, {row['color']!r}"
                )
            regions.append(
                Region(
                    index=int(row["index"]),
                    name=row["name"],
                    hemi=hemi,
                    kind=kind,
                    color=(int(color[0:2], 16), int(color[2:4], 16), int(color[4:6], 16)),
                    aliases=tuple(a for a in (row["aliases"] or "").split("|") if a),
                )
            )
    return tuple(regions)


def write_regions_tsv(regions: list[Region] | tuple[Region, ...], path: str | Path) -> None:
    """Write regions in the ``regions.tsv`` format read by :func:`read_regions_tsv`."""
    with Path(path).open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, delimiter="\t", lineterminator="\n")
        w.writerow(REGION_COLUMNS)
        for r in regions:
            w.writerow([r.index, r.name, r.hemi, r.kind, "#{:02x}{:02x}{:02x}".format(*r.color),
                        "|".join(r.aliases)])


def load_atlas_dir(path: str | Path) -> Atlas:
    """Load an atlas directory (``atlas.json`` + ``regions.tsv`` [+ ``subcortical``]).

    ``atlas.json`` keys: ``name``, ``title``, ``template_labels``, optional
    ``description``, ``citation``, ``aliases``, and ``include`` — a list of
    other region tables in the same directory's parent (e.g. the shared
    ``aseg.tsv`` of subcortical structures). A ``labels.json`` beside them
    makes the directory the atlas's label-set overlay (``Atlas.label_dir``).
    """
    path = Path(path)
    meta_file = path / "atlas.json"
    try:
        meta = json.loads(meta_file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise BrainPainterError(f"cannot read atlas metadata {meta_file}: {exc}") from None
    regions = list(read_regions_tsv(path / "regions.tsv"))
    for extra in meta.get("include", []):
        regions.extend(read_regions_tsv((path / extra).resolve()))
    return Atlas(
        name=meta["name"],
        title=meta.get("title", meta["name"]),
        template_labels=meta.get("template_labels", meta["name"]),
        regions=tuple(regions),
        description=meta.get("description", ""),
        citation=meta.get("citation", ""),
        aliases=tuple(meta.get("aliases", ())),
        label_dir=path if (path / "labels.json").is_file() else None,
        volume_dirs=(path,) if (path / "subcortical.npz").is_file() else (),
        template_dir=path / "template" if (path / "template" / "manifest.json").is_file() else None,
        members=tuple((str(k), tuple(str(m) for m in v)) for k, v in meta.get("groups", {}).items()),
        image_aspect=float(meta["image_aspect"]) if meta.get("image_aspect") else None,
        views=tuple(str(v) for v in meta.get("views", ())),
    )


def combine_atlases(atlases: list[Atlas] | tuple[Atlas, ...]) -> Atlas:
    """One atlas from a cortical atlas and one or more volumetric atlases (or volumetric atlases only).

    The cortex is drawn with the cortical atlas (its regions and label set);
    the subcortical views show the meshes of every volumetric atlas in place of
    the template's own structures, so the cortical atlas's subcortical (aseg)
    regions are left out. One table gives values to regions of all of them.

    Parameters
    ----------
    atlases : sequence of Atlas
        At most one without volume meshes (the cortical atlas), any number with.

    Returns
    -------
    Atlas
        Named ``"A+B"``; ``sources`` says which atlas each region key comes from.
    """
    atlases = list(atlases)
    cortical = [a for a in atlases if not a.volume_dirs]
    volumes = [a for a in atlases if a.volume_dirs]
    name = "+".join(a.name for a in atlases)
    if len(cortical) > 1 or not volumes:
        raise BrainPainterError(
            f"atlas {name!r} combines {[a.name for a in cortical]} without volume meshes; combine one "
            "cortical atlas with volumetric atlases (brainpainter atlas add NAME --volume ...), e.g. "
            "schaefer400_7n+tian_s2")
    base = cortical[0] if cortical else volumes[0]
    regions: list[Region] = list(base.cortical()) if cortical else []
    sources = {r.key: base.name for r in regions}
    for v in volumes:
        for r in v.regions:
            if r.key in sources:
                raise BrainPainterError(f"region {r.key!r} is in both {sources[r.key]!r} and {v.name!r}; "
                                        "combine atlases whose region names differ")
            sources[r.key] = v.name
            regions.append(r)
    citations = list(dict.fromkeys(a.citation for a in atlases if a.citation))
    return Atlas(
        name=name, title=" + ".join(a.title for a in atlases), template_labels=base.template_labels,
        regions=tuple(regions), description="; ".join(a.description for a in atlases if a.description),
        citation="\n".join(citations), label_dir=base.label_dir if cortical else None,
        members=base.members if cortical else (),
        volume_dirs=tuple(d for v in volumes for d in v.volume_dirs), sources=tuple(sources.items()),
    )
