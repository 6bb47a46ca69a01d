"""A registered id of your own works with every command and example that takes a task (``--import``)."""

import importlib.util
import math
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CUSTOM_TASK = str(ROOT / "examples" / "custom_task.py")
DISPERSION = "swarm_examples/Dispersion-v0"


@pytest.fixture(autouse=True)
def _fresh_import(unregistered):
    """Each test imports examples/custom_task.py anew through ``--import`` (module ``custom_task``) and
    registers its id afresh; the id is removed (or its earlier entry restored) afterwards."""
    unregistered(DISPERSION)
    sys.modules.pop("custom_task", None)
    yield
    sys.modules.pop("custom_task", None)


def load_example(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # BenchMARL pickles the example's classes by reference
    spec.loader.exec_module(module)
    return module


def test_demo_takes_an_imported_id(tmp_path, capsys):
    from swarm_envs.demo import main

    out = tmp_path / "dispersion.gif"
    assert main(["--import", CUSTOM_TASK, "--task", DISPERSION, "--policy", "random", "--steps", "3", "--n-robots", "3",
                 "--sensing", "ideal", "--pixels", "160", "--out", str(out)]) == 0
    assert out.stat().st_size > 0 and "mean_spacing" in capsys.readouterr().out


def test_demo_refuses_an_unknown_id_and_a_failed_import(capsys):
    from swarm_envs.demo import main

    with pytest.raises(SystemExit) as exit_info:
        main(["--task", "my_lab/NeverRegistered-v0", "--policy", "random"])
    assert exit_info.value.code == 2 and "unknown task" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_info:
        main(["--import", "no_such_module_anywhere", "--task", DISPERSION])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "cannot import 'no_such_module_anywhere'" in err and "Traceback" not in err
