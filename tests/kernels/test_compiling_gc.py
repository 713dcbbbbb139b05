"""While a cell compiles, the objects alive before are frozen for the cyclic garbage collector and
unfrozen after (methods/assembly/loading.py ``compiling``); a process its owner froze before gnibench
first compiled in it is left frozen. Run in fresh interpreters: the test processes are frozen by
tests/conftest.py."""
from __future__ import annotations

import subprocess
import sys

import pytest

PROBE = """
import gc
from gnibench.methods.assembly.loading import compiling
{before}
outside = gc.get_freeze_count()
with compiling():
    inside = gc.get_freeze_count()
print(outside, inside, gc.get_freeze_count(), gc.isenabled())
"""


def _counts(before: str) -> list[str]:
    out = subprocess.run([sys.executable, "-c", PROBE.format(before=before)], capture_output=True,
                         text=True, timeout=120, check=True).stdout.split()
    return out


def test_a_plain_process_is_frozen_while_compiling_and_unfrozen_after():
    outside, inside, after, enabled = _counts("")
    assert outside == "0" and int(inside) > 1000 and after == "0" and enabled == "True"


@pytest.mark.parametrize("before", ["gc.freeze()", "gc.freeze()\nwith compiling():\n    pass"])
def test_a_process_frozen_by_its_owner_stays_as_it_was(before):
    outside, inside, after, _ = _counts(before)
    assert int(outside) > 1000 and inside == outside and after == outside


def test_a_disabled_collector_is_left_alone():
    outside, inside, after, enabled = _counts("gc.disable()")
    assert outside == inside == after == "0" and enabled == "False"
