"""Tractogram uploads of the web API: bundles (.trk, .tck, .trx, or a .zip of them) drawn with a table.

A tract upload is one or several tractogram files (one bundle each, the file
name is the bundle name, as ``--tracts FOLDER``), or a ``.zip`` of them, plus
at most one table of bundle values or along-tract profiles (``.csv``,
``.tsv``, ``.xlsx``: ``--tract-values``). The files are read in a process of
their own (:func:`brainpainter.web.upload.read_tract_upload`, killed after the
server's parse time limit, its data memory bounded) by the CLI's reader
(:func:`brainpainter.tracts.read.read_bundles`), after the streamline counts
in the files' headers were checked against the server's hard cap. A zip is
unpacked there too: members with ``..`` or an absolute path are refused,
folders inside it are flattened, its files and their inflated size are
capped.

What is kept is a *tract bundle* (:data:`MAGIC`, one JSON line, then the files):
what was read, never the files as sent (a file padded to a gigabyte is kept as
its streamlines): each bundle's streamlines as the reader kept them (at most
:data:`MAX_WEB_STREAMLINES` over all bundles, the most
a render may draw, resampled to :data:`brainpainter.tracts.model.N_POINTS`
points) in one ``.tck`` file named after the bundle, and the values table (at
most :data:`MAX_TABLE_BYTES`). A render names it by its upload id (option ``tracts``); its files are
then written once into ``DATA_DIR/incoming/tracts-<sha256>/`` (content
addressed: two different uploads never share a folder, so never a cached
painter), and the run gets the paths exactly as the CLI's ``--tracts``,
``--tract-values`` and ``--tracts-affine`` give them
(:meth:`TractFiles.run_kwargs`).
"""

from __future__ import annotations

import hashlib
import os
import re
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from brainpainter.errors import BrainPainterError
from brainpainter.tracts.model import SUFFIXES
from brainpainter.web.bundle import bundle_header as read_header
from brainpainter.web.bundle import members, write_bundle, written_once

#: The first bytes of a stored tract upload.
MAGIC = b"BRAINPAINTER-TRACTS/2\n"
#: The first bytes of a stored tract upload of any version (an earlier one reads as damaged).
KIND = b"BRAINPAINTER-TRACTS/"
#: Streamlines a web render draws at most (option ``max_streamlines``); a stored upload keeps as many.
MAX_WEB_STREAMLINES = 20_000
#: Table files of an upload read as tract values (one at most).
VALUE_SUFFIXES = (".csv", ".tsv", ".xlsx")
#: Largest total size the members of an uploaded zip may inflate to (bytes).
MAX_UNZIPPED = 1 << 30
#: Largest values table kept with a tract upload (bytes; one inflated from a zip included).
MAX_TABLE_BYTES = 16 << 20
#: Data memory (bytes) of the process that reads a tract upload.
MEMORY_LIMIT = 4 << 30


def is_tract_upload(names: list[str]) -> bool:
    """Whether an upload of files named `names` is tractograms (a .trk/.tck/.trx or a .zip among them)."""
    return any(n.lower().endswith((*SUFFIXES, ".zip")) for n in names)


def is_tract_bundle(data: bytes) -> bool:
    """Whether stored upload bytes are a tract bundle."""
    return data.startswith(KIND)


def member_name(name: str) -> str:
    """A client's (or a zip member's) file name made safe: no folder, no leading dot, suffix kept.

    ``AF L.trk`` -> ``AF_L.trk``; ``../x/CST_R.tck`` -> ``CST_R.tck``.
    """
    from brainpainter.io.output import safe_name

    base = PurePosixPath(name.replace("\\", "/")).name
    suffix = PurePosixPath(base).suffix.lower()
    stem = base[: len(base) - len(suffix)] if suffix else base
    stem = safe_name(stem).lstrip("._")[:80] or "bundle"
    return stem + "".join(ch for ch in suffix if ch.isalnum() or ch == ".")


