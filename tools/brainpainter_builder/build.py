"""Build a brainpainter template from a FreeSurfer subject directory.

One pipeline (read sources, construct meshes, write, validate)::

    build_template("subjects/fsaverage", "templates/fsaverage")

1. **read**: surfaces, annotations (or a GCSA classifier atlas for DKT),
   ``mri/aseg.mgz`` — every reader fails with a one-line
   :class:`~brainpainter.errors.BrainPainterError` naming the bad file;
2. **cortex**: per hemisphere and label set, one mesh whose faces carry a
   region label, decimated on the pial surface with region boundaries locked,
   shared by the pial, white and inflated surfaces (:mod:`.cortex`);
3. **subcortical**: marching cubes of the aseg structures (:mod:`.subcortical`);
4. **glass**: smooth hull of each pial surface (:mod:`.glass`);
5. **write** into a hidden sibling directory (:mod:`.writer`);
6. **validate** (:func:`.report.template_problems`): every region has faces
   on every hemisphere, no open edge, subcortical volumes within 5 %, size in
   budget — then rename into place. A failure leaves nothing behind.

The output is byte-identical for identical inputs.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.atlas.meshing import Structure
from brainpainter.atlas.template import FORMAT, FORMAT_VERSION, HEMIS, SURFACES
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter_builder import cortex, glass, occlusion, report, sources, subcortical, writer

#: Faces per hemisphere and label set of a default build (full fsaverage: 327680).
DEFAULT_TARGET_FACES = 120_000
#: Size budget of a template, MB (the default fsaverage template is about 17 MB).
DEFAULT_MAX_SIZE_MB = 25.0
#: Faces of each glass-brain hull.
GLASS_FACES = 6000
#: Gap between the inflated hemispheres, mm.
INFLATED_GAP_MM = 10.0
DEFAULT_ATLASES = ("dk", "destrieux", "dkt")


def _hex(rgb: Sequence[int]) -> str:
    return "#{:02x}{:02x}{:02x}".format(*(int(c) for c in rgb[:3]))


def _bounds(arrays: list[NDArray[Any]]) -> list[list[float]]:
    stacked = np.concatenate([a.reshape(-1, 3) for a in arrays])
    return [stacked.min(axis=0).astype(float).tolist(), stacked.max(axis=0).astype(float).tolist()]


def _region_names(per_hemi: dict[str, cortex.LabelledSurface]) -> list[str]:
    """Regions of a label set: non-region names excluded, in colour-table order."""
    out: list[str] = []
    for hemi in HEMIS:
        mesh = per_hemi[hemi]
        used = np.unique(mesh.face_label)
        for i in used:
            name = mesh.names[int(i)]
            if name not in sources.NON_REGIONS and name not in out:
                out.append(name)
    order = {n: i for i, n in enumerate(per_hemi[HEMIS[0]].names)}
    return sorted(out, key=lambda n: (order.get(n, len(order)), n))


def _check_args(atlases: Sequence[str], surfaces: Sequence[str],
                target_faces: int | None) -> tuple[tuple[str, ...], tuple[str, ...]]:
    atlases = tuple(dict.fromkeys(atlases))
    surfaces = tuple(dict.fromkeys(surfaces))
    if not atlases:
        raise BrainPainterError("no atlas given; choose at least one of "
                                f"{list(DEFAULT_ATLASES)} (or an annotation name in label/)")
    for s in surfaces:
        if s not in SURFACES:
            raise choice_error("'surface'", s, SURFACES)
    if "pial" not in surfaces:
        raise BrainPainterError(f"surfaces must include 'pial' (decimation and bounds use it); "
                                f"{list(surfaces)} was given")
    if target_faces is not None and (not isinstance(target_faces, int | np.integer)
                                     or target_faces < 1000):
        raise BrainPainterError(f"target_faces must be an integer >= 1000 or None (full "
                                f"resolution); {target_faces!r} was given")
    return atlases, surfaces


def build_template(subject_dir: str | Path, out_dir: str | Path, *,
                   atlases: tuple[str, ...] | list[str] = DEFAULT_ATLASES,
                   surfaces: tuple[str, ...] | list[str] = SURFACES,
                   target_faces: int | None = DEFAULT_TARGET_FACES, name: str | None = None,
                   gcs_dir: str | Path | None = None, progress: bool = True,
                   freesurfer_version: str | None = None, max_size_mb: float | None = DEFAULT_MAX_SIZE_MB,
                   license_file: str | Path | None = None,
                   expected_regions: dict[str, int] | None = None) -> Path:
    """Build a template directory from a FreeSurfer subject.

    Parameters
    ----------
    subject_dir : path-like
        FreeSurfer subject (``surf/``, ``label/``, ``mri/``).
    out_dir : path-like
        Template directory to create (an existing template there is replaced).
    atlases : sequence of str
        Label sets: ``"dk"`` (aparc), ``"destrieux"`` (aparc.a2009s), ``"dkt"``
        (aparc.DKTatlas, or derived from the DKT40 classifier atlas when the
        subject has no DKT annotation), or any annotation name in ``label/``.
    surfaces : sequence of str
        Among ``"pial"`` (required), ``"white"``, ``"inflated"``.
    target_faces : int or None
        Faces per hemisphere and label set after decimation; None keeps full
        resolution. Region-boundary faces are never removed.
    name : str, optional
        Template name (default: the subject's folder name).
    gcs_dir : path-like, optional
        Folder of FreeSurfer classifier atlases (default
        ``SUBJECT/../../average``, then ``$FREESURFER_HOME/average``).
    progress : bool
        Show a progress bar on stderr.
    freesurfer_version : str, optional
        Recorded in the manifest (default: read ``build-stamp.txt``, else "unknown").
    max_size_mb : float or None
        Fail if the template is larger (None: no limit).
    license_file : path-like, optional
        FreeSurfer's licence text (default: found beside the subjects folder
        or in ``$FREESURFER_HOME``); its Part B goes into the template.
    expected_regions : dict[str, Any] of str to int, optional
        Regions per hemisphere each label set must have (e.g. ``{"dk": 34}``);
        checked in the validation step.

    Returns
    -------
    Path
        The template directory.

    Raises
    ------
    BrainPainterError
        Bad or missing input, or a template that fails validation; nothing
        is left at `out_dir` (or its previous content is untouched).
    """
    atlases, surfaces = _check_args(atlases, surfaces, target_faces)
    writer.check_out_dir(out_dir)  # before minutes of work: never replace what brainpainter did not make
    subject = _subject(subject_dir, gcs_dir, atlases)
    version = freesurfer_version or sources.freesurfer_version(subject.path)
    name = name or subject.name
    step = _Steps(f"template {name}", 2 + 2 * len(atlases) + 1 + 2 + 2, progress)
    try:
        surf, sulc, offsets = _read_surfaces(subject, surfaces, step)
        meshes, label_sources = _cortex(subject, atlases, surf, sulc, offsets, target_faces, step)
        structures = _subcortical(subject, step)
        hulls = _glass(surf, step)
        with writer.staged_dir(out_dir) as stage:
            step("write")
            manifest = _write(stage, name=name, subject=subject, version=version,
                              surfaces=surfaces, target_faces=target_faces, meshes=meshes,
                              label_sources=label_sources, offsets=offsets,
                              structures=structures, hulls=hulls, license_file=license_file)
            step.done()
            step("validate")
            _validate(stage, manifest, name, subject, max_size_mb, expected_regions)
            del manifest
            step.done()
    finally:
        step.close()
    return Path(out_dir).expanduser().absolute()


def _subject(subject_dir: str | Path, gcs_dir: str | Path | None,
             atlases: tuple[str, ...]) -> sources.Subject:
    """The FreeSurfer subject, refused before any work when it lacks a label set's sources."""
    subject = sources.Subject(subject_dir, gcs_dir=gcs_dir)
    for label_set in atlases:
        subject.check_label_set(label_set)
    return subject


