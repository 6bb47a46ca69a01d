"""Top-down rendering with pygame: arena and obstacle walls, robots with heading, IR links, task markers, a caption and a legend.

``rgb_array`` draws on an off-screen surface (no display needed); ``human`` opens a window. A frame shows the
whole arena (``view="arena"``, ``env.render()``) or a square that follows the robots (``view="swarm"``, the
documentation GIFs). :data:`COLOURS` names every colour drawn; :func:`legend_text` is the colour key in words.

:meth:`Renderer.draw` takes plain arrays. :func:`render_env` draws a frame of a running env with what makes
the suite different: the IR links that delivered a decoded reading this step (:func:`fresh_links`, range &
bearing readings on the ``droplet`` and ``epuck`` [F14], decoded beacon frames on the ``rone`` [L Sec. 3.2]),
the SwarmCom application messages decoded this step (:func:`message_links`, [T20]) and, for one chosen robot,
where its ``range_bearing`` observation rows put its neighbours next to where they are
(:func:`neighbour_overlay`). The sensing frame's sender and receiver indices are used for drawing only; no
observation is built from them.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarm_envs.tasks._task_checks import checked_robot_groups
from swarm_envs.sensing.observation import nearest_slots
from swarm_envs.sim.platforms import Platform
from swarm_envs.sensing.base import SensorFrame
from swarm_envs.sim.arena import Arena

__all__ = [
    "Renderer",
    "NeighbourOverlay",
    "PALETTE",
    "COLOURS",
    "VIEWS",
    "legend_text",
    "fresh_links",
    "message_links",
    "neighbour_overlay",
    "overlay_of",
    "render_env",
]

#: what the renderer draws -> (the colour's name, RGB): the one table the frames, the legend drawn in a frame
#: and :func:`legend_text` (quoted by the README and the environment pages) take their colours from
COLOURS: dict[str, tuple[str, tuple[int, int, int]]] = {
    "background": ("off-white", (245, 245, 240)),
    "wall": ("dark grey", (60, 60, 60)),
    "robot": ("blue", (40, 110, 200)),
    "robot_b": ("teal", (20, 140, 140)),  # robots of a task's second group (Task.robot_groups)
    "static": ("orange", (225, 120, 20)),
    "heading": ("white", (255, 255, 255)),
    "link": ("green", (30, 160, 60)),
    "message": ("purple", (150, 70, 190)),
    "marker": ("red", (220, 40, 40)),
    "text": ("black", (30, 30, 30)),
    "estimate": ("magenta", (235, 0, 140)),
    "error": ("grey", (120, 120, 120)),
    "focus": ("black", (20, 20, 20)),
}

_BACKGROUND = COLOURS["background"][1]
_WALL = COLOURS["wall"][1]
_ROBOT = COLOURS["robot"][1]
_ROBOT_B = COLOURS["robot_b"][1]
_STATIC = COLOURS["static"][1]
_HEADING = COLOURS["heading"][1]
_LINK = COLOURS["link"][1]
_MESSAGE = COLOURS["message"][1]
_MARKER = COLOURS["marker"][1]
_TEXT = COLOURS["text"][1]
_ESTIMATE = COLOURS["estimate"][1]
_ERROR = COLOURS["error"][1]
_FOCUS = COLOURS["focus"][1]

#: every colour the renderer draws (shapes and text are not antialiased), so a GIF with this palette shows the
#: frames exactly (:func:`swarm_envs.demo.write_gif`)
PALETTE: tuple[tuple[int, int, int], ...] = tuple(dict.fromkeys(rgb for _, rgb in COLOURS.values()))

#: what a frame shows: ``"arena"`` the whole arena (``env.render()``), ``"swarm"`` a square around the robots
#: and the task's markers that follows them smoothly (the documentation GIFs)
VIEWS = ("arena", "swarm")


def legend_text() -> str:
    """The frames' colour key in words, with the colour names of :data:`COLOURS` (the README quotes it)."""
    c = {key: name for key, (name, _) in COLOURS.items()}
    return (
        f"{c['robot']} robots with a {c['heading']} heading mark ({c['robot_b']}: a task's second group, {c['static']}: "
        f"static robots), {c['link']} lines: IR readings decoded this step, {c['message']} lines: messages, "
        f"{c['marker']} crosses: task markers"
    )


