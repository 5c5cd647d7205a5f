"""Uploads: the body streamed to disk under a deadline, then read with bounded work.

A request body is written to ``DATA_DIR/incoming/`` as it arrives (memory stays
small however many clients send slowly; :class:`brainpainter.web.guard.Guard`
enforces the size limit and the deadline). The table is then checked as
``brainpainter check`` does, with the server's row limit; a spreadsheet
(``.xlsx``, a zip file) is read in a process of its own that is killed after
``parse_time_limit_s``, because reading a large sheet costs seconds of CPU
that a thread could not be stopped from spending.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import tempfile
from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError

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


def check_upload(data: bytes, name: str, options: dict[str, Any], *, max_rows: int,
                 time_limit_s: float) -> tuple[dict[str, Any], list[str]]:
    """``check --json``'s report and the image names of an uploaded table; raises its first error.

    Text tables are read here (their cost is linear in the rows, which :func:`check_rows` bounds);
    spreadsheets in a spawned process that is killed after `time_limit_s` seconds.
    """
    check_rows(data, name, max_rows)
    if not is_spreadsheet(data):
        return check_table(data, name, options, max_rows)
    ctx = mp.get_context("spawn")
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_check_main, args=(child, data, name, options, max_rows), daemon=True,
                       name="brainpainter-read-upload")
    proc.start()
    child.close()
    try:
        if not parent.poll(time_limit_s):
            raise BrainPainterError(
                f"reading {name!r} took longer than this server's limit of {time_limit_s:g} s; save the "
                "sheet as CSV (or remove unused rows and columns) and upload it again."
            )
        status, payload = parent.recv()
    except (EOFError, OSError):
        raise BrainPainterError(f"reading {name!r} stopped unexpectedly; save the sheet as CSV and upload "
                                "it again.") from None
    finally:
        parent.close()
        if proc.is_alive():
            proc.kill()
        proc.join(timeout=5)
    if status != "ok":
        raise BrainPainterError(payload)
    report, images = payload
    return report, images


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
        conn.send(("error", f"cannot read {name!r} ({type(exc).__name__}); save it as CSV and upload it "
                            "again."))
    finally:
        conn.close()
