"""The runner at scale: the resumable store (kill -9 and resume), the lock, executors that give
byte-identical tables, Ctrl-C, and the progress lines."""
from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.runs import store as store_module
from gnibench.suite.runs.store import Store
from support import three_executors

GNIBENCH = [str(Path(sys.executable).with_name("gnibench"))]
TABLES = ("samples.parquet", "cells.parquet")

# Six cells of ~0.15 s each (rk4 on kepler-2d, 5 10^6 steps, a sample every 1.25 10^6 steps): the
# test freezes the run when two are stored, so only the order of events matters, not their length
SLOW = """
name = "slow"
title = "Six slow cells"
reference = "[HLW] (2.2)"
steps = 5000000
every = 1250000

[[cells]]
problems = ["kepler-2d"]
methods = ["rk4"]
vary.h = [1e-4, 2e-4, 3e-4, 4e-4, 5e-4, 6e-4]
"""

TINY = """
name = "tiny"
title = "Tiny"
reference = "[HLW] (2.2)"
steps = 40
every = 10

[[cells]]
problems = ["kepler-2d", "pendulum"]
methods = ["rk4", "stormer-verlet+projection:on=H"]
vary.h = [0.05, 0.1]
"""


def _write(tmp_path, text, name):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


def _tables(out: Path) -> dict[str, bytes]:
    return {name: (out / name).read_bytes() for name in TABLES}


def _records(out: Path) -> int:
    """The records of finished cells in the store's segments (a record cut short not counted)."""
    from gnibench.suite.runs.partfile import scan

    total = 0
    for seg in (out / "parts").glob("*.seg"):
        with open(seg, "rb") as f:
            total += len(scan(f, seg.name)[0])
    return total


def _record_of(segment: Path, k: int) -> bytes:
    """The bytes of the k-th record of a segment."""
    from gnibench.suite.runs.partfile import HEAD, scan

    with open(segment, "rb") as f:
        entries = sorted(scan(f, segment.name)[0].values(), key=lambda e: e.offset)
    e = entries[k]
    return segment.read_bytes()[e.offset - HEAD:e.offset + e.length]