@dataclass
class NeighbourOverlay:
    """One robot's estimates of its neighbours next to the truth, in the world frame.

    Attributes:
        robot: world index of the robot whose observation is shown.
        estimates: (k, 2) m, where its valid ``range_bearing`` rows put the neighbours; for a row without a
            range (the ``rone`` has no range sensor) the point on the estimated bearing at the true distance.
        headings: (k,) rad, the neighbours' estimated headings (world frame).
        truths: (k, 2) m, the true positions of the robots the readings name.
        bearing_only: (k,) bool, rows without a range (drawn as a ray from the robot).
        ages: (k,) control steps since each reading was refreshed (0: this step; older ones are drawn thin).
    """

    robot: int
    estimates: np.ndarray
    headings: np.ndarray
    truths: np.ndarray
    bearing_only: np.ndarray
    ages: np.ndarray


def fresh_links(frame: SensorFrame) -> tuple[np.ndarray, np.ndarray]:
    """(receiver, sender) world indices of the neighbour readings decoded this step (age 0).

    Range & bearing readings persist with an age; only the ones refreshed this step carried a decoded frame.
    The sender is the id the reading names (a misattributed reading draws to the robot it names)."""
    nb = frame.neighbours
    fresh = np.asarray(nb.age) == 0
    return np.asarray(nb.rx)[fresh], np.asarray(nb.tx)[fresh]


def message_links(frame: SensorFrame) -> tuple[np.ndarray, np.ndarray]:
    """(receiver, sender) world indices of the SwarmCom application messages decoded this step."""
    return np.asarray(frame.messages.receiver), np.asarray(frame.messages.sender)


def neighbour_overlay(
    robot: int, rows: np.ndarray, position: np.ndarray, heading: float, truths: np.ndarray
) -> NeighbourOverlay:
    """Turn one robot's ``range_bearing`` rows (k, 7) (:data:`swarm_envs.sensing.observation.RB_FIELDS`) into world points.

    ``position`` (2,) m and ``heading`` rad are the robot's true pose (the rows are in its body frame);
    ``truths`` (k, 2) m are the true positions of the robots the k rows name (NaN for empty rows).
    A row's estimate is ``position + range * (cos, sin)(heading + bearing)``; a valid row with range 0 has
    no range (bearing-only sensing) and is placed on its bearing at the true distance.
    """
    rows = np.asarray(rows, dtype=float)
    truths = np.asarray(truths, dtype=float).reshape(-1, 2)
    position = np.asarray(position, dtype=float)
    valid = rows[:, 0] > 0.5
    bearing = heading + np.arctan2(rows[:, 3], rows[:, 2])
    bearing_only = valid & (rows[:, 1] <= 0)
    distance = np.where(bearing_only, np.hypot(*(truths - position).T), rows[:, 1])
    estimates = position + distance[:, None] * np.stack([np.cos(bearing), np.sin(bearing)], -1)
    headings = heading + np.arctan2(rows[:, 5], rows[:, 4])
    return NeighbourOverlay(int(robot), estimates[valid], headings[valid], truths[valid], bearing_only[valid], rows[valid, 6])


def overlay_of(env: Any, agent: int = 0) -> NeighbourOverlay:
    """:func:`neighbour_overlay` of agent number ``agent`` of a running :class:`swarm_envs.adapters.env.SwarmEnv`.

    The rows are the agent's ``range_bearing`` observation; each row is matched to the reading it was
    built from (the env's nearest-by-estimated-range slots) to find the robot the reading names."""
    if not 0 <= agent < env.n_agents:
        raise ValueError(f"overlay agent must be in [0, {env.n_agents}), got {agent}")
    robot = int(env.agent_robots[agent])
    rows = env.batched_observations()["range_bearing"][robot]
    nb = env.core.frame.neighbours
    k = rows.shape[0]
    n = len(env.world.positions)
    slots = nb.slots if nb.slots is not None and nb.slots.shape == (n, k) else nearest_slots(n, nb.rx, nb.range, k)
    slot = slots[robot]
    positions = env.world.positions
    truths = np.full((k, 2), np.nan)
    truths[slot >= 0] = positions[np.asarray(nb.tx)[slot[slot >= 0]]]
    return neighbour_overlay(robot, rows, positions[robot], float(env.world.headings[robot]), truths)


