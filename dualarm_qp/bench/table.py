"""Rendering of the benchmark tables as aligned text or Markdown."""

from __future__ import annotations

from collections.abc import Sequence


def render_table(cells: Sequence[Sequence[str]], *, markdown: bool = False,
                 left_columns: int = 1) -> str:
    """Render a header row plus data rows.

    Parameters
    ----------
    cells : sequence of sequences of str
        The header first, then one row per line, all of the same length.
    markdown : bool
        A Markdown table instead of aligned text.
    left_columns : int
        How many leading (label) columns are left-aligned in text; the rest, numbers,
        are right-aligned.
    """
    if markdown:
        lines = ["| " + " | ".join(cells[0]) + " |",
                 "|" + "|".join("---" for _ in cells[0]) + "|"]
        return "\n".join(lines + ["| " + " | ".join(c) + " |" for c in cells[1:]])
    widths = [max(len(row[i]) for row in cells) for i in range(len(cells[0]))]
    return "\n".join("  ".join(c.ljust(w) if i < left_columns else c.rjust(w)
                               for i, (c, w) in enumerate(zip(row, widths, strict=True)))
                     for row in cells)
