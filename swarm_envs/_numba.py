"""numba's ``njit`` with an on-disk cache that recovers from corrupted cache files.

With ``cache=True`` numba pickles compiled code next to the source (or under ``NUMBA_CACHE_DIR``). A cache
file truncated or overwritten (a killed process, a full disk, two numba versions) makes numba raise
``UnpicklingError``/``EOFError`` at the first call, i.e. inside ``env.reset``. :func:`njit` here is a
drop-in replacement for ``numba.njit``: when ``cache=True`` it guards the function's cache so that a
cache file that cannot be read is discarded with a :class:`NumbaCacheWarning`, the function is compiled
again and the cache rewritten. Use it in every module with compiled kernels::

    from swarm_envs._numba import njit   # instead of: from numba import njit

Raises ``ImportError`` when numba is not installed (as ``from numba import njit`` would), so modules can
keep their numpy fallback.
"""

from __future__ import annotations

import warnings
from typing import Any, Callable

from numba import njit as _numba_njit

__all__ = ["njit", "guard_cache", "NumbaCacheWarning"]


class NumbaCacheWarning(RuntimeWarning):
    """A numba cache file could not be used; the function was recompiled."""


def guard_cache(dispatcher: Any) -> Any:
    """Make ``dispatcher``'s on-disk cache (numba ``cache=True``) recover from unreadable files: a failed
    load empties the cache index, warns and returns "not cached" (numba then compiles and saves again);
    a failed save warns. Dispatchers without a disk cache are returned unchanged."""
    cache = getattr(dispatcher, "_cache", None)
    if cache is None or not hasattr(cache, "load_overload") or getattr(cache, "_swarm_guarded", False):
        return dispatcher
    load, save = cache.load_overload, cache.save_overload
    name = getattr(dispatcher, "__qualname__", repr(dispatcher))

    def load_overload(sig: Any, target_context: Any) -> Any:
        try:
            return load(sig, target_context)
        except Exception as err:  # any unreadable file: pickle, EOF, bad data, version mismatch
            warnings.warn(
                f"numba cache of {name} is unreadable ({type(err).__name__}: {err}); discarding it and recompiling",
                NumbaCacheWarning,
                stacklevel=2,
            )
            try:
                cache.flush()  # rewrite an empty index, so the save after compiling works
            except Exception:  # pragma: no cover - e.g. a read-only cache directory
                pass
            return None

    def save_overload(sig: Any, data: Any) -> None:
        try:
            save(sig, data)
        except Exception as err:
            warnings.warn(f"could not write the numba cache of {name} ({type(err).__name__}: {err})", NumbaCacheWarning, stacklevel=2)

    cache.load_overload = load_overload
    cache.save_overload = save_overload
    cache._swarm_guarded = True
    return dispatcher


def njit(*args: Any, **kwargs: Any) -> Any:
    """``numba.njit`` (same arguments); with ``cache=True`` the cache is guarded by :func:`guard_cache`."""
    if not kwargs.get("cache", False):
        return _numba_njit(*args, **kwargs)
    if len(args) == 1 and callable(args[0]):  # bare decorator with keyword options: njit(fn, cache=True)
        return guard_cache(_numba_njit(*args, **kwargs))

    def decorate(fn: Callable) -> Any:
        return guard_cache(_numba_njit(*args, **kwargs)(fn))

    return decorate
