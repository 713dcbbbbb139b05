"""The frame-stack chunk cache (suite/foundation/datastack.py, CPython gh-142183).

A call just across the edge of a 16 KiB chunk of CPython's frame stack maps and unmaps a chunk
each time; with the cache it reuses one. Counted in page faults (``ru_minflt``) of a fresh
interpreter, not in seconds: a count that load does not change."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from gnibench.suite.foundation import datastack

pytestmark = pytest.mark.skipif(not (datastack.applies() and datastack.llvm_reads_opaque_pointers()),
                                reason="CPython 3.11-3.13 with the GIL, llvmlite on LLVM >= 15")

#: calls at every depth 1..400 (the edge of a chunk lies at about 100-200 frames), 200 times:
#: each call deeper than an edge crosses it twice
SWEEP = """
import json, resource, sys
from gnibench.suite.foundation import datastack
on = datastack.install()
def down(n):
    return 0 if n == 0 else down(n - 1) + 1
down(400)
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(200):
    for depth in range(1, 400):
        assert down(depth) == depth
faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before
print(json.dumps({"installed": on, "faults": faults}))
"""


def _sweep(**env) -> dict:
    proc = subprocess.run([sys.executable, "-c", SWEEP], capture_output=True, text=True,
                          check=True, env={**os.environ, **env})
    return json.loads(proc.stdout)


def test_calls_across_a_chunk_edge_stop_faulting_in_pages():
    off = _sweep(GNIBENCH_FRAME_CACHE="0")
    on = _sweep()
    assert off["installed"] is False and on["installed"] is True
    assert off["faults"] > 20_000, off               # ~80,000 calls across an edge: one each
    assert on["faults"] < off["faults"] / 20, (on, off)


def test_deep_recursion_threads_generators_and_fork_run_as_before():
    """Blocks of any size, from before and after the install, go back to the allocator they came
    from: deep recursion (frames larger than a chunk, many chunks), threads (one frame stack
    each), suspended generators and a forked child compute the same as without the cache."""
    code = """
import json, os, sys, threading
from gnibench.suite.foundation import datastack
datastack.install()
sys.setrecursionlimit(30000)
def down(n):
    return 0 if n == 0 else down(n - 1) + 1
def wide(n):
    """ + "; ".join(f"a{i} = n + {i}" for i in range(3000)) + """
    return a2999 if n == 0 else wide(n - 1)
out = {"deep": [down(20000) for _ in range(3)], "wide": wide(30)}
gens = [(x * k for x in range(5)) for k in range(200)]
out["gens"] = sum(sum(g) for g in gens)
res = []
ts = [threading.Thread(target=lambda k=k: res.append(down(5000 + k))) for k in range(4)]
for t in ts: t.start()
for t in ts: t.join()
out["threads"] = sorted(res)
r, w = os.pipe()
pid = os.fork()
if pid == 0:
    os.write(w, str(down(8000)).encode()); os._exit(0)
os.waitpid(pid, 0)
out["fork"] = int(os.read(r, 64))
print(json.dumps(out))
"""
    results = []
    for flag in ("0", "1"):
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              check=True, env={**os.environ, "GNIBENCH_FRAME_CACHE": flag})
        results.append(json.loads(proc.stdout))
    assert results[0] == results[1]
    assert results[1]["deep"] == [20000] * 3 and results[1]["fork"] == 8000
    assert results[1]["threads"] == [5000, 5001, 5002, 5003] and results[1]["wide"] == 2999


def test_install_is_idempotent_and_the_commands_install_it():
    assert datastack.install() is True and datastack.install() is True
    assert datastack.installed()
    code = ("import sys\nfrom gnibench.suite.cli.main import main\n"
            "main(['list', 'problems', '--format', 'json'])\n"
            "from gnibench.suite.foundation import datastack\n"
            "print(datastack.installed(), file=sys.stderr)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert proc.stderr.strip().splitlines()[-1] == "True"


@pytest.mark.parametrize("value", ["off", "false", "2", "0x1", "١"])
def test_a_bad_setting_is_one_line_before_any_work(value, tmp_path):
    out = tmp_path / "x.csv"
    proc = subprocess.run([sys.executable, "-m", "gnibench.suite.cli.main", "solve", "kepler-2d",
                           "rk4:h=0.1", "--steps", "5", "-o", str(out)], capture_output=True,
                          text=True, check=False,
                          env={**os.environ, "GNIBENCH_FRAME_CACHE": value})
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert lines[0] == (f"gnibench: error: bad GNIBENCH_FRAME_CACHE={value!r}; allowed: unset, "
                        "0 (off) or 1 (on)")
    assert not out.exists()
    for good in ("", " 0 ", "1"):
        datastack.check_setting({"GNIBENCH_FRAME_CACHE": good})
