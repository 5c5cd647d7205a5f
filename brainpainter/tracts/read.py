"""Tractogram files to packed, resampled, oriented bundles, with bounded memory.

``.trk`` and ``.tck`` are read by ``nibabel.streamlines`` with
``lazy_load=True``: streamlines are streamed in chunks, each chunk is packed
(an ``ArraySequence``), subsampled to the budget and resampled to a few points
right away, so a whole-brain tractogram of a million streamlines never sits in
memory (only the kept, resampled ones do: budget x points x 12 bytes).
``.trx`` is read by trx-python (memory-mapped; its groups are bundles). A
compressed ``.trx`` (a deflated zip) is unpacked here, not by trx-python: every
member's size is checked before anything is written (and the bytes are counted
while they are), into a fresh folder under the caller's `scratch` folder that is
removed on every exit.
Coordinates are the files' RAS millimetres (nibabel's ``RASMM`` space: for
``.tck`` these are MRtrix's scanner coordinates, which need no reference image).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import zipfile
from collections.abc import Iterable, Iterator
from pathlib import Path, PurePosixPath
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError
from brainpainter.tracts.bundles import Tracts
from brainpainter.tracts.names import canonical
from brainpainter.tracts.streamlines import orient, pick, resample

#: Streamlines packed and resampled at a time while streaming a file.
CHUNK = 20_000
TRX_HINT = "pip install 'brainpainter[tracts]' (trx-python)"


def _resampled(chunk: Any, n_points: int) -> NDArray[Any]:
    """Resample an ``ArraySequence`` chunk (its packed data, offsets and lengths).

    An indexed ``ArraySequence`` (``seq[indices]``) shares its parent's data with
    offsets in any order: the chosen points are gathered (copied) first.
    """
    lengths = np.asarray(chunk._lengths, dtype=np.int64)
    offsets = np.asarray(chunk._offsets, dtype=np.int64)
    keep = lengths > 0
    lengths, offsets = lengths[keep], offsets[keep]
    packed = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64) if len(lengths) else offsets
    gather = np.repeat(offsets - packed, lengths) + np.arange(int(lengths.sum()))
    return resample(np.asarray(chunk._data)[gather], packed, lengths, n_points)


def _stream(streamlines: Iterable[NDArray[Any]], chosen: NDArray[Any] | None,
            n_points: int) -> Iterator[NDArray[Any]]:
    """Resampled chunks of the chosen streamlines of an iterable (all where `chosen` is None)."""
    from nibabel.streamlines.array_sequence import ArraySequence

    want = None if chosen is None else set(chosen.tolist())
    seq: Any = ArraySequence()  # type: ignore[no-untyped-call]
    for i, s in enumerate(streamlines):
        if want is not None and i not in want:
            continue
        seq.append(np.asarray(s, dtype=np.float32), cache_build=True)
        if len(seq) >= CHUNK:
            seq.finalize_append()
            yield _resampled(seq, n_points)
            seq = ArraySequence()  # type: ignore[no-untyped-call]
    seq.finalize_append()
    if len(seq):
        yield _resampled(seq, n_points)


def _nibabel_bundle(path: Path, budget: int, n_points: int, seed: int) -> tuple[NDArray[Any], int]:
    """Resampled streamlines of a .trk/.tck (a subsample above `budget`) and the file's count."""
    import nibabel as nib

    load: Any = nib.streamlines.load
    try:
        tg = load(str(path), lazy_load=True)
    except Exception as exc:  # nibabel raises many types for a broken header
        raise BrainPainterError(
            f"tractogram {str(path)!r} could not be read by nibabel ({type(exc).__name__}: {exc}); give a "
            "valid .trk or .tck file.") from None
    key = "nb_streamlines" if path.suffix.lower() == ".trk" else "count"
    try:
        total = int(tg.header.get(key, 0))
    except (TypeError, ValueError):
        total = 0
    if total <= 0:  # count not in the header: count by streaming once
        total = sum(1 for _ in tg.tractogram.streamlines)
        tg = load(str(path), lazy_load=True)
    chosen = pick(total, budget, seed)
    parts = list(_stream(tg.tractogram.streamlines, chosen, n_points))
    lines = np.concatenate(parts) if parts else np.zeros((0, n_points, 3), np.float32)
    return lines, total


