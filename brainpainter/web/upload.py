"""Uploads: the body streamed to disk under a deadline, then read with bounded work.

A request body is written to ``DATA_DIR/incoming/`` as it arrives (memory stays
small however many clients send slowly; :class:`brainpainter.web.guard.Guard`
enforces the size limit and the deadline). The table is then checked as
``brainpainter check`` does, with the server's row limit; a spreadsheet
(``.xlsx``, a zip file) is read in a process of its own that is killed after
``parse_time_limit_s``, because reading a large sheet costs seconds of CPU
that a thread could not be stopped from spending. A map upload (one or two
hemisphere files, or a NIfTI volume: :mod:`brainpainter.web.maps`) is read the
same way, in a process whose data memory is bounded too.
"""

from __future__ import annotations

import errno
import multiprocessing as mp
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError
from brainpainter.web.maps import is_bundle

#: Form encodings a browser may send cross-origin without asking first (a CORS "simple" request);
#: uploads must come with another content type, which only the page itself (same origin) can send.
SIMPLE_CONTENT_TYPES = ("application/x-www-form-urlencoded", "multipart/form-data", "text/plain")


def content_type_allowed(content_type: str | None) -> bool:
    """True when an upload's ``Content-Type`` cannot come from another site's page without a preflight."""
    if not content_type:
        return False
    media = content_type.split(";", 1)[0].strip().lower()
    return bool(media) and media not in SIMPLE_CONTENT_TYPES


def new_incoming(root: Path) -> tuple[Any, Path]:
    """An open binary file (mode 0600) in ``root/incoming`` for a body being received, and its path."""
    folder = root / "incoming"
    folder.mkdir(mode=0o700, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=folder, prefix="body-", suffix=".part")
    return os.fdopen(fd, "wb"), Path(name)


def is_spreadsheet(data: bytes) -> bool:
    return data.startswith(b"PK\x03\x04")


def check_rows(data: bytes, name: str, max_rows: int) -> None:
    """Refuse a text table with more than `max_rows` rows, before it is parsed (a linear byte count).

    Raises
    ------
    BrainPainterError
        One line: the rows given, the limit and what to do.
    """
    if is_spreadsheet(data):
        return  # counted by the reader's process (see check_upload)
    lines = data.count(b"\n") + (0 if data.endswith(b"\n") else 1)
    if lines - 1 > max_rows:
        raise too_many_rows(name, lines - 1, max_rows)


def too_many_rows(name: str, rows: int, max_rows: int) -> BrainPainterError:
    return BrainPainterError(
        f"{name!r} has {rows} rows; this server reads at most {max_rows} rows per upload. Split the "
        "table, or run 'brainpainter render' on your own computer for larger tables."
    )


def _in_child(target: Any, args: tuple[Any, ...], name: str, time_limit_s: float, too_slow: str,
              stopped: str) -> Any:
    """``target(pipe, *args)`` in a spawned process killed after `time_limit_s`; what it sent back.

    The child sends ``("ok", payload)``, ``("error", message)`` or ``("full", message)`` (:func:`_failed`);
    a message, a child too slow (`too_slow`) or one that died (`stopped`) is raised as one line, a full
    disk as ``OSError`` ENOSPC.
    """
    ctx = mp.get_context("spawn")
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=target, args=(child, *args), daemon=True, name=name)
    proc.start()
    child.close()
    try:
        if not parent.poll(time_limit_s):
            raise BrainPainterError(too_slow)
        status, payload = parent.recv()
    except (EOFError, OSError):
        raise BrainPainterError(stopped) from None
    finally:
        parent.close()
        if proc.is_alive():
            proc.kill()
        proc.join(timeout=5)
    if status == "full":  # the disk filled while the child wrote (an inflated member): 507, not a bad file
        raise OSError(errno.ENOSPC, payload)
    if status != "ok":
        raise BrainPainterError(payload)
    return payload


def _failed(exc: BaseException, line: str) -> tuple[str, str]:
    """What a reading process sends for an unexpected error `exc`: ``("full", ...)`` when the disk is
    full (the server answers 507), else ``("error", line)``."""
    from brainpainter.web.disk import disk_full

    return ("full", "no space left on the server's disk") if disk_full(exc) else ("error", line)