class _Steps:
    """The progress bar: one tick per finished step, the current step's name beside it."""

    def __init__(self, desc: str, total: int, show: bool) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=total, desc=desc, unit="step", disable=not show, leave=False,
                        dynamic_ncols=True)

    def __call__(self, what: str) -> None:
        self.bar.set_postfix_str(what, refresh=True)

    def done(self) -> None:
        self.bar.update()

    def close(self) -> None:
        self.bar.close()


Surfaces = dict[str, dict[str, tuple[NDArray[Any], NDArray[Any]]]]


def _read_surfaces(subject: sources.Subject, surfaces: tuple[str, ...], step: _Steps) -> tuple[
        Surfaces, dict[str, Any], dict[str, dict[str, NDArray[Any]]]]:
    """Surfaces (vertices, faces) per hemisphere, sulcal depth, and the inflated hemispheres' offsets."""
    surf: Surfaces = {}
    for hemi in HEMIS:
        step(f"read {hemi} surfaces")
        surf[hemi] = {s: subject.surface(hemi, s) for s in surfaces}
        for s in surfaces:
            if not np.array_equal(surf[hemi][s][1], surf[hemi]["pial"][1]):
                raise BrainPainterError(
                    f"{subject.path / 'surf' / f'{hemi}.{s}'} does not share the triangles "
                    f"of {hemi}.pial; all surfaces of a hemisphere must come from one recon-all run")
        step.done()
    sulc = {h: subject.sulc(h) for h in HEMIS}
    offsets: dict[str, dict[str, NDArray[Any]]] = {h: {} for h in HEMIS}
    if "inflated" in surfaces:
        off = cortex.inflated_offsets(surf["lh"]["inflated"][0], surf["rh"]["inflated"][0],
                                      gap=INFLATED_GAP_MM)
        offsets = {h: {"inflated": off[h]} for h in HEMIS}
    return surf, sulc, offsets


