"""Values shown in error messages: short, and never an error of their own."""

from __future__ import annotations

from typing import Any

__all__ = ["shown"]


def shown(value: Any, width: int = 80) -> str:
    """``repr(value)`` cut to ``width`` characters. An integer past Python's digit limit for ``str`` (4300
    digits), or a container holding one, cannot be printed: it is described instead."""
    try:
        text = repr(value)
    except ValueError:
        if isinstance(value, int):
            text = f"<an integer of about {int(value.bit_length() * 0.30103) + 1} digits>"
        else:
            text = f"<a {type(value).__name__} holding a number too long to print>"
    return text if len(text) <= width else text[: width - 3] + "..."
