"""Templates: everything a renderer needs to draw one brain.

A template is a directory::

    manifest.json                  metadata (see below)
    cortex-{hemi}-{labels}.npz     one hemisphere split by one label set
    subcortical.npz                aseg structures
    glass-{hemi}.npz               smooth hull of the pial surface
    LICENSE.FreeSurfer.txt         licence Part B and attribution (derived data)

All arrays are plain ``.npz`` (loaded with ``allow_pickle=False``); all
coordinates are FreeSurfer tkr-RAS millimetres (x right, y anterior, z
superior), unless the manifest's ``axes`` says which axis is anterior and
which superior (:attr:`Template.to_ras`; templates of other species).
Cortex files hold one mesh per hemisphere whose faces carry a
region label: the per-region meshes are ``faces[face_label == i]``, so
neighbouring regions share their boundary vertices exactly. The pial, white
and inflated surfaces share one topology (``faces``) and differ in vertex
positions; inflated positions are already offset so hemispheres never overlap.

Optional cortex arrays (a reader that does not know them ignores them):
``vertex_label`` (int16, one per vertex: the label of the full-resolution
vertex, index into the names) makes :meth:`Template.cortex` split the faces
that straddle a region boundary when loading, so borders follow the label
boundary instead of the triangles (:func:`brainpainter.atlas.mesh.split_mesh`,
the same code as for label-set overlays); ``face_label`` stays the
whole-triangle labelling for older readers; ``boundary_t`` (float32, one
per label-crossing edge) caches where the border crosses each edge
(:func:`brainpainter.atlas.mesh.smooth_crossings`), so loading only splits.
``sulc`` (float32, one per
vertex) is FreeSurfer's sulcal depth (``surf/?h.sulc``, mm, positive in
sulci) for shading. ``ao_{surface}`` (uint8 per vertex, 255 = open sky) is
the ambient occlusion baked by the builder for each surface
(:mod:`brainpainter.atlas.occlusion`); ``subcortical.npz`` may hold ``ao``
(the structures baked together). A template without them draws without
occlusion (:attr:`Template.notes` says so).

Label-set overlays
------------------
A custom or plugin atlas brings its own label set in a folder beside its
``atlas.json``: ``labels.json`` (format ``brainpainter-labels``, the same
``labels`` entries as a manifest, for one named template) plus
``cortex-{hemi}-{labels}.npz`` files. An overlay file holds labels for one of
the template's own label-set meshes (entry key ``base``; ``base_faces_sha256``
guards against a rebuilt template): ``vertex_label`` (one per vertex; faces
whose vertices differ are split through edge midpoints when loaded, see
:func:`brainpainter.atlas.mesh.split_mesh`) or ``face_label`` (one per face).
An overlay file may instead hold ``source_label``: one label per vertex of the
full-resolution surface the template was built from (e.g. all 163842 of
fsaverage); it is mapped through the base mesh's ``source_vertex`` when
loaded, so it survives a rebuild of the template (no digest needed).
:meth:`Template.with_label_sets` adds such a folder's label sets to a template.
"""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas import registry
from brainpainter.atlas.mesh import CortexMesh, LabelledMesh, faces_digest, labels_at_vertices, split_mesh
from brainpainter.atlas.model import SURFACES as SURFACES  # re-exported: readers of templates look here
from brainpainter.atlas.model import Atlas
from brainpainter.atlas.occlusion import from_stored, occlusion_of_shown
from brainpainter.errors import BrainPainterError
from brainpainter.io.memo import Memo, file_key

FORMAT = "brainpainter-template"
FORMAT_VERSION = 1
HEMIS = ("lh", "rh")
LABELS_FORMAT = "brainpainter-labels"
LABELS_FILE = "labels.json"
_AXIS_VECTORS = {f"{sign}{axis}": tuple(float(sign + "1") * (i == j) for j in range(3))
                 for i, axis in enumerate("xyz") for sign in "+-"}


#: The template files read in this process (:func:`read_npz`; the default template's are 30 MB
#: inflated, a cortex file ~0.02 s to inflate, read again for every figure before).
NPZ_MEMO = Memo(max_bytes=256 * 1024 * 1024)