def _cortex(subject: sources.Subject, atlases: tuple[str, ...], surf: Surfaces, sulc: dict[str, Any],
            offsets: dict[str, dict[str, NDArray[Any]]], target_faces: int | None, step: _Steps) -> tuple[
        dict[str, dict[str, cortex.LabelledSurface]], dict[str, list[str]]]:
    """One labelled, decimated mesh per label set and hemisphere, and the annotations they came from."""
    meshes: dict[str, dict[str, cortex.LabelledSurface]] = {}
    label_sources: dict[str, list[str]] = {}
    for label_set in atlases:
        meshes[label_set] = {}
        label_sources[label_set] = []
        for hemi in HEMIS:
            step(f"{label_set} {hemi}: labels")
            annot = subject.annotation(hemi, label_set)
            label_sources[label_set].append(annot.source)
            step(f"{label_set} {hemi}: split and decimate")
            meshes[label_set][hemi] = cortex.build_labelled_surface(
                surf[hemi], annot.labels, annot.names, annot.ctab, target_faces,
                offsets=offsets[hemi], sulc=sulc[hemi])
            step.done()
    return meshes, label_sources


def _subcortical(subject: sources.Subject, step: _Steps) -> list[Structure]:
    """Meshes of the aseg structures."""
    step("read aseg")
    aseg, vox2ras, voxel_volume = subject.aseg()
    structures = subcortical.build_structures(
        aseg, vox2ras, voxel_volume, progress=lambda s: step(f"subcortical {s}"))
    step.done()
    return structures


def _glass(surf: Surfaces, step: _Steps) -> dict[str, tuple[NDArray[Any], NDArray[Any]]]:
    """The glass-brain hull of each pial surface."""
    hulls = {}
    for hemi in HEMIS:
        step(f"glass {hemi}")
        hulls[hemi] = glass.pial_hull(*surf[hemi]["pial"], target_faces=GLASS_FACES)
        step.done()
    return hulls


def _validate(stage: Path, manifest: dict[str, Any], name: str, subject: sources.Subject,
              max_size_mb: float | None, expected_regions: dict[str, int] | None) -> None:
    """Refuse a template with problems (:func:`.report.template_problems`, region counts)."""
    problems = report.template_problems(stage, max_size_mb=max_size_mb)
    for label_set, n in (expected_regions or {}).items():
        got = len(manifest["labels"].get(label_set, {}).get("regions", []))
        if label_set in manifest["labels"] and got != n:
            problems.append(f"label set {label_set!r} has {got} regions per hemisphere, expected {n}")
    if problems:
        raise BrainPainterError(
            f"template {name!r} from {subject.path} failed validation: " + "; ".join(problems))


def _write(stage: Path, *, name: str, subject: sources.Subject, version: str, surfaces: tuple[str, ...],
           target_faces: int | None, meshes: dict[str, dict[str, cortex.LabelledSurface]],
           label_sources: dict[str, list[str]], offsets: dict[str, dict[str, NDArray[Any]]],
           structures: list[Structure], hulls: dict[str, tuple[NDArray[Any], NDArray[Any]]],
           license_file: str | Path | None) -> dict[str, Any]:
    """Write the template's files into `stage`; returns its manifest."""
    all_vertices: dict[str, list[NDArray[Any]]] = {s: [] for s in surfaces}
    totals = {"cortex": 0, "subcortical": 0, "glass": 0}
    labels_entry = {label_set: _write_cortex(stage, label_set, per_hemi, label_sources[label_set], surfaces,
                                             all_vertices, totals)
                    for label_set, per_hemi in meshes.items()}
    merged = subcortical.merge_structures(structures)
    merged["ao"] = occlusion.subcortical_array(merged["vertices"], merged["faces"])
    writer.save_npz(stage / "subcortical.npz", merged)
    totals["subcortical"] = len(merged["faces"])
    glass_entry = {}
    for hemi in HEMIS:
        v, f = hulls[hemi]
        file = f"glass-{hemi}.npz"
        writer.save_npz(stage / file, {"vertices": v.astype(np.float32), "faces": f.astype(np.int32)})
        glass_entry[hemi] = {"file": file, "n_vertices": len(v), "n_faces": len(f)}
        totals["glass"] += len(f)
    vname = version.removeprefix("freesurfer-")
    manifest = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "name": name,
        "source": {
            "subject": subject.name,
            "freesurfer": version,
            "builder": "brainpainter_builder (tools/brainpainter_builder)",
        },
        "space": f"{subject.name} FreeSurfer surface RAS (tkr-RAS), mm",
        "surfaces": list(surfaces),
        "target_faces": target_faces,
        "labels": labels_entry,
        "subcortical": {"file": "subcortical.npz", "source": "mri/aseg.mgz",
                        "structures": [_structure_entry(s) for s in structures]},
        "glass": glass_entry,
        "inflated_offset": {h: offsets[h]["inflated"].tolist() for h in HEMIS
                            if "inflated" in offsets[h]},
        "bounds": {s: _bounds(all_vertices[s]) for s in surfaces},
        "occlusion": occlusion.manifest_entry(),
        "n_faces": totals,
        "license": "FreeSurfer Software License Agreement, Part B (research use); "
                   "see LICENSE.FreeSurfer.txt",
        "attribution": f"Data derived (modified) from FreeSurfer {vname} ({subject.name}), "
                       "The General Hospital Corporation (MGH); not endorsed by MGH.",
    }
    writer.write_json(stage / "manifest.json", manifest)
    _write_license(stage, license_file, subject, version)
    return manifest