def test_kill_9_then_resume_reuses_cells_and_gives_identical_tables(tmp_path):
    exp = _write(tmp_path, SLOW, "slow")
    whole, killed = tmp_path / "whole", tmp_path / "killed"
    subprocess.run(GNIBENCH + ["run", str(exp), "-o", str(whole), "-j", "1", "--no-report"], check=True,
                   capture_output=True)
    for _ in range(5):           # the run is frozen (SIGSTOP) the moment 2 cells are stored
        shutil.rmtree(killed, ignore_errors=True)
        proc = subprocess.Popen(GNIBENCH + ["run", str(exp), "-o", str(killed), "-j", "1", "--no-report"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 600            # a safety net against a hang only
        while _records(killed) < 2 and proc.poll() is None:
            assert time.monotonic() < deadline
            time.sleep(0.02)
        proc.send_signal(signal.SIGSTOP)
        stored = _records(killed)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        if stored < 6:           # else a loaded machine let it finish first: try again
            break
    assert 2 <= stored < 6
    (killed / "parts" / ".abc.parquet.tmp999").write_bytes(b"half a part")   # as a kill leaves
    segment = max((killed / "parts").glob("*.seg"))           # and a record cut short
    segment.write_bytes(segment.read_bytes() + _record_of(segment, 0)[:150])
    again = subprocess.run(GNIBENCH + ["run", str(exp), "-o", str(killed), "-j", "1", "--no-report"],
                           check=True, capture_output=True, text=True)
    assert f"({stored} reused from the store, {6 - stored} to compute)" in again.stderr
    assert _tables(killed) == _tables(whole)
    assert not list(killed.rglob(".*tmp*"))          # temporary files of killed runs are cleaned


def test_second_run_reuses_everything_and_fresh_recomputes(tmp_path, capsys):
    exp = _write(tmp_path, TINY, "tiny")
    out = tmp_path / "out"
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    first = _tables(out)
    capsys.readouterr()
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    assert "(8 reused from the store, 0 to compute)" in capsys.readouterr().err
    assert _tables(out) == first
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--fresh", "--no-report"]) == 0
    assert "(0 reused from the store, 8 to compute)" in capsys.readouterr().err
    assert _tables(out) == first


def test_changed_spec_or_code_is_recomputed(tmp_path, capsys, monkeypatch):
    exp = _write(tmp_path, TINY, "tiny")
    out = tmp_path / "out"
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    capsys.readouterr()
    exp.write_text(TINY.replace("vary.h = [0.05, 0.1]", "vary.h = [0.05, 0.2]"))
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    assert "(4 reused from the store, 4 to compute)" in capsys.readouterr().err
    monkeypatch.setattr(store_module, "_fingerprint", "another version of the code")
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    assert "(0 reused from the store, 8 to compute)" in capsys.readouterr().err


def test_a_damaged_record_head_is_said_once_and_the_cells_after_it_are_recomputed(tmp_path,
                                                                                  capsys):
    exp = _write(tmp_path, TINY, "tiny")
    out = tmp_path / "out"
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    first = _tables(out)
    segment = max((out / "parts").glob("*.seg"))
    fourth = _record_of(segment, 3)
    raw = segment.read_bytes()
    at = raw.index(fourth)
    segment.write_bytes(raw[:at] + b"X" + raw[at + 1:])      # the head of the 4th record
    capsys.readouterr()
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    err = capsys.readouterr().err
    warnings = [ln for ln in err.splitlines() if ln.startswith("gnibench: warning:")]
    assert len(warnings) == 1 and "damaged after 3 records" in warnings[0]
    assert "(3 reused from the store, 5 to compute)" in err
    assert _tables(out) == first
    capsys.readouterr()
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    err = capsys.readouterr().err
    assert "(8 reused from the store, 0 to compute)" in err        # the new records replace them
    assert len([ln for ln in err.splitlines() if "warning" in ln]) == 1    # said again, once


def test_replaced_records_are_compacted(tmp_path, capsys):
    """--fresh runs append new records of the same keys; once most stored bytes are replaced ones,
    the live records are copied into one segment and the old segments removed; nothing changes in
    the tables or in what is reused."""
    exp = _write(tmp_path, TINY, "tiny")
    out = tmp_path / "out"
    for _ in range(3):
        assert main(["run", str(exp), "-o", str(out), "-j", "1", "--fresh", "--no-report"]) == 0
    first = _tables(out)
    assert len(list((out / "parts").glob("*.seg"))) == 3
    with Store(out) as store:                 # below the size threshold: kept as they are
        assert len(store._index) == 8
        assert store.compact(least=0)
    assert len(list((out / "parts").glob("*.seg"))) == 1 and _records(out) == 8
    capsys.readouterr()
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    assert "(8 reused from the store, 0 to compute)" in capsys.readouterr().err
    assert _tables(out) == first


def test_a_fifo_in_place_of_a_part_is_recomputed_not_waited_on(tmp_path):
    """A FIFO where a segment of stored cells was: opening it would wait for a writer forever.
    The rerun (in a process of its own, so that a hang fails the test by its timeout) says so
    once and recomputes the cells that segment held."""
    import os
    import subprocess
    import sys

    exp = _write(tmp_path, TINY, "tiny")
    out = tmp_path / "out"
    command = [sys.executable, "-m", "gnibench.suite.cli.entry", "run", str(exp), "-o", str(out),
               "-j", "1", "--no-report"]
    assert subprocess.run(command, capture_output=True, timeout=600, check=False).returncode == 0
    first = _tables(out)
    part = max((out / "parts").glob("*.seg"))
    part.unlink()
    os.mkfifo(part)
    again = subprocess.run(command, capture_output=True, text=True, timeout=240, check=False)
    assert again.returncode == 0, again.stderr
    assert "(0 reused from the store, 8 to compute)" in again.stderr
    assert "is a FIFO, not a regular file" in again.stderr
    assert _tables(out) == first and not part.is_fifo()


def test_lock_keeps_a_second_run_off(tmp_path, capsys):
    exp = _write(tmp_path, TINY, "tiny")
    out = tmp_path / "out"
    with Store(out):
        assert main(["run", str(exp), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is in use by another gnibench run" in err[0]
    assert not (out / "cells.parquet").exists()


def test_executors_give_byte_identical_tables(tmp_path):
    """Serial, a 2-process pool and a 2-worker Dask LocalCluster (a real one)."""
    pytest.importorskip("distributed")
    outs = three_executors(_write(tmp_path, TINY, "tiny"), tmp_path)
    assert _tables(outs["pool"]) == _tables(outs["serial"])
    assert _tables(outs["dask"]) == _tables(outs["serial"])


@pytest.mark.parametrize("args,message", [
    (["--executor", "spark"], "bad --executor 'spark'"),
    (["-j", "0"], "bad -j 0"),
    (["--scheduler", "tcp://1.2.3.4:1"], "--scheduler needs --executor dask"),
])
def test_bad_executor_options(tmp_path, capsys, args, message):
    exp = _write(tmp_path, TINY, "tiny")
    out = tmp_path / "out"
    assert main(["run", str(exp), "-o", str(out), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not out.exists()


def test_ctrl_c_stops_a_long_solve_and_keeps_the_samples(tmp_path):
    """10^13 steps would take days (beyond the default step budget, raised here); SIGINT once the
    integration runs (its first progress line: a condition, not a clock) stops it, the samples
    so far are written, exit 130. The timeouts only catch a hang."""
    out = tmp_path / "partial.csv"
    proc = subprocess.Popen(GNIBENCH + ["solve", "kepler-2d", "rk4:h=1e-9", "--t-end", "10000",
                                        "--every", "100000000", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "GNIBENCH_MAX_STEPS": "1e14"})
    first = proc.stderr.readline()                # written 2 s into the integration
    assert "%" in first, first
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=300)
    assert proc.returncode == 130
    lines = out.read_text().splitlines()
    assert lines[0].startswith("t,") and len(lines) >= 2
    assert "Traceback" not in proc.stderr.read()


def test_a_flipped_bit_in_a_stored_part_is_recomputed_with_one_warning(tmp_path, capsys):
    """One bit of one sample value inside a record, the segment still readable: the part's digest
    no longer matches its content; it is recomputed, and the tables are as before."""
    import struct

    import pandas as pd

    exp = _write(tmp_path, TINY, "tiny")
    out = tmp_path / "out"
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    first = _tables(out)
    samples = pd.read_parquet(out / "samples.parquet")
    segment = max((out / "parts").glob("*.seg"))
    raw = bytearray(segment.read_bytes())
    needle = next(struct.pack("<d", v) for v in samples["q1"].dropna().to_numpy()
                  if v != 0 and raw.count(struct.pack("<d", v)) == 1)
    raw[raw.index(needle)] ^= 1
    segment.write_bytes(bytes(raw))
    capsys.readouterr()
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    err = capsys.readouterr().err
    warnings = [ln for ln in err.splitlines() if ln.startswith("gnibench: warning:")]
    assert len(warnings) == 1 and segment.name in warnings[0] and "checksum" in warnings[0]
    assert "(7 reused from the store, 1 to compute)" in err
    assert _tables(out) == first


def test_plain_progress_lines_when_not_a_terminal(tmp_path):
    exp = _write(tmp_path, TINY, "tiny")
    run = subprocess.run(GNIBENCH + ["run", str(exp), "-o", str(tmp_path / "out"), "-j", "2"],
                         check=True, capture_output=True, text=True,
                         env={**os.environ, "COLUMNS": "100"})
    lines = run.stderr.strip().splitlines()
    assert lines[0].startswith("gnibench: tiny: 8 cells")
    done = [ln for ln in lines if re.match(r"\[\d+/8\] \d+ s: cell \d+: ", ln)]
    assert len(done) == 8            # one per finished cell ("running: ..." lines come with time)
    assert "\r" not in run.stderr


def test_tables_of_two_writes_are_refused_in_one_line(tmp_path, capsys):
    """A run killed between writing samples.parquet and cells.parquet leaves tables of two of its
    writes side by side; the report and the API refuse them in one line instead of reading the
    mix (here cells.parquet is made as the write before would have made it: one cell fewer)."""
    import json

    import gnibench
    import pyarrow.parquet as pq

    out = tmp_path / "out"
    assert main(["run", str(_write(tmp_path, TINY, "tiny")), "-o", str(out), "-j", "1",
                 "--no-report"]) == 0
    gnibench.report([out], output=tmp_path / "site")                 # one write: read as usual
    table = pq.read_table(out / "cells.parquet")
    meta = json.loads(table.schema.metadata[b"gnibench"])
    meta["cells_done"] -= 1
    pq.write_table(table.replace_schema_metadata({**table.schema.metadata,
                                                  b"gnibench": json.dumps(meta).encode()}),
                   out / "cells.parquet")
    capsys.readouterr()
    assert main(["report", str(out), "-o", str(tmp_path / "site2")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "come from two writes" in err[0] and "Traceback" not in err[0]
    assert not (tmp_path / "site2").exists()
    from gnibench.suite.api.running import read_tables

    with pytest.raises(gnibench.UserError, match="come from two writes"):
        read_tables(out, out)
