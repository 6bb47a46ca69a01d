"""Compiled (numba) SwarmCom bit-slot loop; :mod:`swarm_envs.comm.reference_slots` (``backend="numpy"``) is its reference.

:func:`slot_loop` runs every bit slot of one control step for all robots in one call [T20 Secs. 3, 4]:

1. CSMA: pending robots count down their access delay / backoff, sense the carrier (their detector is
   inside a frame or saw s1 in the last slot) and start or defer (deferral ``1 + draw``) [Sec. 4.4];
2. emission of the current bit of every sending robot (OOK, all emitters on for an s1);
3. superposed intensities ``y = min(1, sum gains + n_j)`` over the links of the emitting transmitters
   [Eqs. (10),(11)], the detector circuit's response across slots (e-puck; ``v`` follows ``y``,
   :func:`swarm_envs.comm.channel.detector_response`, [T20 Sec. 5.2]) and the 12-bit ADC
   ``m = floor((m_max - m_min)(1 - v) + m_min + n_m)`` clipped to ``[0, m_sup]`` [Eqs. (20)-(22)] with the
   noise drawn before the loop;
4. the detector state machine: ``min`` over the detectors, start detection ``m < m_t = m_max_est - m_tr``
   [Eqs. (30)-(33)], the dynamic threshold ``floor(|m_t + A| / 2)`` [Eq. (36)], bit storage, run-time
   ambient adaptation on idle s0 samples [Sec. 4.5], half duplex;
5. frame check points: marker/type check, header decode (BCH by table look-up: the code's decoding
   table over all 2^15 received words, the same table :class:`swarm_envs.comm.bch.BCHCode` uses), abort,
   completion with the optional CRC (8 or 16 bits) and delivery;
6. ground truth for statistics only (strongest s1 transmitter at a start, the bits it really sent,
   collisions, bit / block errors, corrupt deliveries).

Every random number the step needs is an input (:class:`swarm_envs.comm.draws.StepDraws`, drawn for all
env copies in one compiled call, each copy from its own generator): the kernel and the numpy reference
consume the same arrays and must give the same deliveries and counters (``tests/comm/test_network_kernel.py``).

The flooding dedupe and relaying run once per step in numpy (``Network._finish_step``), not per slot.
"""

from __future__ import annotations


import numpy as np

from swarm_envs._compile._numba import njit
from swarm_envs.sim._vecmath import exp_moderate

__all__ = ["COUNTERS", "PER_ROBOT", "DELIVERY_FIELDS", "link_tables", "build_frames", "slot_loop", "decode_words"]

COUNTERS = (
    "slots",
    "tx_started",  # frames put on air (originals + relays)
    "tx_completed",
    "tx_relays",  # flooding re-sends queued
    "deferrals",  # CSMA found the channel busy
    "queue_dropped",  # oldest waiting frame dropped because the queue was full
    "rx_starts",  # start symbols detected (includes noise-triggered false starts)
    "rx_false_starts",  # ... with no transmitter emitting s1 towards the robot (ground truth)
    "rx_aborted",  # frames abandoned: bad marker/type, undecodable or impossible header
    "rx_decode_failed",  # complete frames with an undecodable block or a failed CRC
    "rx_crc_failed",  # ... of which the CRC failed (crc_bits > 0)
    "rx_decoded",  # complete frames whose blocks all decode and header is valid
    "rx_delivered",  # ... passed to the application (after flooding dedupe)
    "rx_duplicates",  # flooding duplicates suppressed
    "rx_self_named",  # decoded frames naming the receiver itself as origin or sender: not delivered
    "rx_corrupt_delivered",  # delivered but header/payload differ from what was sent (ground truth)
    "rx_lost",  # aligned frames from a real transmitter that were aborted or failed to decode
    "collisions",  # received frames during which >= 2 transmitters were significant at the receiver
    "bits_checked",  # raw bits compared with the truth (aligned frames)
    "bit_errors",
    "blocks_checked",  # complete 15-bit blocks of aligned frames, decoded and compared with the truth
    "block_errors",
)
PER_ROBOT = (
    "tx_started",
    "deferrals",
    "rx_delivered",
    "rx_lost",
    "collisions",
    "bits_checked",
    "bit_errors",
    "blocks_checked",
    "block_errors",
)
#: integer columns of the kernel's delivery records
DELIVERY_FIELDS = ("receiver", "origin", "sender", "seq", "type", "length", "detector", "slot", "corrupt", "done_slot", "transmitter", "interference")