def _write_cortex(stage: Path, label_set: str, per_hemi: dict[str, cortex.LabelledSurface],
                  label_sources: list[str], surfaces: tuple[str, ...],
                  all_vertices: dict[str, list[NDArray[Any]]], totals: dict[str, int]) -> dict[str, Any]:
    """Write ``cortex-{hemi}-{label_set}.npz``; returns the label set's manifest entry."""
    entry: dict[str, Any] = {"source": ", ".join(label_sources), "regions": _region_names(per_hemi),
                             "cortex": {}}
    for hemi in HEMIS:
        m = per_hemi[hemi]
        file = f"cortex-{hemi}-{label_set}.npz"
        arrays = {"faces": m.faces, "face_label": m.face_label}
        arrays.update({s: m.vertices[s] for s in surfaces})
        arrays["source_vertex"] = m.source_vertex
        arrays["vertex_label"] = m.vertex_label
        arrays["boundary_t"] = m.boundary_t
        if m.sulc is not None:
            arrays["sulc"] = m.sulc
        arrays.update(occlusion.cortex_arrays({s: m.vertices[s] for s in surfaces}, m.faces))
        writer.save_npz(stage / file, arrays)
        for s in surfaces:
            all_vertices[s].append(m.vertices[s])
        counts = np.bincount(m.face_label.astype(np.int64), minlength=len(m.names))
        entry["cortex"][hemi] = {
            "file": file,
            "names": list(m.names),
            "colors": [_hex(c) for c in m.colors],
            "n_vertices": len(m.source_vertex),
            "n_faces": len(m.faces),
            "n_source_faces": m.n_source_faces,
            "open_edges": cortex.open_edge_count(m.faces),
            "self_intersecting_faces": {s: {"decimated": b, "template": a}
                                        for s, (b, a) in (m.self_intersections or {}).items()},
            "region_faces": {n: int(counts[i]) for i, n in enumerate(m.names) if counts[i]},
        }
        totals["cortex"] += len(m.faces)
    return entry


def _structure_entry(s: Structure) -> dict[str, Any]:
    """Manifest entry of one subcortical structure."""
    return {
        "name": s.name,
        "index": s.index,
        "n_vertices": len(s.vertices),
        "n_faces": len(s.faces),
        "volume_mm3": s.volume_mm3,
        "voxel_volume_mm3": s.voxel_volume_mm3,
        "volume_error": s.volume_mm3 / s.voxel_volume_mm3 - 1.0,
        "smoothed_volume_error": s.smoothed_volume_mm3 / s.voxel_volume_mm3 - 1.0,
        "watertight": s.watertight,
        "blur_voxels": s.blur,
        "self_intersecting_faces": {"decimated": s.self_intersections[0],
                                    "template": s.self_intersections[1]},
    }


def _write_license(stage: Path, license_file: str | Path | None, subject: sources.Subject,
                   version: str) -> None:
    """``LICENSE.FreeSurfer.txt``: FreeSurfer's Part B when its licence is found, else a pointer to it."""
    lic = Path(license_file) if license_file is not None else writer.find_license(subject.path)
    if lic is not None:
        writer.write_license(stage / "LICENSE.FreeSurfer.txt", lic, subject.name, version)
        return
    vname = version.removeprefix("freesurfer-")
    (stage / "LICENSE.FreeSurfer.txt").write_text(
        f"The files in this directory are data derived (modified) from FreeSurfer {vname}'s\n"
        f"output for {subject.name}. FreeSurfer's Software License Agreement applies; see\n"
        "https://surfer.nmr.mgh.harvard.edu/fswiki/FreeSurferSoftwareLicense\n",
        encoding="utf-8")
