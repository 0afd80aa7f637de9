"""Tables as data: a title, columns and rows of text, built by the core, drawn by the CLI.

No I/O, no rich.  :func:`wormgear_cli.cli.common.render` draws a :class:`Table` with rich,
within the terminal's width and never cutting a number.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Cell:
    """A table cell: its text and an optional style name (e.g. "bold red", "dim")."""

    text: str
    style: str | None = None


@dataclass(frozen=True)
class Column:
    """A table column: header text, alignment ("left" or "right") and ``min_width``: the
    narrowest it may be drawn (a number column kept whole on a narrow terminal), None: any."""

    header: str
    justify: str = "left"
    min_width: int | None = None


#: how a table's rules are drawn: a frame with a heavier rule under the header (the default), or no
#: frame and one rule under the header (the compact look of reports with many tables)
BOXES = ("heavy_head", "simple_head")


@dataclass
class Table:
    """A table as data: ``rows`` hold str or :class:`Cell` values, one per column.

    ``show_header`` False hides the header row (an empty ``title``: no title line); ``box`` one
    of :data:`BOXES`; ``padding`` spaces either side of each cell's text.  Rendering (and the
    rule that a number is never cut to fit the width) is the CLI's:
    :func:`wormgear_cli.cli.common.render`.
    """

    title: str
    columns: list
    rows: list = field(default_factory=list)
    caption: str | None = None
    show_header: bool = True
    box: str = "heavy_head"
    padding: int = 1

    def __post_init__(self) -> None:
        if self.box not in BOXES:
            raise ValueError(f"box: expected one of {', '.join(BOXES)}, got {self.box!r}")

    def add_row(self, *cells) -> None:
        self.rows.append(list(cells))
