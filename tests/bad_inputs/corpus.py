# ruff: noqa: E501  (a table of cases: one case per line reads best)
"""The bad-input corpus: malformed and hostile tables, each with its expected one-line error.

Every case is generated (nothing large is committed): ``write(case, folder)``
writes its files into an empty folder, and the test runs the CLI there
(``brainpainter check|render ...``, in-process through click's ``CliRunner``
streams; a sample also as a real process) and expects exit code 2, one line
on stderr containing ``case.message``, no traceback and no file written.

``SAFE`` lists hostile inputs that are *accepted*: image names that look like
paths are sanitised into file names inside the output folder.

``INPROCESS`` lists more cases of every class (output safety, the input
opener, bombs, ambiguity, non-finite options, configs, locks), which need
what only the in-process harness gives (patched limits, held locks, the tiny
template): arguments may hold ``{tiny}``, the path of a tiny synthetic template.

Run ``python tests/bad_inputs/corpus.py FOLDER`` to write the whole corpus
to FOLDER (one sub-folder per case) for manual inspection.
"""

from __future__ import annotations

import gzip
import io
import os
import random
import re
import sys
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

HEADER = "Image-name-unique,Left-insula,Right-insula\n"
Content = bytes | Callable[[Path], None]


@dataclass(frozen=True)
class Case:
    """One bad input.

    Attributes
    ----------
    id : str
    files : dict of str to bytes or callable
        File name -> content, or a function writing that path (large files).
    args : list of str
        CLI arguments after the command (file names are relative to the case folder).
    message : str
        Expected in the one-line error.
    command : {"check", "render"}
    env : dict of str to str
        Extra environment variables.
    code : int
        Expected exit code (2: a user error; 0: accepted, ``message`` is then expected on stdout).
    patch : dict of str to object
        ``"module:ATTR"`` -> value set for the run (small limits make bombs cheap; in-process cases only).
    lock : str, optional
        Folder (relative to the case folder) that another run holds locked meanwhile (in-process only).
    """

    id: str
    files: dict[str, Content]
    args: list[str]
    message: str
    command: str = "check"
    env: dict[str, str] = field(default_factory=dict)
    code: int = 2
    patch: dict[str, object] = field(default_factory=dict)
    lock: str | None = None


def csv(*lines: str) -> bytes:
    return ("\n".join(lines) + "\n").encode()


def xlsx(sheets: dict[str, list[list[object]]]) -> bytes:
    from openpyxl import Workbook

    wb = Workbook()
    wb.remove(wb.active)
    for title, rows in sheets.items():
        ws = wb.create_sheet(title)
        for row in rows:
            ws.append(row)
    buf = io.BytesIO()
    wb.save(buf)
    return buf.getvalue()


def _big_table(path: Path, megabytes: int = 50) -> None:
    """A well-formed table of `megabytes` MB: too big to be read."""
    values = "," + ",".join(["1.2345678"] * 90) + "\n"
    n = megabytes * 2**20 // (len(values) + 15) + 1
    with path.open("w") as fh:
        fh.write("Image-name-unique," + ",".join(f"Left-insula{i}" for i in range(89)) + ",Left-insula\n")
        for i in range(n):
            fh.write(f"subject-{i:07d}" + values)


def _wide_header(n: int) -> bytes:
    header = "Image-name-unique," + ",".join(f"col{i}" for i in range(n))
    return (header + "\nA," + ",".join("1" * n) + "\n").encode()


