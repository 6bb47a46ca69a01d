"""Binary BCH block codes of length 15 used by SwarmCom [T20 Sec. 4.3].

SwarmCom sends data in 15-bit blocks and offers the binary BCH codes [15,15] (no coding), [15,11]
(corrects t = 1 error), [15,1] (repetition, t = 7) [T20 Sec. 4.3, Sec. 5.4]; we add [15,7] (t = 2) and
[15,5] (t = 3). Codes are systematic with the same conventions as ``galois.BCH`` (message bits first,
most significant coefficient first, then the n - k parity bits), generator polynomials over GF(2)
from the primitive polynomial x^4 + x + 1:

- [15,11]: g = x^4 + x + 1
- [15,7]:  g = x^8 + x^7 + x^6 + x^4 + 1
- [15,5]:  g = x^10 + x^8 + x^5 + x^4 + x^2 + x + 1
- [15,1]:  g = x^14 + x^13 + ... + 1 (repetition)

Decoding is bounded-distance decoding by a full lookup table over all 2^15 received words (built once,
256 kB), so ``decode`` is two vectorised array look-ups. A received word more than t errors away from
every codeword is flagged ``ok = False`` (possible only for the imperfect codes [15,7] and [15,5];
[15,15], [15,11] and [15,1] are perfect codes: every word decodes, possibly wrongly).

Pure numpy: the optional ``galois`` package is used only by the tests as a cross-check.
"""

from __future__ import annotations

from functools import lru_cache
from math import comb

import numpy as np

__all__ = ["BCHCode", "code", "error_free_probability", "SUPPORTED"]

# (n, k) -> (generator polynomial as an int, MSB = highest degree; t)
_GENERATORS: dict[tuple[int, int], tuple[int, int]] = {
    (15, 15): (0b1, 0),
    (15, 11): (0b10011, 1),
    (15, 7): (0b111010001, 2),
    (15, 5): (0b10100110111, 3),
    (15, 1): (0b111111111111111, 7),
}
SUPPORTED: tuple[tuple[int, int], ...] = tuple(_GENERATORS)


def _polymod(a: int, g: int) -> int:
    """Remainder of a(x) / g(x) over GF(2) (polynomials as ints, bit i = coefficient of x^i)."""
    dg = g.bit_length() - 1
    while a and a.bit_length() - 1 >= dg:
        a ^= g << (a.bit_length() - 1 - dg)
    return a


def _bits_to_int(bits: np.ndarray, width: int) -> np.ndarray:
    w = (1 << np.arange(width - 1, -1, -1)).astype(np.int64)
    return np.asarray(bits, dtype=np.int64) @ w


def _int_to_bits(values: np.ndarray, width: int) -> np.ndarray:
    shifts = np.arange(width - 1, -1, -1)
    return ((np.asarray(values, dtype=np.int64)[..., None] >> shifts) & 1).astype(bool)


