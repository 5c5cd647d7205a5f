"""Click settings, parameter types and callbacks shared by every command (imports only click).

Kept apart from :mod:`brainpainter.cli.options` (the options generated from core's option classes,
which import numpy-free but sizeable modules) so that ``brainpainter --help`` and plugin commands
such as the template builder's load only this.
"""

from __future__ import annotations

import json
from typing import Any

import click

#: Settings of every command: ``-h`` as well as ``--help``, help text up to 100 columns wide.
CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


def echo_json(obj: object) -> None:
    """Print `obj` as indented JSON (the commands' ``--json`` output)."""
    click.echo(json.dumps(obj, indent=2))


def echo_scale(scale: Any, layers: Any = ()) -> None:
    """Say which colour scale was chosen and why (``scale: viridis 0-4.7 (values >= 0)``), when automatic.

    `scale` is a :class:`~brainpainter.color.scale.ColourScale`; a scale whose limits were given says nothing.
    With several `layers` (:class:`~brainpainter.rendering.layers.Layer`), each automatic scale of its
    own is named by its layer (``map scale: RdBu_r -3 to 3 (values of both signs)``).
    """
    if len(layers) > 1:
        for layer in layers:
            if layer.own_scale and getattr(layer.scale, "chosen", ""):
                click.echo(f"{layer.kind} scale: {layer.scale.describe()}")
    elif getattr(scale, "chosen", ""):
        click.echo(f"scale: {scale.describe()}")


def beyond_scale_note(value_range: Any, scale: Any) -> str | None:
    """A note where the values reach beyond the colour scale: they are drawn in its end colours.

    `value_range` is ``[min, max]`` of the values (``manifest["input"]["value_range"]``) or None.
    """
    if not value_range or scale is None or getattr(scale, "vmin", None) is None:
        return None
    low, high = (float(v) for v in value_range)
    span = max(abs(scale.vmax - scale.vmin), 1e-12)
    if low >= scale.vmin - 1e-9 * span and high <= scale.vmax + 1e-9 * span:
        return None
    return (f"values {low:g}..{high:g} reach beyond the colour scale {scale.vmin:g}..{scale.vmax:g}: those "
            "beyond it are drawn in its end colours (set --vmin/--vmax to the values' range to tell them "
            "apart)")


class FiniteFloat(click.ParamType):  # type: ignore[type-arg]
    """A float option that refuses NaN and infinities (``--vmin nan``) before anything runs."""

    name = "number"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        import math

        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(f"{value!r} is not a number.", param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number; give a number such as 1.5.", param, ctx)
        return number


class OutPath(click.Path):
    """``click.Path`` for ``--out`` that refuses an empty value.

    ``--out ''`` (often an unset shell variable, ``--out "$DIR"``) would
    otherwise become ``Path('')``, the current folder.
    """

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if isinstance(value, str) and not value.strip():
            self.fail(f"{value!r} is empty, which would mean the current folder; give a folder or file name "
                      "(use '.' for the current folder if that is meant).", param, ctx)
        return super().convert(value, param, ctx)


#: Click type of every float option: finite numbers only.
FINITE = FiniteFloat()


def split_commas(ctx: click.Context, param: click.Parameter, value: tuple[str, ...]) -> list[str]:
    """Callback for repeatable options that also take comma-separated lists."""
    return [v.strip() for item in value for v in item.split(",") if v.strip()]
