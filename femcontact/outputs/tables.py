"""Markdown tables, one writer for every report: a study's summary.md, the family summaries and
the measurement programs' pages (benchmarks/)."""
from typing import Iterable, Sequence

ALIGN = {None: "---", "l": ":---", "c": ":---:", "r": "---:"}
"""Separator cell per column alignment: none given (the renderer's default, left), left, centre, right."""


def format_value(value) -> str:
    """A value as a table shows it: numbers to 4 significant digits, flags yes/no, lists as (a, b)
    (one item: a; none: 'none'), None empty."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, list):
        inner = ", ".join(map(format_value, value))
        return "none" if not value else inner if len(value) == 1 else f"({inner})"
    return "" if value is None else str(value)


def cell_text(value, template: str | None = None) -> str:
    """One cell: a string as it is, a number by `template` (a format string such as "{:.2f} s")
    when given, anything else by `format_value`."""
    if isinstance(value, str):
        return value
    if template is not None and isinstance(value, (int, float)) and not isinstance(value, bool):
        return template.format(value)
    return format_value(value)


def markdown_table(header: Sequence[str], rows: Iterable[Sequence], formats: Sequence[str | None] | None = None,
                   align: str | None = None) -> list[str]:
    """The lines of a Markdown table: the header, the separator and one line per row. `formats`:
    per column, the format string of its numbers (None: `format_value`); `align`: one letter per
    column, l, c or r (default: none given). A '|' in a cell is escaped and a line break becomes
    a space, so every row stays one line of the table."""
    formats = list(formats or [None] * len(header))
    separator = [ALIGN[letter] for letter in align] if align else [ALIGN[None]] * len(header)

    def line(cells) -> str:
        return "| " + " | ".join(text.replace("|", "\\|").replace("\n", " ") for text in cells) + " |"

    return [line(header), "|" + "|".join(separator) + "|",
            *(line(cell_text(value, template) for value, template in zip(row, formats, strict=True)) for row in rows)]
