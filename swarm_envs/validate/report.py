"""One line per validated figure: ours, the paper's value and the paper's setup side by side.

Every experiment of ``python -m swarm_envs.validate`` ends its output with these rows (and puts them in its
``--json`` output under ``"rows"``), so a figure can be re-measured by one command and read off one line.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

__all__ = ["Row", "print_rows", "rows_json"]


@dataclass(frozen=True)
class Row:
    """One compared figure.

    Attributes:
        figure: where the paper shows it, e.g. ``"[T20 Fig. 20a]"``.
        quantity: what is compared, with the unit.
        ours: our value as printed.
        paper: the paper's value as printed (``"-"`` when the text gives none).
        paper_setup: the paper's experiment in a phrase (robots, geometry, thresholds, trials).
        how: how ours was measured, when it differs from the paper's setup or from the row above.
    """

    figure: str
    quantity: str
    ours: str
    paper: str
    paper_setup: str
    how: str = ""


def print_rows(title: str, rows: list[Row]) -> None:
    """Print ``rows`` under ``title``: one line per row, ``figure | quantity | ours | paper | paper's setup | ours: how``."""
    print(f"\n{title}: ours vs the paper, one line per figure")
    print("  figure | quantity | ours | paper | paper's setup | ours measured as")
    for r in rows:
        print(f"  {r.figure} | {r.quantity} | {r.ours} | {r.paper} | {r.paper_setup} | {r.how or 'as the paper'}")


def rows_json(rows: list[Row]) -> list[dict[str, str]]:
    """The rows as plain dicts (for ``--json`` output)."""
    return [asdict(r) for r in rows]
