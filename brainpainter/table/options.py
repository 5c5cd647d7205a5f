"""How a table is read: the one definition of ``--image-column``, ``--value``, ``--region-column``,
``--strict``.

:class:`TableOptions` holds the defaults and help text that the CLI and the
web API show; ``read_table(data, atlas, **options.kwargs())`` reads with them.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import TypedDict, cast


class TableKwargs(TypedDict, total=False):
    """The keyword arguments of :class:`TableOptions` (``render(image_column=...)``, ...)."""

    image_column: str | None
    value: str | None
    region_column: str | None
    strict: bool


@dataclass(frozen=True)
class TableOptions:
    """How a region-value table is read (see :func:`brainpainter.table.region_table.read_table`).

    Attributes
    ----------
    image_column : str, optional
        Column with the image names.
    value : str, optional
        Long tables: the column with the values.
    region_column : str, optional
        Long tables: the column with region names (auto-detected when unambiguous).
    strict : bool
        Names that match no region are an error.
    """

    image_column: str | None = field(default=None, metadata={
        "help": "Column with image names (default Image-name-unique, a FreeSurfer first column, subject...; "
                "otherwise rows are numbered)."})
    value: str | None = field(default=None, metadata={
        "help": "Long tables: the column with the values, e.g. d_icv."})
    region_column: str | None = field(default=None, metadata={
        "help": "Long tables: the column with region names (auto-detected when unambiguous)."})
    strict: bool = field(default=False, metadata={"help": "Names that match no region are an error."})

    def kwargs(self) -> TableKwargs:
        """The options as keyword arguments of ``read_table``."""
        return cast(TableKwargs, asdict(self))