# -- reading (in the process that upload.read_tract_upload starts) ------------------------------
def unzip(path: Path, into: Path, max_files: int,
          subject: str | None = None) -> tuple[list[Path], list[str]]:
    """The members of zip `path` written into `into` (flattened); ``__MACOSX`` and dot files skipped.

    A zip of subject folders (``sub_1/AF_L.trk``, ``sub_2/AF_L.trk``, ...: the same bundle file in
    several top-level folders, as dipy's and pyAFQ's outputs are zipped) gives the members of one
    folder, `subject` (default: the first in natural order), and the files at its top level.

    Returns
    -------
    files : list of Path
        The members written.
    subjects : list of str
        The zip's subject folders, in natural order (empty for a zip of bundles).

    Raises
    ------
    BrainPainterError
        A member named with ``..`` or an absolute path, two members of the same name (not in subject
        folders), more than `max_files` files, more than :data:`MAX_UNZIPPED` bytes inflated, not a zip,
        or a `subject` the zip does not hold.
    """
    shown = path.name
    out: list[Path] = []
    total = 0
    try:
        with zipfile.ZipFile(path) as zf:
            infos = [i for i in zf.infolist() if not i.is_dir()]
            for info in infos:
                parts = PurePosixPath(info.filename.replace("\\", "/")).parts
                if info.filename.startswith(("/", "\\")) or ".." in parts or (parts and ":" in parts[0]):
                    raise BrainPainterError(
                        f"{shown!r} holds {info.filename[:100]!r}, a path outside the zip; zip the bundle "
                        "files themselves (no '..' or absolute paths) and upload it again.")
            infos = [i for i in infos if not any(p.startswith(".") or p == "__MACOSX"
                                                 for p in PurePosixPath(i.filename).parts)]
            subjects = subject_folders([i.filename.replace("\\", "/") for i in infos])
            if subjects or subject is not None:
                chosen = pick_subject(shown, subjects, subject)
                infos = [i for i in infos if _top_folder(i.filename) in (chosen, None)]
            if len(infos) > max_files:
                raise BrainPainterError(f"{shown!r} holds {len(infos)} files; this server reads at most "
                                        f"{max_files} per upload. Upload fewer bundles.")
            for info in infos:
                target = into / member_name(info.filename)
                if target.exists():
                    raise BrainPainterError(
                        f"{shown!r} holds two files named {target.name!r} (in different folders); give each "
                        "bundle once.")
                with zf.open(info) as src, target.open("wb") as dst:
                    while block := src.read(1 << 20):
                        total += len(block)
                        if total > MAX_UNZIPPED:
                            raise BrainPainterError(
                                f"{shown!r} inflates to more than {MAX_UNZIPPED >> 20} MB; this server reads "
                                "at most that much. Upload fewer or smaller bundles.")
                        dst.write(block)
                out.append(target)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, EOFError) as exc:
        raise BrainPainterError(f"{shown!r} is not a readable zip file ({type(exc).__name__}); zip the "
                                "bundle files (.trk, .tck, .trx) and upload it again.") from None
    return out, subjects


def _top_folder(name: str) -> str | None:
    """The top-level folder of zip member `name` (None for a file at the zip's top level)."""
    parts = PurePosixPath(name.replace("\\", "/")).parts
    return parts[0] if len(parts) > 1 else None


