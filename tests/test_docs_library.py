"""The library page's online-estimator example runs as written and says what it prints.

``docs/guide/library.md`` shows the N-joint estimator on its own: a 3 s UR5 record carrying 2 kg,
run through ``run_online``; its comment says the mass comes to about 2.0 kg. The block is taken
from the page and run as it stands (a walk-through found an example of that page that did not run
on a user's arm).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

PAGE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "library.md"


def _block(marker: str) -> str:
    blocks = re.findall(r"```python\n(.*?)```", PAGE.read_text(), re.S)
    found = [b for b in blocks if marker in b]
    assert len(found) == 1, f"{PAGE}: one python block with {marker!r}, got {len(found)}"
    return found[0]


def test_the_online_estimator_block_is_on_the_page():
    code = _block("run_online(sc.arm")
    assert "about 2.0 kg" in code and "payload_parameters(2.0)" in code


@pytest.mark.slow  # the UR5's kernels and a 3 s record
def test_the_online_estimator_block_runs_and_learns_the_payload():
    scope: dict = {}
    exec(compile(_block("run_online(sc.arm"), str(PAGE), "exec"), scope)
    assert abs(scope["out"].mass[0, -1] - 2.0) < 0.05
    assert scope["out"].alarm_times() == [[]]  # one payload from the start: no change to find