def check_upload(data: bytes, name: str, options: dict[str, Any], *, max_rows: int,
                 time_limit_s: float) -> tuple[dict[str, Any], list[str]]:
    """``check --json``'s report and the image names of an uploaded table; raises its first error.

    Text tables are read here (their cost is linear in the rows, which :func:`check_rows` bounds);
    spreadsheets in a spawned process that is killed after `time_limit_s` seconds.
    """
    check_rows(data, name, max_rows)
    from brainpainter.web.tracts import is_tract_bundle

    if is_bundle(data) or is_tract_bundle(data):  # only the server writes map and tract bundles
        raise BrainPainterError(f"{name!r} is not a table (it starts as a stored map or tract upload); "
                                "upload the table, map or tractogram files themselves.")
    if not is_spreadsheet(data):
        return check_table(data, name, options, max_rows)
    return _in_child(  # type: ignore[no-any-return]
        _check_main, (data, name, options, max_rows), "brainpainter-read-upload", time_limit_s,
        f"reading {name!r} took longer than this server's limit of {time_limit_s:g} s; save the sheet as "
        "CSV (or remove unused rows and columns) and upload it again.",
        f"reading {name!r} stopped unexpectedly; save the sheet as CSV and upload it again.")


def read_and_check(path: Path, name: str, options: dict[str, Any], *, max_rows: int,
                   time_limit_s: float) -> tuple[bytes, tuple[dict[str, Any], list[str]]]:
    """The received body at `path` and :func:`check_upload`'s answer for it."""
    data = path.read_bytes()
    return data, check_upload(data, name, options, max_rows=max_rows, time_limit_s=time_limit_s)


def check_table(data: bytes, name: str, options: dict[str, Any],
                max_rows: int) -> tuple[dict[str, Any], list[str]]:
    """The check report and image names (in this process); raises the first error as the CLI does."""
    from brainpainter.table.region_table import inspect_table
    from brainpainter.table.report import check_report
    from brainpainter.web.options import table_stream

    scale = options.pop("scale", None) or {}
    table = inspect_table(table_stream(data, name), options.get("atlas"),
                          image_column=options.get("image_column"), value=options.get("value"),
                          region_column=options.get("region_column"), strict=bool(options.get("strict")))
    if len(table.images) > max_rows:
        raise too_many_rows(name, len(table.images), max_rows)
    report = check_report(table, **scale)
    if report["errors"]:
        raise BrainPainterError(report["errors"][0])
    return report, list(table.images)


def _check_main(conn: Any, data: bytes, name: str, options: dict[str, Any], max_rows: int) -> None:
    """Entry point of the reading process: send ``("ok", (report, images))`` or ``("error", line)``."""
    from brainpainter.web.worker import die_with_parent

    die_with_parent()
    try:
        conn.send(("ok", check_table(data, name, options, max_rows)))
    except BrainPainterError as exc:
        conn.send(("error", str(exc).splitlines()[0] if str(exc) else type(exc).__name__))
    except Exception as exc:
        conn.send(_failed(exc, f"cannot read {name!r} ({type(exc).__name__}); save it as CSV and upload it "
                               "again."))
    finally:
        conn.close()


# -- maps (brainpainter.web.maps): read in a process of their own, bounded in time and memory -------
def read_map_upload(path: Path, names: list[str], sizes: list[int], hemis: list[str], folder: Path, *,
                    max_images: int, time_limit_s: float) -> tuple[bytes, tuple[dict[str, Any], list[str]]]:
    """The received body at `path` (the files `names`) read as a map: ``(bundle, (report, images))``.

    See :func:`brainpainter.web.maps.split_body`, :func:`~brainpainter.web.maps.hemispheres` and
    :func:`read_map_files`.
    """
    from brainpainter.web.maps import hemispheres, split_body

    parts = split_body(path.read_bytes(), names, sizes)
    sides = hemispheres(parts, hemis)
    bundle, report, images = read_map_files(parts, sides, folder, max_images=max_images,
                                            time_limit_s=time_limit_s)
    return bundle, (report, images)


