"""GIfTI files read without following them elsewhere: :func:`read_gifti`, the one GIfTI reader.

A GIfTI ``DataArray`` may keep its values in another file
(``Encoding="ExternalFileBinary"``, ``ExternalFileName="/etc/passwd"``), which
nibabel opens while it parses. So the XML is scanned first (with expat, as
nibabel parses it; entity declarations are refused): where external data is
not allowed (``external="refuse"``: the web server) any is an error; else
(``"folder"``: the command line and Python) the external file must lie inside
the GIfTI's own folder (its resolved path: no ``..``, absolute path or
symbolic link out of it). The same scan stops a gzipped data array that
inflates to more than its ``Dim``s say. nibabel then parses the bytes already
read, from memory: it can follow a reference only when the scan allowed it.
Gzipped GIfTI (``.gii.gz``, as nilearn ships fsaverage5) is inflated in
memory, bounded.
"""

from __future__ import annotations

import io
import math
import zlib
from pathlib import Path
from typing import Any, Literal

from brainpainter.errors import BrainPainterError
from brainpainter.io.files import MAX_DATA_FILE, inflated, read_input
from brainpainter.io.sniff import GIFTI, HEAD, what_is

#: Where a GIfTI's external data may be: only inside its own folder, or nowhere.
External = Literal["folder", "refuse"]


def read_gifti(path: str | Path, *, external: External = "folder", what: str = "GIfTI file") -> Any:
    """Read a GIfTI file (or a gzipped one) with nibabel, following no reference it may not.

    Parameters
    ----------
    path : path-like
        A ``.gii`` file, or gzip-compressed (``.gii.gz``).
    external : {"folder", "refuse"}
        ``"folder"``: a ``DataArray`` may keep its data in a file inside the
        GIfTI's own folder; ``"refuse"``: in no other file at all.
    what : str
        What the file is, for messages (``"map file"``; its name follows).

    Returns
    -------
    nibabel.gifti.GiftiImage
        Its data arrays in memory (external data read, not memory-mapped).

    Raises
    ------
    BrainPainterError
        Not a regular file, too large, not GIfTI (the message names what it
        is), external data where it may not be, an entity declaration.
    """
    from nibabel.fileholders import FileHolder
    from nibabel.gifti.gifti import GiftiImage

    path = Path(path)
    raw = read_input(path, what, MAX_DATA_FILE)
    what = f"{what} {path.name!r}"
    raw = inflated(raw, what)
    found = what_is(raw[:HEAD])
    if found != GIFTI:
        seen = f"looks like {found}" if found else "does not start with XML"
        raise BrainPainterError(f"{what} {seen}, not a GIfTI file; give the GIfTI file your software wrote "
                                "(.gii, or gzipped .gii.gz).")
    names = external_files(raw, what)
    stream = io.BytesIO(raw)  # nameless: nibabel refuses external data in it
    if names:
        if external == "refuse":
            raise BrainPainterError(
                f"{what} keeps its data in another file ({names[0][:80]!r}, Encoding=ExternalFileBinary); "
                "this server reads only data inside the file. Save it with its data inside (e.g. "
                "Encoding=GZipBase64Binary) and upload it again.")
        _inside(path, names, what)
        stream.name = str(path)  # nibabel finds the external files beside this name
    holder = FileHolder(fileobj=stream)
    return GiftiImage.from_file_map({"image": holder}, buffer_size=None, mmap=False)  # type: ignore[no-untyped-call]


def external_files(raw: bytes, what: str) -> list[str]:
    """The ``ExternalFileName`` of every ``DataArray`` whose data is in an external file.

    Also checks, before nibabel inflates them whole, that no gzipped data
    array (``GZipBase64Binary``) inflates to more than its ``Dim``s and
    ``DataType`` say: a few kilobytes of XML cannot become gigabytes.

    Raises
    ------
    BrainPainterError
        The XML declares entities (refused, as defusedxml does), is not well
        formed, or holds a gzipped array larger than it says.
    """
    from xml.parsers import expat

    from nibabel.gifti.util import gifti_encoding_codes

    names: list[str] = []
    gz: dict[str, Any] = {}  # the gzipped array being read: its expected size and its text so far

    def start(tag: str, attrs: dict[str, str]) -> None:
        code = gifti_encoding_codes.label.get(attrs.get("Encoding"))  # nibabel's table of the encodings
        if tag == "DataArray" and code == "External":
            names.append(attrs.get("ExternalFileName", ""))
        elif tag == "DataArray" and code == "B64GZ":
            gz.update(size=_array_bytes(attrs), text=[])
        elif tag == "Data" and "size" in gz:
            gz["open"] = True

    def text(data: str) -> None:
        if gz.get("open"):
            gz["text"].append(data)

    def end(tag: str) -> None:
        if tag == "Data" and gz.get("open"):
            _check_inflated("".join(gz["text"]), gz["size"], what)
            gz.clear()

    def entity(name: str, *_: object) -> None:
        raise BrainPainterError(f"{what} declares the XML entity {name[:40]!r}; GIfTI files declare none, "
                                "and this reader refuses them. Give the file your software wrote.")

    parser = expat.ParserCreate()
    parser.buffer_text = True
    parser.StartElementHandler = start
    parser.CharacterDataHandler = text
    parser.EndElementHandler = end
    parser.EntityDeclHandler = entity
    try:
        parser.Parse(raw, True)
    except expat.ExpatError as exc:
        raise BrainPainterError(f"{what} is not well-formed XML ({exc}); give the file your software "
                                "wrote.") from None
    return names


def _array_bytes(attrs: dict[str, str]) -> int:
    """Bytes a ``DataArray`` holds by its ``Dim0``... and ``DataType`` (0 when they are not valid)."""
    from nibabel.nifti1 import data_type_codes

    dtype: Any = data_type_codes.dtype.get(attrs.get("DataType"))
    try:
        dims = [int(attrs[f"Dim{i}"]) for i in range(int(attrs.get("Dimensionality", "0")))]
    except (KeyError, ValueError):
        return 0
    return 0 if dtype is None or any(d < 0 for d in dims) else math.prod(dims) * int(dtype.itemsize)


def _check_inflated(text: str, size: int, what: str) -> None:
    """Refuse base64 gzip data `text` that inflates to more than `size` bytes (inflating stops there)."""
    import base64
    import binascii

    try:
        data = base64.b64decode(text.encode("ascii"))
        out = zlib.decompressobj().decompress(data, size + 1)
    except (binascii.Error, UnicodeEncodeError, zlib.error):
        return  # nibabel says what is wrong
    if len(out) > size:
        raise BrainPainterError(f"{what} holds a gzipped data array that inflates to more than the {size} "
                                "bytes its Dim and DataType say; give the file your software wrote.")


def _inside(path: Path, names: list[str], what: str) -> None:
    """Check that every external file (relative to `path`'s folder, as nibabel finds it) is a file in it."""
    folder = path.parent.resolve()
    for name in names:
        target = (path.parent / name).resolve()
        if not target.is_relative_to(folder):
            raise BrainPainterError(
                f"{what} keeps its data in {name[:80]!r}, outside its own folder; GIfTI external data is "
                "read only from the GIfTI's folder. Move the data file beside it, or save the GIfTI with "
                "its data inside.")
        if not target.is_file():
            raise BrainPainterError(f"{what} keeps its data in {name[:80]!r}, which is not a file in its "
                                    "folder; put the data file beside it, or save the GIfTI with its data "
                                    "inside.")