class Renderer:
    """Draws one frame per call; ``pixels`` is the square image size.

    ``view="arena"`` (default) shows the whole arena in every frame; ``view="swarm"`` shows a square around
    the robots and the task's markers with a margin of ``3 x`` the robot radius (at least ``16`` radii wide),
    inside the arena where it fits. It grows at once when a robot would leave it; it holds still while the
    robots fill enough of it and otherwise moves towards their square by the fraction ``follow`` per frame,
    so it neither jitters nor cuts a robot off. Arena and obstacle walls are drawn where they are in view.
    """

    #: swarm view: margin around the robots, in robot radii (a robot and its heading mark stay whole)
    MARGIN_RADII = 3.0
    #: swarm view: the smallest view side, in robot radii (one robot alone is not blown up to the frame)
    MIN_VIEW_RADII = 16.0
    #: swarm view: it holds still until the robots' square is smaller than this fraction of it (or leaves it)
    HOLD = 0.6
    #: swarm view: the square it moves to is this much larger than the robots' (room for small moves)
    SLACK = 1.15

    def __init__(
        self,
        arena: Arena,
        platform: Platform,
        human: bool = False,
        pixels: int = 480,
        fps: int = 10,
        obstacles: np.ndarray | None = None,
        view: str = "arena",
        follow: float = 0.15,
    ) -> None:
        if view not in VIEWS:
            raise ValueError(f"view must be one of {list(VIEWS)}, got {view!r}")
        if not 0.0 < follow <= 1.0:
            raise ValueError(f"follow must be in (0, 1], got {follow!r}")
        self.obstacles = np.zeros((0, 2, 2)) if obstacles is None else np.asarray(obstacles, dtype=float).reshape(-1, 2, 2)
        if not human:
            os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        import pygame

        self.pygame = pygame
        self.arena, self.platform, self.human, self.pixels, self.fps = arena, platform, human, int(pixels), fps
        self.view, self.follow = view, float(follow)
        self.surface = pygame.Surface((self.pixels, self.pixels))
        self.font_size = max(14, self.pixels // 30)
        self._font = None
        self._text_cache: dict[str, Any] = {}
        self.view_centre, self.view_half = np.zeros(2), self.arena.half  # m: the square of the world shown
        self._followed: int | None = None  # swarm view: the number of points it follows (None: start anew)
        self._moving = False  # swarm view: moving towards the robots' square
        self._layout(0, 0)
        self.window = None
        self.clock = None
        if human:
            pygame.init()
            pygame.display.init()
            self.window = pygame.display.set_mode((self.pixels, self.pixels))
            pygame.display.set_caption("swarm_envs")
            self.clock = pygame.time.Clock()

    # -- geometry ------------------------------------------------------------------------------------
    def _layout(self, top: int, bottom: int) -> None:
        """Fit the view between a caption band of ``top`` and a legend band of ``bottom`` pixels."""
        self.top, self.bottom = top, bottom
        height = self.pixels - top - bottom
        self.side = min(self.pixels, height) - 20  # pixels of the shown square
        self.centre = np.array([self.pixels / 2, top + height / 2])
        self.scale = self.side / (2.0 * self.view_half)  # pixels per metre

    def reset_view(self) -> None:
        """Start the swarm view anew at the next frame (a new episode): it jumps to the robots."""
        self._followed = None

    def _swarm_square(self, points: np.ndarray) -> tuple[np.ndarray, float]:
        """(centre (2,) m, half side m) of the square around ``points`` (k, 2) with the margin and slack."""
        r = self.platform.radius
        lo, hi = points.min(axis=0), points.max(axis=0)
        half = max(self.SLACK * (0.5 * float((hi - lo).max()) + self.MARGIN_RADII * r), 0.5 * self.MIN_VIEW_RADII * r)
        return 0.5 * (lo + hi), half

    def _inside_arena(self, centre: np.ndarray, half: float) -> tuple[np.ndarray, float]:
        """The square moved inside the arena (plus a wall's margin) where it fits, else the whole arena."""
        edge = self.arena.half + 0.5 * self.platform.radius
        if half >= edge:
            return np.zeros(2), edge
        return np.clip(centre, -edge + half, edge - half), half

    def _update_view(self, points: np.ndarray) -> None:
        """Move the swarm view towards the square around ``points`` (k, 2) m; every point stays inside.

        The view holds still while it holds every point and is at most ``1 / HOLD`` times the square's
        size; otherwise it moves (``follow`` of the way per frame) until it is within 2 % of the square."""
        points = points[np.all(np.isfinite(points), axis=1)]
        if self.view != "swarm" or not len(points):
            self.view_centre, self.view_half = np.zeros(2), self.arena.half
            return
        target_centre, target_half = self._swarm_square(points)
        margin = self.MARGIN_RADII * self.platform.radius
        if self._followed != len(points):  # first frame: jump there
            centre, half, self._moving = target_centre, target_half, False
        else:
            centre, half = self.view_centre, self.view_half
            holds = float(np.abs(points - centre).max()) + margin <= half
            if not self._moving and (not holds or target_half < self.HOLD * half):
                self._moving = True
            if self._moving:
                centre = centre + self.follow * (target_centre - centre)
                half = half + self.follow * (target_half - half)
                close = 0.02 * target_half
                self._moving = bool(np.abs(centre - target_centre).max() > close or abs(half - target_half) > close)
        half = max(half, float(np.abs(points - centre).max()) + margin)  # grows at once: no robot leaves the view
        self.view_centre, self.view_half = self._inside_arena(centre, half)
        self._followed = len(points)

    def _px(self, xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, dtype=float) - self.view_centre
        return np.stack([self.centre[0] + xy[..., 0] * self.scale, self.centre[1] - xy[..., 1] * self.scale], -1)

    # -- text ----------------------------------------------------------------------------------------
    def _text(self, text: str):
        surf = self._text_cache.get(text)
        if surf is None:
            if self._font is None:
                self.pygame.font.init()
                self._font = self.pygame.font.Font(None, self.font_size)
            surf = self._font.render(text, False, _TEXT, _BACKGROUND)  # crisp, few colours
            if len(self._text_cache) > 512:  # captions change every frame; legends do not
                self._text_cache.clear()
            self._text_cache[text] = surf
        return surf

    def _wrap(self, text: str, width: int) -> list[str]:
        """``text`` in lines no wider than ``width`` pixels (breaking at spaces)."""
        lines: list[str] = []
        for paragraph in text.split("\n"):
            line = ""
            for word in paragraph.split(" "):
                trial = f"{line} {word}" if line else word
                if line and self._text(trial).get_width() > width:
                    lines.append(line)
                    line = word
                else:
                    line = trial
            lines.append(line)
        return lines

    def _legend_items(
        self, links: bool, messages: bool, static: bool, markers: list[str], overlay: bool, group_labels: tuple[str, ...] | None = None
    ) -> list[tuple[str, tuple, str]]:
        if group_labels:
            items = [("robot", colour, label) for colour, label in zip((_ROBOT, _ROBOT_B), group_labels)]
        else:
            items = [("robot", _ROBOT, "robot, heading")]
        if static:
            items.append(("robot", _STATIC, "static robot"))
        if links:
            items.append(("line", _LINK, "IR reading this step"))
        if messages:
            items.append(("line", _MESSAGE, "message this step"))
        if markers:
            items.append(("cross", _MARKER, " / ".join(name.replace("_", " ") for name in markers)))
        if overlay:
            items.append(("ring", _ESTIMATE, "ringed robot's estimates"))
        return items

    def _legend_rows(self, items: list[tuple[str, tuple, str]]) -> list[list[tuple[str, tuple, str, int]]]:
        """Legend items flowed into rows that fit the image width, each item with its x offset."""
        rows: list[list] = [[]]
        x, swatch, gap = 6, self.font_size, self.font_size // 2
        for kind, colour, label in items:
            width = swatch + 3 + self._text(label).get_width() + gap
            if x + width > self.pixels and rows[-1]:
                rows.append([])
                x = 6
            rows[-1].append((kind, colour, label, x))
            x += width
        return rows

    def _draw_swatch(self, kind: str, colour: tuple, x: int, y: int) -> None:
        pg, s = self.pygame, self.font_size
        cx, cy = x + s // 2, y + s // 2
        if kind == "robot":
            pg.draw.circle(self.surface, colour, (cx, cy), s // 2 - 1)
            pg.draw.line(self.surface, _HEADING, (cx, cy), (cx + s // 2 - 1, cy), 2)
        elif kind == "line":
            pg.draw.line(self.surface, colour, (x, cy), (x + s, cy), 2)
        elif kind == "cross":
            h = s // 3
            pg.draw.line(self.surface, colour, (cx - h, cy - h), (cx + h, cy + h), 2)
            pg.draw.line(self.surface, colour, (cx - h, cy + h), (cx + h, cy - h), 2)
        elif kind == "ring":
            pg.draw.circle(self.surface, colour, (cx, cy), s // 2 - 2, 2)

    # -- drawing ---------------------------------------------------------------------------------------
    def draw(
        self,
        positions: np.ndarray,
        headings: np.ndarray,
        links: tuple[np.ndarray, np.ndarray] | None = None,
        markers: dict[str, np.ndarray] | None = None,
        static: np.ndarray | None = None,
        *,
        messages: tuple[np.ndarray, np.ndarray] | None = None,
        overlay: NeighbourOverlay | None = None,
        caption: str | None = None,
        legend: bool = False,
        groups: tuple[np.ndarray, tuple[str, str]] | None = None,
    ) -> np.ndarray | None:
        """Draw a frame; returns an (H, W, 3) uint8 array (``rgb_array``) or None (``human``).

        Args:
            positions: (n, 2) robot centres (m); headings: (n,) rad.
            links: (receiver, sender) robot indices of IR links to draw (green).
            markers: task markers, name -> world point (2,) m (red crosses).
            static: (n,) bool, robots drawn as anchors (orange).
            messages: (receiver, sender) indices of decoded messages (purple).
            overlay: one robot's neighbour estimates next to the truth (:class:`NeighbourOverlay`).
            caption: text above the arena (wrapped to the width; ``\\n`` starts a line).
            legend: draw a legend of what is shown below the arena.
            groups: ((n,) group 0 or 1 of each robot, the two groups' legend labels): group 1 is drawn in a
                second colour (:meth:`swarm_envs.tasks.task.Task.robot_groups`, e.g. odd ids).
        """
        pg = self.pygame
        surf = self.surface
        surf.fill(_BACKGROUND)
        static = np.zeros(len(positions), bool) if static is None else np.asarray(static, bool)
        line_height = self._text("Ag").get_height()
        caption_lines = self._wrap(caption, self.pixels - 12) if caption else []
        legend_rows = (
            self._legend_rows(
                self._legend_items(
                    links is not None, messages is not None, bool(static.any()), sorted(markers or {}), overlay is not None,
                    None if groups is None else groups[1],
                )
            )
            if legend
            else []
        )
        top = len(caption_lines) * line_height + (6 if caption_lines else 0)
        bottom = len(legend_rows) * (line_height + 2) + (4 if legend_rows else 0)
        if (top, bottom) != (self.top, self.bottom):
            self._layout(top, bottom)
        for i, line in enumerate(caption_lines):
            surf.blit(self._text(line), (6, 3 + i * line_height))
        for r, row in enumerate(legend_rows):
            y = self.pixels - bottom + 2 + r * (line_height + 2)
            for kind, colour, label, x in row:
                self._draw_swatch(kind, colour, x, y + (line_height - self.font_size) // 2)
                surf.blit(self._text(label), (x + self.font_size + 3, y))

        marker_points = np.asarray(list((markers or {}).values()), dtype=float).reshape(-1, 2)
        self._update_view(np.concatenate([np.asarray(positions, dtype=float).reshape(-1, 2), marker_points]))
        self.scale = self.side / (2.0 * self.view_half)
        corner = self.centre - self.side / 2
        surf.set_clip(pg.Rect(int(corner[0]) - 1, int(corner[1]) - 1, self.side + 3, self.side + 3))  # the scene stays in its square
        for a, b in np.concatenate([self.arena.wall_segments(), self.obstacles]):
            pg.draw.line(surf, _WALL, self._px(a), self._px(b), 2)
        centres = self._px(positions)
        for pairs, colour, width in ((links, _LINK, 2), (messages, _MESSAGE, 2)):
            if pairs is not None and len(pairs[0]):
                rx, tx = np.asarray(pairs[0]), np.asarray(pairs[1])
                keep = (rx != tx) & (rx < len(positions)) & (tx < len(positions))
                for a, b in zip(centres[rx[keep]], centres[tx[keep]]):
                    pg.draw.line(surf, colour, a, b, width)
        radius_px = max(2, int(round(self.platform.radius * self.scale)))
        nose = self._px(positions + self.platform.radius * np.stack([np.cos(headings), np.sin(headings)], -1))
        tick = max(2, radius_px // 3)
        second = np.zeros(len(positions), bool) if groups is None else np.asarray(groups[0]) == 1
        for c, n, s, g in zip(centres, nose, static, second):
            pg.draw.circle(surf, _STATIC if s else (_ROBOT_B if g else _ROBOT), c, radius_px)
            pg.draw.line(surf, _HEADING, c, n, tick)
        for point in (markers or {}).values():
            c = self._px(point)
            pg.draw.line(surf, _MARKER, c - (6, 6), c + (6, 6), 2)
            pg.draw.line(surf, _MARKER, c + (-6, 6), c + (6, -6), 2)
        if overlay is not None:
            self._draw_overlay(overlay, centres, radius_px)
        surf.set_clip(None)
        if self.human:
            self.window.blit(surf, (0, 0))
            pg.event.pump()
            pg.display.flip()
            self.clock.tick(self.fps)
            return None
        return np.transpose(pg.surfarray.array3d(surf), (1, 0, 2)).copy()

    def _draw_overlay(self, overlay: NeighbourOverlay, centres: np.ndarray, radius_px: int) -> None:
        pg, surf = self.pygame, self.surface
        own = centres[overlay.robot]
        pg.draw.circle(surf, _FOCUS, own, radius_px + 3, 2)
        est = self._px(overlay.estimates)
        truth = self._px(overlay.truths)
        ring = max(3, radius_px // 2)
        for e, t, h, ray, age in zip(est, truth, overlay.headings, overlay.bearing_only, overlay.ages):
            if not np.all(np.isfinite(e)):
                continue
            width = 2 if age == 0 else 1
            if ray:
                pg.draw.line(surf, _ESTIMATE, own, e, 1)
            if np.all(np.isfinite(t)):
                pg.draw.line(surf, _ERROR, e, t, 1)  # estimate -> the robot the reading names
            pg.draw.circle(surf, _ESTIMATE, e, ring, width)
            tip = e + (ring + 4) * np.array([np.cos(h), -np.sin(h)])
            pg.draw.line(surf, _ESTIMATE, e, tip, width)

    def close(self) -> None:
        if self.window is not None:
            self.pygame.display.quit()
            self.window = None


def render_env(env: Any, renderer: Renderer, caption: str | None = None, overlay_agent: int | None = None, legend: bool = True) -> np.ndarray | None:
    """Draw the current state of a :class:`swarm_envs.adapters.env.SwarmEnv` (after ``reset``) with ``renderer``.

    Links are the readings decoded this step (:func:`fresh_links`) and the decoded application messages
    (:func:`message_links`, drawn when the env sends messages, ``message_bits > 0``); ``overlay_agent`` (an
    agent number) adds :func:`overlay_of` that agent.
    """
    frame = env.core.frame
    if frame is None:
        raise RuntimeError("render_env() needs a started episode; call env.reset() first")
    world = env.world
    messages = message_links(frame) if env.layout.message_bits > 0 else None
    overlay = overlay_of(env, overlay_agent) if overlay_agent is not None else None
    return renderer.draw(
        world.positions,
        world.headings,
        fresh_links(frame),
        env._markers(),  # the task's markers, checked
        static=np.arange(len(world.positions)) < env.n_static,
        messages=messages,
        overlay=overlay,
        caption=caption,
        legend=legend,
        groups=checked_robot_groups(env.task, env.task.robot_groups()),
    )
