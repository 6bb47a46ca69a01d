"""Droplet range & bearing from the brightness matrix [F14], and its per-step sensor (docs/design.md#range-and-bearing).

Pipeline for one (receiver RX, transmitter TX) pair:

1. :func:`swarm_envs.sensing.range_bearing_model.brightness` -- noiseless full-power brightness matrix Lambda (n_d x n_e; rows = RX sensors i,
   cols = TX emitters j), ``lambda_ij = S(alpha_ij) E(beta_ij) A(r_ij)`` [F14 Eq. (4)], from the shared
   IR layer (:func:`swarm_envs.ir.layer.pair_gains`).
2. :func:`swarm_envs.sensing.range_bearing_model.measure` -- what the RX's ADC reads: ``clip(round(p lambda + n), 0, adc_max)``, n ~ N(0, sigma^2)
   i.i.d. per entry, with power selection (docs/design.md#range-and-bearing): if the full-power reading saturates, the TX fires
   again at the largest power factor p of :data:`swarm_envs.sensing.range_bearing_model.POWER_LADDER` whose reading does not saturate.
3. :func:`swarm_envs.sensing.range_bearing_model.estimate` -- range R, bearing theta and heading phi from Lambda / p [F14 Sec. II, Eqs. (5)-(18)],
   generic over the number and layout of channels (Droplet 6x6, e-puck 8x8).

:class:`RangeBearingSensor` runs this each 0.1 s control step for all pairs of an
:class:`~swarm_envs.ir.links.IRLinks`, with the firing schedule of docs/design.md#range-and-bearing and reading ages.

Noise level (``sigma``). [F14 Sec. IV] calls the calibrated error "approximately Gaussian with mu = 0";
the sigma is lost in the PDF. We use sigma = 2 ADC counts for the Droplet: it is "a few counts", it
puts the firmware's 7-count no-reading floor at 3.5 sigma (pure noise passes it in ~2 % of 6x6 matrices,
the paper's rare "spurious data point"), and with it the validation sweep (``python -m swarm_envs.validate range-bearing``) meets the
paper's claims of [F14 Sec. V] with margin (range |mean| + std well below one diameter at every distance,
bearing error a few degrees, heading error larger and 60-degree periodic). The sweep also reports
sigma = 0, 1, 4, 8 counts so the sensitivity to this choice is visible. For the e-puck the ADC noise of
[T20] (variance 2.5 counts^2) is used.

Hardware error. [F14 Sec. V] finds its bearing error "uniformly below 0" and attributes it to an
asymmetry of the real sensors (Fig. 4a) that its model does not include, and its conclusion (Sec. VI)
notes that sensors and emitters differ from robot to robot; neither gives a magnitude. In the env each
robot's emitter powers, detector gains and axis angles are drawn at reset with assumed spreads
(:mod:`swarm_envs.ir.hardware`, docs/design.md#hardware-variation) and enter the links' gains, so the
matrices measured here are those of the robots' own channels while :func:`swarm_envs.sensing.range_bearing_model.estimate` keeps the nominal
calibration; the brightness noise above comes on top.

Collisions and the decoded transmitter (docs/design.md#range-and-bearing). A measurement starts with a message: [F14 Sec. II]
"RX ... requests R&B information from a specific robot TX"; in the Droplet firmware the TX broadcasts an
``rnb_r`` command (a UART frame on the 38 kHz carrier whose header holds the 16-bit sender id and a
CRC-16) and, a fixed delay after it, lights emitter 0..5 in turn for fixed times; a receiver that decodes
the command samples its 6 sensors in the same fixed slots [F14 Sec. II: "predetermined duration and
sequence"]. Two transmitters that fire in the same control step (any two robots whose timers expire
in that step, docs/design.md#range-and-bearing) are modelled with *aligned slots*: the step is one slot of the schedule, both
commands start at its beginning, so bit k of both frames coincide and emitter j of both lands in column j
of the receiver's matrix. Light adds. So, at a receiver u:

- **id message** (:func:`swarm_envs.sensing.range_bearing_frames.decode_ids`): each firing TX w sends ``frame(w)`` = a start bit (1), its 16 id
  bits (LSB first; a copy's own robot number) and the 16 bits of ``CRC-16(id)`` (avr-libc
  ``_crc16_update``, polynomial 0xA001, over the two id bytes; the init 0xFFFF is our choice: firmware
  versions differ on whether the header CRC covers the sender id), on-off keyed with all its
  emitters on. Detector i of u sees, in bit slot k, ``sum_w frame_k(w) sum_j lambda_ij(w)`` (a bit of
  colliding frames is the OR of their bits), read through the same ADC as the matrix (noise sigma,
  rounding, clipping) and taken as 1 at or above the firmware's 7-count floor (``no_reading_floor``;
  the demodulating receiver's own threshold is not published, so the message is heard where the R&B
  light is above the floor). Each detector is a separate UART channel (the Droplet has one per
  direction): a channel *hears* a frame when its start bit is 1, and the frame *checks* when its CRC
  bits equal the CRC of its id bits (``id_check=True``; ``False`` models a firmware whose CRC covers
  only the payload, identical for every ``rnb_r``, so the sender id is unchecked).
- **rule**: the receiver measures only if at least one channel's frame checks and all checking channels
  name the same id; it attributes the reading to that *decoded* id. Nothing checks: no request heard,
  no reading. Checking channels that disagree (two senders heard in one slot): the light cannot be
  attributed, the receiver discards the slot. A decoded id that is not a robot of the receiver's own
  env copy, or is the receiver itself, is rejected. OR-ed ids almost never pass a CRC, so two colliding
  TXs that both reach a channel are rejected; a TX too weak to corrupt any channel's frame still adds
  its light to the matrix (a *corrupted* reading attributed to the stronger one).
- **matrix**: the receiver's matrix is the sum of all firing TXs' noiseless brightness matrices it
  sees, then power selection, ADC noise and clipping (:func:`swarm_envs.sensing.range_bearing_model.measure`) and :func:`swarm_envs.sensing.range_bearing_model.estimate`. With one
  firing TX in view this is exactly the single-pair reading (bit for bit: the id noise comes from its
  own child stream).

The true transmitter (the one contributing the brightest entry) and the number of overlapping firings
are kept as ground truth (``RangeBearingReadings.true_tx``, ``.n_overlap``) for infos and metrics only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from swarm_envs.sim.copies import CopyRandom, CopyStream
from swarm_envs.ir.hardware import Hardware
from swarm_envs.ir.layer import pair_gains
from swarm_envs.ir.links import IRLinks
from swarm_envs.sim.platforms import Platform, get_platform
from swarm_envs.sensing.range_bearing_kernels import FRAME_WORDS_MAX_GROUP, firing_sums, group_brightest, merge_readings, priority_independent_set, priority_independent_set_sorted
from swarm_envs.sensing.numpy_sums import PAIRWISE_INIT, segment_sum, sum_last
from swarm_envs.sensing.range_bearing_frames import ID_BITS, decode_ids, id_frames
from swarm_envs.sensing.range_bearing_model import POWER_LADDER, amplitude_model, read

__all__ = ["SCHEDULES", "TIMER_PERIOD", "TIMER_JITTER", "RangeBearingReadings", "RangeBearingSensor"]


#: Firing schedules of :class:`RangeBearingSensor` (docs/design.md#range-and-bearing).
SCHEDULES = ("timer", "contention", "every_step")
#: Period (s) of each robot's R&B timer: the Droplet example application's ``if (get_time() - lastBroadcast
#: > 1000) { lastBroadcast = get_time(); broadcast_rnb_data(); }`` (cu-droplet ``user_template.c``).
TIMER_PERIOD = 1.0
#: Largest late start (s) of a firing after its timer expires (uniform): the application polls its timer
#: in ``loop()``, which an R&B measurement of a neighbour blocks for ~0.19 s (cu-droplet ``range_algs.h``:
#: 30 ms after the command, 2 ms to set the powers, 6 x (16 + 10) ms of emitter slots). An assumption.
TIMER_JITTER = 0.2
_N_CHILDREN = 5  # child streams per copy: priorities, matrix noise, id noise, timer phases, late starts


@dataclass
class RangeBearingReadings:
    """Flat range & bearing readings held by all robots (one row per (rx, tx) reading), sorted by (rx, tx).

    Attributes:
        rx: (K,) int receiving robot.
        tx: (K,) int robot the reading is attributed to: the id the receiver *decoded* from the request
            (module docstring), as a row index of the receiver's own env copy.
        range: (K,) estimated centre distance (m).
        bearing: (K,) estimated bearing of tx in rx's frame (rad).
        heading: (K,) estimated heading of tx in rx's frame (rad).
        age: (K,) int control steps since the reading was measured (0 = this step).
        true_tx: (K,) int ground truth, never an observation: the firing robot whose light gave the
            brightest entry of the reading's matrix (``!= tx``: misattributed).
        n_overlap: (K,) int ground truth: number of firing robots whose light superposed in the matrix
            (1 = a clean single firing).
    """

    rx: np.ndarray
    tx: np.ndarray
    range: np.ndarray
    bearing: np.ndarray
    heading: np.ndarray
    age: np.ndarray
    true_tx: np.ndarray | None = None
    n_overlap: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.rx.shape[0])


class RangeBearingSensor:
    """Per-step range & bearing sensing for a swarm (docs/design.md#range-and-bearing), fed by the IR layer's links.

    Each control step (0.1 s, the Droplet's 10 Hz R&B rate [F14 Sec. V]):

    - power control: a saturated matrix is re-measured on the power ladder (docs/design.md#range-and-bearing), or with
      ``near_model=True`` (Droplet) once at the firmware's low power and inverted with its own amplitude
      fit (:class:`swarm_envs.ir.models.DropletLowPowerIR`).
    - ``schedule="timer"`` (default; the Droplet firmware, docs/design.md#range-and-bearing): each robot
      *fires* (sends the request and its R&B sequence) when its own timer expires, every ``period``
      seconds plus a late start drawn uniform in [0, ``jitter``] s at each firing, from a phase drawn
      uniform in [0, ``period``) at reset. The firmware sends the high-priority ``rnb_r`` command
      without listening first (``hpIrTargetedCmd`` defers only to another R&B in progress) and nothing
      else coordinates the robots, so the schedule reads no link: robots that see each other can fire in
      the same step, and their frames and light superpose at every receiver that sees more than one
      (module docstring). A robot that fires does not measure in that step (its R&B blocks its
      receivers: ``hp_ir_block_bm``).
    - ``schedule="contention"`` (an oracle, for ablation): every robot draws a random priority; a robot
      fires iff no robot it shares an IR link with and of higher priority fires: the greedy maximal
      independent set in priority order over the *true* link graph of the step (vectorised Luby rounds),
      which no robot knows. Only robots hidden from each other by a third may fire together.
      ``schedule="every_step"``: every robot fires every step, measured one at a time as on the paper's
      gantry (idealised: no superposition).
    - every robot with a link to a firing TX decodes the request id (:func:`swarm_envs.sensing.range_bearing_frames.decode_ids`) and, when that
      names a robot of its own copy other than itself, gets a fresh reading attributed to that id (age 0):
      the summed noiseless gains of the firing TXs it sees -> :func:`swarm_envs.sensing.range_bearing_model.measure` (noise, power selection,
      clipping) -> :func:`swarm_envs.sensing.range_bearing_model.estimate`. Matrices below the no-reading floor give nothing.
    - earlier readings persist with ``age + 1`` until refreshed, and are dropped once older than
      ``max_age`` steps.

    ``collisions=False`` measures every firing as if alone and attributes it to the true TX (no
    superposition; a baseline for validation). ``id_check=False``: the sender id is not CRC-checked.
    Nothing here reads ground truth except through the links' gains (the brightness matrices); the
    true transmitter goes only to the ground-truth fields of the readings. ``hardware``
    (:class:`swarm_envs.ir.hardware.Hardware`, one row per robot, or None): the robots' channel
    deviations, for the matrices this sensor computes itself (the near model's low-power light); the
    links' gains carry them already when the IR layer was given them. The estimator keeps the nominal
    calibration.
    """

    def __init__(
        self,
        platform: Platform | str,
        n_robots: int,
        rng: np.random.Generator | CopyRandom,
        noise_sigma: float | None = None,
        schedule: str = "timer",
        max_age: int = 10,
        ladder: tuple[float, ...] = POWER_LADDER,
        near_model: bool = False,
        collisions: bool = True,
        id_check: bool = True,
        period: float = TIMER_PERIOD,
        jitter: float = TIMER_JITTER,
        dt: float = 0.1,
        hardware: Hardware | None = None,
    ) -> None:
        self.platform = get_platform(platform)
        amplitude_model(self.platform)
        if near_model and self.platform.name != "droplet":
            raise ValueError(f"near_model=True is the Droplet firmware's low-power fit; platform {self.platform.name!r} has none")
        self.near_model = bool(near_model)
        if schedule not in SCHEDULES:
            raise ValueError(f"schedule must be one of {SCHEDULES}, got {schedule!r}")
        if not (dt > 0 and period >= dt and jitter >= 0):
            raise ValueError(f"need dt > 0, period >= dt and jitter >= 0 (s), got dt={dt}, period={period}, jitter={jitter}")
        self.rng = rng if isinstance(rng, CopyRandom) else CopyRandom([rng])
        self.copy_size = int(n_robots)
        if collisions and self.copy_size > 2**ID_BITS:
            raise ValueError(f"n_robots={self.copy_size} does not fit the {ID_BITS}-bit id of the R&B request")
        self.n_robots = self.copy_size * self.rng.n_copies
        self.copy_of = np.repeat(np.arange(self.rng.n_copies), self.copy_size)
        self.noise_sigma = float(self.platform.ir_model.default_noise_sigma if noise_sigma is None else noise_sigma)
        self.schedule = schedule
        self.period, self.jitter, self.dt = float(period), float(jitter), float(dt)
        self.hardware = hardware
        self.max_age = int(max_age)
        self.ladder = tuple(ladder)
        self.collisions = bool(collisions)
        self.id_check = bool(id_check)
        self._frames = id_frames(np.arange(self.copy_size)) if self.collisions else None
        # child streams of each copy's generator: buffered ones (one Generator call per copy every few steps
        # instead of several per step) for priorities, matrix noise, id-decoding noise (its own stream, so
        # the matrix noise draws are as without ids) and the timers' late starts; the timer phases are
        # drawn from the fourth child at reset
        kids = [g.spawn(_N_CHILDREN) for g in self.rng.generators]
        self.prio_rng = CopyStream([k[0] for k in kids], "uniform", chunk=max(64, 16 * self.copy_size))
        self.noise_rng = CopyStream([k[1] for k in kids], "normal")
        self.id_rng = CopyStream([k[2] for k in kids], "normal")
        self.jitter_rng = CopyStream([k[4] for k in kids], "uniform", chunk=max(64, 16 * self.copy_size))
        #: (N,) s from the start of the next step until each robot's timer expires (``schedule="timer"``)
        self.countdown = np.concatenate([self._phases(k[3]) for k in kids])
        self.last_fired = np.zeros(self.n_robots, dtype=bool)
        self.reset()

    def _phases(self, g: np.random.Generator) -> np.ndarray:
        """One copy's timer phases: uniform in [0, period) s (the robots were switched on at unrelated times)."""
        return g.random(self.copy_size) * self.period

    def reset(self, copies: np.ndarray | None = None, rngs: list[np.random.Generator] | None = None) -> None:
        """Forget all readings (of ``copies`` only, given; their streams become ``rngs`` if given, and their
        timers get new phases)."""
        if copies is None:
            self._key = np.zeros(0, dtype=np.int64)
            self._range = np.zeros(0)
            self._bearing = np.zeros(0)
            self._heading = np.zeros(0)
            self._age = np.zeros(0, dtype=np.int64)
            self._true = np.zeros(0, dtype=np.int64)
            self._overlap = np.zeros(0, dtype=np.int64)
            self.last_fired = np.zeros(self.n_robots, dtype=bool)
            return
        copies = np.asarray(copies, dtype=np.int64).reshape(-1)
        if rngs is not None:
            for b, g in zip(copies, rngs):
                self.rng.generators[b] = g
                kids = g.spawn(_N_CHILDREN)
                for stream, kid in zip((self.prio_rng, self.noise_rng, self.id_rng, None, self.jitter_rng), kids):
                    if stream is not None:
                        stream.set_generator(int(b), kid)
                self.countdown[int(b) * self.copy_size : (int(b) + 1) * self.copy_size] = self._phases(kids[3])
        keep = ~np.isin((self._key // self.n_robots) // self.copy_size, copies)
        self._key, self._range, self._bearing = self._key[keep], self._range[keep], self._bearing[keep]
        self._heading, self._age = self._heading[keep], self._age[keep]
        self._true, self._overlap = self._true[keep], self._overlap[keep]
        self.last_fired[np.isin(self.copy_of, copies)] = False

    # -- scheduling ------------------------------------------------------------------------------------
    def fire_mask(self, links: IRLinks) -> np.ndarray:
        """(N,) bool: robots that fire this step. ``"timer"``: the robots whose timer expires within this step
        (reads no link; draws a late start for every robot and advances the timers); ``"contention"``:
        draws priorities and reads the links."""
        N = self.n_robots
        if self.schedule == "every_step":
            return np.ones(N, dtype=bool)
        if self.schedule == "timer":
            fire = self.countdown < self.dt
            late = self.jitter_rng.draw(self.copy_of)  # every robot, every step: a fixed count per step
            self.countdown = self.countdown - self.dt + np.where(fire, self.period + self.jitter * late, 0.0)
            return fire
        prio = self.prio_rng.draw(self.copy_of)
        rx, tx = np.asarray(links.rx, np.int64), np.asarray(links.tx, np.int64)
        fired, ok = priority_independent_set_sorted(prio, rx, tx)  # links sorted by receiver: no adjacency list
        return fired if ok else priority_independent_set(prio, rx, tx)

    # -- one control step ------------------------------------------------------------------------------
    def step(
        self, links: IRLinks, fired: np.ndarray | None = None, gain_rows: Callable[[np.ndarray], np.ndarray] | None = None
    ) -> RangeBearingReadings:
        """Advance one control step with this step's links; return all current readings.

        ``fired``: optional (N,) bool robots that fire this step instead of the schedule's choice (for
        validation and tests; no priorities are drawn then). ``gain_rows``: optional reader of the links'
        gain matrices, ``gain_rows(link indices) -> (S, n_d, n_e)`` equal to ``links.gains[indices]``
        (default; e.g. :meth:`swarm_envs.ir.gain_kernels.ChunkRows.take` before the rows are gathered)."""
        N = self.n_robots
        if fired is None:
            fired = self.fire_mask(links)
        else:
            fired = np.asarray(fired, dtype=bool).reshape(-1)
            if fired.shape != (N,):
                raise ValueError(f"fired must have shape ({N},), got {fired.shape}")
        self.last_fired = fired
        sel = np.nonzero(fired[links.tx])[0]  # links from firing TXs, sorted by (rx, tx)
        if self.schedule == "timer":  # a robot that fires does not measure in the same step
            sel = sel[~fired[links.rx[sel]]]
        rx_sel = links.rx[sel]
        superpose = self.collisions and self.schedule != "every_step"
        if superpose and sel.size:
            starts = np.flatnonzero(np.r_[True, rx_sel[1:] != rx_sel[:-1]])
        else:
            starts = np.arange(sel.size)
        grx = rx_sel[starts]
        n_over = np.diff(np.r_[starts, sel.size]).astype(np.int64)
        tx_sel = links.tx[sel]
        gains = links.gains[sel] if gain_rows is None else gain_rows(sel)  # the firing links' matrices
        n_d = gains.shape[1]
        fused = sel.size > 0 and gains.dtype == np.float64 and int(n_over.max()) <= FRAME_WORDS_MAX_GROUP
        if fused:  # the sums and the brightest link of every group in one pass (kernels.firing_sums)
            lam, light, group_light, best = firing_sums(gains.reshape(sel.size, -1), starts.astype(np.int64), n_d, PAIRWISE_INIT)
            lam = lam.reshape(starts.size, *gains.shape[1:])
            true = tx_sel[best]  # ground truth: the firing TX with the brightest entry of each group
        else:
            lam = segment_sum(gains, starts) if starts.size < sel.size else gains
            light, group_light = (sum_last(gains) if self.collisions and sel.size else None), None
            # ground truth: the firing TX with the brightest entry of each group
            if starts.size == sel.size:
                true = tx_sel
            else:
                true = group_brightest(gains.reshape(sel.size, -1), starts.astype(np.int64), tx_sel)

        if self.collisions and sel.size:
            local = np.asarray(tx_sel, dtype=np.int64) % self.copy_size
            dec = decode_ids(
                light, self._frames[local], starts, self.id_rng, self.noise_sigma, self.platform,
                self.id_check, self.copy_of[grx], group_light,
            )
            base = self.copy_of[grx].astype(np.int64) * self.copy_size
            ok = (dec >= 0) & (dec < self.copy_size) & (base + dec != grx)
            tx_dec = base + dec
        else:
            ok = np.ones(starts.size, dtype=bool)
            tx_dec = true.astype(np.int64)
        g = np.flatnonzero(ok)
        if g.size:
            low = None
            if self.near_model:
                from swarm_envs.ir.models import DropletLowPowerIR

                hw = None if self.hardware is None else self.hardware.pairs(links.rx[sel], links.tx[sel])
                low_l = pair_gains(links.rel_position[sel], links.rel_heading[sel], self.platform, model=DropletLowPowerIR(self.platform), hardware=hw)
                low_l = low_l * (gains > 0)  # rays occluded at full power stay dark
                low = (segment_sum(low_l, starts) if starts.size < sel.size else low_l)[g]
            single = starts.size == sel.size
            R, th, ph, _ = read(
                lam[g], links.rel_position[sel][starts[g]] if single else None,
                links.rel_heading[sel][starts[g]] if single else None, self.noise_rng, self.noise_sigma,
                self.platform, self.ladder, self.near_model, self.copy_of[grx[g]], low,
            )
            fin = np.isfinite(R)
            g, R, th, ph = g[fin], R[fin], th[fin], ph[fin]
        else:
            R = th = ph = np.zeros(0)
        new_key = grx[g].astype(np.int64) * N + tx_dec[g]
        new_true, new_over = true[g].astype(np.int64), n_over[g].astype(np.int64)
        args = (
            self._key, np.stack([self._range, self._bearing, self._heading]),
            np.stack([self._age, self._true, self._overlap]).astype(np.int64), self.max_age, new_key,
            np.stack([R, th, ph]).astype(float).reshape(3, -1), np.stack([np.zeros_like(new_over), new_true, new_over]),
        )
        if new_key.size < 2 or bool(np.all(new_key[1:] >= new_key[:-1])):
            key, fl, it = merge_readings(*args)  # one merge of the two sorted tables
        else:  # new keys out of order (decoded ids): a stable sort
            key, fl, it = merge_readings_numpy(*args)
        self._key, (self._range, self._bearing, self._heading) = key, fl
        self._age, self._true, self._overlap = it
        return self.readings()

    def readings(self) -> RangeBearingReadings:
        """Current readings (copies)."""
        rx, tx = np.divmod(self._key, self.n_robots)
        return RangeBearingReadings(
            rx.astype(np.intp), tx.astype(np.intp), self._range.copy(), self._bearing.copy(),
            self._heading.copy(), self._age.copy(), self._true.astype(np.intp), self._overlap.copy(),
        )


def merge_readings_numpy(
    old_key: np.ndarray, old_f: np.ndarray, old_i: np.ndarray, max_age: int, new_key: np.ndarray, new_f: np.ndarray,
    new_i: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reading table update (reference of the compiled :func:`swarm_envs.sensing.range_bearing_kernels.merge_readings`;
    any order of ``new_key``): old rows (sorted ``old_key``, float columns ``old_f`` (3, K) = range, bearing,
    heading; int columns ``old_i`` (3, K) = age, true tx, overlap) age by one and are dropped when older
    than ``max_age`` or refreshed by a new key; new rows enter with age 0; the result is stably sorted
    by key. Returns key (K',), floats (3, K'), ints (3, K')."""
    age = old_i[0] + 1
    keep = (age <= max_age) & ~_member(old_key, new_key)
    key = np.concatenate([old_key[keep], new_key])
    order = np.argsort(key, kind="stable")
    fl = np.concatenate([old_f[:, keep], new_f], axis=1)[:, order]
    it = np.concatenate([np.stack([age[keep], old_i[1, keep], old_i[2, keep]]), np.stack([np.zeros_like(new_i[0]), new_i[1], new_i[2]])], axis=1)
    return key[order], fl, it[:, order]


def _member(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.isin(a, b)`` for integer arrays, by binary search in sorted ``b``."""
    if b.size == 0:
        return np.zeros(a.shape, dtype=bool)
    b = np.sort(b)
    pos = np.minimum(np.searchsorted(b, a), b.size - 1)
    return b[pos] == a
