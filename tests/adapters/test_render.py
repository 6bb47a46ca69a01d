"""The renderer's swarm view (follows the robots, keeps every robot in view, draws walls in view) and the
colour key the README quotes (the same colour names the frames are drawn with)."""

import colorsys
import re
from pathlib import Path

import numpy as np
import pytest

from swarm_envs.adapters import render
from swarm_envs.agents.evaluation import make_env
from swarm_envs.demo import DEFAULT_SHOWCASE, SHOWCASE, TASKS
from swarm_envs.sim.platforms import get_platform
from swarm_envs.sim.arena import Arena

README = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")


def _colours(frame: np.ndarray) -> set[tuple[int, int, int]]:
    return {tuple(int(v) for v in c) for c in np.unique(frame.reshape(-1, 3), axis=0)}


def _in_view(renderer: render.Renderer, positions: np.ndarray) -> bool:
    reach = np.abs(positions - renderer.view_centre).max(axis=1) + renderer.platform.radius
    return bool(np.all(reach <= renderer.view_half + 1e-9))


def test_swarm_view_holds_every_robot_and_zooms_in():
    arena, platform = Arena("square", 4.0), get_platform("epuck")
    rng = np.random.default_rng(0)
    grid = np.stack(np.meshgrid(np.arange(3), np.arange(3)), -1).reshape(-1, 2)[:8]
    positions = np.array([0.2, 0.3]) + 0.15 * grid  # 15 cm apart: no robot overlaps another
    headings = rng.uniform(-np.pi, np.pi, 8)
    swarm = render.Renderer(arena, platform, pixels=320, view="swarm")
    whole = render.Renderer(arena, platform, pixels=320)
    whole.draw(positions, headings)
    for step in range(60):  # a drifting swarm with one robot that runs off and comes back
        positions = positions + np.array([0.01, -0.005]) + rng.normal(0, 0.002, positions.shape)
        positions[0] = positions[1:].mean(axis=0) + (0.7 if 20 <= step < 40 else 0.3) * np.array([1.0, 0.3])
        frame = swarm.draw(positions, headings)
        assert frame.shape == (320, 320, 3) and frame.dtype == np.uint8
        assert _in_view(swarm, positions), f"step {step}: a robot left the view"
        # the body of every robot is drawn: the pixel half a radius behind its centre is robot blue
        back = swarm._px(positions - 0.5 * platform.radius * np.stack([np.cos(headings), np.sin(headings)], -1))
        for x, y in np.round(back).astype(int):
            assert tuple(frame[y, x]) == render._ROBOT
    assert swarm.scale > 2.5 * whole.scale  # 8 robots within 0.5 m in a 4 m arena: zoomed in
    assert swarm.platform.radius * swarm.scale >= 10  # pixels: the heading mark is visible


def test_swarm_view_holds_still_while_the_robots_jiggle():
    renderer = render.Renderer(Arena("square", 3.0), get_platform("rone"), pixels=320, view="swarm")
    rng = np.random.default_rng(1)
    positions = rng.uniform(-0.5, 0.5, (6, 2))
    renderer.draw(positions, np.zeros(6))
    view = (renderer.view_centre.copy(), renderer.view_half)
    for _ in range(20):
        renderer.draw(positions + rng.normal(0, 0.002, positions.shape), np.zeros(6))
        assert np.array_equal(renderer.view_centre, view[0]) and renderer.view_half == view[1]


def test_walls_are_drawn_when_in_view_and_only_then():
    arena, platform = Arena("square", 4.0), get_platform("epuck")
    headings = np.zeros(3)
    centre = np.array([[0.0, 0.0], [0.1, 0.05], [-0.1, 0.05]])
    corner = centre + np.array([1.85, 1.85])  # 0.1 m from two walls
    for positions, walls in ((centre, False), (corner, True)):
        renderer = render.Renderer(arena, platform, pixels=320, view="swarm")
        frame = renderer.draw(positions, headings)
        assert (render._WALL in _colours(frame)) is walls
        assert _in_view(renderer, positions)
    # an obstacle wall inside the arena is drawn where it crosses the view
    obstacle = np.array([[[0.05, -1.0], [0.05, 1.0]]])
    renderer = render.Renderer(arena, platform, pixels=320, obstacles=obstacle, view="swarm")
    frame = renderer.draw(np.array([[-0.15, 0.0], [0.25, 0.0]]), np.zeros(2))
    columns = np.flatnonzero((frame == render._WALL).all(axis=2).any(axis=0))
    assert len(columns) and abs(columns.mean() - renderer._px(np.array([0.05, 0.0]))[0]) < 2


def test_arena_view_is_the_whole_arena_and_views_are_checked():
    arena, platform = Arena("square", 1.0), get_platform("epuck")
    renderer = render.Renderer(arena, platform, pixels=300)
    renderer.draw(np.array([[0.3, 0.3]]), np.zeros(1))
    assert np.array_equal(renderer.view_centre, np.zeros(2)) and renderer.view_half == arena.half
    with pytest.raises(ValueError, match="view"):
        render.Renderer(arena, platform, view="robots")