def read_map_files(parts: list[tuple[str, bytes]], hemis: list[str | None], folder: Path, *,
                   max_images: int, time_limit_s: float) -> tuple[bytes, dict[str, Any], list[str]]:
    """Read map files into a bundle: ``(bundle bytes, report, image names)``; raises the first error.

    Parameters
    ----------
    parts : list of (str, bytes)
        The client's file names and contents.
    hemis : list of str or None
        From :func:`brainpainter.web.maps.hemispheres`.
    folder : Path
        A private folder for the work (under the server's data folder; removed after).
    max_images : int
        Most images (volumes of a 4-D file, data arrays of a GIfTI) one upload may hold.
    time_limit_s : float
        The reading process is killed after this many seconds.
    """
    from brainpainter.web.maps import file_name

    work = Path(tempfile.mkdtemp(prefix="maps-", dir=folder))
    try:
        entries = []
        for k, ((name, data), hemi) in enumerate(zip(parts, hemis, strict=True)):
            sub = work / f"in{k}"
            sub.mkdir()
            (sub / file_name(name)).write_bytes(data)
            entries.append((hemi, str(sub / file_name(name))))
        shown = " + ".join(file_name(n) for n, _ in parts)
        report, images = _in_child(
            _map_main, (str(work), entries, max_images), "brainpainter-read-map", time_limit_s,
            f"reading {shown!r} took longer than this server's limit of {time_limit_s:g} s; upload a smaller "
            "map (fewer images or volumes), or render it with 'brainpainter render' on your own computer.",
            f"reading {shown!r} stopped unexpectedly (too large for this server?); upload a smaller map.")
        return (work / "bundle.bin").read_bytes(), report, images
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _map_main(conn: Any, work: str, entries: list[tuple[str | None, str]], max_images: int) -> None:
    """Entry point of the map reading process: send ``("ok", (report, images))`` or ``("error", line)``."""
    from brainpainter.web.maps import build_bundle
    from brainpainter.web.worker import die_with_parent, limit_memory

    die_with_parent()
    limit_memory()
    try:
        conn.send(("ok", build_bundle(Path(work), [(h, Path(p)) for h, p in entries], max_images)))
    except BrainPainterError as exc:
        line = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        conn.send(_failed(exc, line.replace(work + "/", "").replace(work, "")))
    except MemoryError:
        conn.send(("error", "the map needs more memory than this server gives one upload; upload a smaller "
                            "map (fewer images or volumes, or a coarser volume)."))
    except Exception as exc:
        conn.send(_failed(exc, f"cannot read the map ({type(exc).__name__}); check that the file is what its "
                               "name says (docs/maps.md lists the formats)."))
    finally:
        conn.close()


# -- tractograms (brainpainter.web.tracts): read in a process of their own, bounded in time and memory ---
def read_tract_upload(path: Path, names: list[str], sizes: list[int], folder: Path, *, max_files: int,
                      max_streamlines: int, time_limit_s: float,
                      subject: str | None = None) -> tuple[bytes, dict[str, Any]]:
    """The received body at `path` (the files `names`, `sizes` bytes each) read as tractograms:
    ``(tract bundle, report)``; raises the first error as one line.

    Parameters
    ----------
    folder : Path
        A private folder for the work (under the server's data folder; removed after).
    max_files : int
        Most files (bundles and a values table, a zip's members counted) one upload may hold.
    max_streamlines : int
        Most streamlines the files may hold together (the hard cap; fewer are drawn).
    time_limit_s : float
        The reading process is killed after this many seconds.
    subject : str, optional
        The folder read from a zip of subject folders (default: the first).
    """
    from brainpainter.web.maps import split_body
    from brainpainter.web.tracts import member_name

    if len(names) > max_files:
        raise BrainPainterError(f"{len(names)} files were sent; this server reads at most {max_files} per "
                                "upload. Upload fewer bundles, or a .zip of them.")
    data = path.read_bytes()
    parts = split_body(data, names, sizes, max_files=max_files)
    work = Path(tempfile.mkdtemp(prefix="tract-upload-", dir=folder))
    try:
        (work / "in").mkdir()
        written = []
        for name, body in parts:
            target = work / "in" / member_name(name)
            if target.exists():
                raise BrainPainterError(f"two files are named {target.name!r}; give each bundle once.")
            target.write_bytes(body)
            written.append(str(target))
        shown = " + ".join(member_name(n) for n in names)[:200]
        report = _in_child(
            _tracts_main, (str(work), written, max_files, max_streamlines, subject),
            "brainpainter-read-tracts",
            time_limit_s,
            f"reading {shown!r} took longer than this server's limit of {time_limit_s:g} s; upload fewer "
            "streamlines (a subsample), or render them with 'brainpainter render --tracts' on your own "
            "computer.",
            f"reading {shown!r} stopped unexpectedly (too large for this server?); upload fewer streamlines.")
        return (work / "bundle.bin").read_bytes(), report
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _tracts_main(conn: Any, work: str, files: list[str], max_files: int, max_streamlines: int,
                 subject: str | None) -> None:
    """Entry point of the tract reading process: send ``("ok", report)`` or ``("error", line)``."""
    from brainpainter.web.tracts import build_tract_bundle
    from brainpainter.web.worker import die_with_parent, limit_memory

    die_with_parent()
    limit_memory()
    try:
        report = build_tract_bundle(Path(work), [Path(f) for f in files], max_files, max_streamlines,
                                    subject)
        conn.send(("ok", report))
    except BrainPainterError as exc:
        line = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        for prefix in (work + "/in/", work + "/given/", work + "/kept/", work + "/", work):
            line = line.replace(prefix, "")
        conn.send(_failed(exc, line))
    except MemoryError:
        conn.send(("error", "the tractograms need more memory than this server gives one upload; upload "
                            "fewer streamlines."))
    except Exception as exc:
        conn.send(_failed(exc, f"cannot read the tractograms ({type(exc).__name__}); check that each file is "
                               "a .trk, .tck or .trx file (docs/tracts.md)."))
    finally:
        conn.close()