def read_npz(path: Path) -> dict[str, NDArray[Any]]:
    """The arrays of a template's ``.npz`` file (no pickles), read-only; read again only when the
    file changes (:data:`NPZ_MEMO`, keyed by its path and ``os.stat``)."""
    def read() -> dict[str, NDArray[Any]]:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    arrays: dict[str, NDArray[Any]] = NPZ_MEMO.get(file_key(path), read)
    return arrays


@dataclass
class Template:
    """A loaded template directory. Arrays are read on first use and cached."""

    path: Path
    manifest: dict[str, Any]
    _cache: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def name(self) -> str:
        return str(self.manifest["name"])

    @property
    def label_sets(self) -> list[str]:
        return sorted(self.manifest["labels"])

    @property
    def surfaces(self) -> list[str]:
        return list(self.manifest["surfaces"])

    def _npz(self, file: str) -> dict[str, NDArray[Any]]:
        if file not in self._cache:
            self._cache[file] = read_npz(self.path / file)
        arrays: dict[str, NDArray[Any]] = self._cache[file]
        return arrays

    def _entry(self, labels: str, hemi: str) -> dict[str, Any]:
        if labels not in self.manifest["labels"]:
            raise BrainPainterError(
                f"template {self.name!r} has no label set {labels!r}; it has {self.label_sets}. "
                "Build the template with that atlas (brainpainter template build --atlas ...)."
            )
        entry: dict[str, Any] = self.manifest["labels"][labels]["cortex"][hemi]
        return entry

    def base_cortex(self, labels: str, hemi: str) -> CortexMesh:
        """The stored mesh of one of the template's own label sets, faces not split.

        Its vertices are all vertices of the full-resolution surface
        (`source_vertex` >= 0) and its faces are labelled whole (majority of
        the vertex labels): the mesh that label-set overlays label.
        """
        entry = self._entry(labels, hemi)
        if "base" in entry:
            raise BrainPainterError(f"label set {labels!r} of template {self.name!r} is an overlay on "
                                    f"{entry['base']!r}, not a mesh of its own")
        z = self._npz(entry["file"])
        return CortexMesh(
            hemi=hemi,
            labels=labels,
            faces=z["faces"],
            face_label=z["face_label"],
            label_names=tuple(entry["names"]),
            vertices={s: z[s] for s in self.surfaces if s in z},
            source_vertex=z["source_vertex"],
            sulc=z.get("sulc"),
            occlusion=self._occlusion(z),
        )

    def _occlusion(self, z: dict[str, NDArray[Any]]) -> dict[str, NDArray[Any]] | None:
        """The baked ``ao_{surface}`` arrays of a cortex file, or None when one surface lacks it."""
        if not all(f"ao_{s}" in z for s in self.surfaces if s in z):
            return None
        return {s: from_stored(z[f"ao_{s}"]) for s in self.surfaces if s in z}

    @property
    def has_occlusion(self) -> bool:
        """Whether the template has baked ambient occlusion (``occlusion`` in its manifest)."""
        return bool(self.manifest.get("occlusion"))

    @property
    def notes(self) -> list[str]:
        """What a user may want to know about this template (e.g. a feature an old build lacks)."""
        if self.has_occlusion:
            return []
        return [f"template {self.name!r} has no baked ambient occlusion (built before it existed): folds "
                "are shaded by the lights only; rebuild it with 'brainpainter template build' to add it."]

    def cortex_names(self, labels: str, hemi: str) -> tuple[str, ...]:
        """``cortex(labels, hemi).label_names``, read from the manifest (no mesh is loaded)."""
        label_set = self.manifest["labels"].get(labels)
        if label_set is not None and hemi not in label_set.get("cortex", {}):
            return ()
        return tuple(self._entry(labels, hemi)["names"])

    def subcortical_names(self) -> tuple[str, ...]:
        """``subcortical().label_names``, read from the manifest (no mesh is loaded)."""
        return tuple(s["name"] for s in (self.manifest.get("subcortical") or {}).get("structures", []))

    def cortex(self, labels: str, hemi: str) -> CortexMesh:
        """The hemisphere `hemi` split by label set `labels`.

        Where per-vertex labels are known (``vertex_label`` in the template
        file, or a per-vertex overlay), faces that straddle a region boundary
        are split so that the border follows it (computed once per template
        object). A template without this hemisphere's cortex (made of volume
        labels only) gives an empty mesh.
        """
        label_set = self.manifest["labels"].get(labels)
        if label_set is not None and hemi not in label_set.get("cortex", {}):
            return CortexMesh(hemi=hemi, labels=labels, faces=np.zeros((0, 3), np.int32),
                              face_label=np.zeros(0, np.int16), label_names=(),
                              vertices={s: np.zeros((0, 3), np.float32) for s in self.surfaces},
                              source_vertex=np.zeros(0, np.int32))
        entry = self._entry(labels, hemi)
        z = self._npz(entry["file"])
        if "base" in entry:  # an overlay: labels for the vertices or faces of one of our own meshes
            base = self.base_cortex(entry["base"], hemi)
            if "source_label" in z:  # one label per full-resolution vertex: fits any rebuild of the base
                return self._source_labelled(base, z["source_label"], labels, entry)
            per_vertex = "vertex_label" in z
            n = len(z["vertex_label"]) if per_vertex else len(z["face_label"])
            digest = entry.get("base_faces_sha256")
            if n != (len(base.source_vertex) if per_vertex else len(base.faces)) or (
                    digest and faces_digest(base.faces) != digest):
                raise BrainPainterError(
                    f"label set {labels!r} ({entry['file']}) was made for the {entry['base']!r} mesh of "
                    f"template {self.name!r} as it was then, and that mesh has changed; add the atlas "
                    "again (brainpainter atlas add ... --replace)."
                )
            if not per_vertex:
                return CortexMesh(hemi=hemi, labels=labels, faces=base.faces, face_label=z["face_label"],
                                  label_names=tuple(entry["names"]), vertices=base.vertices,
                                  source_vertex=base.source_vertex, sulc=base.sulc,
                                  occlusion=base.occlusion)
        else:
            base = self.base_cortex(labels, hemi)
            if "vertex_label" not in z:
                return base
        key = f"{entry['file']}#{labels}"  # computed once per template object
        if key not in self._cache:
            self._cache[key] = split_mesh(base, z["vertex_label"], labels, tuple(entry["names"]),
                                          z.get("boundary_t"))
        mesh: CortexMesh = self._cache[key]
        return mesh

    def _source_labelled(self, base: CortexMesh, source_label: NDArray[Any], labels: str,
                         entry: dict[str, Any]) -> CortexMesh:
        """`base` labelled by `source_label` (one label per vertex of the full-resolution surface)."""
        n_source = int(entry.get("n_source_vertices", len(source_label)))
        if len(source_label) != n_source or int(base.source_vertex.max(initial=-1)) >= n_source:
            raise BrainPainterError(
                f"label set {labels!r} ({entry['file']}) labels {len(source_label)} source vertices, but the "
                f"{entry['base']!r} mesh of template {self.name!r} was made from a surface with more; "
                "use the template the atlas was made for."
            )
        key = f"{entry['file']}#{labels}"
        if key not in self._cache:
            vertex_label = labels_at_vertices(source_label, base)
            self._cache[key] = split_mesh(base, vertex_label, labels, tuple(entry["names"]))
        mesh: CortexMesh = self._cache[key]
        return mesh

    def with_label_sets(self, folder: str | Path) -> Template:
        """This template plus the label sets of an overlay folder (``labels.json``).

        The overlay's label sets win over the template's own ones of the same
        name. An overlay made for another template is an error.
        """
        folder = Path(folder)
        meta_file = folder / LABELS_FILE
        try:
            meta = json.loads(meta_file.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise BrainPainterError(f"cannot read label-set overlay {meta_file}: {exc}") from None
        if meta.get("format") != LABELS_FORMAT or meta.get("format_version") != FORMAT_VERSION:
            raise BrainPainterError(f"{meta_file} is not a {LABELS_FORMAT} version {FORMAT_VERSION} file; "
                                    "add the atlas again with 'brainpainter atlas add'.")
        if meta.get("template") != self.name:
            raise BrainPainterError(
                f"the label sets in {folder} were made for template {meta.get('template')!r}, not "
                f"{self.name!r}; render with --template {meta.get('template')} or add the atlas again "
                f"with --template {self.name}."
            )
        manifest = dict(self.manifest)
        manifest["labels"] = dict(manifest["labels"])
        for name, entry in meta.get("labels", {}).items():
            entry = copy.deepcopy(entry)
            for hemi_entry in entry.get("cortex", {}).values():
                hemi_entry["file"] = str((folder / hemi_entry["file"]).absolute())
            manifest["labels"][name] = entry
        return Template(path=self.path, manifest=manifest, _cache=self._cache)

    def subcortical(self) -> LabelledMesh:
        """All subcortical structures (names as in FreeSurfer's aseg LUT, or a volume atlas's keys).

        A template without them (the user's own surfaces) gives an empty mesh.
        """
        entry = self.manifest.get("subcortical")
        if not entry:
            return LabelledMesh(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int32),
                                np.zeros(0, np.int16), ())
        names = self.subcortical_names()
        files = entry.get("parts", [entry["file"]])
        arrays = [self._npz(f) for f in files]
        occlusion = (np.concatenate([from_stored(z["ao"]) for z in arrays])
                     if all("ao" in z for z in arrays) else None)
        if len(arrays) == 1:
            z = arrays[0]
            return LabelledMesh(z["vertices"], z["faces"], z["face_label"], names, occlusion)
        verts, faces, labels, n_v, n_l = [], [], [], 0, 0
        for z in arrays:
            verts.append(z["vertices"])
            faces.append(z["faces"] + n_v)
            labels.append(z["face_label"] + n_l)
            n_v += len(z["vertices"])
            n_l += int(z["face_label"].max()) + 1 if len(z["face_label"]) else 0
        return LabelledMesh(np.concatenate(verts), np.concatenate(faces).astype(np.int32),
                            np.concatenate(labels).astype(np.int16), names, occlusion)

    def subcortical_occlusion(self, hidden: frozenset[str] = frozenset()) -> NDArray[Any] | None:
        """The baked occlusion of :meth:`subcortical`, or with the `hidden` structures taken away.

        Hiding a structure uncovers the ones it shaded (the caudate and thalamus beside the
        ventricles): their occlusion is baked again without it (a few seconds for the aseg
        structures), once per set of hidden structures. None when the template has none baked.
        """
        sub = self.subcortical()
        gone = [i for i, name in enumerate(sub.label_names) if name in hidden]
        if sub.occlusion is None or not gone:
            return sub.occlusion
        entry = self.manifest["subcortical"]
        key = f"subcortical-occlusion:{entry.get('parts', [entry['file']])}:{gone}"
        if key not in self._cache:
            shown = ~np.isin(np.asarray(sub.face_label), gone)
            self._cache[key] = occlusion_of_shown(sub.vertices, sub.faces, shown, sub.occlusion)
        out: NDArray[Any] = self._cache[key]
        return out

    def with_volumes(self, folders: list[Path] | tuple[Path, ...]) -> Template:
        """This template with the meshes of volumetric atlases as its subcortical part.

        Each folder holds ``atlas.json`` and ``subcortical.npz`` written by
        :func:`brainpainter.atlas.volumes.build_volume_atlas` for this template; its
        structures replace the template's own (aseg) ones, several folders are
        drawn together.
        """
        structures: list[dict[str, Any]] = []
        parts: list[str] = []
        for folder in folders:
            folder = Path(folder)
            try:
                meta = json.loads((folder / "atlas.json").read_text(encoding="utf-8"))
            except (OSError, ValueError) as exc:
                raise BrainPainterError(f"cannot read volume atlas {folder}: {exc}") from None
            if meta.get("template") != self.name:
                raise BrainPainterError(
                    f"the volume atlas in {folder} was made for template {meta.get('template')!r}, not "
                    f"{self.name!r}; render with --template {meta.get('template')} or add it again with "
                    f"--template {self.name}.")
            structures.extend({"name": s["name"]} for s in meta["structures"])
            parts.append(str((folder / "subcortical.npz").absolute()))
        manifest = dict(self.manifest)
        manifest["subcortical"] = {"file": parts[0], "parts": parts, "structures": structures}
        return Template(path=self.path, manifest=manifest, _cache=self._cache)

    def glass(self, hemi: str) -> tuple[NDArray[Any], NDArray[Any]]:
        """Glass-brain hull of one hemisphere: ``(vertices (n, 3), faces (m, 3))``.

        The manifest entry names the file and, optionally, its vertex array
        (``"vertices": "pial"``: a mesh template's glass is its cortex file).
        """
        entry = self.manifest["glass"][hemi]
        z = self._npz(entry["file"])
        return z[entry.get("vertices", "vertices")], z["faces"]

    @cached_property
    def to_ras(self) -> NDArray[Any]:
        """3 x 3 rotation from the template's coordinates to RAS (x right, y anterior, z superior).

        The manifest's optional ``axes`` entry says which axis points anterior
        and which superior (``{"anterior": "-z", "superior": "+y"}``; default
        ``+y`` and ``+z``): the views turn with it, so any species' brain is
        drawn the right way up whatever its coordinates. Right is anterior x
        superior (the coordinates are right-handed, as meshes with outward
        faces need).
        """
        axes = self.manifest.get("axes") or {}
        vec = {}
        for key, default in (("anterior", "+y"), ("superior", "+z")):
            text = str(axes.get(key, default)).strip().lower()
            if text not in _AXIS_VECTORS:
                raise BrainPainterError(f"template {self.name!r}: axes.{key} must be one of "
                                        f"{sorted(_AXIS_VECTORS)}; {text!r} was given")
            vec[key] = np.asarray(_AXIS_VECTORS[text], dtype=float)
        if abs(float(vec["anterior"] @ vec["superior"])) > 0:
            raise BrainPainterError(f"template {self.name!r}: axes.anterior and axes.superior must be two "
                                    "different axes")
        return np.vstack([np.cross(vec["anterior"], vec["superior"]), vec["anterior"], vec["superior"]])

    @cached_property
    def bounds(self) -> NDArray[Any]:
        """Bounding box of the pial surfaces, shape (2, 3): min and max corner."""
        return np.asarray(self.manifest["bounds"]["pial"], dtype=float)

    def files(self) -> list[Path]:
        return sorted(p for p in self.path.iterdir() if p.is_file())


