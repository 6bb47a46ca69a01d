"""Helpers for the task modules' environment factories (``parallel_env`` of each task)."""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["reports_unknown_kwargs"]


_Factory = TypeVar("_Factory", bound=Callable[..., Any])


def reports_unknown_kwargs(factory: _Factory) -> _Factory:
    """Decorate an env factory with explicit keyword arguments so that an unknown or misspelt name raises
    ``TypeError`` listing the allowed names (as ``SwarmEnv`` does), not Python's bare message.

    The signature, type hints and docstring stay the factory's (``functools.wraps``).
    """
    allowed = sorted(inspect.signature(factory).parameters)

    @functools.wraps(factory)
    def checked(*args: Any, **kwargs: Any) -> Any:
        unknown = sorted(set(kwargs) - set(allowed))
        if unknown:
            raise TypeError(f"{factory.__module__}.{factory.__name__}() got unknown keyword argument(s) {unknown}; allowed: {allowed}")
        return factory(*args, **kwargs)

    return checked  # type: ignore[return-value]