def read_connectome_upload(path: Path, names: list[str], sizes: list[int], roles: list[str], folder: Path, *,
                           max_nodes: int, time_limit_s: float) -> tuple[bytes, dict[str, Any]]:
    """The received body at `path` (the files `names`, `sizes` bytes each, `roles` each) read as a
    connectome (:mod:`brainpainter.web.connectomes`): ``(connectome bundle, report)``; raises the first
    error as one line.

    Parameters
    ----------
    folder : Path
        A private folder for the work (under the server's data folder; removed after).
    max_nodes : int
        Most nodes a matrix may have.
    time_limit_s : float
        The reading process is killed after this many seconds.
    """
    from brainpainter.web.connectomes import ROLES, roles_of
    from brainpainter.web.maps import split_body
    from brainpainter.web.tracts import member_name

    roles = roles_of(names, roles)
    parts = split_body(path.read_bytes(), names, sizes, max_files=len(ROLES))
    work = Path(tempfile.mkdtemp(prefix="connectome-upload-", dir=folder))
    try:
        (work / "in").mkdir()
        written: dict[str, str] = {}
        for role, (name, body) in zip(roles, parts, strict=True):
            (work / "in" / role).mkdir()
            target = work / "in" / role / member_name(name)
            target.write_bytes(body)
            written[role] = str(target)
        shown = member_name(names[roles.index("matrix")])
        report = _in_child(
            _connectome_main, (str(work), written, max_nodes), "brainpainter-read-connectome", time_limit_s,
            f"reading {shown!r} took longer than this server's limit of {time_limit_s:g} s; give a smaller "
            "matrix, or render it with 'brainpainter render --connectome' on your own computer.",
            f"reading {shown!r} stopped unexpectedly (too large for this server?); give a smaller matrix.")
        return (work / "bundle.bin").read_bytes(), report
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _connectome_main(conn: Any, work: str, files: dict[str, str], max_nodes: int) -> None:
    """Entry point of the connectome reading process: send ``("ok", report)`` or ``("error", line)``."""
    from brainpainter.web.connectomes import ROLES, build_connectome_bundle
    from brainpainter.web.worker import die_with_parent, limit_memory

    die_with_parent()
    limit_memory()
    try:
        conn.send(("ok", build_connectome_bundle(Path(work), {r: Path(p) for r, p in files.items()},
                                                 max_nodes)))
    except BrainPainterError as exc:
        line = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        for role in ROLES:
            line = line.replace(f"{work}/in/{role}/", "")
        conn.send(_failed(exc, line.replace(work + "/", "")))
    except MemoryError:
        conn.send(("error", "the connectome needs more memory than this server gives one upload; give a "
                            "smaller matrix."))
    except Exception as exc:
        conn.send(_failed(exc, f"cannot read the connectome ({type(exc).__name__}); check that the matrix "
                               "is a CSV/TSV/text matrix, .edge, .npy, .mat or .pconn.nii."))
    finally:
        conn.close()