def _zip(files: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in files.items():
            zf.writestr(name, data)
    return buf.getvalue()


def _zip_bomb(mb: int) -> bytes:
    """A workbook-looking zip whose sheet expands to `mb` MB."""
    return _zip({"[Content_Types].xml": b"<Types/>", "xl/workbook.xml": b"<workbook/>",
                 "xl/worksheets/sheet1.xml": b"\0" * (mb * 2**20)})


_rng = random.Random(5)
GARBAGE = bytes(_rng.randrange(256) for _ in range(4096))
PNG = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x00\x01\x00\x00\x00\x01\x08\x02\x00\x00\x00\x90wS\xde"
GOOD = csv(HEADER.strip(), "A,1,2")
DESTRIEUX = csv("Image-name-unique,Left-G_cuneus,Right-S_central", "A,1,2")
LONG = csv("Structure,d.icv,se.icv", "L_insula,0.2,0.1", "R_insula,0.3,0.1")
#: What the render cases of CASES add: an output folder and the stand-in renderer (default template).
STAND_IN = ["--out", "out", "--renderer", "solid", "--quiet"]

CASES: list[Case] = [
    # -- empty and truncated ------------------------------------------------------------------
    Case("empty-file", {"in.csv": b""}, ["in.csv"], "is empty"),
    Case("blank-lines-only", {"in.csv": b"\n\n   \r\n\t\n"}, ["in.csv"], "is empty"),
    Case("header-only", {"in.csv": csv(HEADER.strip())}, ["in.csv"], "has a header but no rows"),
    Case("header-only-xlsx", {"in.xlsx": xlsx({"S": [["Image-name-unique", "Left-insula"]]})}, ["in.xlsx"],
         "has a header but no rows"),
    Case("empty-workbook", {"in.xlsx": xlsx({"S": []})}, ["in.xlsx"], "no filled cells"),
    Case("short-row", {"in.csv": csv(HEADER.strip(), "A,1")}, ["in.csv"],
         "has 2 fields but the header has 3"),
    Case("long-row", {"in.csv": csv(HEADER.strip(), "A,1,2,3")}, ["in.csv"],
         "has 4 fields but the header has 3"),
    Case("unterminated-quote", {"in.csv": csv(HEADER.strip(), 'A,"1,2')}, ["in.csv"], "cannot parse"),
    # -- not a text table --------------------------------------------------------------------------
    Case("binary-garbage", {"in.csv": GARBAGE}, ["in.csv"], "binary"),
    Case("png-named-csv", {"in.csv": PNG}, ["in.csv"], "NUL bytes"),
    Case("high-bytes", {"in.csv": bytes(range(128, 256)) * 40}, ["in.csv"], "neither UTF-8 nor Windows-1252"),
    Case("control-characters", {"in.csv": bytes(range(1, 9)) * 300}, ["in.csv"], "control characters"),
    Case("gzip-csv", {"in.csv": gzip.compress(GOOD)}, ["in.csv"], "compressed"),
    Case("xlsx-renamed-csv", {"in.csv": xlsx({"S": [["Image-name-unique", "Left-insula"], ["A", 1]]})},
         ["in.csv"], "is an Excel workbook (a zip file) although it is named '.csv'"),
    Case("csv-renamed-xlsx", {"in.xlsx": GOOD}, ["in.xlsx"], "is not an Excel workbook"),
    Case("truncated-xlsx", {"in.xlsx": xlsx({"S": [["Image-name-unique", "Left-insula"], ["A", 1]]})[:300]},
         ["in.xlsx"], "damaged"),
    Case("zip-not-xlsx", {"in.xlsx": _zip({"table.csv": GOOD})}, ["in.xlsx"], "not an Excel .xlsx workbook"),
    Case("xls-97", {"in.xls": b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + b"\0" * 504}, ["in.xls"], "(.xls)"),
    Case("xlsx-zip-bomb", {"in.xlsx": _zip_bomb(12)}, ["in.xlsx"], "when unzipped",
         env={"BRAINPAINTER_MAX_INPUT_MB": "1"}),
    Case("xlsx-several-sheets", {"in.xlsx": xlsx({"lh": [["Image-name-unique", "Left-insula"], ["A", 1]],
                                                  "rh": [["Image-name-unique", "Right-insula"], ["A", 2]]})},
         ["in.xlsx"], "has 2 sheets with data ['lh', 'rh']"),
    Case("xlsx-stray-cell",
         {"in.xlsx": xlsx({"S": [["Image-name-unique", "Left-insula"], ["A", 1, None, 5]]})},
         ["in.xlsx"], "beyond the last named column"),
    Case("xlsx-error-cell",
         {"in.xlsx": xlsx({"S": [["Image-name-unique", "Left-insula"], ["A", "#DIV/0!"]]})},
         ["in.xlsx"], "'#DIV/0!', which is not a number"),
    # -- sizes ----------------------------------------------------------------------------------------
    Case("50-MB-file", {"in.csv": _big_table}, ["in.csv"], "MB is read, to keep memory bounded"),
    Case("100000-columns", {"in.csv": _wide_header(100_000)}, ["in.csv"],
         "has 100001 columns; at most 16384"),
    Case("huge-cell", {"in.csv": csv(HEADER.strip(), "A,1," + "9" * 200_000)}, ["in.csv"], "field larger"),
    Case("bad-size-limit", {"in.csv": GOOD}, ["in.csv"], "BRAINPAINTER_MAX_INPUT_MB must be a number",
         env={"BRAINPAINTER_MAX_INPUT_MB": "lots"}),
    # -- region names ------------------------------------------------------------------------------
    Case("two-columns-one-region", {"in.csv": csv("Image-name-unique,Left-insula,ctx-lh-insula", "A,1,2")},
         ["in.csv"], "both name region 'Left-insula'"),
    Case("same-column-twice", {"in.csv": csv("Image-name-unique,Left-insula,Left-insula", "A,1,2")},
         ["in.csv"], "both name region 'Left-insula'"),
    Case("bare-and-sided-name", {"in.csv": csv("Image-name-unique,insula,Right-insula", "A,1,2")},
         ["in.csv"], "both name region 'Right-insula'"),
    Case("no-region-names", {"in.csv": csv("Image-name-unique,foo,bar", "A,1,2")}, ["in.csv"],
         "no column name or value names a region of any installed atlas"),
    Case("wrong-atlas", {"in.csv": DESTRIEUX}, ["in.csv", "--atlas", "dk"], "give --atlas destrieux"),
    Case("unknown-atlas", {"in.csv": GOOD}, ["in.csv", "--atlas", "dkk"], "Did you mean 'dk'?"),
    Case("strict-unmatched", {"in.csv": csv("Image-name-unique,Left-insula,Left-insulaa", "A,1,2")},
         ["in.csv", "--strict"], "did you mean 'Left-insula'?"),
    Case("control-char-in-column-name", {"in.csv": csv("Image-name-unique,Left-insula,x\x1b[2Jy", "A,1,2")},
         ["in.csv"], "contains control characters"),
    # -- cells ----------------------------------------------------------------------------------------
    Case("non-numeric-cell", {"in.csv": csv(HEADER.strip(), "A,1,high")}, ["in.csv"],
         "'high', which is not a number"),
    Case("thousands-separator", {"in.csv": csv('Image-name-unique,Left-insula', 'A,"1,234"')}, ["in.csv"],
         "'1,234', which is not a number"),
    Case("repeated-header-row", {"in.csv": csv(HEADER.strip(), "A,1,2", HEADER.strip(), "B,1,2")},
         ["in.csv"], "repeats the header"),
    Case("inf", {"in.csv": csv(HEADER.strip(), "A,inf,1")}, ["in.csv"], "is infinite"),
    Case("minus-infinity", {"in.csv": csv(HEADER.strip(), "A,1,-Infinity")}, ["in.csv"], "is infinite"),
    Case("overflow-to-inf", {"in.csv": csv(HEADER.strip(), "A,1e999,1")}, ["in.csv"], "is infinite"),
    Case("render-non-numeric", {"in.csv": csv(HEADER.strip(), "A,1,high")}, ["in.csv", *STAND_IN],
         "'high', which is not a number", command="render"),
    Case("check-collide-as-files", {"in.csv": csv(HEADER.strip(), "a/B,1,2", "a_b,2,3")}, ["in.csv"],
         "become the same file name"),
    # -- image names ----------------------------------------------------------------------------------
    Case("image-name-with-nul", {"in.csv": csv(HEADER.strip(), "a\x00b,1,2")}, ["in.csv"], "NUL"),
    Case("image-name-with-escape", {"in.csv": csv(HEADER.strip(), "\x1b[31mred,1,2")}, ["in.csv"],
         "contains control characters"),
    Case("image-name-1001-chars", {"in.csv": csv(HEADER.strip(), "x" * 1001 + ",1,2")}, ["in.csv"],
         "is 1001 characters long; at most 1000"),
    Case("duplicate-image-names", {"in.csv": csv(HEADER.strip(), "A,1,2", "A,2,3")}, ["in.csv"],
         "'A' appears at line 2 and line 3"),
    Case("image-names-differ-in-case", {"in.csv": csv(HEADER.strip(), "sub-A,1,2", "sub-a,2,3")}, ["in.csv"],
         "differ only in case"),
    Case("image-names-collide-as-files", {"in.csv": csv(HEADER.strip(), "a/b,1,2", "a:b,2,3")},
         ["in.csv", *STAND_IN], "become the same file name", command="render"),
    Case("empty-image-name", {"in.csv": csv(HEADER.strip(), ",1,2")}, ["in.csv"], "empty image name"),
    # -- options and layouts ----------------------------------------------------------------------------
    Case("image-column-missing", {"in.csv": GOOD}, ["in.csv", "--image-column", "subject"],
         "--image-column 'subject' is not a column"),
    Case("value-column-missing", {"in.csv": LONG}, ["in.csv", "--value", "d_icv"], "Did you mean 'd.icv'?"),
    Case("long-needs-value", {"in.csv": LONG}, ["in.csv"], "choose one with --value"),
    Case("long-value-is-text", {"in.csv": csv("Structure,group,d", "L_insula,patients,0.2")},
         ["in.csv", "--value", "group"], "'patients', which is not a number"),
    Case("long-repeated-region", {"in.csv": csv("Structure,d", "L_insula,0.2", "ctx-lh-insula,0.3")},
         ["in.csv"], "region 'Left-insula' appears twice for image 'd'"),
    Case("long-value-is-region-column", {"in.csv": LONG}, ["in.csv", "--value", "Structure"],
         "is also the region or image column"),
    # -- files and merging ------------------------------------------------------------------------------
    Case("missing-file", {}, ["nope.csv"], "does not exist"),
    Case("device-file", {}, ["/dev/zero"], "is not a regular file"),
    Case("same-region-in-two-inputs", {"a.csv": GOOD, "b.csv": GOOD}, ["a.csv", "b.csv"],
         "both give region 'Left-insula'"),
    Case("named-and-numbered-inputs", {"a.csv": GOOD, "b.csv": csv("Left-Hippocampus", "3")},
         ["a.csv", "b.csv"], "has no image-name column"),
    Case("second-input-empty", {"a.csv": GOOD, "b.csv": b""}, ["a.csv", "b.csv"], "'b.csv' is empty"),
]

# -- in-process cases ----------------------------------------------------------------------------------
def _fifo(path: Path) -> None:
    os.mkfifo(path)


def _link_to(target: str) -> Callable[[Path], None]:
    def make(path: Path) -> None:
        path.symlink_to(target)
    return make


def _folder(files: dict[str, bytes]) -> Callable[[Path], None]:
    def make(path: Path) -> None:
        path.mkdir()
        for name, data in files.items():
            (path / name).write_bytes(data)
    return make


def _xlsx_xml(sheet_xml: Callable[[bytes], bytes]) -> bytes:
    """A real workbook whose sheet XML is rewritten by `sheet_xml` (bombs, lies in <dimension>)."""
    base = xlsx({"S": [["Image-name-unique", "Left-insula"], ["A", 1]]})
    zin = zipfile.ZipFile(io.BytesIO(base))
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as out:
        for info in zin.infolist():
            data = zin.read(info)
            if info.filename.startswith("xl/worksheets/sheet"):
                data = sheet_xml(data)
            out.writestr(info, data)
    return buf.getvalue()


def _dimension(ref: bytes) -> bytes:
    return _xlsx_xml(lambda x: re.sub(rb'<dimension ref="[^"]*"\s*/>', b'<dimension ref="' + ref + b'"/>', x))


def _far_row(r: int) -> bytes:
    return _xlsx_xml(lambda x: x.replace(b"</sheetData>", b'<row r="%d"><c r="B%d"><v>1</v></c></row></sheetData>'
                                         % (r, r)))


def _wide_row() -> bytes:
    return _xlsx_xml(lambda x: x.replace(b"</sheetData>", b'<row r="3"><c r="XFD3"><v>1</v></c></row>'
                                         b'<row r="4"><c r="A4"><v>1</v></c></row></sheetData>'))


def _formula(cached: bool) -> bytes:
    value = b"<v>2</v>" if cached else b"<v />"
    return _xlsx_xml(lambda x: re.sub(rb'<c r="B2"( t="n")?><v>1</v></c>', b'<c r="B2"><f>1+1</f>' + value
                                      + b"</c>", x))


def _annot(path: Path) -> None:
    import numpy as np
    from nibabel.freesurfer import write_annot

    ctab = np.array([[25, 5, 25, 0, 0], [200, 0, 0, 0, 0]], dtype=np.int32)
    write_annot(str(path), np.array([0, 1, 1, 0]), ctab, [b"unknown", b"net1"], fill_ctab=True)


def _annot_names(*names: bytes) -> Callable[[Path], None]:
    """An .annot whose colour table has `names` (the first is the background)."""
    def make(path: Path) -> None:
        import numpy as np
        from nibabel.freesurfer import write_annot

        ctab = np.array([[25 + 40 * i, 5, 25, 0, 0] for i in range(len(names))], dtype=np.int32)
        write_annot(str(path), np.array([i % len(names) for i in range(8)]), ctab, list(names), fill_ctab=True)
    return make


def _gifti(structure: str) -> Callable[[Path], None]:
    def make(path: Path) -> None:
        import nibabel as nib
        import numpy as np

        table = nib.gifti.GiftiLabelTable()
        for key, name in ((0, "unknown"), (1, "net1")):
            label = nib.gifti.GiftiLabel(key=key, red=1.0, green=0.0, blue=0.0, alpha=1.0)
            label.label = name
            table.labels.append(label)
        arr = nib.gifti.GiftiDataArray(np.array([0, 1, 1, 0], dtype=np.int32), intent="NIFTI_INTENT_LABEL",
                                       datatype="NIFTI_TYPE_INT32")
        img = nib.gifti.GiftiImage(darrays=[arr], labeltable=table,
                                   meta=nib.gifti.GiftiMetaData({"AnatomicalStructurePrimary": structure}))
        nib.save(img, str(path))
    return make


def _gifti_external(name: str, gz: bool = False) -> Callable[[Path], None]:
    """A fsaverage5 .func.gii whose data array says it is in the file `name` (``ExternalFileBinary``)."""
    def make(path: Path) -> None:
        import nibabel as nib
        import numpy as np

        da = nib.gifti.GiftiDataArray(np.zeros(10242, np.float32), datatype="NIFTI_TYPE_FLOAT32")
        xml = nib.gifti.GiftiImage(darrays=[da]).to_xml(enc="utf-8").decode()
        xml = xml.replace('Encoding="GZipBase64Binary"', 'Encoding="ExternalFileBinary"')
        xml = re.sub(r"<Data>.*?</Data>", "<Data></Data>", xml.replace('ExternalFileName=""',
                                                                      f'ExternalFileName="{name}"'), flags=re.S)
        path.write_bytes(gzip.compress(xml.encode()) if gz else xml.encode())
    return make


def toml(text: str) -> bytes:
    return text.strip().encode() + b"\n"


LOBES = toml('[atlas]\nbase = "dk"\n[groups]\nfrontal = ["superiorfrontal"]\n')
def _surface(path: Path) -> None:
    """A FreeSurfer surface of 12 vertices (an icosahedron) as ``lh.pial``."""
    import numpy as np
    import trimesh
    from nibabel.freesurfer import write_geometry

    ico = trimesh.creation.icosahedron()
    write_geometry(str(path), np.asarray(ico.vertices) * 40.0, np.asarray(ico.faces, np.int32))


#: A GIfTI surface whose point set lies in a file outside its folder (``/etc/passwd``): never to be opened.
EXTERNAL_GIFTI = b"""<?xml version="1.0" encoding="UTF-8"?>
<GIFTI Version="1.0" NumberOfDataArrays="2">
<DataArray Intent="NIFTI_INTENT_POINTSET" DataType="NIFTI_TYPE_FLOAT32" ArrayIndexingOrder="RowMajorOrder" Dimensionality="2" Dim0="3" Dim1="3" Encoding="ExternalFileBinary" Endian="LittleEndian" ExternalFileName="/etc/passwd" ExternalFileOffset="0"><Data></Data></DataArray>
<DataArray Intent="NIFTI_INTENT_TRIANGLE" DataType="NIFTI_TYPE_INT32" ArrayIndexingOrder="RowMajorOrder" Dimensionality="2" Dim0="1" Dim1="3" Encoding="ASCII" Endian="LittleEndian" ExternalFileName="" ExternalFileOffset=""><Data>0 1 2</Data></DataArray>
</GIFTI>
"""


RENDER = ["--renderer", "solid", "--template", "{tiny}", "--views", "lateral-left", "--size", "32x32", "-q"]
TEMPLATE_MANIFEST = b'{"format": "brainpainter-template", "format_version": 1}'
RENDER_MANIFEST = b'{"software": {"brainpainter": "0.1.0"}, "files": []}'
LONG_NAME = "x" * 300
ONE_ROW_EMPTY = csv(HEADER.strip(), "A,1,")


def _movie(args: list[str], message: str, cid: str, files: dict[str, Content] | None = None,
           **kw: object) -> Case:
    return Case(cid, files or {"in.csv": csv(HEADER.strip(), "A,1,2", "B,2,3")}, ["in.csv", *RENDER, *args],
                message, command="movie", **kw)  # type: ignore[arg-type]


def _figure(args: list[str], message: str, cid: str, files: dict[str, Content] | None = None,
            **kw: object) -> Case:
    return Case(cid, files or {"in.csv": GOOD}, ["in.csv", *RENDER, *args], message, command="figure",
                **kw)  # type: ignore[arg-type]


def _render(args: list[str], message: str, cid: str, files: dict[str, Content] | None = None,
            **kw: object) -> Case:
    return Case(cid, files or {"in.csv": GOOD}, ["in.csv", *RENDER, *args], message, command="render",
                **kw)  # type: ignore[arg-type]


INPROCESS: list[Case] = [
    # -- never delete what brainpainter did not make (template build, atlas add --out) ---------------------
    Case("template-into-render-folder", {"renders": _folder({"manifest.json": RENDER_MANIFEST, "a.png": PNG}),
                                         "subj": _folder({})},
         ["build", "subj", "--out", "renders"], "was not made by brainpainter", command="template"),
    Case("template-into-foreign-folder", {"data": _folder({"table.csv": GOOD}), "subj": _folder({})},
         ["build", "subj", "--out", "data"], "was not made by brainpainter", command="template"),
    Case("template-out-empty-string", {"manifest.json": TEMPLATE_MANIFEST, "in.csv": GOOD, "subj": _folder({})},
         ["build", "subj", "--out", ""], "the current folder", command="template"),
    Case("template-out-dot", {"manifest.json": TEMPLATE_MANIFEST, "subj": _folder({})},
         ["build", "subj", "--out", "."], "the current folder", command="template"),
    Case("template-out-is-file", {"t": b"mine", "subj": _folder({})}, ["build", "subj", "--out", "t"],
         "is a file", command="template"),
    Case("template-out-symlink", {"real": _folder({"manifest.json": TEMPLATE_MANIFEST}),
                                  "link": _link_to("real"), "subj": _folder({})},
         ["build", "subj", "--out", "link"], "is a symbolic link", command="template"),
    Case("template-out-fake-manifest", {"t": _folder({"manifest.json": b'{"format": "other"}', "x": b"1"}),
                                        "subj": _folder({})},
         ["build", "subj", "--out", "t"], "was not made by brainpainter", command="template"),
    Case("template-out-manifest-not-json", {"t": _folder({"manifest.json": b"\xff\x00", "x": b"1"}),
                                            "subj": _folder({})},
         ["build", "subj", "--out", "t"], "was not made by brainpainter", command="template"),
    Case("template-out-name-too-long", {"subj": _folder({})}, ["build", "subj", "--out", LONG_NAME],
         "too long", command="template"),
    Case("template-subject-missing", {}, ["build", "nosubj", "--out", "t"], "nosubj", command="template"),
    Case("template-subject-is-fifo", {"subj": _fifo}, ["build", "subj", "--out", "t"], "subj",
         command="template"),
    Case("atlas-add-out-not-empty", {"lh.a.annot": _annot, "rh.a.annot": _annot, "o": _folder({"x": b"1"})},
         ["add", "net", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot", "--out", "o"],
         "was not made by brainpainter", command="atlas"),
    Case("atlas-add-out-name-too-long", {"lh.a.annot": _annot, "rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot", "--out", LONG_NAME],
         "too long", command="atlas"),
    # -- output folders and files ----------------------------------------------------------------------------
    _render(["--out", "o"], "is in use by another brainpainter run", "render-locked-folder", lock="o"),
    _figure(["--out", "f/fig.png"], "is in use by another brainpainter run", "figure-locked-folder", lock="f"),
    _movie(["--out", "m/movie.gif"], "is in use by another brainpainter run", "movie-locked-folder", lock="m"),
    _render(["--out", "blocker/out"], "not a folder", "render-out-under-a-file",
            files={"in.csv": GOOD, "blocker": b""}),
    _render(["--out", "out.png"], "is a file", "render-out-is-a-file",
            files={"in.csv": GOOD, "out.png": PNG}),
    _render(["--out", LONG_NAME], "too long", "render-out-name-too-long"),
    _render(["--out", "a/" + LONG_NAME + "/b"], "too long", "render-out-deep-name-too-long"),
    _figure(["--out", LONG_NAME + ".png"], "too long", "figure-out-name-too-long"),
    _figure(["--out", "fig.bmp"], "must be a file name ending in", "figure-bad-ending"),
    _figure(["--out", "d.png"], "is a folder", "figure-out-is-folder", files={"in.csv": GOOD, "d.png": _folder({})}),
    _figure(["--out", "blocker/fig.png"], "is a file, not a folder", "figure-out-under-a-file",
            files={"in.csv": GOOD, "blocker": b""}),
    _movie(["--out", "m.avi"], "must be a file name ending in", "movie-bad-ending"),
    _movie(["--out", LONG_NAME + ".mp4"], "too long", "movie-out-name-too-long"),
    _movie(["--out", "m.gif", "--frames-per-step", "2500"], "at most 2000 are made", "gif-frame-cap"),
    _movie(["--out", "m.mp4", "--frames-per-step", "30000"], "between 1 and 20000", "movie-frame-cap"),
    _movie(["--out", "m.mp4", "--hold", "-1"], "hold must be 0 or more", "movie-negative-hold"),
    _movie(["--out", "m.mp4", "--transparent"], "no transparency", "movie-transparent"),
    # -- the input opener: regular files only, size limits ----------------------------------------------------
    Case("table-is-fifo", {"in.csv": _fifo}, ["in.csv"], "is not a regular file (a named pipe"),
    Case("table-is-dev-null", {}, ["/dev/null"], "is not a regular file (a device)"),
    Case("table-symlink-to-dev-zero", {"in.csv": _link_to("/dev/zero")}, ["in.csv"], "is not a regular file"),
    Case("table-dangling-symlink", {"in.csv": _link_to("nowhere.csv")}, ["in.csv"], "does not exist"),
    Case("table-is-folder", {"d.csv": _folder({})}, ["d.csv"], "is a directory"),
    Case("table-name-too-long", {}, [LONG_NAME + ".csv"], "too long"),
    Case("render-table-is-fifo", {"in.csv": _fifo}, ["in.csv", "--out", "o", *RENDER], "named pipe",
         command="render"),
    Case("config-is-dev-zero", {"in.csv": GOOD}, ["in.csv", "--atlas-config", "/dev/zero", "--out", "o",
                                                   *RENDER], "is not a regular file (a device)", command="render"),
    Case("config-is-fifo", {"in.csv": GOOD, "c.toml": _fifo},
         ["in.csv", "--atlas-config", "c.toml", "--out", "o", *RENDER], "named pipe", command="render"),
    Case("config-symlink-to-dev-zero", {"in.csv": GOOD, "c.toml": _link_to("/dev/zero")},
         ["in.csv", "--atlas-config", "c.toml", "--out", "o", *RENDER], "not a regular file", command="render"),
    Case("config-too-big", {"in.csv": GOOD, "c.toml": b"# " + b"x" * (2 * 2**20) + b"\n"},
         ["in.csv", "--atlas-config", "c.toml", "--out", "o", *RENDER], "at most 1 MB is read", command="render"),
    Case("config-missing", {"in.csv": GOOD}, ["in.csv", "--atlas-config", "no.toml", "--out", "o", *RENDER],
         "does not exist", command="render"),
    Case("atlas-add-config-fifo", {"c.toml": _fifo}, ["add", "lobes", "--config", "c.toml"], "named pipe",
         command="atlas"),
    Case("atlas-add-config-dev-zero", {}, ["add", "lobes", "--config", "/dev/zero"], "not a regular file",
         command="atlas"),
    Case("annot-is-fifo", {"lh.a.annot": _fifo, "rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot"], "named pipe", command="atlas"),
    Case("annot-is-dev-zero", {"rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=/dev/zero", "--annot", "rh=rh.a.annot"], "not a regular file",
         command="atlas"),
    Case("annot-is-folder", {"lh.a.annot": _folder({}), "rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot"], "is a folder", command="atlas"),
    Case("annot-too-big", {"lh.a.annot": b"\0" * 4096, "rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot"], "at most",
         command="atlas", patch={"brainpainter.io.files:LIMITS": {"label map": 1024}}),
    Case("annot-garbage", {"lh.a.annot": GARBAGE, "rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot"], "cannot read",
         command="atlas"),
    # -- bounded parsing: workbook bombs -----------------------------------------------------------------------
    Case("xlsx-dimension-claims-whole-sheet", {"in.xlsx": _dimension(b"A1:XFD1048576")}, ["in.xlsx"],
         "claims 1048576 rows"),
    Case("xlsx-dimension-beyond-excel", {"in.xlsx": _dimension(b"A1:ZZZZ2")}, ["in.xlsx"],
         "as an Excel workbook"),
    Case("xlsx-dimension-claims-2m-rows", {"in.xlsx": _dimension(b"A1:B2000000")}, ["in.xlsx"],
         "claims 2000000 rows"),
    Case("xlsx-far-row", {"in.xlsx": _far_row(5000)}, ["in.xlsx"], "more than 1000 rows",
         patch={"brainpainter.io.excel:MAX_ROWS": 1000}),
    Case("xlsx-cell-bomb", {"in.xlsx": _wide_row()}, ["in.xlsx"], "cells",
         patch={"brainpainter.io.excel:MAX_CELLS": 500}),
    Case("xlsx-formula-without-result", {"in.xlsx": _formula(False)}, ["in.xlsx"], "without a saved result"),
    Case("render-xlsx-formula-without-result", {"in.xlsx": _formula(False)}, ["in.xlsx", "--out", "o", *RENDER],
         "without a saved result", command="render"),
    Case("xlsx-zip-bomb-small-limit", {"in.xlsx": _zip_bomb(2)}, ["in.xlsx"], "when unzipped",
         env={"BRAINPAINTER_MAX_INPUT_MB": "0.1"}),
    Case("csv-over-limit", {"in.csv": csv(HEADER.strip(), *[f"s{i},1,2" for i in range(2000)])}, ["in.csv"],
         "to keep memory bounded", env={"BRAINPAINTER_MAX_INPUT_MB": "0.01"}),
    # -- ambiguity is an error ------------------------------------------------------------------------------------
    Case("lh-rh-image-names-differ-in-case",
         {"lh.csv": csv("Image-name-unique,Left-insula", "sub-A,1"),
          "rh.csv": csv("Image-name-unique,Right-insula", "sub-a,2")}, ["lh.csv", "rh.csv"],
         "differ only in case"),
    Case("render-lh-rh-image-names-differ-in-case",
         {"lh.csv": csv("Image-name-unique,Left-insula", "sub-A,1"),
          "rh.csv": csv("Image-name-unique,Right-insula", "sub-a,2")}, ["lh.csv", "rh.csv", "--out", "o", *RENDER],
         "differ only in case", command="render"),
    Case("names-collide-ignoring-case", {"in.csv": csv(HEADER.strip(), "a/B,1,2", "a_b,2,3")}, ["in.csv"],
         "become the same file name"),
    Case("names-collide-space", {"in.csv": csv(HEADER.strip(), "a b,1,2", "A_B,2,3")}, ["in.csv"],
         "become the same file name"),
    Case("render-names-collide-ignoring-case", {"in.csv": csv(HEADER.strip(), "x:Y,1,2", "X/y,2,3")},
         ["in.csv", "--out", "o", *RENDER], "become the same file name", command="render"),
    Case("two-image-columns", {"in.csv": csv("Image-name-unique,subject,Left-insula", "A,s1,1")}, ["in.csv"],
         "could both hold the image names"),
    Case("two-image-columns-id", {"in.csv": csv("subject,id,Left-insula", "A,1,1")}, ["in.csv"],
         "could both hold the image names"),
    Case("mixed-decimals-semicolon", {"in.csv": csv("Image-name-unique;Left-insula;Right-insula", "A;1,5;1.234")},
         ["in.csv"], "are mixed"),
    Case("mixed-decimals-tab", {"in.tsv": csv("Image-name-unique\tLeft-insula", "A\t1,5", "B\t2.5")}, ["in.tsv"],
         "are mixed"),
    Case("mixed-decimals-long", {"in.csv": csv("Structure;d", "L_insula;0,2", "R_insula;0.25")}, ["in.csv"],
         "are mixed"),
    Case("bidi-override-in-image-name", {"in.csv": csv(HEADER.strip(), "abc\u202edef,1,2")}, ["in.csv"],
         "contains control characters"),
    Case("bidi-isolate-in-column", {"in.csv": csv("Image-name-unique,Left-insula,x\u2066y", "A,1,2")}, ["in.csv"],
         "contains control characters"),
    Case("zero-width-space-in-name", {"in.csv": csv(HEADER.strip(), "sub\u200b1,1,2")}, ["in.csv"],
         "contains control characters"),
    Case("rtl-mark-in-column", {"in.csv": csv("Image-name-unique,Left-insula,Right-insula\u200f", "A,1,2")}, ["in.csv"],
         "contains control characters"),
    Case("bom-inside-name", {"in.csv": csv(HEADER.strip(), "a\ufeffb,1,2")}, ["in.csv"],
         "contains control characters"),
    Case("render-bidi-name", {"in.csv": csv(HEADER.strip(), "\u202egnp.exe,1,2")}, ["in.csv", "--out", "o", *RENDER],
         "contains control characters", command="render"),
    Case("swapped-annot-names", {"lh.a.annot": _annot, "rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=rh.a.annot", "--annot", "rh=lh.a.annot"], "swap the files",
         command="atlas"),
    Case("swapped-gifti-structure", {"a.label.gii": _gifti("CortexRight"), "b.label.gii": _gifti("CortexLeft")},
         ["add", "net", "--annot", "lh=a.label.gii", "--annot", "rh=b.label.gii"], "AnatomicalStructurePrimary",
         command="atlas"),
    Case("group-name-with-bidi", {"c.toml": toml('[atlas]\nbase = "dk"\n[groups]\n"fr\u202eontal" = ["insula"]')},
         ["add", "lobes", "--config", "c.toml"], "control characters", command="atlas"),
    # -- names: any script, case-folding, Unicode forms, duplicate columns, reserved atlas names ---------------------
    Case("image-names-nfc-nfd", {"in.csv": csv(HEADER.strip(), "Jos\u00e9,1,2", "Jose\u0301,2,3")}, ["in.csv"],
         "accents encoded differently"),
    Case("render-image-names-nfc-nfd", {"in.csv": csv(HEADER.strip(), "Jos\u00e9,1,2", "Jose\u0301,2,3")},
         ["in.csv", "--out", "o", *RENDER], "accents encoded differently", command="render"),
    Case("image-names-equal-after-casefold", {"in.csv": csv(HEADER.strip(), "STRASSE,1,2", "stra\u00dfe,2,3")},
         ["in.csv"], "differ only in case"),
    Case("lh-rh-image-names-nfc-nfd", {"lh.csv": csv("Image-name-unique,Left-insula", "Jos\u00e9,1"),
                                       "rh.csv": csv("Image-name-unique,Right-insula", "Jose\u0301,2")},
         ["lh.csv", "rh.csv"], "accents encoded differently"),
    Case("cjk-names-collide-as-files", {"in.csv": csv(HEADER.strip(), "\u60a3\u8005 1,1,2", "\u60a3\u8005/1,2,3")},
         ["in.csv"], "become the same file name"),
    Case("two-image-name-columns-same-name",
         {"in.csv": csv("Image-name-unique,Image-name-unique,Left-insula", "A,B,1")}, ["in.csv"],
         "columns 1 ('Image-name-unique') and 2 ('Image-name-unique') have the same name"),
    Case("render-two-image-name-columns-same-name",
         {"in.csv": csv("Image-name-unique,Left-insula,Image-name-unique", "A,1,B")}, ["in.csv", "--out", "o", *RENDER],
         "have the same name", command="render"),
    Case("image-columns-differ-in-case", {"in.csv": csv("subject,Subject,Left-insula", "A,B,1")}, ["in.csv"],
         "have the same name ignoring case"),
    Case("image-column-option-names-two", {"in.csv": csv("name,Left-insula,NAME", "A,1,B")},
         ["in.csv", "--image-column", "name"], "have the same name ignoring case"),
    Case("long-two-value-columns-same-name", {"in.csv": csv("Structure,d,d", "L_insula,0.2,0.3")}, ["in.csv"],
         "columns 2 ('d') and 3 ('d') have the same name"),
    Case("atlas-name-con", {"c.toml": LOBES}, ["add", "CON", "--config", "c.toml"], "Windows reserves 'CON'",
         command="atlas"),
    Case("atlas-name-nul-lower", {"c.toml": LOBES}, ["add", "nul", "--config", "c.toml"], "Windows reserves 'NUL'",
         command="atlas"),
    Case("atlas-name-con-with-extension", {"c.toml": LOBES}, ["add", "CON.txt", "--config", "c.toml"],
         "Windows reserves 'CON'", command="atlas"),
    Case("atlas-name-com1", {"c.toml": LOBES}, ["add", "COM1", "--config", "c.toml"], "Windows reserves 'COM1'",
         command="atlas"),
    Case("atlas-name-lpt9-ext", {"c.toml": LOBES}, ["add", "Lpt9.x", "--config", "c.toml"],
         "Windows reserves 'LPT9'", command="atlas"),
    Case("atlas-name-aux-annot", {"lh.a.annot": _annot, "rh.a.annot": _annot},
         ["add", "aux", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot"], "Windows reserves 'AUX'",
         command="atlas"),
    Case("atlas-name-final-dot", {"c.toml": LOBES}, ["add", "lobes.", "--config", "c.toml"], "drops a final '.'",
         command="atlas"),
    Case("annot-region-names-differ-in-case", {"lh.a.annot": _annot_names(b"unknown", b"Net1", b"net1"),
                                               "rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot"], "differ only in case",
         command="atlas"),
    Case("annot-region-names-differ-in-case-rh", {"lh.a.annot": _annot,
                                                  "rh.a.annot": _annot_names(b"unknown", b"VIS", b"vis", b"Vis")},
         ["add", "net", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot"], "'VIS' and 'vis' differ only in case",
         command="atlas"),
    # -- limits from environment variables: one line for any text ---------------------------------------------
    *[Case(f"max-input-mb-{cid}", {"in.csv": GOOD}, ["in.csv"], "BRAINPAINTER_MAX_INPUT_MB must be a number of megabytes greater than 0",
           env={"BRAINPAINTER_MAX_INPUT_MB": value})
      for cid, value in (("inf", "inf"), ("nan", "nan"), ("minus-inf", "-inf"), ("negative", "-1"), ("zero", "0"),
                         ("overflow", "1e400"), ("huge", "1e12"))],
    _render(["--out", "o", "--views", "lateral-left"], "BRAINPAINTER_MAX_INPUT_MB must be a number", "render-max-input-mb-nan",
            env={"BRAINPAINTER_MAX_INPUT_MB": "nan"}),
    *[_render(["--out", "o"], "is not host:port", f"scheduler-env-{cid}", env={"BRAINPAINTER_SCHEDULER": value})
      for cid, value in (("nan", "nan"), ("negative", "-1"), ("no-port", "tcp://host"), ("text-port", "host:abc"))],
    _render(["--out", "o", "--scheduler", "inf"], "is not host:port", "scheduler-option-inf"),
    # -- paths: an empty --out is a mistake, not the current folder ----------------------------------------------
    _render(["--out", ""], "is empty, which would mean the current folder", "render-out-empty"),
    _render(["--out", "  "], "is empty, which would mean the current folder", "render-out-blank"),
    _figure(["--out", ""], "is empty, which would mean the current folder", "figure-out-empty"),
    _movie(["--out", ""], "is empty, which would mean the current folder", "movie-out-empty"),
    Case("export-out-empty", {"in.csv": GOOD}, ["in.csv", "--row", "A", "--out", ""],
         "is empty, which would mean the current folder", command="export"),
    Case("atlas-add-out-empty", {"c.toml": LOBES, "lh.a.annot": _annot, "rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=lh.a.annot", "--annot", "rh=rh.a.annot", "--out", ""],
         "is empty, which would mean the current folder", command="atlas"),
    Case("annot-gifti-claims-two-arrays",
         {"lh.a.label.gii": b'<?xml version="1.0"?><GIFTI Version="1.0" NumberOfDataArrays="2"></GIFTI>',
          "rh.a.annot": _annot},
         ["add", "net", "--annot", "lh=lh.a.label.gii", "--annot", "rh=rh.a.annot"], "holds no data array",
         command="atlas"),
    # -- files that point elsewhere: a GIfTI reads external data only from its own folder (issue 33) -----------
    *[Case(f"gifti-external-{cid}", {"lh.x.func.gii": _gifti_external(name), **extra},
           ["--lh", "lh.x.func.gii", "--out", "o", *RENDER], message, command="render")
      for cid, name, extra, message in (
          ("absolute", "/etc/passwd", {}, "keeps its data in '/etc/passwd', outside its own folder"),
          ("parent", "../../secret.bin", {}, "keeps its data in '../../secret.bin', outside its own folder"),
          ("symlink-out", "in.bin", {"in.bin": _link_to("/etc/passwd")}, "'in.bin', outside its own folder"),
          ("missing", "gone.bin", {}, "keeps its data in 'gone.bin', which is not a file in its folder"))],
    Case("volume-is-gifti-with-external-data", {"lh.x.func.gii": _gifti_external("/etc/passwd")},
         ["--volume", "lh.x.func.gii", "--out", "o", *RENDER], "looks like a GIfTI file, not a NIfTI or MGH volume",
         command="render"),
    Case("volume-is-gzipped-gifti", {"thick_left.gii.gz": _gifti_external("x.bin", gz=True)},
         ["--volume", "thick_left.gii.gz", "--out", "o", *RENDER],
         "looks like gzip-compressed data (a GIfTI file inside), not a NIfTI or MGH volume", command="render"),
    Case("gifti-gz-external-absolute", {"lh.x.func.gii.gz": _gifti_external("/etc/hostname", gz=True)},
         ["--lh", "lh.x.func.gii.gz", "--out", "o", *RENDER], "outside its own folder", command="render"),
    Case("gifti-xml-entity", {"lh.x.func.gii": b'<?xml version="1.0"?><!DOCTYPE GIFTI [<!ENTITY a "b">]>'
                                               b'<GIFTI Version="1.0" NumberOfDataArrays="0"></GIFTI>'},
         ["--lh", "lh.x.func.gii", "--out", "o", *RENDER], "declares the XML entity 'a'", command="render"),
    Case("map-gzip-named-curv", {"lh.thickness": gzip.compress(b'<?xml version="1.0"?><GIFTI></GIFTI>')},
         ["--lh", "lh.thickness", "--out", "o", *RENDER],
         "looks like gzip-compressed data (a GIfTI file inside), not a FreeSurfer curv file", command="render"),
    # -- finite numbers only, checked before anything is written -----------------------------------------------
    _render(["--out", "o", "--vmin", "nan"], "is not a finite number", "vmin-nan"),
    _render(["--out", "o", "--vmax", "inf"], "is not a finite number", "vmax-inf"),
    _render(["--out", "o", "--center", "-inf"], "is not a finite number", "center-minus-inf"),
    _render(["--out", "o", "--center", "nan"], "is not a finite number", "center-nan"),
    _render(["--out", "o", "--glass-opacity", "nan"], "is not a finite number", "glass-opacity-nan"),
    _render(["--out", "o", "--vmin", "1e999"], "is not a finite number", "vmin-overflow"),
    _render(["--out", "o", "--views", "camera:nan:0"], "azimuth must be a finite number", "camera-azimuth-nan"),
    _render(["--out", "o", "--views", "camera:inf:0"], "azimuth must be a finite number", "camera-azimuth-inf"),
    _render(["--out", "o", "--views", "camera:0:nan"], "elevation must be in", "camera-elevation-nan"),
    _render(["--out", "o", "--views", "camera:0:0:nan"], "zoom in", "camera-zoom-nan"),
    _render(["--out", "o", "--views", "camera:0:0:inf"], "zoom in", "camera-zoom-inf"),
    _render(["--out", "o", "--views", "camera:0:0:0"], "zoom in", "camera-zoom-zero"),
    _render(["--out", "o", "--views", "camera:0:91"], "elevation must be in", "camera-elevation-91"),
    _render(["--out", "o", "--size", "nanxnan"], "WIDTHxHEIGHT", "size-nan"),
    _render(["--out", "o", "--size", "0x10"], "between 16 and 8192", "size-zero"),
    _figure(["--out", "f.png", "--font-size", "nan"], "is not a finite number", "font-size-nan"),
    _figure(["--out", "f.png", "--font-size", "inf"], "is not a finite number", "font-size-inf"),
    _figure(["--out", "f.png", "--font-size", "0"], "font size must be", "font-size-zero"),
    _figure(["--out", "f.png", "--font-size", "1e6"], "font size must be", "font-size-huge"),
    _figure(["--out", "f.png", "--dpi", "nan"], "is not a finite number", "dpi-nan"),
    _figure(["--out", "f.png", "--dpi", "5"], "dpi must be between", "dpi-tiny"),
    _figure(["--out", "f.png", "--fig-width", "inf"], "is not a finite number", "fig-width-inf"),
    _movie(["--out", "m.mp4", "--fps", "nan"], "is not a finite number", "fps-nan"),
    _movie(["--out", "m.mp4", "--fps", "1000"], "fps must be between", "fps-huge"),
    _movie(["--out", "m.mp4", "--orbit", "inf"], "is not a finite number", "orbit-inf"),
    Case("check-vmin-nan", {"in.csv": GOOD}, ["in.csv", "--vmin", "nan"], "is not a finite number"),
    # -- region-group configs --------------------------------------------------------------------------------------
    Case("toml-atlas-is-string", {"in.csv": GOOD, "c.toml": toml('atlas = "dk"')},
         ["in.csv", "--atlas-config", "c.toml", "--out", "o", *RENDER], "must be tables", command="render"),
    Case("toml-groups-is-list", {"c.toml": toml('groups = [1, 2]\n[atlas]\nbase = "dk"')},
         ["add", "lobes", "--config", "c.toml"], "must be tables", command="atlas"),
    Case("toml-base-is-number", {"c.toml": toml('[atlas]\nbase = 3\n[groups]\nf = ["insula"]')},
         ["add", "lobes", "--config", "c.toml"], "base must be an atlas name", command="atlas"),
    Case("toml-name-is-table", {"in.csv": GOOD, "c.toml": toml('[atlas]\nbase = "dk"\nname = {a = 1}\n[groups]\n'
                                                               'f = ["insula"]')},
         ["in.csv", "--atlas-config", "c.toml", "--out", "o", *RENDER], "name must be a text", command="render"),
    Case("toml-refers-to-itself", {"lobes.toml": toml('[atlas]\nbase = "lobes"\n[groups]\nf = ["insula"]')},
         ["add", "lobes", "--config", "lobes.toml"], "is the atlas being defined", command="atlas"),
    Case("toml-refers-to-itself-by-case", {"c.toml": toml('[atlas]\nbase = "LOBES"\n[groups]\nf = ["insula"]')},
         ["add", "lobes", "--config", "c.toml"], "is the atlas being defined", command="atlas"),
    Case("toml-invalid", {"c.toml": b"[atlas\nbase = 1\n"}, ["add", "lobes", "--config", "c.toml"],
         "is not valid TOML", command="atlas"),
    Case("toml-binary", {"c.toml": GARBAGE}, ["add", "lobes", "--config", "c.toml"], "is not valid TOML",
         command="atlas"),
    Case("toml-empty", {"c.toml": b""}, ["add", "lobes", "--config", "c.toml"], "needs base", command="atlas"),
    Case("atlas-add-both-sources", {"c.toml": LOBES}, ["add", "lobes", "--config", "c.toml", "--annot", "x"],
         "one of them", command="atlas"),
    # -- the user's own surfaces (--lh-surface): the map fits the surface, the surface is one whole file -------
    Case("own-surface-count-mismatch", {"lh.pial": _surface, "lh.x.txt": b"0\n1\n2\n"},
         ["--lh", "lh.x.txt", "--lh-surface", "lh.pial", "--out", "o", *RENDER],
         "has 3 values per hemisphere, but the surface it is drawn on has 12 vertices", command="render"),
    Case("own-surface-not-a-surface", {"lh.pial": b"not a surface\n", "lh.x.txt": b"0\n1\n2\n"},
         ["--lh", "lh.x.txt", "--lh-surface", "lh.pial", "--out", "o", *RENDER], "cannot read surface file 'lh.pial'",
         command="render"),
    Case("own-surface-external-file", {"lh.pial.surf.gii": EXTERNAL_GIFTI, "lh.x.txt": b"0\n1\n2\n"},
         ["--lh", "lh.x.txt", "--lh-surface", "lh.pial.surf.gii", "--out", "o", *RENDER],
         "keeps its data in '/etc/passwd', outside its own folder", command="render"),
    Case("own-surface-with-a-table", {"in.csv": GOOD, "lh.pial": _surface},
         ["in.csv", "--lh-surface", "lh.pial", "--out", "o", *RENDER], "a region table is drawn on the template's",
         command="render"),
    # -- accepted, with a stated warning -------------------------------------------------------------------------
    Case("one-row-empty-column", {"in.csv": ONE_ROW_EMPTY}, ["in.csv", "--out", "o", *RENDER],
         "drawn in the NaN colour", command="render", code=0),
    Case("check-one-row-empty-column", {"in.csv": ONE_ROW_EMPTY}, ["in.csv"], "drawn in the NaN colour", code=0),
    Case("render-misspelled-column", {"in.csv": csv("Image-name-unique,Left-insula,Left-insulaa", "A,1,2")},
         ["in.csv", "--out", "o", *RENDER], "'Left-insulaa' (did you mean 'Left-insula'?)", command="render",
         code=0),
    Case("xlsx-formula-with-result", {"in.xlsx": _formula(True)}, ["in.xlsx"], "values 2..2", code=0),
    Case("decimal-commas-only", {"in.csv": csv("Image-name-unique;Left-insula", "A;1,5")}, ["in.csv"],
         "decimal commas read as decimal points", code=0),
]


def _sphere_volume(shift: float = 0.0) -> Callable[[Path], None]:
    """A 4 mm MNI152-grid volume: 5 in a sphere of radius 12 mm at (40, -20, 50), 0 elsewhere; `shift`
    moves the grid that many millimetres along every axis (off MNI152)."""
    def make(path: Path) -> None:
        import nibabel as nib
        import numpy as np

        affine = np.array([[4.0, 0, 0, -96 + shift], [0, 4, 0, -132 + shift], [0, 0, 4, -72 + shift],
                           [0, 0, 0, 1]])
        ijk = np.stack(np.meshgrid(*[np.arange(n) for n in (49, 58, 47)], indexing="ij"), axis=-1)
        xyz = ijk @ affine[:3, :3].T + affine[:3, 3]
        inside = np.linalg.norm(xyz - (np.array([40.0, -20.0, 50.0]) + shift), axis=-1) <= 12
        nib.save(nib.Nifti1Image(np.where(inside, 5.0, 0.0).astype(np.float32), affine), path)

    return make


def _cifti(kind: str) -> Callable[[Path], None]:
    """A CIFTI file that brainpainter refuses (issue 34): CIFTI-1, a connectome, a mesh of no known
    count, a truncated dscalar."""
    def make(path: Path) -> None:
        import nibabel as nib
        import numpy as np
        from nibabel.cifti2 import cifti2_axes as axes

        if kind == "version-1":
            img = nib.Nifti2Image(np.zeros((1, 1, 1, 1, 1, 3), np.float32), np.eye(4))
            img.header.extensions.append(nib.nifti1.Nifti1Extension(32, b'<CIFTI Version="1.0"></CIFTI>'))
            img.to_filename(str(path))
            return
        n = 1000 if kind == "odd-mesh" else 32492
        model = axes.BrainModelAxis.from_surface(np.arange(3), n, "CortexLeft")
        rows = model if kind == "dconn" else axes.ScalarAxis(["m"])
        nib.Cifti2Image(np.zeros((len(rows), 3), np.float32), header=(rows, model)).to_filename(str(path))
        if kind == "truncated":
            path.write_bytes(path.read_bytes()[:-6])
    return make


def _fslr_gifti(n: int) -> Callable[[Path], None]:
    def make(path: Path) -> None:
        import nibabel as nib
        import numpy as np

        arr = nib.gifti.GiftiDataArray(np.zeros(n, np.float32), intent="NIFTI_INTENT_SHAPE")
        nib.save(nib.gifti.GiftiImage(darrays=[arr]), str(path))
    return make


INPROCESS += [
    # -- CIFTI and fsLR maps (issue 34) ----------------------------------------------------------------------
    Case("cifti-version-1", {"x.dscalar.nii": _cifti("version-1")}, ["x.dscalar.nii", "--out", "o", *RENDER],
         "-cifti-version-convert x.dscalar.nii 2 OUT.dscalar.nii", command="render"),
    Case("cifti-dconn", {"x.dconn.nii": _cifti("dconn")}, ["x.dconn.nii", "--out", "o", *RENDER],
         "is a CIFTI connectome (dconn/pconn), not a map", command="render"),
    Case("cifti-two-grayordinate-axes", {"x.dscalar.nii": _cifti("dconn")},
         ["x.dscalar.nii", "--out", "o", *RENDER], "grayordinates on both axes", command="render"),
    Case("cifti-mesh-of-no-known-count", {"x.dscalar.nii": _cifti("odd-mesh")},
         ["x.dscalar.nii", "--out", "o", *RENDER], "1000 values per hemisphere, which fits no known mesh",
         command="render"),
    Case("cifti-truncated", {"x.dscalar.nii": _cifti("truncated")}, ["x.dscalar.nii", "--out", "o", *RENDER],
         "truncated", command="render"),
    Case("cifti-fifo", {"x.dscalar.nii": _fifo}, ["x.dscalar.nii", "--out", "o", *RENDER],
         "not a regular file", command="render"),
    Case("cifti-frames-outside", {"x.dscalar.nii": _cifti("scalar")},
         ["x.dscalar.nii", "--frames", "1", "--out", "o", *RENDER], "outside", command="render"),
    Case("cifti-frames-not-rows", {"x.dscalar.nii": _cifti("scalar")},
         ["x.dscalar.nii", "--frames", "a:b", "--out", "o", *RENDER], "start:stop:step", command="render"),
    Case("cifti-with-lh", {"x.dscalar.nii": _cifti("scalar")},
         ["--lh", "x.dscalar.nii", "--out", "o", *RENDER], "holds both hemispheres", command="render"),
    Case("fslr-59k", {"lh.x.shape.gii": _fslr_gifti(59292)}, ["--lh", "lh.x.shape.gii", "--out", "o", *RENDER],
         "fsLR 59k", command="render"),
    Case("fslr-32k-said-fsaverage", {"lh.x.shape.gii": _fslr_gifti(32492)},
         ["--lh", "lh.x.shape.gii", "--space", "fsaverage", "--out", "o", *RENDER], "not fsaverage",
         command="render"),
    # -- blobs and cutaways (issue 45) ---------------------------------------------------------------------------
    Case("volume-surface-not-mni", {"z.nii.gz": _sphere_volume(500.0)},
         ["--volume-surface", "z.nii.gz", "--threshold", "2.3", "--out", "o", *RENDER], "is not an MNI152 volume",
         command="render"),
    Case("volume-surface-threshold-above-max", {"z.nii.gz": _sphere_volume()},
         ["--volume-surface", "z.nii.gz", "--threshold", "6", "--out", "o", *RENDER],
         "at or above the largest |value| of z (5)", command="render"),
    Case("volume-surface-no-cluster-left", {"z.nii.gz": _sphere_volume()},
         ["--volume-surface", "z.nii.gz", "--threshold", "2.3", "--min-cluster-mm3", "1e6", "--out", "o",
          *RENDER], "give a smaller --min-cluster-mm3", command="render"),
    _render(["--out", "o", "--clip", "x<500"], "removes all the cortex and glass", "clip-removes-everything"),
    _render(["--out", "o", "--clip", "left"], "is not a plane", "clip-not-a-plane"),
]

# Hostile image names that are accepted: each becomes a safe file name inside the output folder.
SAFE = {
    "../../x": "x",
    "/etc/passwd": "etc_passwd",
    "C:\\evil\\name": "C_evil_name",
    "a:b": "a_b",
    "..": "image",
    "~/.ssh/id": "ssh_id",
}


def is_big(case: Case) -> bool:
    """Whether `case` writes a big file (tests mark it ``slow`` and share the file, see ``write``)."""
    return _big_table in case.files.values()


def params(cases: list[Case]) -> list[object]:
    """`cases` as pytest parameters, the big ones marked ``slow``."""
    import pytest

    return [pytest.param(c, id=c.id, marks=pytest.mark.slow) if is_big(c) else pytest.param(c, id=c.id)
            for c in cases]


def write(case: Case, folder: Path, shared: dict[Callable[[Path], None], Path] | None = None) -> None:
    """Write the files of `case` into `folder`.

    `shared` maps a file-writing function (``_big_table``) to a file it already
    wrote: that file is hard-linked instead of written again.
    """
    folder.mkdir(parents=True, exist_ok=True)
    for name, content in case.files.items():
        path = folder / name
        if callable(content) and shared and content in shared:
            os.link(shared[content], path)
        elif callable(content):
            content(path)
        else:
            path.write_bytes(content)


if __name__ == "__main__":  # pragma: no cover
    root = Path(sys.argv[1])
    for case in CASES:
        write(case, root / case.id)
    print(f"{len(CASES)} cases written to {root}")
