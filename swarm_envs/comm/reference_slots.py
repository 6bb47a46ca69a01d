"""The numpy reference of SwarmCom's slot loop (``Network(backend="numpy")``): the vectorised loop over the bit
slots of a step that the compiled :func:`swarm_envs.comm.kernels.slot_loop` must equal (tests/comm/test_network_kernel.py).
Each function takes the :class:`swarm_envs.comm.network.Network` (``net``) whose state it reads and updates
exactly as the kernel does."""

from __future__ import annotations

from typing import Any

import numpy as np

from swarm_envs.comm.channel import detector_response
from swarm_envs.comm.protocol import RECV, bits_to_uint, concat_padded

__all__ = ["link_tables_numpy", "slots_numpy"]


def _ranges(start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Concatenate ``arange(start[i], stop[i])`` for all i (vectorised)."""
    counts = stop - start
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    offs = np.repeat(start - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
    return offs + np.arange(total)


def link_tables_numpy(net: Any, rx: np.ndarray, tx: np.ndarray, gains: np.ndarray) -> tuple:
    """The step's link tables as the kernel's :func:`swarm_envs.comm.kernels.link_tables` builds them:
    (tx_ptr, rx, tx, G, flat, sig_ptr, sig_rx); all emitters on, summed from 0.0 in emitter order, links
    grouped by transmitter."""
    n, nd, a = net.n, net.n_det, net.adc_model
    acc = np.zeros(gains.shape[:2])
    for e in range(gains.shape[-1]):
        acc += gains[..., e]
    G = a.intensity_scale * acc  # (P, nd)
    order = np.argsort(tx, kind="stable")
    rx, tx, G = rx[order], tx[order], G[order]
    tx_ptr = np.searchsorted(tx, np.arange(n + 1))
    flat = (rx[:, None] * nd + np.arange(nd)[None, :]).ravel()
    strength = G.max(axis=1) if G.size else np.zeros(0)
    significant = strength * (net.ambient[rx] - a.m_min) > net.m_tr
    sig_rx = rx[significant]
    sig_ptr = np.searchsorted(tx[significant], np.arange(n + 1))
    return tx_ptr, rx, tx, G, flat, sig_ptr, sig_rx


def slots_numpy(net: Any, S, draws, tx_ptr, rx, tx, G, flat, sig_ptr, sig_rx) -> list[dict[str, np.ndarray]]:
    """The vectorised numpy slot loop (the reference of the compiled kernel)."""
    n, nd = net.n, net.n_det
    a = net.adc_model
    noise = draws.noise  # empty: an ADC without noise
    span = (net.ambient - a.m_min)[:, None]
    deliveries: list[dict[str, np.ndarray]] = []
    first_check = net.fmt.first_check_slots
    # per link: the receiver's detectors that its light reaches with at least m_tr counts (bit d = detector d)
    lit_bits = ((G * (net.ambient[rx] - a.m_min)[:, None] > net.m_tr).astype(np.int64) << np.arange(nd, dtype=np.int64)).sum(1) if G.size else np.zeros(0, np.int64)
    for s in range(S):
        n_m = noise[s] if noise.size else 0.0  # this slot's ADC noise
        # 1. CSMA
        pending = (net.q_count > 0) & ~net.sending
        if pending.any():
            busy = (net.det.state == RECV) | net.det.last_s1
            go, defer = net.csma.decide(pending, busy, draws.backoff[:, s])
            if defer.size:
                net._count("deferrals", defer)
            if go.size:
                _start_tx(net, go)
        # 2. emission
        snd = np.flatnonzero(net.sending)
        bit = net.cur_bits[snd, net.cur_pos[snd]] if snd.size else np.zeros(0, bool)
        on = snd[bit]
        foreign = _foreign_light(net, on, tx_ptr, rx, tx, lit_bits)
        # 3. intensity (superposition over emitting transmitters)
        if net.response_kt > 0:  # detector response across slots (channel.detector_response)
            if on.size:
                li = _ranges(tx_ptr[on], tx_ptr[on + 1])
                ysum = np.bincount(flat.reshape(-1, nd)[li].ravel(), weights=G[li].ravel(), minlength=n * nd).reshape(n, nd)
            else:
                ysum = np.zeros((n, nd))
            if net.intensity_sigma > 0:
                ysum = ysum + draws.intensity_noise[s]
            yt = np.clip(ysum, 0.0, 1.0)
            v0 = net.rx_level
            v = detector_response(v0, yt, 1.0 / net.bitrate, a.response_c, a.response_bias)
            net.rx_level = v
            m = np.floor(span * (1.0 - v) + a.m_min + n_m)
        elif on.size:
            li = _ranges(tx_ptr[on], tx_ptr[on + 1])
            ysum = np.bincount(flat.reshape(-1, nd)[li].ravel(), weights=G[li].ravel(), minlength=n * nd).reshape(n, nd)
            if net.intensity_sigma > 0:
                ysum = ysum + draws.intensity_noise[s]
            y = np.minimum(ysum, 1.0)
            m = np.floor(span * (1.0 - y) + a.m_min + n_m)
        else:
            y = None
            if net.intensity_sigma > 0:
                yy = np.minimum(draws.intensity_noise[s], 1.0)
                m = np.floor(span * (1.0 - yy) + a.m_min + n_m)
            else:
                m = np.floor(span + a.m_min + n_m)
        np.clip(m, 0, a.m_sup, out=m)
        # 4./5. detectors
        listen = ~net.sending
        ev = net.det.sample(m, listen, first_check, net.slot)
        if ev["deaf"].size:
            net.det.finish(ev["deaf"])
        started, got = ev["started"], ev["got_bit"]
        if started.size:
            net._count("rx_starts", values=started.size)
            _truth_on_start(net, started, on, tx_ptr, tx, rx, G)
        if got.size:
            if net.det.buf.shape[1] > net.gt_buf.shape[1]:
                net._ensure_frame_capacity(net.det.buf.shape[1])
            _truth_bits(net, got)
            _interference(net, got, foreign)
            if snd.size:
                sl = _ranges(sig_ptr[snd], sig_ptr[snd + 1])
                if sl.size:
                    cnt = np.bincount(sig_rx[sl], minlength=n)
                    net.collided[got] |= cnt[got] >= 2
        # advance transmitters
        if snd.size:
            net.cur_pos[snd] += 1
            fin = snd[net.cur_pos[snd] >= net.cur_slots[snd]]
            if fin.size:
                net.sending[fin] = False
                net._count("tx_completed", values=fin.size)
                net.csma.arm(fin[net.q_count[fin] > 0], draws.backoff[:, s])  # fresh access delay (fairness)
        if ev["check"].size:
            d = _check_points(net, ev["check"])
            if d is not None:
                deliveries.append(d)
        net.slot += 1
    return deliveries


def _start_tx(net, go: np.ndarray) -> None:
    h = net.q_head[go]
    F = net.q_bits.shape[2]
    net.cur_bits[go, :F] = net.q_bits[go, h, :]
    net.cur_slots[go] = net.q_slots[go, h]
    net.cur_pos[go] = 0
    net.cur_id[go] += 1  # a robot's frames are numbered one after the other (slot_loop)
    net.sending[go] = True
    net.q_head[go] = (h + 1) % net.Q
    net.q_count[go] -= 1
    # a robot that was receiving drops its frame (half duplex); CSMA normally prevents this
    recv = go[net.det.state[go] == RECV]
    if recv.size:
        net.det.finish(recv)
    net._count("tx_started", go)


def _foreign_light(net, on: np.ndarray, tx_ptr, rx, tx, lit_bits) -> np.ndarray:
    """(N,) per robot receiving a frame: bitmask of its detectors lit in this slot by robots ``on``
    (emitting) other than the frame's transmitter (``gt_tx``)."""
    out = np.zeros(net.n, dtype=np.int64)
    if on.size:
        li = _ranges(tx_ptr[on], tx_ptr[on + 1])
        r = rx[li]
        f = (net.det.state[r] == RECV) & (tx[li] != net.gt_tx[r])
        np.bitwise_or.at(out, r[f], lit_bits[li[f]])
    return out


def _interference(net, got: np.ndarray, foreign: np.ndarray) -> None:
    """Deliveries.interference: foreign light of this slot counts at robots ``got`` (that stored a bit)
    whose frame's transmitter is dark in this slot."""
    t = net.gt_tx[got]
    ts = np.maximum(t, 0)
    on = (t >= 0) & net.sending[ts] & net.cur_bits[ts, np.minimum(net.cur_pos[ts], net.cur_bits.shape[1] - 1)]
    dark = got[~on]
    net.rx_foreign[dark] |= foreign[dark]


def _truth_on_start(net, started, on, tx_ptr, tx, rx, G) -> None:
    """Ground truth: the strongest transmitter emitting s1 at each robot that just detected a start."""
    net.rx_foreign[started] = 0
    net.gt_tx[started] = -1
    net.gt_id[started] = -1
    net.collided[started] = False
    if on.size:
        li = _ranges(tx_ptr[on], tx_ptr[on + 1])
        is_started = np.zeros(net.n, dtype=bool)
        is_started[started] = True
        li = li[is_started[rx[li]]]
        r, t, st = rx[li], tx[li], G[li].max(axis=1)
        o = np.lexsort((-st, r))
        r, t, st = r[o], t[o], st[o]
        firsts = np.r_[True, r[1:] != r[:-1]] if r.size else np.zeros(0, dtype=bool)
        r, t, st = r[firsts], t[firsts], st[firsts]
        sig = st * (net.ambient[r] - net.adc_model.m_min) > 0.5  # at least half a count of light
        best = np.full(net.n, -1, dtype=np.int64)
        best[r[sig]] = t[sig]
        net.gt_tx[started] = best[started]
        ok = net.gt_tx[started] >= 0
        srt = started[ok]
        tt = net.gt_tx[srt]
        # aligned only if the transmitter is emitting its own start symbol right now
        aligned = net.cur_pos[tt] == 0
        net.gt_id[srt[aligned]] = net.cur_id[tt[aligned]]
    nfalse = int((net.gt_tx[started] < 0).sum())
    if nfalse:
        net._count("rx_false_starts", values=nfalse)


def _truth_bits(net, got: np.ndarray) -> None:
    k = net.det.nbits[got] - 1
    t = net.gt_tx[got]
    valid = t >= 0
    tb = np.zeros(got.size, dtype=bool)
    if valid.any():
        tv = t[valid]
        same = net.sending[tv] & (net.cur_id[tv] == net.gt_id[got[valid]])
        bits = net.cur_bits[tv, np.minimum(net.cur_pos[tv], net.cur_bits.shape[1] - 1)]
        tb[valid] = same & bits
    net.gt_buf[got, k] = tb

# ------------------------------------------------------------------ frame check points
def _check_points(net, robots: np.ndarray) -> dict[str, np.ndarray] | None:
    out = None
    det, fmt, c = net.det, net.fmt, net.code
    valid_types = net.kinds.valid_codes()
    todo = robots
    while todo.size:
        nxt = []
        ph = det.phase[todo]
        # phase 0: marker/type check
        p0 = todo[ph == 0]
        if p0.size:
            if c.k == c.n:
                info = det.buf[p0, :4]
            else:
                info, _ = c.decode(det.buf[p0, : c.n])
            good = info[:, 0].copy()
            if info.shape[1] >= 4:
                good &= valid_types[bits_to_uint(info[:, 1:4])]
            _abort(net, p0[~good])
            g = p0[good]
            det.phase[g] = 1
            det.expect[g] = fmt.header_blocks * c.n
            nxt.append(g[det.expect[g] == det.nbits[g]])
        # phase 1: header decode -> frame length
        p1 = todo[ph == 1]
        if p1.size:
            hb = fmt.header_blocks
            info, ok = c.decode_stream(det.buf[p1, : hb * c.n])
            h = fmt.parse_header(info)
            good = ok & (h["marker"] == 1) & valid_types[h["type"]] & (h["origin"] < net.copy_size) & (h["sender"] < net.copy_size)
            _abort(net, p1[~good])
            g = p1[good]
            total = fmt.n_blocks(h["length"][good]) * c.n
            det.ensure_capacity(int(total.max()) if total.size else 0)
            net._ensure_frame_capacity(int(total.max()) + 1 if total.size else 0)
            det.phase[g] = 2
            det.expect[g] = total
            nxt.append(g[det.expect[g] == det.nbits[g]])
        # phase 2: frame complete -> decode and deliver
        p2 = todo[ph == 2]
        if p2.size:
            d = _complete(net, p2)
            if d is not None:
                out = d if out is None else {k: np.concatenate([out[k], d[k]]) if k != "payload" else concat_padded([out[k], d[k]]) for k in out}
        todo = np.concatenate(nxt) if nxt else np.zeros(0, dtype=np.int64)
    return out


def _score_bits(net, robots: np.ndarray) -> None:
    """Ground-truth scoring of aligned frames at their end (delivered or aborted): raw bit errors over
    the bits received, and errors of every complete 15-bit block after BCH decoding."""
    al = robots[net.gt_id[robots] >= 0]
    if not al.size:
        return
    nb = net.det.nbits[al]
    W = int(nb.max())
    rxb, tb = net.det.buf[al, :W], net.gt_buf[al, :W]
    mask = np.arange(W)[None, :] < nb[:, None]
    err = ((rxb != tb) & mask).sum(axis=1)
    net._count("bits_checked", al, nb)
    net._count("bit_errors", al, err)
    if net.collided[al].any():
        net._count("collisions", al[net.collided[al]])
    c = net.code
    B = W // c.n
    if B:
        nblk = nb // c.n
        shape = (al.size, B, c.n)
        info, _ = c.decode(rxb[:, : B * c.n].reshape(shape))
        tinfo, _ = c.decode(tb[:, : B * c.n].reshape(shape))
        bad = (info != tinfo).any(axis=2) & (np.arange(B)[None, :] < nblk[:, None])
        net._count("blocks_checked", al, nblk)
        net._count("block_errors", al, bad.sum(axis=1))


def _abort(net, robots: np.ndarray) -> None:
    if not robots.size:
        return
    _score_bits(net, robots)
    lost = robots[net.gt_id[robots] >= 0]
    if lost.size:
        net._count("rx_lost", lost)
    net._count("rx_aborted", values=robots.size)
    net.det.finish(robots)


def _complete(net, robots: np.ndarray) -> dict[str, np.ndarray] | None:
    det, fmt, c = net.det, net.fmt, net.code
    _score_bits(net, robots)
    nbits = det.nbits[robots]
    out: dict[str, list] = {k: [] for k in ("receiver", "origin", "sender", "seq", "type", "length", "payload", "detector", "slot", "corrupt", "done_slot", "transmitter", "interference")}
    for nb in np.unique(nbits):
        R = robots[nbits == nb]
        info, ok = c.decode_stream(det.buf[R, :nb])
        h = fmt.parse_header(info)
        # ground truth comparison (aligned frames only)
        al = net.gt_id[R] >= 0
        corrupt = np.zeros(R.size, dtype=bool)
        if al.any():
            tinfo, _ = c.decode_stream(net.gt_buf[R[al], :nb])
            used = fmt.header_bits + h["length"][al]
            mask = np.arange(info.shape[1])[None, :] < used[:, None]
            corrupt[al] = ((info[al] != tinfo) & mask).any(axis=1)
        crc = fmt.crc_ok(info, h["length"]) | ~ok
        if not crc.all():
            net._count("rx_crc_failed", values=int((~crc).sum()))
            ok = ok & crc
        bad = ~ok
        if bad.any():
            net._count("rx_decode_failed", values=int(bad.sum()))
            lost = R[bad & al]
            if lost.size:
                net._count("rx_lost", lost)
        g = ok
        if not g.any():
            continue
        H = fmt.header_bits
        L = h["length"][g]
        Lmax = int(L.max()) if L.size else 0
        pay = info[g, H : H + Lmax] & (np.arange(Lmax)[None, :] < L[:, None])
        out["receiver"].append(R[g])
        out["origin"].append(h["origin"][g])
        out["sender"].append(h["sender"][g])
        out["seq"].append(h["seq"][g])
        out["type"].append(h["type"][g])
        out["length"].append(L)
        out["payload"].append(pay)
        out["detector"].append(det.best_det[R[g]])
        out["slot"].append(det.start_slot[R[g]])
        out["corrupt"].append(corrupt[g])
        out["done_slot"].append(np.full(int(g.sum()), net.slot, dtype=np.int64))
        out["transmitter"].append(net.gt_tx[R[g]])
        out["interference"].append(net.rx_foreign[R[g]])
    det.finish(robots)
    if not out["receiver"]:
        return None
    res = {k: (np.concatenate(v) if k != "payload" else concat_padded(v)) for k, v in out.items()}
    net._count("rx_decoded", values=res["receiver"].size)
    return res

# ------------------------------------------------------------------ end of step