# counter indices (compile-time constants in the kernel)
_C_TX_STARTED, _C_TX_COMPLETED, _C_DEFERRALS = COUNTERS.index("tx_started"), COUNTERS.index("tx_completed"), COUNTERS.index("deferrals")
_C_RX_STARTS, _C_FALSE_STARTS, _C_ABORTED = COUNTERS.index("rx_starts"), COUNTERS.index("rx_false_starts"), COUNTERS.index("rx_aborted")
_C_DECODE_FAILED, _C_CRC_FAILED, _C_DECODED = COUNTERS.index("rx_decode_failed"), COUNTERS.index("rx_crc_failed"), COUNTERS.index("rx_decoded")
_C_LOST, _C_COLL, _C_BITS = COUNTERS.index("rx_lost"), COUNTERS.index("collisions"), COUNTERS.index("bits_checked")
_C_BIT_ERR, _C_BLOCKS, _C_BLOCK_ERR = COUNTERS.index("bit_errors"), COUNTERS.index("blocks_checked"), COUNTERS.index("block_errors")
_P_TX_STARTED, _P_DEFERRALS, _P_LOST, _P_COLL = PER_ROBOT.index("tx_started"), PER_ROBOT.index("deferrals"), PER_ROBOT.index("rx_lost"), PER_ROBOT.index("collisions")
_P_BITS, _P_BIT_ERR, _P_BLOCKS, _P_BLOCK_ERR = PER_ROBOT.index("bits_checked"), PER_ROBOT.index("bit_errors"), PER_ROBOT.index("blocks_checked"), PER_ROBOT.index("block_errors")
_IDLE, _RECV = 0, 1  # detector states (as protocol.IDLE / protocol.RECV)
#: a dark detector whose response level falls below this is set to 0 (as channel.DARK_LEVEL)
_DARK_LEVEL = 1e-6


_jit = njit(cache=True, nogil=True)
#: for loops the compiler should vectorise: numpy's error model (no ZeroDivisionError branch in the loop)
_jit_vector = njit(cache=True, nogil=True, error_model="numpy")
#: small helpers of one kernel, inlined where numba types the caller (one compile unit less each on the first run)
_jit_inline = njit(cache=True, nogil=True, inline="always")


@_jit
def link_tables(n, rx, tx, gains, scale, ambient, m_min, m_tr):
    """Links grouped by transmitter (a stable counting sort, as ``argsort(tx, kind="stable")``), with the
    all-emitters-on gain per detector ``G = scale * sum_e gains[..., e]`` (summed in emitter order) and
    the significant links (``max_d G * (ambient[rx] - m_min) > m_tr``: at least m_tr counts of light).

    Returns (tx_ptr (n+1,), rx (P,), G (P, n_det), sig_ptr (n+1,), sig_rx (Ps,)); the links of
    transmitter t are ``tx_ptr[t]:tx_ptr[t+1]`` (same for ``sig_ptr``). ``Network`` does the same in
    numpy for the reference backend. ``gains`` may also be the emitter sums (P, n_det, 1) when the IR layer
    provides them: the sum from 0.0 is then the sum itself (same G, an eighth of the memory read)."""
    P, nd, ne = gains.shape
    tx_ptr = np.empty(n + 1, np.int64)
    tx_ptr[:] = 0
    for p in range(P):
        tx_ptr[tx[p] + 1] += 1
    for t in range(n):
        tx_ptr[t + 1] += tx_ptr[t]
    nxt = tx_ptr[:n].copy()
    lrx = np.empty(P, np.int64)
    G = np.empty((P, nd), np.float64)
    sig = np.empty(P, np.bool_)
    sig[:] = False
    sig_ptr = np.empty(n + 1, np.int64)
    sig_ptr[:] = 0
    for p in range(P):
        t = tx[p]
        q = nxt[t]
        nxt[t] += 1
        r = rx[p]
        lrx[q] = r
        st = -np.inf
        for d in range(nd):
            acc = 0.0
            for e in range(ne):
                acc += gains[p, d, e]
            g = scale * acc
            G[q, d] = g
            if g > st:
                st = g
        if P > 0 and st * (ambient[r] - m_min) > m_tr:
            sig[q] = True
            sig_ptr[t + 1] += 1
    for t in range(n):
        sig_ptr[t + 1] += sig_ptr[t]
    sig_rx = np.empty(sig_ptr[n], np.int64)
    k = 0
    for q in range(P):
        if sig[q]:
            sig_rx[k] = lrx[q]
            k += 1
    return tx_ptr, lrx, G, sig_ptr, sig_rx