@contextlib.contextmanager
def _open_trx(path: Path, scratch: Path | None, max_inflated: int | None) -> Iterator[Any]:
    """The ``TrxFile`` of `path`, closed (and its unpacked copy removed) on every exit.

    A stored (uncompressed) zip or a folder is memory-mapped where it is; a compressed zip is
    unpacked into a fresh folder under `scratch` (when None: trx-python's ``TRX_TMPDIR`` if set, else
    the system's temporary folder) after its members' sizes were checked against `max_inflated` bytes
    (None: the free space there).
    """
    try:
        import trx.trx_file_memmap as tmm
    except ImportError:
        raise BrainPainterError(f"reading {str(path)!r} needs trx-python, which is not installed; "
                                f"{TRX_HINT}, or convert it to .trk/.tck.") from None
    folder: str | None = None
    try:
        try:
            if path.is_dir():
                trx = tmm.load(str(path))
            else:
                with zipfile.ZipFile(path) as zf:
                    infos = [i for i in zf.infolist() if not i.is_dir()]
                    if all(i.compress_type == zipfile.ZIP_STORED for i in infos):
                        trx = tmm.load_from_zip(str(path))
                    else:
                        folder = tempfile.mkdtemp(prefix="trx-", dir=scratch or _trx_tmpdir())
                        _unpack(path, zf, infos, Path(folder), max_inflated)
                        trx = tmm.load_from_directory(folder)
        except BrainPainterError:
            raise
        except Exception as exc:
            raise BrainPainterError(f"{str(path)!r} could not be read as a .trx file ({type(exc).__name__}: "
                                    f"{exc}); give a valid TRX file.") from None
        try:
            yield trx
        finally:
            trx.close()
    finally:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)


def _trx_tmpdir() -> Path | None:
    """trx-python's ``TRX_TMPDIR`` (``use_working_dir``: the current folder); None when not set."""
    given = os.environ.get("TRX_TMPDIR")
    return None if given is None else Path.cwd() if given == "use_working_dir" else Path(given)


def _unpack(path: Path, zf: zipfile.ZipFile, infos: list[zipfile.ZipInfo], folder: Path,
            max_inflated: int | None) -> None:
    """Write the members `infos` of a .trx's zip into `folder`, checking sizes before and while writing.

    Raises
    ------
    BrainPainterError
        A member named outside the folder, or members that (say they) inflate to more than
        `max_inflated` bytes (the free space of `folder` when None).
    """
    limit = max_inflated if max_inflated is not None else shutil.disk_usage(folder).free
    where = "this server unpacks at most" if max_inflated is not None else "the free space is"
    declared = sum(i.file_size for i in infos)

    def too_big(size: int) -> BrainPainterError:
        return BrainPainterError(
            f"{str(path)!r} unpacks to {size / 2**20:,.0f} MB or more; {where} {limit / 2**20:,.0f} MB. "
            "Give a smaller .trx (a subsample), or save it uncompressed (trx-python's save without "
            "compression).")

    if declared > limit:
        raise too_big(declared)
    total = 0
    for info in infos:
        parts = PurePosixPath(info.filename.replace("\\", "/")).parts
        if not parts or info.filename.startswith(("/", "\\")) or ".." in parts or ":" in parts[0]:
            raise BrainPainterError(f"{str(path)!r} holds {info.filename[:100]!r}, a path outside the .trx; "
                                    "give a valid TRX file.")
        target = folder.joinpath(*parts)
        target.parent.mkdir(parents=True, exist_ok=True)
        with zf.open(info) as src, target.open("wb") as dst:
            while block := src.read(1 << 20):
                total += len(block)
                if total > limit:
                    raise too_big(total)
                dst.write(block)


