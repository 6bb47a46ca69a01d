"""Top-down rendering with pygame: arena, robots with heading, IR links and task markers.

``rgb_array`` draws on an off-screen surface (no display needed); ``human`` opens a window.
"""

from __future__ import annotations

import os

import numpy as np

from swarm_envs.platforms import Platform
from swarm_envs.world import Arena

__all__ = ["Renderer"]

_BACKGROUND = (245, 245, 240)
_WALL = (60, 60, 60)
_ROBOT = (40, 110, 200)
_STATIC = (200, 120, 40)
_HEADING = (255, 255, 255)
_LINK = (170, 200, 170)
_MARKER = (220, 40, 40)


class Renderer:
    """Draws one frame per call; ``pixels`` is the square image size."""

    def __init__(self, arena: Arena, platform: Platform, human: bool = False, pixels: int = 480, fps: int = 10) -> None:
        if not human:
            os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        import pygame

        self.pygame = pygame
        self.arena, self.platform, self.human, self.pixels, self.fps = arena, platform, human, pixels, fps
        self.scale = (pixels - 20) / arena.size  # pixels per metre
        self.surface = pygame.Surface((pixels, pixels))
        self.window = None
        self.clock = None
        if human:
            pygame.init()
            pygame.display.init()
            self.window = pygame.display.set_mode((pixels, pixels))
            pygame.display.set_caption("swarm_envs")
            self.clock = pygame.time.Clock()

    def _px(self, xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, dtype=float)
        return np.stack([self.pixels / 2 + xy[..., 0] * self.scale, self.pixels / 2 - xy[..., 1] * self.scale], -1)

    def draw(
        self,
        positions: np.ndarray,
        headings: np.ndarray,
        links: tuple[np.ndarray, np.ndarray] | None = None,
        markers: dict[str, np.ndarray] | None = None,
        static: np.ndarray | None = None,
    ) -> np.ndarray | None:
        """Draw a frame; returns an (H, W, 3) uint8 array (``rgb_array``) or None (``human``)."""
        pg = self.pygame
        surf = self.surface
        surf.fill(_BACKGROUND)
        for a, b in self.arena.wall_segments():
            pg.draw.line(surf, _WALL, self._px(a), self._px(b), 2)
        centres = self._px(positions)
        if links is not None and len(links[0]):
            rx, tx = links
            for a, b in zip(centres[rx[rx < tx]], centres[tx[rx < tx]]):
                pg.draw.line(surf, _LINK, a, b, 1)
        radius_px = max(2, int(round(self.platform.radius * self.scale)))
        nose = self._px(positions + self.platform.radius * np.stack([np.cos(headings), np.sin(headings)], -1))
        static = np.zeros(len(positions), bool) if static is None else static
        for c, n, s in zip(centres, nose, static):
            pg.draw.circle(surf, _STATIC if s else _ROBOT, c, radius_px)
            pg.draw.line(surf, _HEADING, c, n, max(1, radius_px // 4))
        for point in (markers or {}).values():
            c = self._px(point)
            pg.draw.line(surf, _MARKER, c - (6, 6), c + (6, 6), 2)
            pg.draw.line(surf, _MARKER, c + (-6, 6), c + (6, -6), 2)
        if self.human:
            self.window.blit(surf, (0, 0))
            pg.event.pump()
            pg.display.flip()
            self.clock.tick(self.fps)
            return None
        return np.transpose(pg.surfarray.array3d(surf), (1, 0, 2)).copy()

    def close(self) -> None:
        if self.window is not None:
            self.pygame.display.quit()
            self.window = None
