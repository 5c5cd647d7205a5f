"""What a file's first bytes say it is, so that a file named for one format but holding another is
named in the error (``'lh.thickness' looks like gzip-compressed data, not a FreeSurfer curv file``)
instead of being parsed as the wrong format."""

from __future__ import annotations

import zlib

#: Bytes :func:`what_is` needs: NIfTI-1 keeps its magic at byte 344, GIfTI's root may follow a long prolog.
HEAD = 4096

GZIP = "gzip-compressed data"
ZIP = "a zip archive"
GIFTI = "a GIfTI file"
XML = "an XML file that is not GIfTI"
CURV = "a FreeSurfer curv file"
SURFACE = "a FreeSurfer surface (a mesh, not values)"
MGH = "an MGH image"
NIFTI1 = "a NIfTI-1 image"
NIFTI2 = "a NIfTI-2 image"
NPY = "a NumPy .npy array"
TRK = "a TrackVis .trk tractogram"
TCK = "an MRtrix .tck tractogram"
PNG = "a PNG image"
PDF = "a PDF document"


def what_is(head: bytes) -> str | None:
    """The format the first bytes of a file say (one of this module's names), or None if unknown.

    Parameters
    ----------
    head : bytes
        The file's first :data:`HEAD` bytes (or all of it, if shorter).

    Notes
    -----
    Only formats with a magic number are named; text, FreeSurfer ``.annot``
    and old-style curv files have none (None).
    """
    if head[:2] == b"\x1f\x8b":
        return GZIP
    if head[:4] in (b"PK\x03\x04", b"PK\x05\x06"):
        return ZIP
    if head[:6] == b"\x93NUMPY":
        return NPY
    if head[:8] == b"\x89PNG\r\n\x1a\n":
        return PNG
    if head[:5] == b"%PDF-":
        return PDF
    if head[:5] == b"TRACK":
        return TRK
    if head[:13] == b"mrtrix tracks":
        return TCK
    if head[:3] == b"\xff\xff\xff":
        return CURV
    if head[:3] in (b"\xff\xff\xfe", b"\xff\xff\xfd"):
        return SURFACE
    if head[:4] in (b"\x5c\x01\x00\x00", b"\x00\x00\x01\x5c") and head[344:347] in (b"n+1", b"ni1"):
        return NIFTI1
    if head[:4] in (b"\x1c\x02\x00\x00", b"\x00\x00\x02\x1c") and head[4:7] in (b"n+2", b"ni2"):
        return NIFTI2
    if head[:4] == b"\x00\x00\x00\x01":
        return MGH
    text = head.lstrip(b"\xef\xbb\xbf \t\r\n")
    if text.startswith(b"<"):
        return GIFTI if b"<GIFTI" in head else XML
    return None


def described(head: bytes) -> str | None:
    """:func:`what_is`, and for gzip what its first inflated bytes are (``gzip-compressed data (a GIfTI
    file inside)``), for messages."""
    found = what_is(head)
    if found == GZIP:
        try:
            inner = what_is(zlib.decompressobj(wbits=31).decompress(head, HEAD))
        except zlib.error:
            inner = None
        found += f" ({inner} inside)" if inner else ""
    return found


#: Formats that are never a volume (nibabel would read a GIfTI by ``nib.load``, following its external data).
NOT_VOLUMES = (GIFTI, XML, CURV, SURFACE, NPY, TRK, TCK, PNG, PDF, ZIP)


def not_a_volume(head: bytes) -> str | None:
    """What a file is (:func:`described`) when its first bytes say a format that is no volume, else None."""
    found = described(head)
    return found if found and any(kind in found for kind in NOT_VOLUMES) else None
