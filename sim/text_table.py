"""Rows of cells as a text table: Markdown, or plain columns for a terminal."""

from __future__ import annotations


def text_table(head, rows, markdown: bool = False) -> str:
    """``head`` (n cells) over ``rows`` (each n cells, str) as a Markdown table, or as plain
    text whose columns are as wide as their widest cell, two spaces apart."""
    rows = [tuple(r) for r in rows]
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(head)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    return "\n".join([fmt.format(*head)] + [fmt.format(*r) for r in rows])
