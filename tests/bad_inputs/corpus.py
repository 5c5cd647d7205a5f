"""The bad-input corpus: malformed and hostile tables, each with its expected one-line error.

Every case is generated (nothing large is committed): ``write(case, folder)``
writes its files into an empty folder, and the test runs the real CLI there
(``python -m brainpainter check|render ...``) and expects exit code 2, one
line on stderr containing ``case.message``, no traceback and no file written.

``SAFE`` lists hostile inputs that are *accepted*: image names that look like
paths are sanitised into file names inside the output folder.

Run ``python tests/bad_inputs/corpus.py FOLDER`` to write the whole corpus
to FOLDER (one sub-folder per case) for manual inspection.
"""

from __future__ import annotations

import gzip
import io
import random
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
    """

    id: str
    files: dict[str, Content]
    args: list[str]
    message: str
    command: str = "check"
    env: dict[str, str] = field(default_factory=dict)


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
    Case("column-all-nan", {"in.csv": csv(HEADER.strip(), "A,1,", "B,2,NaN")}, ["in.csv"],
         "column 'Right-insula' (region 'Right-insula') has no value in any row"),
    Case("render-non-numeric", {"in.csv": csv(HEADER.strip(), "A,1,high")}, ["in.csv"],
         "'high', which is not a number", command="render"),
    Case("render-all-nan", {"in.csv": csv(HEADER.strip(), "A,1,")}, ["in.csv"], "has no value in any row",
         command="render"),
    # -- image names ----------------------------------------------------------------------------------
    Case("image-name-with-nul", {"in.csv": csv(HEADER.strip(), "a\x00b,1,2")}, ["in.csv"], "NUL"),
    Case("image-name-with-escape", {"in.csv": csv(HEADER.strip(), "\x1b[31mred,1,2")}, ["in.csv"],
         "contains control characters"),
    Case("image-name-300-chars", {"in.csv": csv(HEADER.strip(), "x" * 300 + ",1,2")}, ["in.csv"],
         "is 300 characters long; at most 200"),
    Case("duplicate-image-names", {"in.csv": csv(HEADER.strip(), "A,1,2", "A,2,3")}, ["in.csv"],
         "'A' appears at line 2 and line 3"),
    Case("image-names-differ-in-case", {"in.csv": csv(HEADER.strip(), "sub-A,1,2", "sub-a,2,3")}, ["in.csv"],
         "differ only in case"),
    Case("image-names-collide-as-files", {"in.csv": csv(HEADER.strip(), "a/b,1,2", "a:b,2,3")}, ["in.csv"],
         "become the same file name", command="render"),
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

# Hostile image names that are accepted: each becomes a safe file name inside the output folder.
SAFE = {
    "../../x": "x",
    "/etc/passwd": "etc_passwd",
    "C:\\evil\\name": "C_evil_name",
    "a:b": "a_b",
    "..": "image",
    "~/.ssh/id": "ssh_id",
}


def write(case: Case, folder: Path) -> None:
    """Write the files of `case` into `folder`."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, content in case.files.items():
        path = folder / name
        if callable(content):
            content(path)
        else:
            path.write_bytes(content)


if __name__ == "__main__":  # pragma: no cover
    root = Path(sys.argv[1])
    for case in CASES:
        write(case, root / case.id)
    print(f"{len(CASES)} cases written to {root}")