@pytest.mark.parametrize("task", sorted(SHOWCASE))
def test_showcase_first_frames_show_robots_large_enough(task):
    """At the documentation GIFs' 320 pixels a robot is at least 5 pixels in radius (its heading mark shows)."""
    preset = {**DEFAULT_SHOWCASE, **SHOWCASE[task]}
    kwargs = {"platform": preset["platform"], "n_robots": preset["n_robots"], "max_cycles": 5, **preset.get("env", {})}
    env = make_env(task, **{k: v for k, v in kwargs.items() if v is not None})
    env.reset(seed=preset["seed"])
    renderer = render.Renderer(env.arena, env.platform, pixels=320, obstacles=env.task.obstacle_segments, view="swarm")
    frame = render.render_env(env, renderer, caption=task)
    assert _in_view(renderer, env.world.positions)
    assert env.platform.radius * renderer.scale >= 5
    assert _colours(frame) <= set(render.PALETTE)
    env.close()


# -- the colour key ------------------------------------------------------------------------------------------
#: hue ranges (degrees) of the colour names the key uses; white, grey and black by low saturation
HUES = {"red": (345, 15), "orange": (15, 45), "green": (80, 160), "teal": (160, 200), "blue": (200, 250),
        "purple": (250, 300), "magenta": (300, 345)}


@pytest.mark.parametrize("key", sorted(render.COLOURS))
def test_each_colour_name_fits_its_rgb(key):
    name, rgb = render.COLOURS[key]
    h, s, v = colorsys.rgb_to_hsv(*(c / 255 for c in rgb))
    if name in HUES:
        low, high = HUES[name]
        hue = h * 360
        assert s > 0.5 and v > 0.5, f"{key}: {rgb} is too pale to call {name}"
        assert (low <= hue < high) if low < high else (hue >= low or hue < high), f"{key}: hue {hue:.0f} is not {name}"
    else:
        assert s < 0.1, f"{key}: {rgb} is not a grey"
        expected = {"white": (0.9, 1.01), "off-white": (0.9, 1.01), "grey": (0.3, 0.7), "dark grey": (0.15, 0.3), "black": (0.0, 0.15)}
        low, high = expected[name]
        assert low <= v < high, f"{key}: brightness {v:.2f} is not {name}"


def test_readme_quotes_the_renderers_colour_key():
    assert render.legend_text() in " ".join(README.split())
    assert set(render.PALETTE) == {rgb for _, rgb in render.COLOURS.values()}


def test_readme_environments_table_names_what_each_gif_shows():
    """The agents column names the GIF's platform and robot count: the defaults, or "(GIF: ...)"."""
    words = {"droplet": "Droplet", "epuck": "e-puck", "rone": "r-one"}
    for task, env_id in TASKS.items():
        row = next(line for line in README.splitlines() if line.startswith(f"| `{env_id}`"))
        agents = row.rstrip(" |").rsplit("|", 1)[1].strip()
        shown = re.search(r"\(GIF: ([^)]*)\)", agents)
        text = shown.group(1) if shown else agents
        preset = {**DEFAULT_SHOWCASE, **SHOWCASE[task]}
        kwargs = {"platform": preset["platform"], "n_robots": preset["n_robots"], **preset.get("env", {})}
        env = make_env(task, **{k: v for k, v in kwargs.items() if v is not None})
        assert words[env.platform.name] in text, f"{task}: the table says {agents!r}, the GIF shows {env.platform.name}"
        count = re.match(r"\d+", text)
        if count:
            assert int(count.group()) == env.n_agents, f"{task}: the table says {agents!r}, the GIF shows {env.n_agents} agents"
        gif = re.search(rf"!\[([^\]]*)\]\(docs/img/envs/{task}\.gif\)", README)
        assert gif and words[env.platform.name].lower() in gif.group(1).lower(), f"{task}: the GIF's alt text names another platform"
        env.close()


def test_environment_pages_name_only_the_renderers_colours():
    """The GIF captions of docs/environments/*.md name colours the frames use (red, green, teal, ...)."""
    names = {name for name, _ in render.COLOURS.values()}
    common = {"red", "orange", "yellow", "green", "teal", "cyan", "blue", "purple", "violet", "magenta", "pink", "grey",
              "gray", "brown", "black", "white"}
    pages = sorted((Path(__file__).resolve().parents[2] / "docs" / "environments").glob("*.md"))
    assert pages
    for page in pages:
        caption = page.read_text(encoding="utf-8").split("\n\n")[:3]  # title, GIF, the paragraph about it
        used = {w for w in re.findall(r"[a-z]+", " ".join(caption).lower()) if w in common}
        assert used <= names, f"{page.name} names {sorted(used - names)}, which the frames do not use"