@_jit
def build_frames(type_code, seq, origin, sender, payload, length, header_bits, id_bits, with_sender, crc_bits, crc_table, code_n, code_k, codewords):
    """Compiled :meth:`swarm_envs.comm.protocol.FrameFormat.build` (the reference; same bits, same array
    shape): M frames from (M,) type codes, sequence numbers (mod 128), origins, senders (flooding), lengths and
    the payload bits (M, >= max length), each the start symbol then the BCH-encoded blocks of header,
    payload and optional CRC of ``crc_bits`` bits (``crc_table``: :func:`swarm_envs.comm.protocol.crc_table` of
    that width), zero beyond the frame. Returns (bits (M, 1 + B n) bool, slots (M,))."""
    M = type_code.shape[0]
    lmax = 0
    for i in range(M):
        lmax = max(lmax, length[i])
    cols = header_bits + lmax + crc_bits  # information columns of the reference
    nb = max(1, (cols + code_k - 1) // code_k)
    bits = np.empty((M, 1 + nb * code_n), np.bool_)
    bits[:] = False
    slots = np.empty(M, np.int64)
    info = np.empty(nb * code_k, np.bool_)
    info[:] = False
    for i in range(M):
        info[:] = False
        o = 0
        for f in range(5 if with_sender else 4):  # marker 1 | type 3 | length 8 | seq 7 | origin | [sender]
            if f == 0:
                v, w = (1 << 3) | (type_code[i] & 7), 4
            elif f == 1:
                v, w = length[i], 8
            elif f == 2:
                v, w = seq[i] % 128, 7
            elif f == 3:
                v, w = origin[i], id_bits
            else:
                v, w = sender[i], id_bits
            for j in range(w):
                info[o + j] = (v >> (w - 1 - j)) & 1 == 1
            o += w
        L = length[i]
        for j in range(L):
            info[o + j] = payload[i, j]
        end = header_bits + L
        if crc_bits > 0:
            c = _crc(info, end, crc_table)
            for j in range(crc_bits):
                info[end + j] = (c >> (crc_bits - 1 - j)) & 1 == 1
        nblk = (end + crc_bits + code_k - 1) // code_k
        slots[i] = 1 + nblk * code_n
        bits[i, 0] = True
        for b in range(nblk):
            cw = _word(info, b * code_k, code_k)
            for j in range(code_n):
                bits[i, 1 + b * code_n + j] = codewords[cw, j]
    return bits, slots


@_jit
def _word(bits, off, n):
    """n bits starting at ``off`` (MSB first) -> int (BCH words and header fields)."""
    w = 0
    for i in range(n):
        w = (w << 1) | (1 if bits[off + i] else 0)
    return w


@_jit
def _decode_block(word, n, k, table_msg, table_ok):
    """BCH bounded-distance decoding by table look-up (as ``BCHCode.decode``): (message int, ok)."""
    if table_ok[word]:
        return table_msg[word], True
    return word >> (n - k), False


@_jit
def _decode_stream(bits, nbits, n, k, table_msg, table_ok, info):
    """Decode the ``nbits // n`` whole blocks of ``bits`` into ``info`` (k bits per block); all ok?"""
    ok_all = True
    for b in range(nbits // n):
        msg, ok = _decode_block(_word(bits, b * n, n), n, k, table_msg, table_ok)
        ok_all = ok_all and ok
        for i in range(k):
            info[b * k + i] = (msg >> (k - 1 - i)) & 1 == 1
    return ok_all


@_jit
def decode_words(words, n, k, table_msg, table_ok):
    """Vector form of the kernel's block decoder (for tests): words (M,) -> (messages (M,), ok (M,))."""
    msg = np.empty(words.size, np.int64)
    msg[:] = 0
    ok = np.empty(words.size, np.bool_)
    ok[:] = False
    for i in range(words.size):
        msg[i], ok[i] = _decode_block(words[i], n, k, table_msg, table_ok)
    return msg, ok


@_jit
def _crc(info, end, crc_table):
    """CRC of the first ``end`` bits (as ``protocol.crc``: XOR of ``crc_table[j]`` = x^(j+w) mod g over the set
    bits, j bits before the end)."""
    c = 0
    for i in range(end):
        if info[i]:
            c ^= crc_table[end - 1 - i]
    return c


@_jit
def _score(r, nbits, buf, gt_buf, gt_id, collided, n, k, table_msg, table_ok, counts, per_robot):
    """Ground-truth scoring of an aligned frame at its end (as ``Network._score_bits``)."""
    if gt_id[r] < 0:
        return
    nb = nbits[r]
    err = 0
    for i in range(nb):
        if buf[r, i] != gt_buf[r, i]:
            err += 1
    counts[_C_BITS] += nb
    per_robot[_P_BITS, r] += nb
    counts[_C_BIT_ERR] += err
    per_robot[_P_BIT_ERR, r] += err
    if collided[r]:
        counts[_C_COLL] += 1
        per_robot[_P_COLL, r] += 1
    nblk = nb // n
    bad = 0
    for b in range(nblk):
        m1, _ = _decode_block(_word(buf[r], b * n, n), n, k, table_msg, table_ok)
        m2, _ = _decode_block(_word(gt_buf[r], b * n, n), n, k, table_msg, table_ok)
        if m1 != m2:
            bad += 1
    counts[_C_BLOCKS] += nblk
    per_robot[_P_BLOCKS, r] += nblk
    counts[_C_BLOCK_ERR] += bad
    per_robot[_P_BLOCK_ERR, r] += bad


@_jit
def _abort(r, state, nbits, buf, gt_buf, gt_id, collided, n, k, table_msg, table_ok, counts, per_robot):
    _score(r, nbits, buf, gt_buf, gt_id, collided, n, k, table_msg, table_ok, counts, per_robot)
    if gt_id[r] >= 0:
        counts[_C_LOST] += 1
        per_robot[_P_LOST, r] += 1
    counts[_C_ABORTED] += 1
    state[r] = _IDLE
    nbits[r] = 0


@_jit_vector
def _respond(ysum: np.ndarray, inoise: np.ndarray, level: np.ndarray, b: float, kt: float) -> None:
    """One bit slot of the detector response (:func:`swarm_envs.comm.channel.detector_response`, the same
    arithmetic) for every detector, flat over (robot, detector): the light ``ysum`` plus the intensity
    noise ``inoise`` (same shape, or empty for none) clipped to [0, 1], the levels ``level`` updated in place;
    ``b`` the response bias, ``kt`` = slot duration / c > 0. Branch-free, with the library's own ``exp``
    (:func:`swarm_envs.sim._vecmath.exp_moderate`), so the compiler vectorises the loop. A dark detector at
    level 0 stays at 0 (its update, ``b b / b - b``, is within rounding of 0 and below DARK_LEVEL)."""
    noisy = inoise.shape[0] > 0
    for k in range(ysum.shape[0]):
        y = ysum[k] + inoise[k] if noisy else ysum[k]
        y = min(max(y, 0.0), 1.0)
        Y = y + b
        u0 = level[k] + b
        v = Y * u0 / (u0 + (Y - u0) * exp_moderate(-Y * kt)) - b
        level[k] = 0.0 if (y == 0.0 and v < _DARK_LEVEL) else v


@_jit
def slot_loop(
    S, slot0, n_det, m_min, m_sup, m_tr, alpha, first_check,
    tx_ptr, lrx, G, sig_ptr, sig_rx, ambient, rx_v, resp_kt, resp_b,
    noise, inoise, pool,
    q_bits, q_slots, q_head, q_count, cur_bits, cur_slots, cur_pos, cur_id, sending, backoff,
    state, m_max_est, thr, nbits, expect, phase, buf, best_m, best_det, last_s1, start_slot,
    gt_tx, gt_id, gt_buf, collided,
    code_n, code_k, table_msg, table_ok, header_blocks, header_bits, id_bits, with_sender, crc_bits, crc_table, valid_types,
    n_ids, counts, per_robot, d_int, d_pay, rx_foreign, r0, r1,
):  # fmt: skip
    """All S bit slots of one control step for the robots ``r0:r1`` (module docstring), whole env copies:
    no link leaves a copy, so the robots of other copies are neither read nor written, and disjoint ranges
    may run at the same time on threads. State arrays are updated in place; a robot's frames are numbered
    in ``cur_id`` (one more than its last frame's; the ground truth matches a receiver's frame with its
    transmitter's by that number). ``counts`` gets the range's counters. Deliveries are written to
    ``d_int`` (D, 12) with columns :data:`DELIVERY_FIELDS` and ``d_pay`` (D, >= 255) bool, by slot and then
    by receiver; returns the number written. Header ids are a copy's own robot numbers, valid below
    ``n_ids`` (the robots per env copy). ``rx_foreign`` (N,) int64: per
    receiving robot, the detectors (bit d) that light of a robot other than its frame's transmitter reached
    (``G * (ambient - m_min) > m_tr``) in a slot where that transmitter was dark; reset at a start symbol,
    reported as the delivery's ``interference`` column.

    Detector response: with ``resp_kt = slot duration / c > 0`` every detector's level ``rx_v`` (N, n_det)
    follows the light through :func:`swarm_envs.comm.channel.detector_response` (same arithmetic) in every
    slot, also while its robot sends, and the ADC samples the level; ``resp_kt = 0``: instantaneous.

    ADC noise ``noise`` (S, N, n_det), empty for an ADC without noise (n_m = 0): then an instantaneous detector
    bank that no light reached in a slot (no intensity noise) reads the same sample on every detector,
    computed once."""
    n = sending.shape[0]
    Q = q_bits.shape[1]
    F = cur_bits.shape[1]
    Fq = q_bits.shape[2]
    W = buf.shape[1]
    has_inoise = inoise.shape[0] > 0
    filt = resp_kt > 0.0
    ysum = np.empty((n, n_det), np.float64)  # rows r0:r1 used
    ysum[:] = 0.0
    ysum_flat = ysum.reshape(-1)[r0 * n_det : r1 * n_det]  # the range's (robot, detector) rows, for _respond
    level_flat = rx_v.reshape(-1)[r0 * n_det : r1 * n_det]
    best_str = np.empty(n, np.float64)
    best_str[:] = -np.inf
    best_tx = np.empty(n, np.int64)
    best_tx[:] = -1
    sigcnt = np.empty(n, np.int64)
    sigcnt[:] = 0
    fmask = np.empty(n, np.int64)  # this slot's foreign light per receiving robot (bit d = detector d)
    fmask[:] = 0
    check = np.empty(n, np.bool_)
    check[:] = False
    lit = np.empty(n, np.bool_)  # this slot's light reached the robot
    lit[:] = False
    has_noise = noise.shape[0] > 0
    same_dark_sample = not (filt or has_inoise or has_noise)  # a dark robot's detectors all read the same
    info = np.empty(W, np.bool_)
    info[:] = False
    tinfo = np.empty(W, np.bool_)
    tinfo[:] = False
    dirty = False
    nd_out = 0
    for s in range(S):
        slot = slot0 + s
        # 1. CSMA [Sec. 4.4]
        for r in range(r0, r1):
            if q_count[r] > 0 and not sending[r]:
                if backoff[r] > 0:
                    backoff[r] -= 1
                elif state[r] == _RECV or last_s1[r]:
                    counts[_C_DEFERRALS] += 1
                    per_robot[_P_DEFERRALS, r] += 1
                    backoff[r] = 1 + pool[r, s]
                else:  # start sending the head of the queue
                    h = q_head[r]
                    for i in range(min(q_slots[r, h], Fq)):  # bits beyond the frame are never read
                        cur_bits[r, i] = q_bits[r, h, i]
                    cur_slots[r] = q_slots[r, h]
                    cur_pos[r] = 0
                    cur_id[r] += 1
                    sending[r] = True
                    q_head[r] = (h + 1) % Q
                    q_count[r] -= 1
                    if state[r] == _RECV:  # half duplex (CSMA normally prevents this)
                        state[r] = _IDLE
                        nbits[r] = 0
                    counts[_C_TX_STARTED] += 1
                    per_robot[_P_TX_STARTED, r] += 1
        # 2./3. emission and superposed intensities [Eqs. (10),(11)]
        if dirty:  # the range's rows of this slot's light (one pass over memory each)
            ysum[r0:r1] = 0.0
            best_str[r0:r1] = -np.inf
            best_tx[r0:r1] = -1
            sigcnt[r0:r1] = 0
            fmask[r0:r1] = 0
            lit[r0:r1] = False
            dirty = False
        for t in range(r0, r1):
            if not sending[t]:
                continue
            dirty = True
            for j in range(sig_ptr[t], sig_ptr[t + 1]):
                sigcnt[sig_rx[j]] += 1
            if cur_bits[t, cur_pos[t]]:
                for li in range(tx_ptr[t], tx_ptr[t + 1]):
                    r = lrx[li]
                    lit[r] = True
                    st = -np.inf
                    foreign = state[r] == _RECV and gt_tx[r] != t
                    for d in range(n_det):
                        g = G[li, d]
                        ysum[r, d] += g
                        if g > st:
                            st = g
                        if foreign and g * (ambient[r] - m_min) > m_tr:
                            fmask[r] |= np.int64(1) << d
                    if st > best_str[r]:
                        best_str[r] = st
                        best_tx[r] = t
        # detector response across slots (channel.detector_response), every robot
        if filt:
            _respond(ysum_flat, inoise[s].reshape(-1)[r0 * n_det : r1 * n_det] if has_inoise else inoise.reshape(-1), level_flat, resp_b, resp_kt)
        # 4./5. ADC [Eqs. (20)-(22)] and detectors [Sec. 4.2, Eq. (36), Sec. 4.5]
        for r in range(r0, r1):
            listen = not sending[r]
            in_frame = state[r] == _RECV
            if not listen:
                last_s1[r] = False
                if in_frame:  # a transmitting robot drops what it was receiving
                    state[r] = _IDLE
                    nbits[r] = 0
                continue
            span = ambient[r] - m_min
            mv = np.inf
            md = 0
            msum = 0.0
            if same_dark_sample and not lit[r]:  # no light, no noise: the else branch's sample (y = 0, n_m = 0), once
                m = np.floor(span * (1.0 - 0.0) + m_min + 0.0)
                if m < 0.0:
                    m = 0.0
                elif m > m_sup:
                    m = m_sup
                mv = m
                for d in range(n_det):
                    msum += m
            else:
                for d in range(n_det):
                    if filt:
                        y = rx_v[r, d]
                    else:
                        y = ysum[r, d]
                        if has_inoise:
                            y = y + inoise[s, r, d]
                        if y > 1.0:
                            y = 1.0
                    n_m = np.float64(noise[s, r, d]) if has_noise else 0.0
                    m = np.floor(span * (1.0 - y) + m_min + n_m)
                    if m < 0.0:
                        m = 0.0
                    elif m > m_sup:
                        m = m_sup
                    msum += m
                    if m < mv:
                        mv = m
                        md = d
            m_t = m_max_est[r] - m_tr
            s1 = mv < (thr[r] if in_frame else m_t)
            last_s1[r] = s1
            if not in_frame:
                if s1:  # start symbol
                    state[r] = _RECV
                    thr[r] = np.floor(abs(m_t + mv) / 2.0)  # Eq. (36)
                    nbits[r] = 0
                    expect[r] = first_check
                    phase[r] = 0
                    best_m[r] = np.int64(mv)
                    best_det[r] = md
                    start_slot[r] = slot
                    counts[_C_RX_STARTS] += 1
                    # ground truth: strongest transmitter emitting s1 towards r
                    rx_foreign[r] = 0
                    gt_tx[r] = -1
                    gt_id[r] = -1
                    collided[r] = False
                    t = best_tx[r]
                    if t >= 0 and best_str[r] * (ambient[r] - m_min) > 0.5:
                        gt_tx[r] = t
                        if cur_pos[t] == 0:
                            gt_id[r] = cur_id[t]
                    else:
                        counts[_C_FALSE_STARTS] += 1
                else:  # run-time ambient adaptation on idle s0 samples
                    m_max_est[r] = m_max_est[r] + alpha * (msum / n_det - m_max_est[r])
            else:  # store a bit
                kb = nbits[r]
                buf[r, kb] = s1
                nbits[r] = kb + 1
                if mv < best_m[r]:
                    best_m[r] = np.int64(mv)
                    best_det[r] = md
                t = gt_tx[r]
                tb = False
                if t >= 0:
                    if sending[t] and cur_id[t] == gt_id[r]:
                        tb = cur_bits[t, min(cur_pos[t], F - 1)]
                gt_buf[r, kb] = tb
                if not (t >= 0 and sending[t] and cur_bits[t, min(cur_pos[t], F - 1)]):  # the frame's light is off
                    rx_foreign[r] |= fmask[r]
                if sigcnt[r] >= 2:
                    collided[r] = True
                if nbits[r] == expect[r]:
                    check[r] = True
        # advance transmitters
        for t in range(r0, r1):
            if sending[t]:
                cur_pos[t] += 1
                if cur_pos[t] >= cur_slots[t]:
                    sending[t] = False
                    counts[_C_TX_COMPLETED] += 1
                    if q_count[t] > 0:
                        backoff[t] = pool[t, s]  # fresh access delay (fairness)
        # 5. frame check points
        for r in range(r0, r1):
            if not check[r]:
                continue
            check[r] = False
            while True:
                ph = phase[r]
                if ph == 0:  # marker / type
                    if code_k == code_n:
                        for i in range(4):
                            info[i] = buf[r, i]
                        good = info[0] and valid_types[_word(info, 1, 3)]
                    else:
                        _decode_stream(buf[r], code_n, code_n, code_k, table_msg, table_ok, info)
                        good = info[0]
                        if code_k >= 4:
                            good = good and valid_types[_word(info, 1, 3)]
                    if not good:
                        _abort(r, state, nbits, buf, gt_buf, gt_id, collided, code_n, code_k, table_msg, table_ok, counts, per_robot)
                        break
                    phase[r] = 1
                    expect[r] = header_blocks * code_n
                    if expect[r] != nbits[r]:
                        break
                elif ph == 1:  # header -> frame length
                    ok = _decode_stream(buf[r], header_blocks * code_n, code_n, code_k, table_msg, table_ok, info)
                    typ = _word(info, 1, 3)
                    length = _word(info, 4, 8)
                    origin = _word(info, 19, id_bits)
                    sender = _word(info, 19 + id_bits, id_bits) if with_sender else origin
                    good = ok and info[0] and valid_types[typ] and origin < n_ids and sender < n_ids
                    if not good:
                        _abort(r, state, nbits, buf, gt_buf, gt_id, collided, code_n, code_k, table_msg, table_ok, counts, per_robot)
                        break
                    phase[r] = 2
                    expect[r] = ((header_bits + length + crc_bits + code_k - 1) // code_k) * code_n
                    if expect[r] != nbits[r]:
                        break
                else:  # complete: decode, check, deliver
                    _score(r, nbits, buf, gt_buf, gt_id, collided, code_n, code_k, table_msg, table_ok, counts, per_robot)
                    nb = nbits[r]
                    ok = _decode_stream(buf[r], nb, code_n, code_k, table_msg, table_ok, info)
                    width = (nb // code_n) * code_k
                    typ = _word(info, 1, 3)
                    length = _word(info, 4, 8)
                    seq = _word(info, 12, 7)
                    origin = _word(info, 19, id_bits)
                    sender = _word(info, 19 + id_bits, id_bits) if with_sender else origin
                    aligned = gt_id[r] >= 0
                    corrupt = False
                    if aligned:
                        _decode_stream(gt_buf[r], nb, code_n, code_k, table_msg, table_ok, tinfo)
                        for i in range(min(header_bits + length, width)):
                            if info[i] != tinfo[i]:
                                corrupt = True
                                break
                    if crc_bits > 0 and ok:
                        end = header_bits + length
                        got = 0
                        for i in range(crc_bits):
                            got = (got << 1) | (1 if info[min(end + i, width - 1)] else 0)
                        if got != _crc(info, end, crc_table):
                            counts[_C_CRC_FAILED] += 1
                            ok = False
                    if not ok:
                        counts[_C_DECODE_FAILED] += 1
                        if aligned:
                            counts[_C_LOST] += 1
                            per_robot[_P_LOST, r] += 1
                    else:
                        if nd_out >= d_int.shape[0]:
                            raise RuntimeError("delivery buffer too small")
                        d_int[nd_out, 0] = r
                        d_int[nd_out, 1] = origin
                        d_int[nd_out, 2] = sender
                        d_int[nd_out, 3] = seq
                        d_int[nd_out, 4] = typ
                        d_int[nd_out, 5] = length
                        d_int[nd_out, 6] = best_det[r]
                        d_int[nd_out, 7] = start_slot[r]
                        d_int[nd_out, 8] = 1 if corrupt else 0
                        d_int[nd_out, 9] = slot
                        d_int[nd_out, 10] = gt_tx[r]
                        d_int[nd_out, 11] = rx_foreign[r]
                        for i in range(length):
                            d_pay[nd_out, i] = info[header_bits + i]
                        nd_out += 1
                        counts[_C_DECODED] += 1
                    state[r] = _IDLE
                    nbits[r] = 0
                    break
    return nd_out
