"""``python -m swarm_envs.demo``: the GIF it writes plays at the env's frame rate (read back with Pillow)."""

import pytest
from PIL import Image

from swarm_envs.demo import main


def test_demo_gif_frame_delays_are_100_ms(tmp_path, capsys):
    out = tmp_path / "demo.gif"
    steps = 4
    assert main(["--task", "flocking", "--sensing", "ideal", "--n-robots", "3", "--steps", str(steps), "--out", str(out)]) == 0
    assert f"{steps + 1} frames" in capsys.readouterr().out
    with Image.open(out) as gif:
        assert gif.format == "GIF"
        assert gif.n_frames == steps + 1  # reset frame + one per step, none merged away
        delays = []
        for i in range(gif.n_frames):
            gif.seek(i)
            delays.append(gif.info["duration"])
        assert gif.info.get("loop") == 0  # loops forever
    assert delays == pytest.approx([100] * (steps + 1))  # 1000 ms / render_fps (10)