def template_for(atlas: Atlas, template: Template) -> Template:
    """`template` with what `atlas` brings: its cortex label set overlay and its volume meshes.

    Parameters
    ----------
    atlas : brainpainter.atlas.model.Atlas
    template : Template
    """
    if atlas.label_dir is not None and atlas.template_labels not in template.label_sets:
        template = template.with_label_sets(atlas.label_dir)
    if atlas.volume_dirs:
        template = template.with_volumes(atlas.volume_dirs)
    return template


def load_template(name_or_path: str | Path = "fsaverage") -> Template:
    """Load a template by registry name or directory path.

    Parameters
    ----------
    name_or_path : str or path-like
        ``"fsaverage"`` (the bundled default), another registered template
        name, or a directory made by ``brainpainter template build``.
    """
    path = Path(name_or_path)
    if not (path / "manifest.json").is_file():
        if isinstance(name_or_path, str) and "/" not in name_or_path and "\\" not in name_or_path:
            path = registry.templates.get(name_or_path)
        else:
            raise BrainPainterError(
                f"template {str(name_or_path)!r} is not a directory with a manifest.json; "
                "give a registered template name (e.g. 'fsaverage') or a folder made by "
                "'brainpainter template build'."
            )
    manifest_file = path / "manifest.json"
    try:
        manifest = json.loads(manifest_file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise BrainPainterError(f"cannot read template manifest {manifest_file}: {exc}") from None
    if manifest.get("format") != FORMAT or manifest.get("format_version") != FORMAT_VERSION:
        raise BrainPainterError(
            f"{manifest_file} is not a {FORMAT} version {FORMAT_VERSION} manifest; "
            "rebuild it with 'brainpainter template build'."
        )
    return Template(path=path, manifest=manifest)