class BCHCode:
    """A systematic binary [n, k] BCH code correcting ``t`` errors per n-bit block.

    Attributes:
        n: block (codeword) length in bits.
        k: information bits per block.
        t: number of correctable bit errors per block.
        generator: generator polynomial as an int (bit i = coefficient of x^i).
    """

    def __init__(self, n: int, k: int) -> None:
        if (n, k) not in _GENERATORS:
            raise ValueError(f"unsupported BCH code [{n},{k}]; allowed: {sorted(SUPPORTED)}")
        self.n, self.k = int(n), int(k)
        self.generator, self.t = _GENERATORS[(n, k)]
        nk = n - k
        msgs = np.arange(1 << k, dtype=np.int64)
        cw = np.array([(m << nk) | _polymod(m << nk, self.generator) for m in range(1 << k)], dtype=np.int64)
        self._codewords_int = cw
        self._codewords = _int_to_bits(cw, n)
        # Bounded-distance decoding table over every received word.
        errs = [0]
        for w in range(1, self.t + 1):
            errs.extend(_patterns(n, w))
        errs_arr = np.asarray(errs, dtype=np.int64)
        received = (cw[:, None] ^ errs_arr[None, :]).ravel()
        table_msg = np.zeros(1 << n, dtype=np.int64)
        table_ok = np.zeros(1 << n, dtype=bool)
        table_msg[received] = np.repeat(msgs, errs_arr.size)
        table_ok[received] = True
        self._table_msg = table_msg
        self._table_ok = table_ok

    def __repr__(self) -> str:
        return f"BCHCode([{self.n},{self.k}], t={self.t})"

    @property
    def rate(self) -> float:
        """Code rate k / n."""
        return self.k / self.n

    def encode(self, bits: np.ndarray) -> np.ndarray:
        """Encode information bits ``(..., k)`` (bool/0-1) into codewords ``(..., n)`` (bool)."""
        bits = np.asarray(bits)
        if bits.shape[-1] != self.k:
            raise ValueError(f"encode expects (..., {self.k}) bits, got shape {bits.shape}")
        return self._codewords[_bits_to_int(bits, self.k)]

    def decode(self, bits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Decode received words ``(..., n)`` -> (information bits ``(..., k)`` bool, ok ``(...)`` bool).

        ``ok`` is False when the word is more than ``t`` errors from every codeword (detected failure);
        the returned bits are then the received systematic bits unchanged.
        """
        bits = np.asarray(bits)
        if bits.shape[-1] != self.n:
            raise ValueError(f"decode expects (..., {self.n}) bits, got shape {bits.shape}")
        idx = _bits_to_int(bits, self.n)
        ok = self._table_ok[idx]
        msg = np.where(ok, self._table_msg[idx], idx >> (self.n - self.k))
        return _int_to_bits(msg, self.k), ok

    def encode_stream(self, info: np.ndarray) -> np.ndarray:
        """Zero-pad info bits ``(..., L)`` to a multiple of k and encode: ``(..., ceil(L/k) * n)``."""
        info = np.asarray(info, dtype=bool)
        nb = max(1, -(-info.shape[-1] // self.k))
        pad = np.zeros(info.shape[:-1] + (nb * self.k - info.shape[-1],), dtype=bool)
        blocks = np.concatenate([info, pad], axis=-1).reshape(info.shape[:-1] + (nb, self.k))
        return self.encode(blocks).reshape(info.shape[:-1] + (nb * self.n,))

    def decode_stream(self, bits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Decode ``(..., B*n)`` -> (info ``(..., B*k)``, all blocks ok ``(...)``)."""
        bits = np.asarray(bits, dtype=bool)
        nb = bits.shape[-1] // self.n
        msg, ok = self.decode(bits[..., : nb * self.n].reshape(bits.shape[:-1] + (nb, self.n)))
        return msg.reshape(bits.shape[:-1] + (nb * self.k,)), ok.all(axis=-1)

    def blocks_for(self, info_bits: int) -> int:
        """Number of n-bit blocks needed to carry ``info_bits`` information bits."""
        return max(1, -(-int(info_bits) // self.k))


def _patterns(n: int, w: int) -> list[int]:
    from itertools import combinations

    return [sum(1 << i for i in c) for c in combinations(range(n), w)]


@lru_cache(maxsize=None)
def code(n: int, k: int) -> BCHCode:
    """Return the (cached) BCH code [n, k]; supported: [15,15], [15,11], [15,7], [15,5], [15,1]."""
    return BCHCode(int(n), int(k))


def error_free_probability(p_e: float | np.ndarray, n: int, t: int) -> float | np.ndarray:
    """Probability that an n-bit block has at most t bit errors, independent errors of probability
    ``p_e`` [T20 Eq. (34)]: ``P_f = sum_{i<=t} C(n,i) p_e^i (1-p_e)^(n-i)``."""
    p = np.asarray(p_e, dtype=float)
    out = sum(comb(n, i) * p**i * (1.0 - p) ** (n - i) for i in range(int(t) + 1))
    return float(out) if np.ndim(out) == 0 else out
