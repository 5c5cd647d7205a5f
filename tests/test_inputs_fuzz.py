"""Fuzzing the reader: generated inputs, no exception but BrainPainterError.

Marked ``slow``: 300 examples by default (seconds, what CI runs);
``BRAINPAINTER_FUZZ_EXAMPLES=10000`` runs the long campaign.

Each example is built in memory (bytes, dicts, DataFrames, lists of inputs)
from one hypothesis-drawn seed, which keeps generation cheap (the whole run
takes well under a minute), plus raw random bytes. The builder starts from a
valid table (real region names in many spellings, non-region measures, image
names, numbers) in one of the supported layouts and formats, then corrupts it
at a random rate: junk names and cells, control characters, empty and
infinite cells, quotes, duplicates, wrong options. Successful reads must give
a consistent table; the check report must build for it too.
"""

from __future__ import annotations

import math
import os
import random

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from brainpainter.atlas.registry import get_atlas
from brainpainter.errors import BrainPainterError
from brainpainter.table.region_table import inspect_table, read_table
from brainpainter.table.report import check_report, format_report

DK, DESTRIEUX = get_atlas("dk"), get_atlas("destrieux")
REGION_NAMES = [
    *DK.keys, *[r.name for r in DK.cortical("lh")], *[f"ctx-rh-{r.name}" for r in DK.cortical("rh")],
    *[f"lh_{r.name}_thickness" for r in DK.cortical("lh")], *[f"R_{r.name}" for r in DK.cortical("rh")],
    *[f"rh_{r.name}_area" for r in DESTRIEUX.cortical("rh")][:20], "Lhippo", "Rthal", "LLatVent",
    "Laccumb", "Left-Thalamus-Proper", "Thalamus-Proper", "Brain-Stem",
]
NOT_REGIONS = ["eTIV", "ICV", "BrainSegVolNotVent", "lh_MeanThickness_thickness", "unknown", "Left-vessel",
               "Age", "Sex", "foo", ""]
IMAGE_COLUMNS = ["Image-name-unique", "SubjID", "subject", "lh.aparc.thickness", "Measure:volume", "name"]
JUNK = ["", " ", "high", "1,234", "1.234,5", "inf", "-Infinity", "1e999", "nan", "NA", "#N/A", "TRUE",
        "0x10", "1_000", "\u00a0", "\x00", "\x1b[2J", "\r", '"', '""', "a\nb", "x" * 250, "é", "名前",
        "../../x", "/etc/passwd", "a:b", "A", "a", "Left-insula", "Structure", "d.icv", "9" * 400]
SEPARATORS = [",", ",", ";", "\t", " ", "|"]
PREFIXES = [b"", b"", b"", b"\xef\xbb\xbf", b"\xff\xfe", b"PK\x03\x04", b"\xd0\xcf\x11\xe0", b"\x1f\x8b"]


def _number(rnd: random.Random) -> object:
    v = rnd.choice([rnd.uniform(-5, 5), rnd.randint(-3, 3), rnd.uniform(0, 1e6)])
    return v if rnd.random() < 0.5 else f"{v:g}"


def _table(rnd: random.Random, p: float) -> tuple[list[str], list[list[object]], str | None]:
    """A header, rows and the value column name (long tables) for one valid-ish table."""

    def junk(good: object) -> object:
        return rnd.choice(JUNK) if rnd.random() < p else good

    n_rows = rnd.choice([0, 1, 1, 2, 3, 5])
    if rnd.random() < 0.3:  # long
        header = [junk("Structure"), junk("d.icv"), junk("se")] + (["Image-name-unique"] if rnd.random() < .3
                                                                    else [])
        names = rnd.sample(REGION_NAMES, min(len(REGION_NAMES), rnd.randint(1, 6)))
        rows = [[junk(n), junk(_number(rnd)), junk(_number(rnd))] + ([junk(f"img{rnd.randint(0, 2)}")]
                                                                     if len(header) == 4 else [])
                for n in names]
        return header, rows, rnd.choice(["d.icv", "d.icv", None, "se", "Structure"])
    k = rnd.randint(1, 6)
    names = [junk(n) for n in rnd.sample(REGION_NAMES + NOT_REGIONS, k)]
    image = [junk(rnd.choice(IMAGE_COLUMNS))] if rnd.random() < 0.8 else []
    header = image + names
    rows = [([junk(f"sub-{i:02d}")] if image else []) + [junk(_number(rnd)) for _ in names]
            for i in range(n_rows)]
    return header, rows, None


