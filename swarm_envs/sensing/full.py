"""The ``sensing="full"`` stack: every observation value comes from the modelled infrared hardware.

Each control step, in this order (data flows one way):

1. **IR layer** (:func:`swarm_envs.ir.layer.compute_links`): candidate pairs (KD-tree), line of sight,
   emitter-detector gains of every visible pair, once for everything below. On the ``droplet`` and
   ``epuck`` (``hw_variation=True``) the gains are those of each robot's own channels: emitter powers,
   detector gains and axis angles drawn per robot at reset (:mod:`swarm_envs.ir.hardware`,
   docs/design.md#hardware-variation), so range & bearing and SwarmCom see them and the estimator's
   nominal calibration does not match them.
2. **Range & bearing** [F14] (:class:`swarm_envs.sensing.range_bearing.RangeBearingSensor`) on the
   ``droplet`` and ``epuck``: firing on each robot's own timer (``rb_schedule="timer"``), noisy
   brightness matrices, the estimator, readings that persist with an age.
3. **SwarmCom** [T20] (:class:`swarm_envs.comm.network.Network`): bit-slot simulation of the channel.
   With ``message_bits > 0`` each robot queues its current action payload whenever its transmit queue
   is empty (so the newest payload goes out as soon as the radio is free). Decoded application frames
   become the ``messages`` observation; the sender's bearing is the axis of the receiver's brightest
   detector during the frame (a coarse bearing from the detector itself, not from ground truth).
   **Sector bearings** (``bearing_source="sectors"``, the ``rone`` default, docs/design.md#bearing-only-sensing) are measured on the
   decoded frames (:class:`swarm_envs.sensing.bearing_sensor.MessageBearings`): each decoded frame gives
   its receiver the sector bearing and orientation of the robot its header names, from the receivers whose
   own copy of the frame no other robot's light corrupted (``Deliveries.interference``). A robot's readings
   are its last complete round's measurements, with their ages: at the start of each of its rounds it
   clears all prior neighbour information [L Sec. 3.2.2] and the round that just ended becomes its
   readings. Every robot broadcasts at the start of each round, once per ``BEACON_PERIOD`` steps, the thesis round
   ``T_round = 2 (1 + N)^2 t_msg`` for its N = 5 neighbours and 3-byte 32.8 ms messages, 2.36 s
   [L Sec. 3.2.1] rounded up to whole steps: with ``exchange="network"`` its bearing-list message *is* the
   beacon ([L Sec. 3.2.3]: the announcement message carries the encoded orientation bit; [L Sec. 5.2.2]
   step 1 "broadcast id, record bearings" and step 2 share it, and the rounds of the bearings are the
   exchange's), otherwise a header-only beacon.
   ``bearing_noise`` (default on, r-one) gives each robot, at reset, its own receiver arcs from the
   measured 63-74 degree spread, mean 68 [L Sec. 3.2.1, Fig. 3.9(b)]. The ``rone`` has no
   range sensor: its ``range_bearing`` rows hold these readings with range 0, most recently decoded first
   (ties in a random order drawn each step from the copy's ranking stream,
   :func:`swarm_envs.sensing.observation.ranked_slots`): the K kept are the K heard last, and a row's position
   carries nothing of the decoded id.
4. **Bearing exchange and scale-free coordinates** [L] (:class:`swarm_envs.sensing.exchange.BearingExchange`,
   :func:`swarm_envs.sensing.scale_free.coordinates_all`): bearings from ``bearing_source``
   (``"sectors"`` default on ``rone``, ``"range_bearing"`` elsewhere) travel as SwarmCom system traffic
   (``exchange="network"``, in the same rounds: a robot's coordinates come from its last complete round)
   or instantly (``exchange="ideal"``); the 2-hop algorithm turns what each robot knows into neighbour
   coordinates up to scale.

Channel and sensor statistics go to ``infos[agent]["sensing"][name]``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from swarm_envs._compile._worker import worker
from swarm_envs.comm.channel import recommended_relative_threshold
from swarm_envs.comm.network import Network
from swarm_envs.comm.deliveries import PreparedStep
from swarm_envs.sim.copies import CopyRandom
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.ir.hardware import Hardware, draw_hardware
from swarm_envs.ir.layer import compute_links_with_rows, gain_threads
from swarm_envs.ir.models import RoneIR
from swarm_envs.sensing.observation import nearest_slots, pack_nearest, range_bearing_rows, ranked_slots
from swarm_envs.sim.platforms import Platform
from swarm_envs.sensing.base import MessageReadings, NeighbourReadings, ScaleFreeReadings, SensorFrame
from swarm_envs.sensing.bearing_sensor import RONE_ARC_MEAN_DEG, RONE_ARC_RANGE_DEG, MessageBearings
from swarm_envs.sensing.exchange import BearingExchange, thesis_round_time
from swarm_envs.sensing.range_bearing import RangeBearingSensor
from swarm_envs.sensing.scale_free import coordinates, coordinates_all_chunks

__all__ = ["FullSensing", "BEACON_PERIOD", "SECTOR_MAX_AGE", "RB_MAX_AGE", "rb_max_age", "reading_max_age", "rb_on_worker_thread"]

#: steps between two broadcasts of a robot (bearing beacons / exchange lists on the sector source): the
#: thesis round 2 (1 + 5)^2 x 32.8 ms = 2.36 s [L Sec. 3.2.1] in 0.1 s control steps, rounded up
BEACON_PERIOD = int(np.ceil(round(thesis_round_time(5) / 0.1, 9)))
#: the oldest a sector reading gets (steps): measured in a round's first step, shown until the following round ends
SECTOR_MAX_AGE = 2 * BEACON_PERIOD - 1


#: steps a range & bearing reading persists under the schedules that fire every few steps ("contention",
#: "every_step"): one second
RB_MAX_AGE = 10


def rb_max_age(cfg: dict[str, Any]) -> int:
    """Steps a range & bearing reading persists: ``rb_max_age``, or when it is None, until the neighbour's
    next firing is due at its latest: ``ceil((rb_period + rb_jitter) / 0.1 s) + 1`` steps under the
    ``"timer"`` schedule (13 at the defaults), :data:`RB_MAX_AGE` under the others."""
    if cfg["rb_max_age"] is not None:
        return int(cfg["rb_max_age"])
    if cfg["rb_schedule"] == "timer":
        return int(np.ceil(round((cfg["rb_period"] + cfg["rb_jitter"]) / 0.1, 9))) + 1
    return RB_MAX_AGE


def reading_max_age(cfg: dict[str, Any], platform: Platform) -> int:
    """The largest age (steps) of an observation's ``range_bearing`` row: :func:`rb_max_age` on range &
    bearing platforms, :data:`SECTOR_MAX_AGE` where the rows hold message-borne sector readings (no range
    model)."""
    return rb_max_age(cfg) if hasattr(platform.ir_model, "amplitude_inverse") else SECTOR_MAX_AGE

BEACON_KIND = "bearing_beacon"  # SwarmCom system kind of the header-only beacons

_STAT_NAMES = ("tx_started", "deferrals", "rx_delivered", "rx_lost", "collisions", "bits_checked", "bit_errors")


def rb_on_worker_thread(n_links: int) -> bool:
    """Whether range & bearing runs on the worker thread (:mod:`swarm_envs._compile._worker`) while SwarmCom runs on
    the calling thread: when the scene (one env or a batch of copies) is large enough for the
    gain kernel's threads (:func:`gain_threads` of its ``n_links`` links: numba on more than one thread,
    called from the main thread). The two read the same links, draw from their own streams and touch
    disjoint state, and their compiled kernels release the GIL (``nogil``), so the result is the same bit
    for bit either way."""
    return gain_threads(n_links) > 1


def _observation_rows(neighbours: NeighbourReadings, n: int, k: int) -> None:
    """Each robot's k nearest readings (``neighbours.slots``) and their observation rows (``neighbours.rows``),
    which the observation builder would otherwise compute after the sensing (on the worker thread, while
    the exchange and scale-free coordinates run on the calling thread)."""
    slots = nearest_slots(n, neighbours.rx, neighbours.range, k)
    neighbours.rows = range_bearing_rows(slots, neighbours.range, neighbours.bearing, neighbours.heading, neighbours.age)
    neighbours.slots = slots


def _ranked_observation_rows(neighbours: NeighbourReadings, n: int, k: int, tie: np.ndarray) -> None:
    """Each robot's k most recently decoded readings (``neighbours.slots``, :func:`ranked_slots` by age, ties
    by ``tie`` (P,)) and their observation rows (``neighbours.rows``): the rows of a platform without a
    range sensor, whose readings all have range 0."""
    slots = ranked_slots(n, neighbours.rx, neighbours.age, tie, k)
    neighbours.rows = range_bearing_rows(slots, neighbours.range, neighbours.bearing, neighbours.heading, neighbours.age)
    neighbours.slots = slots


class FullSensing:
    """Physically modelled sensing for ``n_robots`` robots of one platform (module docstring)."""

    def __init__(self, platform: Platform, n_robots: int, config: dict[str, Any], n_copies: int = 1, obstacles: np.ndarray | None = None) -> None:
        self.platform = platform
        #: static obstacle segments (S, 2, 2) m that block light per ray (None: none)
        self.obstacles = obstacles if obstacles is not None and len(obstacles) else None
        self.copy_size = int(n_robots)
        self.n_copies = int(n_copies)
        self.n = self.copy_size * self.n_copies
        self.config = config
        self.has_range = hasattr(platform.ir_model, "amplitude_inverse")
        source = config.get("bearing_source") or ("range_bearing" if self.has_range else "sectors")
        if source == "range_bearing" and not self.has_range:
            raise ValueError(f"bearing_source='range_bearing' needs a range & bearing platform; {platform.name!r} has none (use 'sectors')")
        self.bearing_source = source
        self.k = int(config["n_neighbours"])
        self.message_bits = int(config["message_bits"])
        self.method = config["scale_free_method"]
        self.hops = int(config["scale_free_k"])
        self.copy_of = np.repeat(np.arange(self.n_copies), self.copy_size)
        #: whether the last step's scene was large enough for the worker thread (:func:`rb_on_worker_thread`)
        self.large_scene = False
        self._scene_threads = 1  # threads of the last step's scene (gain_threads)
        # one stack for all copies; each module keeps one generator per copy (placeholders until reset)
        streams = [CopyRandom([np.random.default_rng(0) for _ in range(self.n_copies)]) for _ in range(5)]
        #: the ties of the observation-row ranking on a platform without range (:func:`ranked_slots`)
        self._rank_rng = streams[4]
        #: each robot's channel deviations (:mod:`swarm_envs.ir.hardware`; rows drawn at reset), or None:
        #: the nominal platform (``hw_variation=False``, or a platform without range & bearing)
        self.hardware: Hardware | None = None
        if self.has_range and config["hw_variation"]:
            self.hardware = Hardware.nominal(self.n, platform)
            self._spreads = (float(config["hw_emitter_spread"]), float(config["hw_detector_spread"]), float(config["hw_angle_spread"]))
        self.rb: RangeBearingSensor | None = None
        if self.has_range:
            self.rb = RangeBearingSensor(
                platform,
                self.copy_size,
                streams[0],
                noise_sigma=config["rb_noise"],
                schedule=config["rb_schedule"],
                max_age=rb_max_age(config),
                near_model=config["rb_near_model"],
                period=config["rb_period"],
                jitter=config["rb_jitter"],
                hardware=self.hardware,
            )
        threshold = config["relative_threshold"]
        self.network = Network(
            platform,
            self.copy_size,
            streams[1],
            bitrate=platform.ir_bitrate if config["bitrate"] is None else config["bitrate"],
            relative_threshold=recommended_relative_threshold(platform) if threshold is None else threshold,
            code=tuple(config["code"]),
            comm_mode=config["comm_mode"],
            payload_bits=self.message_bits,
            n_copies=self.n_copies,
        )
        self.bearings: MessageBearings | None = None
        extra = {}
        if source == "sectors":
            noisy = bool(config.get("bearing_noise", True)) and isinstance(platform.ir_model, RoneIR)
            self.bearings = MessageBearings(
                platform,
                self.copy_size,
                streams[3],
                n_copies=self.n_copies,
                period=BEACON_PERIOD,
                arc_range=RONE_ARC_RANGE_DEG if noisy else None,
                arc_mean=RONE_ARC_MEAN_DEG,
            )
            extra["period"] = BEACON_PERIOD  # the exchange's broadcasts are the beacons
        self.exchange = BearingExchange(
            self.copy_size, mode=config["exchange"], network=self.network, rng=streams[2], n_copies=self.n_copies, **extra
        )
        # register the system kinds now: the network numbers kinds on first use and accepts only registered type
        # codes, so registering when the first copy sends would make a copy's decoding depend on the others
        if self.exchange.mode == "network":
            self.network.kinds.code(self.exchange.kind)
        elif self.bearings is not None:
            self.network.kinds.code(BEACON_KIND)

    @classmethod
    def from_config(
        cls, platform: Platform, n_robots: int, config: dict[str, Any], n_copies: int = 1, obstacles: np.ndarray | None = None
    ) -> FullSensing:
        """The stack for a task's resolved settings ``config`` (:mod:`swarm_envs.sensing.stacks`)."""
        return cls(platform, n_robots, config, n_copies, obstacles=obstacles)

    def reset(self, copies: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """Fresh sensor, channel and exchange state of env ``copies``, from independent child streams
        (range & bearing, channel, exchange, sector bearings, hardware variation, row-ranking ties) of each
        copy's generator ``rngs[k]``; other copies untouched."""
        copies = np.asarray(copies, dtype=np.int64).reshape(-1)
        children = [g.spawn(6) for g in rngs]
        for b, c in zip(copies, children):
            self._rank_rng.generators[int(b)] = c[5]
        if self.hardware is not None:  # each robot's channels, from the copy's own child stream
            for b, c in zip(copies, children):
                rows = np.arange(int(b) * self.copy_size, (int(b) + 1) * self.copy_size)
                self.hardware.set_rows(rows, draw_hardware(c[4], self.copy_size, self.platform, *self._spreads))
        if self.rb is not None:
            self.rb.reset(copies, [c[0] for c in children])
        self.network.reset_copies(copies, [c[1] for c in children])
        self.exchange.reset(copies=copies, rngs=[c[2] for c in children])
        if self.bearings is not None:
            self.bearings.reset(copies, [c[3] for c in children])
            if self.exchange.mode == "network":  # the exchange's broadcast is the beacon: one round per robot
                rows = np.flatnonzero(np.isin(self.copy_of, copies))
                self.bearings.phase[rows] = self.exchange.phase[rows]

    # ------------------------------------------------------------------------------------------------
    def prepare_step(self, payloads: np.ndarray | None, sending: np.ndarray | None = None) -> PreparedStep:
        """The part of a step that reads nothing the physics changes: the application ``payloads`` (N, b)
        bool or None are queued (robots with an empty transmit queue, among ``sending`` (N,) bool, default
        all), then the bearing exchange's messages or the beacons, and the channel's random numbers of the
        step are drawn (:meth:`Network.prepare_step`). :class:`swarm_envs.core.SwarmCore` runs it on the
        worker thread while the physics of a large scene runs; pass the result to :meth:`step`."""
        net = self.network
        if payloads is not None and self.message_bits > 0:
            free = net.q_count == 0
            if sending is not None:
                free &= np.asarray(sending, bool)
            free = np.flatnonzero(free)
            if free.size:
                net.send_many(free, payloads[free])
        if self.exchange.mode == "network":
            self.exchange.send(net)
        elif self.bearings is not None:
            self.bearings.send_beacons(net, BEACON_KIND)
        return net.prepare_step()

    def step(
        self,
        positions: np.ndarray,
        headings: np.ndarray,
        payloads: np.ndarray | None = None,
        sending: np.ndarray | None = None,
        prepared: PreparedStep | None = None,
        silent: np.ndarray | None = None,
        emit_off: np.ndarray | None = None,
        detect_off: np.ndarray | None = None,
    ) -> SensorFrame:
        """One control step of sensing (module docstring) at the robots' ``positions`` (N, 2) m and
        ``headings`` (N,) rad: :meth:`prepare_step` with ``payloads`` and ``sending``, or its result
        ``prepared`` when it has run already (then ``payloads`` must be None), then the links and sensors.
        ``silent`` (N,) bool: switched-off robots, in no IR link (they neither emit nor detect);
        ``emit_off`` / ``detect_off`` (N,) bool: robots in no link as transmitter / as receiver."""
        if prepared is None:
            prepared = self.prepare_step(payloads, sending)
        elif payloads is not None:
            raise ValueError("payloads were queued by prepare_step; pass either payloads or prepared")
        # the IR links; in a large scene the gain matrices stay where the gain kernel's chunks left them
        # (swarm_envs.ir.gain_kernels.ChunkRows): range & bearing reads the rows it needs from there, SwarmCom
        # reads only the emitter sums, and nothing here reads links.gains before gain_rows.gather()
        links, gain_rows = compute_links_with_rows(
            positions, headings, self.platform, copy=self.copy_of if self.n_copies > 1 else None, deferred=True, obstacles=self.obstacles,
            silent=silent, hardware=self.hardware, emit_off=emit_off, detect_off=detect_off,
        )
        take = None if gain_rows is None else gain_rows.take

        # range & bearing (large scenes: on the worker thread, while SwarmCom runs here)
        self.large_scene = rb_on_worker_thread(len(links))
        self._scene_threads = gain_threads(len(links))
        rb_future = rb = neighbours = None
        try:
            if self.has_range:
                if self.large_scene:
                    rb_future = worker().submit(self._range_bearing, links, take)
                else:
                    rb, neighbours = self._range_bearing(links, take)
            # SwarmCom: application payloads and the bearing exchange share the channel (queued by prepare_step);
            # its slot loop takes the scene's threads unless range & bearing has one of them (the worker)
            deliveries = self.network.step(links, prepared, threads=1 if rb_future is not None else self._scene_threads)
        finally:  # never leave the worker running on this step's state
            if rb_future is not None:
                rb_future.exception()  # waits
        if rb_future is not None:
            rb, neighbours = rb_future.result()
        if gain_rows is not None and self.bearings is not None:
            gain_rows.gather()  # the sector bearings read links.gains (range & bearing's reads are done)
        # the readings' observation rows on the worker thread, while the exchange and scale-free run here
        rows_future = worker().submit(_observation_rows, neighbours, self.n, self.k) if rb_future is not None else None
        try:
            frame = self._finish_step(links, deliveries, rb, neighbours)
        finally:  # never leave the worker running on this step's readings
            if rows_future is not None:
                rows_future.exception()  # waits
        if rows_future is not None:
            rows_future.result()  # (the rows' error, if any)
        return frame

    def _finish_step(self, links: Any, deliveries: Any, rb: Any, neighbours: NeighbourReadings | None) -> SensorFrame:
        """The rest of :meth:`step` after range & bearing and SwarmCom: sector bearings, messages, the bearing
        exchange and scale-free coordinates, statistics."""
        # sector bearings measured on the decoded frames (any kind): the last complete round's readings
        sectors = self.bearings.step(deliveries, links) if self.bearings is not None else None
        if not self.has_range:
            neighbours = sectors
            _ranked_observation_rows(neighbours, self.n, self.k, self._rank_rng.random(self.copy_of[neighbours.rx]))
        bearing_readings = sectors if self.bearing_source == "sectors" else neighbours
        if self.bearing_source == "sectors" and self.exchange.mode == "network":
            bearing_readings = self.bearings.fresh  # a received list pairs with the bearing measured on its own frame
        app = deliveries.for_kind("app")
        # an uncoded header can decode to a wrong length or an id outside the receiver's swarm: such a frame is
        # not a well-formed message
        base = self.copy_of[app.receiver] * self.copy_size
        well_formed = (app.length == self.message_bits) & (app.origin >= base) & (app.origin < base + self.copy_size)
        if self.message_bits > 0 and well_formed.any():
            payload = np.zeros((len(app), self.message_bits))
            width = min(self.message_bits, app.payload.shape[1])
            payload[:, :width] = app.payload[:, :width]
            # the detector's axis as a bearing in (-pi, pi] (the axes of the Droplet and r-one run over [0, 2 pi))
            sender_bearing = wrap_angle(self.platform.detector_directions[app.detector])
            messages = MessageReadings(
                app.receiver[well_formed], app.origin[well_formed], sender_bearing[well_formed], payload[well_formed]
            )
        else:
            messages = MessageReadings(payload=np.zeros((0, self.message_bits)))

        # views of the exchange's tables: consumed by _scale_free right away (the result holds no view)
        knowledge = self.exchange.step(bearing_readings, deliveries if self.exchange.mode == "network" else None, copy=False)
        scale_free = self._scale_free(knowledge)

        stats = {name: np.asarray(deliveries.stats[f"{name}_per_robot"]) for name in _STAT_NAMES if f"{name}_per_robot" in deliveries.stats}
        stats["ir_links"] = np.bincount(links.rx, minlength=self.n)
        if sectors is not None:
            stats["bearing_readings"] = np.bincount(sectors.rx, minlength=self.n)
        if self.rb is not None:
            stats["rb_fired"] = self.rb.last_fired.astype(np.int64)
            # ground truth about the R&B readings (infos only): named by a decoded id that is not the robot
            # whose light dominated, and fresh readings from overlapping firings
            stats["rb_misattributed"] = np.bincount(rb.rx[rb.tx != rb.true_tx], minlength=self.n)
            stats["rb_overlapped"] = np.bincount(rb.rx[(rb.age == 0) & (rb.n_overlap > 1)], minlength=self.n)
        stats["rigid"] = scale_free.rigid.astype(np.int64)
        return SensorFrame(neighbours, messages, scale_free, stats)

    def _range_bearing(self, links: Any, gain_rows: Callable[[np.ndarray], np.ndarray] | None = None) -> tuple[Any, NeighbourReadings]:
        """Range & bearing's step on ``links`` (their gain rows read with ``gain_rows``, default
        ``links.gains``) and its readings."""
        rb = self.rb.step(links, gain_rows=gain_rows)
        return rb, NeighbourReadings(rb.rx, rb.tx, rb.range, rb.bearing, rb.heading, rb.age.astype(float))

    def _scale_free(self, knowledge) -> ScaleFreeReadings:
        if self.method == "two_hop":  # in a large scene the robots in chunks on threads (the same result)
            result = coordinates_all_chunks(knowledge, self._scene_threads)
            xy, valid, rigid = result.xy, result.valid, result.rigid
        else:  # null-space k-hop method: one robot at a time (slow; an analysis option, see README)
            xy, valid, rigid = self._null_space(knowledge)
        row, slot = np.nonzero(valid)
        points = xy[row, slot]
        # ranked by the distance of the coordinates as the observation holds them (float32), so that equal
        # distances are equal for a firmware computing them from those values too
        rounded = points.astype(np.float32).astype(np.float64)
        distance = np.hypot(rounded[:, 0], rounded[:, 1])
        if self.has_range:
            packed, order = pack_nearest(self.n, row, distance, points, self.k)
        else:  # bearing-only: equal scale-free distances (one neighbour, symmetric triangles) in a random order
            order = ranked_slots(self.n, row, distance, self._rank_rng.random(self.copy_of[row]), self.k)
            packed = np.zeros((self.n, self.k, 2))
            if len(row):
                packed = np.where((order >= 0)[..., None], points[np.maximum(order, 0)], 0.0)
        ids = np.where(order >= 0, knowledge.ids[row, slot][np.maximum(order, 0)] if len(row) else -1, -1)  # decoded ids
        return ScaleFreeReadings(packed, order >= 0, np.asarray(rigid, bool), ids)

    def _null_space(self, knowledge) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n, kmax = knowledge.ids.shape
        xy = np.full((n, kmax, 2), np.nan)
        valid = np.zeros((n, kmax), bool)
        rigid = np.zeros(n, bool)
        for u in range(n):
            # what robot u knows: its own bearings and the rows its neighbours reported
            local = np.full((n, n), np.nan)
            own = knowledge.ids[u] >= 0
            local[u, knowledge.ids[u][own]] = knowledge.bearings[u][own]
            rid, rth = knowledge.row_ids[u], knowledge.row_bearings[u]
            for slot, v in enumerate(knowledge.ids[u]):
                if v >= 0:
                    good = rid[slot] >= 0
                    local[v, rid[slot][good]] = rth[slot][good]
            pos, rigid[u] = coordinates(local, u, method="null_space", k=self.hops)
            for slot, v in enumerate(knowledge.ids[u]):
                if v >= 0 and np.all(np.isfinite(pos[v])):
                    xy[u, slot], valid[u, slot] = pos[v], True
        return xy, valid, rigid

