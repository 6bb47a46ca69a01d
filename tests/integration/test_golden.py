"""Golden record: every registered env's fixed-seed rollouts (observations, rewards, flags, infos) are those
recorded in tests/golden/rollouts.json. A change that alters them must be intended: then follow the
versioning rule (docs/versioning.md) and re-record with ``python tests/golden/rollouts.py``."""

import importlib.util
import json
from pathlib import Path

import pytest

_spec = importlib.util.spec_from_file_location("golden_rollouts", Path(__file__).resolve().parents[1] / "golden" / "rollouts.py")
golden = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(golden)
RECORDED = json.loads(golden.RECORD.read_text())


def test_every_case_is_recorded():
    assert sorted(RECORDED) == sorted(" ".join(case) for case in golden.cases())


@pytest.mark.parametrize("case", golden.cases(), ids=" ".join)
def test_rollout_matches_the_record(case):
    assert golden.rollout(*case) == RECORDED[" ".join(case)], f"{case}: the rollout differs from tests/golden/rollouts.json"