def _text(rnd: random.Random, header, rows) -> bytes:
    sep = rnd.choice(SEPARATORS)
    quote = rnd.random() < 0.3
    decimal = sep in (";", "\t") and rnd.random() < 0.5

    def cell(c: object) -> str:
        s = str(c) if not isinstance(c, float) else f"{c:g}"
        if decimal:
            s = s.replace(".", ",")
        return f'"{s}"' if quote and rnd.random() < 0.5 else s

    newline = rnd.choice(["\n", "\r\n", "\r"])
    text = newline.join(sep.join(cell(c) for c in row) for row in [header, *rows]) + newline
    if rnd.random() < 0.1:  # a ragged row
        text += sep.join("1" for _ in range(rnd.randint(0, len(header) + 2)))
    data = text.encode(rnd.choice(["utf-8", "utf-8", "cp1252", "utf-16"]), errors="replace")
    if rnd.random() < 0.15:
        data = rnd.choice(PREFIXES) + data
    if rnd.random() < 0.05:
        i = rnd.randrange(len(data) + 1)
        data = data[:i] + bytes(rnd.randrange(256) for _ in range(rnd.randint(1, 8))) + data[i:]
    return data


def _python(rnd: random.Random, header, rows) -> object:
    kind = rnd.choice(["frame", "dict", "nested", "scalar"])
    cols = {h: [r[j] if j < len(r) else None for r in rows] for j, h in enumerate(header)}
    if kind == "frame":
        frame = pd.DataFrame(cols)
        if rnd.random() < 0.3 and len(frame):
            frame = frame.set_index(frame.columns[0])
        return frame
    if kind == "dict":
        return cols
    if kind == "nested":
        return {str(r[0]) if r else "x": dict(zip(header[1:], r[1:], strict=False)) for r in rows}
    return {h: (v[0] if v else None) for h, v in cols.items()}


def make_case(seed: int) -> tuple[object, dict]:
    rnd = random.Random(seed)
    p = rnd.choice([0.0, 0.0, 0.0, 0.02, 0.1, 0.3])
    header, rows, value = _table(rnd, p)
    form = rnd.random()
    if form < 0.6:
        data: object = _text(rnd, header, rows)
    elif form < 0.85:
        data = _python(rnd, header, rows)
    else:
        h2, r2, _ = _table(rnd, p)
        data = [_text(rnd, header, rows), _text(rnd, h2, r2)]
    options = {
        "atlas": rnd.choice([None, None, DK, DESTRIEUX]),
        "image_column": rnd.choice([None] * 8 + ["Image-name-unique", "SubjID", "nope"]),
        "value": value if value is None or rnd.random() < 0.9 else "nope",
        "region_column": rnd.choice([None] * 8 + ["Structure", "nope"]),
        "strict": rnd.random() < 0.2,
    }
    return data, options


CASES = st.one_of(
    st.integers(0, 2**32 - 1).map(make_case),
    st.integers(0, 2**32 - 1).map(make_case),
    st.integers(0, 2**32 - 1).map(make_case),
    st.tuples(st.binary(max_size=200), st.just({})),
)
STATS = {"ok": 0, "error": 0}
EXAMPLES = int(os.environ.get("BRAINPAINTER_FUZZ_EXAMPLES", "300"))


@pytest.mark.slow
@settings(max_examples=EXAMPLES, deadline=None, database=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(case=CASES)
def test_reader_raises_only_brainpainter_errors(case):
    data, options = case
    try:
        table = read_table(data, **options)
    except BrainPainterError as exc:
        assert str(exc).strip()
        STATS["error"] += 1
        return
    STATS["ok"] += 1
    n, m = table.values.shape
    assert n == len(table.images) == len(set(table.images)) and m == len(table.regions) >= 1
    assert set(table.regions) <= set(table.atlas.keys)
    assert not np.isinf(table.values).any()
    assert all(0 < len(i) <= 200 for i in table.images)
    report = check_report(inspect_table(data, **options))
    assert report["ok"] and format_report(report)
    rng = table.summary()["value_range"]
    assert rng is None or all(math.isfinite(v) for v in rng)


@pytest.mark.slow
def test_fuzz_reached_both_outcomes():
    """Runs after the fuzz test (file order): both good and bad tables were generated."""
    if STATS["ok"] + STATS["error"] == 0:  # run alone (-k): fuzz first
        test_reader_raises_only_brainpainter_errors()
    assert STATS["ok"] > EXAMPLES // 10 and STATS["error"] > EXAMPLES // 10, STATS