def _trx_bundles(path: Path, budget: int, n_points: int, seed: int, scratch: Path | None = None,
                 max_inflated: int | None = None) -> list[tuple[str, NDArray[Any], int]]:
    """``(name, resampled streamlines, count)`` per group of a .trx (the file name when it has none);
    a compressed one is unpacked under `scratch` (see :func:`_open_trx`)."""
    with _open_trx(path, scratch, max_inflated) as trx:
        seq = trx.streamlines
        groups = dict(trx.groups) or {_stem(path): np.arange(len(seq))}
        out = []
        for name, members in sorted(groups.items()):
            members = np.asarray(members, dtype=np.int64)
            chosen = pick(len(members), budget, seed)
            idx = members if chosen is None else members[chosen]
            lines = np.concatenate([_resampled(seq[idx[i:i + CHUNK]], n_points)
                                    for i in range(0, len(idx), CHUNK)] or
                                   [np.zeros((0, n_points, 3), np.float32)])
            out.append((str(name), lines, len(members)))
        return out


def _stem(path: Path) -> str:
    return path.name[: -len(path.suffix)] if path.suffix else path.name


def read_bundles(files: Iterable[Path], to_template: NDArray[Any], max_streamlines: int, n_points: int,
                 seed: int = 0, *, scratch: Path | None = None, max_inflated: int | None = None) -> Tracts:
    """Read every bundle, subsample to `max_streamlines` in all, resample, orient, place.

    Parameters
    ----------
    files : iterable of Path
        One bundle per .trk/.tck file (named after the file), one per group of a .trx.
    to_template : ndarray of float, shape (4, 4)
        Files' RAS millimetres -> template coordinates.
    max_streamlines : int
        Over all bundles; each bundle keeps its share of the budget
        (proportional to its count; at least one streamline).
    n_points : int
    seed : int
    scratch : Path, optional
        Where a compressed .trx is unpacked (a fresh folder, removed after; default: the system's
        temporary folder).
    max_inflated : int, optional
        Largest size (bytes) a compressed .trx may unpack to (default: the free space there).

    Returns
    -------
    Tracts

    Raises
    ------
    BrainPainterError
        A file that cannot be read, two files of the same bundle, or no streamline at all.
    """
    files = list(files)
    counts: dict[str, int] = {}
    # the budget per file is the whole budget; bundles are trimmed to their share afterwards
    read: list[tuple[str, NDArray[Any], int, Path]] = []
    for path in files:
        if path.suffix.lower() == ".trx":
            bundles = _trx_bundles(path, max_streamlines, n_points, seed, scratch, max_inflated)
            for name, lines, total in bundles:
                read.append((canonical(name), lines, total, path))
        else:
            lines, total = _nibabel_bundle(path, max_streamlines, n_points, seed)
            read.append((canonical(_stem(path)), lines, total, path))
    seen: dict[str, Path] = {}
    for name, _, total, path in read:
        if name in seen:
            raise BrainPainterError(
                f"bundle {name!r} was given twice ({str(seen[name])!r} and {str(path)!r}); give each bundle "
                "once (one file per bundle).")
        seen[name] = path
        counts[name] = total
    grand = sum(len(lines) for _, lines, _, _ in read)
    if grand == 0:
        raise BrainPainterError(f"the tractograms {[str(f) for f in files]} hold no streamline; give "
                                "non-empty bundles.")
    names, chunks, bundle_of, notes = [], [], [], []
    for i, (name, lines, total, _) in enumerate(read):
        share = len(lines) if grand <= max_streamlines else max(1, int(len(lines) * max_streamlines / grand))
        chosen = pick(len(lines), share, seed)
        kept = lines if chosen is None else lines[chosen]
        if len(kept) < total:
            notes.append(f"{name}: {len(kept):,} of {total:,} streamlines drawn (a random subsample, seed "
                         f"{seed}; --max-streamlines {max_streamlines:,} over all bundles)")
        pts = kept.reshape(-1, 3).astype(np.float64) @ to_template[:3, :3].T + to_template[:3, 3]
        names.append(name)
        chunks.append(orient(pts.reshape(kept.shape).astype(np.float32)))
        bundle_of.append(np.full(len(kept), i, np.int32))
    return Tracts(tuple(names), np.concatenate(chunks), np.concatenate(bundle_of),
                  tuple(counts[n] for n in names), tuple(notes))
