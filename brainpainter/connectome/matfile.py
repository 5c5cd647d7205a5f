"""MATLAB v5 ``.mat`` files checked before scipy reads their numbers.

``scipy.io.loadmat`` trusts the element tags of the variable it reads: a tag
naming an unknown data type, or a data element longer or shorter than the
array's dimensions say, crashes the process (a segmentation fault in its
Cython reader, not an exception). So the variable about to be read is walked
here first, tag by tag (compressed variables inflated, at most the input
limit): the array flags, dimensions, name, and the real (and imaginary) part,
each of a known type, inside its parent element, with exactly the bytes the
dimensions need. Layout: MATLAB's "MAT-File Format" (v5, level 5).
"""

from __future__ import annotations

import math
import struct
import zlib

from brainpainter.errors import BrainPainterError

#: Bytes per item of each numeric data type (miINT8 ... miUINT64), by type number.
ITEM_BYTES = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8}
MI_INT8, MI_INT32, MI_UINT32, MI_MATRIX, MI_COMPRESSED = 1, 5, 6, 14, 15
_COMPLEX = 0x0800


class _Broken(Exception):
    """What is wrong with the variable's bytes (becomes the one-line error)."""


def check_variable(raw: bytes, name: str, limit: int, source: str) -> None:
    """Check that numeric variable `name` of the v5 MAT file `raw` is well formed before scipy reads it.

    Parameters
    ----------
    raw : bytes
        The whole file.
    name : str
        The variable scipy will read (as ``scipy.io.whosmat`` named it).
    limit : int
        Most bytes a compressed variable may inflate to.
    source : str
        For messages.

    Raises
    ------
    BrainPainterError
        The variable's elements are broken, or it is not in the file.
    """
    try:
        endian = {b"IM": "<", b"MI": ">"}[raw[126:128]]
        pos = 128
        while pos + 8 <= len(raw):
            mdtype, nbytes, start = _tag(raw, pos, endian, len(raw))
            body = raw[start:start + nbytes]
            if mdtype == MI_COMPRESSED:
                body = _inflated(body, limit)
                mdtype, inner, begin = _tag(body, 0, endian, len(body))
                body = body[begin:begin + inner]
            if mdtype == MI_MATRIX and _matrix_name(body, endian) == name:
                _check_matrix(body, endian)
                return
            pos = start + nbytes + (-nbytes % 8 if mdtype != MI_COMPRESSED else 0)
    except (_Broken, KeyError, struct.error) as exc:
        why = str(exc) if isinstance(exc, _Broken) else "its header or element tags are broken"
        raise BrainPainterError(f"connectome matrix {source!r}: MATLAB variable {name!r} cannot be read "
                                f"safely ({why}); the file is damaged. Save it again with MATLAB's "
                                "save.") from None
    raise BrainPainterError(f"connectome matrix {source!r}: MATLAB variable {name!r} was not found where its "
                            "header said; the file is damaged. Save it again with MATLAB's save.")


def _tag(data: bytes, pos: int, endian: str, end: int) -> tuple[int, int, int]:
    """(type, byte count, where the data start) of the element tag at `pos`; its data must end by `end`."""
    word, second = struct.unpack_from(endian + "II", data, pos)
    if word >> 16:  # small data element: count and type in one word, data in the next four bytes
        mdtype, nbytes, start = word & 0xFFFF, word >> 16, pos + 4
        if nbytes > 4:
            raise _Broken(f"a small data element of {nbytes} bytes (at most 4)")
    else:
        mdtype, nbytes, start = word, second, pos + 8
    if start + nbytes > end:
        raise _Broken(f"an element of {nbytes} bytes runs past the {end - pos} bytes left")
    return mdtype, nbytes, start


def _inflated(body: bytes, limit: int) -> bytes:
    d = zlib.decompressobj()
    try:
        out = d.decompress(body, limit + 1)
    except zlib.error as exc:
        raise _Broken(f"its compressed data are broken: {exc}") from None
    if len(out) > limit:
        raise _Broken(f"it inflates to more than {limit >> 20} MB")
    return out


def _subelements(body: bytes, endian: str) -> list[tuple[int, bytes]]:
    """(type, data) of the first four subelements of a matrix element (fewer if it has fewer)."""
    out: list[tuple[int, bytes]] = []
    pos = 0
    while pos + 8 <= len(body) and len(out) < 5:
        mdtype, nbytes, start = _tag(body, pos, endian, len(body))
        out.append((mdtype, body[start:start + nbytes]))
        small = start == pos + 4
        pos = pos + 8 if small else start + nbytes + (-nbytes % 8)
    return out


def _matrix_name(body: bytes, endian: str) -> str | None:
    parts = _subelements(body, endian)
    if len(parts) < 3 or parts[2][0] != MI_INT8:
        return None
    return parts[2][1].decode("latin1")


def _check_matrix(body: bytes, endian: str) -> None:
    parts = _subelements(body, endian)
    if len(parts) < 4:
        raise _Broken("its array has no data element")
    (flags_type, flags), (dims_type, dims_raw), _, (real_type, real) = parts[:4]
    if flags_type != MI_UINT32 or len(flags) != 8 or dims_type != MI_INT32 or len(dims_raw) % 4 or \
            len(dims_raw) < 8:
        raise _Broken("its array flags or dimensions are broken")
    dims = struct.unpack(endian + f"{len(dims_raw) // 4}i", dims_raw)
    if min(dims) < 0:
        raise _Broken(f"negative dimensions {dims}")
    values = [(real_type, real)]
    if struct.unpack_from(endian + "I", flags)[0] & _COMPLEX:
        if len(parts) < 5:
            raise _Broken("its imaginary part is missing")
        values.append(parts[4])
    for mdtype, data in values:
        if mdtype not in ITEM_BYTES:
            raise _Broken(f"its data are of unknown type {mdtype}")
        if len(data) != math.prod(dims) * ITEM_BYTES[mdtype]:
            raise _Broken(f"{len(data)} bytes of data for a {' x '.join(map(str, dims))} array")