def _natural(name: str) -> tuple[Any, ...]:
    """A sort key putting ``sub_2`` before ``sub_10``."""
    return tuple(int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", name))


def subject_folders(names: list[str]) -> list[str]:
    """The subject folders of a zip whose members are `names`: top-level folders holding the same
    tractogram file name (``sub_1/AF_L.trk``, ``sub_2/AF_L.trk``), in natural order; empty when no
    tractogram name repeats across top-level folders (a zip of bundles, folders flattened)."""
    folders: dict[str, set[str]] = {}
    for name in names:
        top = _top_folder(name)
        if top is not None and name.lower().endswith(SUFFIXES):
            folders.setdefault(member_name(name), set()).add(top)
    if not any(len(tops) > 1 for tops in folders.values()):
        return []
    return sorted({top for tops in folders.values() for top in tops}, key=_natural)


def pick_subject(shown: str, subjects: list[str], subject: str | None) -> str:
    """The subject folder to read: `subject`, or the first of `subjects`."""
    if subject is None:
        return subjects[0]
    if subject not in subjects:
        listed = ", ".join(repr(s) for s in subjects[:10]) + (", ..." if len(subjects) > 10 else "")
        what = f"its subject folders are {listed}" if subjects else "it has no subject folders"
        raise BrainPainterError(f"subject {subject[:100]!r} is not a folder of {shown!r}; {what}. Choose "
                                "one of them (or leave subject out).")
    return subject


def header_count(path: Path) -> int | None:
    """Streamlines a tractogram's header says it holds (None when it does not say)."""
    if path.suffix.lower() == ".trx":
        return None  # counted by the reader (memory-mapped)
    import nibabel as nib

    load: Any = nib.streamlines.load
    try:
        header = load(str(path), lazy_load=True).header
        count = int(header.get("nb_streamlines" if path.suffix.lower() == ".trk" else "count", 0))
    except Exception:
        return None  # the reader says what is wrong
    return count if count > 0 else None


def build_tract_bundle(work: Path, files: list[Path], max_files: int,
                       max_streamlines: int, subject: str | None = None) -> dict[str, Any]:
    """Read the uploaded `files` (tractograms, zips, one values table) and write ``work/bundle.bin``.

    `subject`: the folder read from a zip of subject folders (default: the first; :func:`unzip`).

    Returns
    -------
    dict
        The upload's report (``summary``: what was understood and drawn by default).
    """
    import numpy as np

    from brainpainter.tracts.model import MAX_STREAMLINES, N_POINTS
    from brainpainter.tracts.read import read_bundles

    found, subjects = _unzipped(files, work / "given", max_files, subject)
    tracts = [f for f in found if f.suffix.lower() in SUFFIXES]
    tables = [f for f in found if f.suffix.lower() in VALUE_SUFFIXES]
    ignored = sorted(f.name for f in found if f not in tracts and f not in tables)
    if not tracts:
        raise BrainPainterError(
            f"the upload holds no tractogram ({', '.join(SUFFIXES)}); upload one file per bundle "
            "(AF_left.trk, ...) or a .zip of them.")
    if len(tracts) + len(tables) > max_files:
        raise BrainPainterError(f"the upload holds {len(tracts) + len(tables)} files; this server reads at "
                                f"most {max_files} per upload. Upload fewer bundles.")
    if len(tables) > 1:
        listed = ", ".join(f.name for f in tables)
        raise BrainPainterError(f"the upload holds {len(tables)} tables ({listed}); "
                                "give at most one table of bundle values or along-tract profiles.")
    counted = [header_count(f) or 0 for f in tracts]
    if sum(counted) > max_streamlines:
        raise BrainPainterError(
            f"the tractograms hold {sum(counted):,} streamlines; this server reads at most "
            f"{max_streamlines:,} per upload. Upload a subsample (e.g. MRtrix's tckedit -number), or "
            "render it with 'brainpainter render --tracts' on your own computer.")
    if tables and tables[0].stat().st_size > MAX_TABLE_BYTES:
        raise BrainPainterError(
            f"the table {tables[0].name!r} has {tables[0].stat().st_size / 2**20:.0f} MB; this server keeps "
            f"at most {MAX_TABLE_BYTES >> 20} MB of bundle values per upload. Upload a smaller table.")
    read = read_bundles(sorted(tracts), np.eye(4), MAX_WEB_STREAMLINES, N_POINTS, scratch=work,
                        max_inflated=MAX_UNZIPPED)
    if sum(read.counts) > max_streamlines:  # files whose headers did not say
        raise BrainPainterError(
            f"the tractograms hold {sum(read.counts):,} streamlines; this server reads at most "
            f"{max_streamlines:,} per upload. Upload a subsample, or render it on your own computer.")
    kept = write_kept(read, work / "kept")
    drawn = read_bundles(kept, np.eye(4), MAX_STREAMLINES, N_POINTS)  # as a render draws by default
    summary = drawn.summary()
    for b, total in zip(summary["bundles"], read.counts, strict=True):
        b["streamlines"] = total
    notes = [f"{n}: {drawn.drawn(i):,} of {t:,} streamlines drawn by default (a random subsample; "
             f"option max_streamlines draws up to {read.drawn(i):,})"
             for i, (n, t) in enumerate(zip(read.names, read.counts, strict=True)) if drawn.drawn(i) < t]
    values: dict[str, Any] | None = None
    if tables:
        values = _values_report(tables[0], notes)
    if ignored:
        notes.append(f"ignored (not a tractogram or a table): {', '.join(ignored[:10])}")
    summary["notes"] = []
    report = tract_report(summary, [f.name for f in files], values, notes)
    if subjects:
        report["subjects"] = subjects
        report["subject"] = pick_subject("", subjects, subject)
        report["summary"] += f"; subject {report['subject']} of {len(subjects)}"
    stored = [("bundles", f) for f in kept] + [("values", f) for f in tables]
    write_bundle(work / "bundle.bin", MAGIC, {"report": report}, "role", list(stored))
    return report


def _unzipped(files: list[Path], given: Path, max_files: int,
              subject: str | None) -> tuple[list[Path], list[str]]:
    """The uploaded `files` with each zip's members in its place (written into `given`), and the subject
    folders of a zip of them (:func:`unzip`)."""
    given.mkdir(exist_ok=True)
    found: list[Path] = []
    subjects: list[str] = []
    zips = [f for f in files if f.suffix.lower() == ".zip"]
    if subject is not None and len(zips) != 1:
        raise BrainPainterError(f"subject {subject[:100]!r} names a folder of a zip, but {len(zips)} zips "
                                "were uploaded; upload one .zip of subject folders.")
    for f in files:
        if f.suffix.lower() == ".zip":
            got, subjects = unzip(f, given, max_files, subject)
            found += got
        else:
            found.append(f)
    return found, subjects


def write_kept(tracts: Any, folder: Path) -> list[Path]:
    """Each bundle's kept streamlines as ``folder/<name>.tck`` (RAS millimetres, as read); their paths.

    Parameters
    ----------
    tracts : brainpainter.tracts.bundles.Tracts
        Read with an identity placement: ``lines`` of shape (n_streamlines, n_points, 3) in the files'
        RAS millimetres.
    """
    import numpy as np
    from nibabel.streamlines.tck import TckFile
    from nibabel.streamlines.tractogram import Tractogram

    folder.mkdir()
    out = []
    for i, name in enumerate(tracts.names):
        lines = tracts.lines[tracts.bundle == i]
        path = folder / member_name(f"{name}.tck")
        tractogram: Any = Tractogram(lines, affine_to_rasmm=np.eye(4))  # type: ignore[no-untyped-call]
        TckFile(tractogram).save(str(path))  # type: ignore[no-untyped-call]
        out.append(path)
    return out


def _values_report(table: Path, notes: list[str]) -> dict[str, Any]:
    from brainpainter.tracts.values import read_tract_values

    try:
        tv = read_tract_values(table)
    except BrainPainterError as exc:
        if "value columns" not in str(exc):
            raise
        notes.append(f"{table.name}: several value columns; choose one with the option tract_value")
        return {"file": table.name, "bundles": [], "nodes": None, "images": ["1"]}
    nodes = max((n for _, n in tv.nodes), default=1)
    return {"file": table.name, "bundles": list(tv.bundles), "nodes": nodes if nodes > 1 else None,
            "images": list(tv.images or ("1",))[:5000]}


def tract_report(summary: dict[str, Any], names: list[str], values: dict[str, Any] | None,
                 notes: list[str]) -> dict[str, Any]:
    """The report of a tract upload; ``summary`` is the line the page shows (what is drawn by default)."""
    bundles = summary["bundles"]
    drawn = sum(b["drawn"] for b in bundles)
    total = sum(b["streamlines"] for b in bundles)
    line = f"tracts: {', '.join(b['name'] for b in bundles)} ({drawn:,} streamlines of {total:,})"
    if values is not None:
        what = f"profiles of {values['nodes']} nodes" if values["nodes"] else "one value per bundle"
        line += f"; values: {values['file']} ({what})"
    return {"ok": True, "kind": "tracts", "summary": line, "files": names, "bundles": bundles,
            "values": values, "notes": notes + list(summary["notes"]), "errors": []}


# -- a stored tract bundle -----------------------------------------------------------------------
def bundle_header(data: bytes) -> tuple[dict[str, Any], int]:
    """The JSON header of a tract bundle and where its files start."""
    return read_header(data, MAGIC, "role", ("bundles", "values"),
                       "the stored tract upload is damaged; upload the tractograms again.")


def report_of(data: bytes) -> dict[str, Any]:
    """The report stored with a tract bundle."""
    report: dict[str, Any] = bundle_header(data)[0]["report"]
    return report


@dataclass(frozen=True)
class TractFiles:
    """A tract bundle's files on disk: what ``--tracts`` and ``--tract-values`` name.

    Attributes
    ----------
    folder : Path
        ``DATA_DIR/incoming/tracts-<sha256>``.
    bundles : Path
        The folder of tractograms (``--tracts``).
    values : Path or None
        The table of bundle values (``--tract-values``), if the upload had one.
    """

    folder: Path
    bundles: Path
    values: Path | None

    def affine_file(self, text: str) -> Path:
        """`text` (4 rows of 4 numbers, or 16 or 12 numbers; commas allowed) as a matrix file.

        Raises
        ------
        BrainPainterError
            Not a finite 4x4 (or 3x4) affine with last row 0 0 0 1.
        """
        from brainpainter.tracts.model import read_affine

        numbers = [t for t in re.split(r"[\s,;\[\]]+", text) if t]
        rows = [numbers[i:i + 4] for i in range(0, len(numbers), 4)] if len(numbers) % 4 == 0 else [numbers]
        body = "\n".join(" ".join(r) for r in rows) + "\n"
        path = self.folder / f"affine-{hashlib.sha256(body.encode()).hexdigest()[:24]}.txt"
        if not path.exists():
            fd, tmp = tempfile.mkstemp(dir=self.folder, prefix=".affine-")
            with os.fdopen(fd, "w") as fh:
                fh.write(body)
            os.replace(tmp, path)
        try:
            read_affine(path)
        except BrainPainterError as exc:
            path.unlink(missing_ok=True)
            message = str(exc).splitlines()[0].replace(f"--tracts-affine {str(path)!r}", "--tracts-affine")
            raise BrainPainterError(message) from None
        return path


def materialise(data: bytes, root: Path) -> TractFiles:
    """The files of tract bundle `data` in ``root/incoming/tracts-<sha256>`` (written once, then reused:
    :func:`~brainpainter.web.bundle.written_once`)."""
    header, start = bundle_header(data)

    def fill(work: Path) -> None:
        for f, content in members(data, header, start):
            sub = work / str(f["role"])
            sub.mkdir(exist_ok=True)
            (sub / member_name(str(f["name"]))).write_bytes(content)
        (work / "bundles").mkdir(exist_ok=True)

    folder = written_once(data, root, "tracts", fill)
    tables = sorted((folder / "values").glob("*")) if (folder / "values").is_dir() else []
    return TractFiles(folder, folder / "bundles", tables[0] if tables else None)
