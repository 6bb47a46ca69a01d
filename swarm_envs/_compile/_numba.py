"""numba's ``njit`` with the package's compiler flags and an on-disk cache that recovers from bad files.

With ``cache=True`` numba pickles compiled code next to the source (or under ``NUMBA_CACHE_DIR``). A cache
file truncated or overwritten (a killed process, a full disk, two numba versions) makes numba raise
``UnpicklingError``/``EOFError`` at the first call, i.e. inside ``env.reset``. :func:`njit` here is a
drop-in replacement for ``numba.njit``: when ``cache=True`` it guards the function's cache so that a
cache file that cannot be read (or holds code of another signature) is discarded with a
:class:`NumbaCacheWarning`, the function is compiled again and the cache rewritten. Use it in every
module with compiled kernels::

    from swarm_envs._compile._numba import njit   # instead of: from numba import njit

It also keeps the first run's compile time down (:mod:`swarm_envs._compile._first_run`): every kernel gets the
same flags (``nogil=True``, ``error_model="numpy"`` unless given), so the library functions kernels call
(``np.empty``, ...) compile once per session instead of once per set of flags, and a kernel called from
another with constant arguments compiles once, not once per constant value.

Kernels allocate with ``np.empty(shape, dtype)``, the dtype given and positional, and fill the array in
place (``x[:] = 0``) instead of calling ``np.zeros``, ``np.ones`` or ``np.full``: numba compiles each of
those library functions once per shape and dtype and process, about 30 ms each on the first run, and
``np.zeros`` compiles ``np.empty`` and a fill function besides (``tests/compile/test_first_run.py`` checks the form).

numba is a required dependency: the kernels are the simulator's only implementation of their steps (their
plain numpy references, for the tests, are in :mod:`swarm_envs._compile.reference`).
"""

from __future__ import annotations

import warnings
from typing import Any, Callable

from numba import njit as _numba_njit
from numba.core import sigutils, types

__all__ = ["njit", "guard_cache", "unliteral_calls", "NumbaCacheWarning"]


class NumbaCacheWarning(RuntimeWarning):
    """A numba cache file could not be used; the function was recompiled."""


def guard_cache(dispatcher: Any) -> Any:
    """Make ``dispatcher``'s on-disk cache (numba ``cache=True``) recover from unreadable files: a failed
    load, or a loaded entry compiled for another signature than the one asked for, empties the cache
    index, warns and returns "not cached" (numba then compiles and saves again); a failed save warns.
    Dispatchers without a disk cache are returned unchanged."""
    cache = getattr(dispatcher, "_cache", None)
    if cache is None or not hasattr(cache, "load_overload") or getattr(cache, "_swarm_guarded", False):
        return dispatcher
    load, save = cache.load_overload, cache.save_overload
    name = getattr(dispatcher, "__qualname__", repr(dispatcher))

    def discard(why: str) -> None:
        warnings.warn(f"numba cache of {name} {why}; discarding it and recompiling", NumbaCacheWarning, stacklevel=3)
        try:
            cache.flush()  # rewrite an empty index, so the save after compiling works
        except Exception:  # pragma: no cover - e.g. a read-only cache directory
            pass

    def load_overload(sig: Any, target_context: Any) -> Any:
        try:
            cres = load(sig, target_context)
        except Exception as err:  # any unreadable file: pickle, EOF, bad data, version mismatch
            discard(f"is unreadable ({type(err).__name__}: {err})")
            return None
        if cres is not None and tuple(cres.signature.args) != tuple(sigutils.normalize_signature(sig)[0]):
            # two processes that saved two signatures of this function at once can name one data file
            discard(f"holds code of another signature ({cres.signature.args} for {sig})")
            return None
        return cres

    def save_overload(sig: Any, data: Any) -> None:
        try:
            save(sig, data)
        except Exception as err:
            warnings.warn(f"could not write the numba cache of {name} ({type(err).__name__}: {err})", NumbaCacheWarning, stacklevel=2)

    cache.load_overload = load_overload
    cache.save_overload = save_overload
    cache._swarm_guarded = True
    return dispatcher


def unliteral_calls(dispatcher: Any) -> Any:
    """Make calls to ``dispatcher`` from other compiled functions use the plain types of their constant
    arguments: numba otherwise compiles one specialisation per literal value (``f(x, 0)`` and ``f(x, 1)``
    from compiled code are two compilations of ``f`` with ``Literal[int](0)`` and ``Literal[int](1)``).
    The arithmetic is the same; only compile time is saved."""
    if getattr(dispatcher, "_swarm_unliteral", False) or not hasattr(dispatcher, "get_call_template"):
        return dispatcher
    get_call_template = dispatcher.get_call_template

    def plain_call_template(args: Any, kws: Any) -> Any:
        return get_call_template(tuple(types.unliteral(a) for a in args), {k: types.unliteral(v) for k, v in kws.items()})

    dispatcher.get_call_template = plain_call_template
    dispatcher._swarm_unliteral = True
    return dispatcher


def njit(*args: Any, **kwargs: Any) -> Any:
    """``numba.njit`` (same arguments) with the package's defaults ``nogil=True`` and
    ``error_model="numpy"`` (one set of flags for every kernel: numba compiles the library functions a
    kernel calls, ``np.empty`` and the like, once per set of flags, so kernels that share the flags share
    them), calls from compiled code without per-constant specialisations (:func:`unliteral_calls`), and
    with ``cache=True`` the cache guarded by :func:`guard_cache`."""
    kwargs.setdefault("nogil", True)
    kwargs.setdefault("error_model", "numpy")

    def wrap(dispatcher: Any) -> Any:
        dispatcher = unliteral_calls(dispatcher)
        return guard_cache(dispatcher) if kwargs.get("cache", False) else dispatcher

    if len(args) == 1 and callable(args[0]):  # bare decorator with keyword options: njit(fn, cache=True)
        return wrap(_numba_njit(*args, **kwargs))

    def decorate(fn: Callable) -> Any:
        return wrap(_numba_njit(*args, **kwargs)(fn))

    return decorate
