"""Careless and hostile input to the command line (issue 18): one line, exit 2, nothing written,
before any work; faults during work (a full disk, a closed pipe) are one line and lose nothing
finished.

Classes: numbers (one ASCII grammar everywhere), output files (regular files only, probed before
work), budgets given as environment variables, the report and bench commands, ``verify --list``,
standard streams that close or fill up.
"""
from __future__ import annotations

import contextlib
import errno
import json
import os
import stat
import subprocess
import sys
import threading
from pathlib import Path

import pandas as pd
import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.outputs import check_output_file

GNIBENCH = str(Path(sys.executable).with_name("gnibench"))
OSC = "harmonic-oscillator"
SOLVE = ["solve", OSC, "rk4:h=0.1", "--steps", "20"]
TINY = """
name = "tiny"
title = "Tiny"
reference = "[HLW] (2.2)"
steps = 40
every = 10

[[cells]]
problems = ["harmonic-oscillator", "pendulum"]
methods = ["rk4"]
vary.h = [0.05, 0.1]
"""


def one_error_line(code, err, status=2):
    lines = err.strip().splitlines()
    assert code == status, err
    assert len(lines) == 1 and lines[0].startswith("gnibench: error:"), err
    assert "Traceback" not in err
    return lines[0]


def run(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


# ---- numbers: one grammar for every option and budget ---------------------------------------

BAD_NUMBERS = ["١٠", "1_0", "inf", "nan", "1e400", "0x10", "", " "]
NUMBER_OPTIONS = {
    "--steps": ["solve", OSC, "rk4:h=0.1", "--steps", "{}"],
    "--t-end": ["solve", OSC, "rk4:h=0.1", "--t-end", "{}"],
    "--every": ["solve", OSC, "rk4:h=0.1", "--steps", "10", "--every", "{}"],
    "--dt-out": ["solve", OSC, "rk4:h=0.1", "--steps", "10", "--dt-out", "{}"],
    "--section": ["solve", "henon-heiles", "rk4:h=0.1", "--steps", "10", "--section", "{}"],
    "-j": ["run", "quick", "-j", "{}"],
    "--accuracy": ["report", ".", "--accuracy", "{}"],
    "bench --steps": ["bench", "--steps", "{}"],
    "--threshold": ["bench", "--threshold", "{}"],
}


@pytest.mark.parametrize("text", BAD_NUMBERS)
@pytest.mark.parametrize("option", list(NUMBER_OPTIONS))
def test_numbers_are_ascii_finite_and_checked_before_work(option, text, capsys, tmp_path,
                                                          monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = [a.format(text) for a in NUMBER_OPTIONS[option]]
    code, out, err = run(argv, capsys)
    line = one_error_line(code, err)
    assert option.split()[-1] in line
    assert out == "" and not list(tmp_path.iterdir())


@pytest.mark.parametrize("value", ["1e14", "100000000000000"])
def test_integral_counts_may_use_an_exponent(value, capsys):
    """--steps 1e14 is a number of steps (refused here by the step budget, not as text)."""
    code, _out, err = run(["solve", OSC, "rk4:h=0.1", "--steps", value], capsys)
    assert "GNIBENCH_MAX_STEPS" in one_error_line(code, err)


@pytest.mark.parametrize("name", ["GNIBENCH_MAX_STEPS", "GNIBENCH_MAX_ROWS",
                                  "GNIBENCH_MAX_OUTPUT_MB", "GNIBENCH_MAX_CELLS"])
@pytest.mark.parametrize("text", ["inf", "-inf", "nan", "1_0", "١٠", "0", "-5", "2.5", "lots"])
def test_budget_variables_are_checked_before_work(name, text, capsys, monkeypatch, tmp_path):
    monkeypatch.setenv(name, text)
    out_path = tmp_path / "x.csv"
    code, _out, err = run(SOLVE + ["-o", str(out_path)], capsys)
    assert name in one_error_line(code, err)
    assert not out_path.exists()


def test_budget_variables_accept_exponents(capsys, monkeypatch):
    monkeypatch.setenv("GNIBENCH_MAX_STEPS", "1e3")
    code, _out, err = run(["solve", OSC, "rk4:h=0.1", "--steps", "1001"], capsys)
    assert "at most 1000" in one_error_line(code, err)
    assert run(["solve", OSC, "rk4:h=0.1", "--steps", "1000"], capsys)[0] == 0


def test_disabled_jit_is_refused_before_work(capsys, monkeypatch, tmp_path):
    """NUMBA_DISABLE_JIT=1 made every cell of a run end in error (stored, and reused by the next
    run without it) and a solve a traceback."""
    monkeypatch.setenv("NUMBA_DISABLE_JIT", "1")
    out = tmp_path / "out"
    for argv in (SOLVE, ["run", "quick", "-o", str(out), "-j", "1"]):
        code, _out, err = run(argv, capsys)
        assert "NUMBA_DISABLE_JIT" in one_error_line(code, err)
    assert not out.exists()
    monkeypatch.setenv("NUMBA_DISABLE_JIT", "0")
    assert run(SOLVE, capsys)[0] == 0


BAD_NUMBA = [("NUMBA_DISABLE_JIT", "x"), ("NUMBA_DISABLE_JIT", ""), ("NUMBA_DISABLE_JIT", "2"),
             ("NUMBA_OPT", "x"), ("NUMBA_OPT", "4"), ("NUMBA_OPT", ""), ("NUMBA_OPT", " 3"),
             ("NUMBA_NUM_THREADS", "x"), ("NUMBA_NUM_THREADS", "0"), ("NUMBA_NUM_THREADS", "-1"),
             ("NUMBA_NUM_THREADS", "1_0"), ("NUMBA_NUM_THREADS", "١"), ("NUMBA_NUM_THREADS", ""),
             ("NUMBA_BOUNDSCHECK", "x"), ("NUMBA_BOUNDSCHECK", "2"),
             ("NUMBA_CACHE_DIR", "{file}"), ("NUMBA_CACHE_DIR", "{file}/sub"),
             ("NUMBA_CACHE_DIR", " "), ("NUMBA_CACHE_DIR", "{dangling}")]


@pytest.mark.parametrize("name, text", BAD_NUMBA)
def test_bad_numba_settings_are_refused_before_numba_reads_them(name, text, tmp_path):
    """numba printed its own multi-line warning (a traceback inside a RuntimeWarning) and went on
    with its default, exit 0; NUMBA_NUM_THREADS=0 was a traceback; a NUMBA_CACHE_DIR that is a
    file was ignored without a word. Run in a fresh process: numba reads them when imported."""
    (tmp_path / "file").write_text("")
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    value = text.format(file=tmp_path / "file", dangling=tmp_path / "dangling")
    out_path = tmp_path / "x.csv"
    env = {**os.environ, name: value}
    p = subprocess.run([GNIBENCH, *SOLVE, "-o", str(out_path)], capture_output=True, text=True,
                       env=env, check=False)
    line = one_error_line(p.returncode, p.stderr)
    assert f"bad {name}=" in line and "allowed:" in line
    assert not out_path.exists()


@pytest.mark.parametrize("name, text", [("NUMBA_DISABLE_JIT", " 0"), ("NUMBA_OPT", "max"),
                                        ("NUMBA_OPT", "0"), ("NUMBA_NUM_THREADS", "3"),
                                        ("NUMBA_BOUNDSCHECK", "0"), ("NUMBA_CACHE_DIR", ""),
                                        ("NUMBA_CACHE_DIR", "{tmp}/new/numba")])
def test_good_numba_settings_are_accepted(name, text, tmp_path):
    from gnibench.suite.foundation.numba_settings import check_numba_settings

    check_numba_settings({name: text.format(tmp=tmp_path)})
    assert not (tmp_path / "new").exists()            # checked, not created


@pytest.mark.parametrize("value", [":::", "", " : ", ":"])
def test_empty_gnibench_load_entries_are_skipped(value, capsys, monkeypatch):
    """Empty entries are skipped (``GNIBENCH_LOAD="$GNIBENCH_LOAD:defs.toml"`` with the variable
    unset starts with one); nothing is loaded, nothing is said."""
    from gnibench.suite.cell.user import loader

    monkeypatch.setattr(loader, "_discovered", False)
    monkeypatch.setenv("GNIBENCH_LOAD", value)
    assert loader.load_paths() == []
    code, out, err = run(["list", "methods"], capsys)
    assert code == 0 and err == "" and "rk4" in out


@pytest.mark.parametrize("entry", ["missing.toml", "{dir}", "{file}"])
@pytest.mark.parametrize("command", [["list", "methods"], SOLVE, ["run", "quick", "-j", "1"]])
def test_a_bad_gnibench_load_entry_is_one_line_before_work(entry, command, capsys, monkeypatch,
                                                           tmp_path):
    from gnibench.suite.cell.user import loader

    monkeypatch.chdir(tmp_path)
    (tmp_path / "file.toml").write_text("not = toml = at all\n")
    entry = entry.format(dir=tmp_path, file=tmp_path / "file.toml")
    monkeypatch.setattr(loader, "_discovered", False)
    monkeypatch.setenv("GNIBENCH_LOAD", f"::{entry}:")
    before = set(tmp_path.iterdir())
    code, out, err = run(command, capsys)
    line = one_error_line(code, err)
    assert line.startswith("gnibench: error: GNIBENCH_LOAD: ") and Path(entry).name in line
    assert out == "" and set(tmp_path.iterdir()) == before
    assert not loader._discovered                       # the next call says so again


def test_cells_that_ended_in_error_are_computed_again(tmp_path, capsys, monkeypatch):
    """An unexpected failure is not a result of a cell's inputs: the next run computes the cell
    again (the tables then hold the new part, not the one in error read at the start)."""
    from gnibench.suite.cell import driver

    exp = tmp_path / "tiny.toml"
    exp.write_text(TINY)
    out = tmp_path / "out"
    real = driver.integrate

    def broken(spec, **k):
        if spec.problem.record.id == "pendulum":
            raise MemoryError("out of memory")
        return real(spec, **k)

    monkeypatch.setattr(driver, "integrate", broken)
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    cells = pd.read_parquet(out / "cells.parquet")
    assert sorted(cells["status"]) == ["error", "error", "ok", "ok"]
    monkeypatch.setattr(driver, "integrate", real)
    capsys.readouterr()
    assert main(["run", str(exp), "-o", str(out), "-j", "1", "--no-report"]) == 0
    err = capsys.readouterr().err
    assert "(2 reused from the store, 2 to compute, 2 of them ended in error before)" in err
    assert list(pd.read_parquet(out / "cells.parquet")["status"]) == ["ok"] * 4


def _unblock(fifo: Path, stop: threading.Event, every: float = 20.0) -> None:
    """Open ``fifo`` for writing and close it every ``every`` seconds until ``stop``: a reader
    blocked on it (the bug) then reads an end of file and the test fails instead of hanging.
    Without a reader the non-blocking open fails at once and nothing happens."""
    while not stop.wait(every):
        with contextlib.suppress(OSError):
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))


@pytest.mark.parametrize("kind", ["fifo", "device", "directory"])
def test_input_files_are_regular_files(kind, tmp_path, capsys):
    """A FIFO given as --load or as the experiment blocked the read for ever, /dev/zero never
    ended it (memory grew without a bound): refused before they are read."""
    path = {"fifo": tmp_path / "in.toml", "device": Path("/dev/zero"),
            "directory": tmp_path / "dir.toml"}[kind]
    stop = threading.Event()
    if kind == "fifo":
        os.mkfifo(path)
        threading.Thread(target=_unblock, args=(path, stop), daemon=True).start()
    elif kind == "directory":
        path.mkdir()
    try:
        for argv in (SOLVE + ["--load", str(path)], ["run", str(path), "-o", str(tmp_path / "o")]):
            code, _out, err = run(argv, capsys)
            assert "allowed: a regular file" in one_error_line(code, err)
    finally:
        stop.set()
    assert not (tmp_path / "o").exists()


# ---- output files: regular files only ----------------------------------------------------------

def test_fifo_and_symlink_outputs_are_refused_and_left_alone(tmp_path, capsys):
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    target = tmp_path / "target.csv"
    target.write_text("keep me\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    for path, kind in ((fifo, "FIFO"), (link, "symlink")):
        for fmt in ("csv", "json", "parquet"):
            code, _out, err = run(SOLVE + ["--format", fmt, "-o", str(path)], capsys)
            assert kind in one_error_line(code, err)
    assert stat.S_ISFIFO(fifo.lstat().st_mode) and link.is_symlink()
    assert target.read_text() == "keep me\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo.csv", "link.csv", "target.csv"]


@pytest.mark.parametrize("device", ["/dev/null", "/dev/full"])
def test_device_outputs_are_refused(device):
    """Checked on the real devices without writing (run as root, a rename would replace them)."""
    with pytest.raises(UserError, match="character device"):
        check_output_file(Path(device))

def test_a_broken_symlink_as_the_results_directory_is_named(tmp_path, capsys):
    link = tmp_path / "out"
    link.symlink_to(tmp_path / "gone" / "dir")
    code, _out, err = run(["run", "quick", "-o", str(link)], capsys)
    assert "broken symlink" in one_error_line(code, err)
    assert not (tmp_path / "gone").exists()


@pytest.mark.parametrize("place", ["/proc/gnibench-x.csv", "/proc/self/x.csv", "/sys/x.csv"])
def test_outputs_where_nothing_can_be_created_are_refused(place, capsys):
    if not Path(place).parent.is_dir():
        pytest.skip(f"no {Path(place).parent}")
    code, _out, err = run(SOLVE + ["-o", place], capsys)
    assert "cannot write" in one_error_line(code, err) or "not writable" in err


def test_disk_full_while_writing_is_one_line_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    """ENOSPC in solve -o, simulated in the write itself (part of a file, then the error)."""
    import builtins

    import pyarrow.parquet as pq
    from gnibench.suite.runs import writers

    out_path = tmp_path / "x.parquet"

    class Full:
        """A text file that takes 9 characters, then the disk is full."""

        def __init__(self, path, *a, **k):
            self.f = builtins.open(path, *a, **k)

        def write(self, text):
            self.f.write(text[:9])
            raise OSError(errno.ENOSPC, "No space left on device")

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.f.close()

    monkeypatch.setattr(writers, "open", Full, raising=False)
    for fmt in ("csv", "json"):
        code, _, err = run(SOLVE + ["--format", fmt, "-o", str(tmp_path / f"x.{fmt}")], capsys)
        assert "No space left on device" in one_error_line(code, err, status=1)

    class FullParquet:
        def __init__(self, path, schema, **k):
            Path(path).write_bytes(b"PAR1 half")

        def write_table(self, table, **k):
            raise OSError(errno.ENOSPC, "No space left on device")

        def close(self):
            pass

    monkeypatch.setattr(pq, "ParquetWriter", FullParquet)
    code, _out, err = run(SOLVE + ["--format", "parquet", "-o", str(out_path)], capsys)
    assert "No space left on device" in one_error_line(code, err, status=1)
    assert not list(tmp_path.iterdir())          # no result, no temporary file


def test_stdout_on_a_full_device_is_one_line():
    with open("/dev/full", "w") as full:
        p = subprocess.run([GNIBENCH, *SOLVE], stdout=full, stderr=subprocess.PIPE, text=True,
                           timeout=300, check=False)
    assert "No space left on device" in one_error_line(p.returncode, p.stderr, status=1)


def test_disk_full_during_a_run_keeps_the_stored_cells_and_a_rerun_completes(tmp_path, capsys,
                                                                            monkeypatch):
    from gnibench.suite.runs import store

    exp = tmp_path / "tiny.toml"
    exp.write_text(TINY)
    whole, full = tmp_path / "whole", tmp_path / "full"
    assert main(["run", str(exp), "-o", str(whole), "-j", "1", "--no-report"]) == 0
    written = []
    real = store.Store.write

    def write(self, key, part, empty):
        if len(written) == 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        written.append(key)
        real(self, key, part, empty)

    monkeypatch.setattr(store.Store, "write", write)
    capsys.readouterr()
    code = main(["run", str(exp), "-o", str(full), "-j", "1", "--no-report"])
    err = [ln for ln in capsys.readouterr().err.splitlines() if not ln.startswith("[")]
    assert code == 1 and err[-1].startswith("gnibench: error:"), err
    assert "No space left on device" in err[-1] and "2 of 4 cells are stored" in err[-1]
    assert len(list((full / "parts").glob("*.parquet"))) == 2
    monkeypatch.setattr(store.Store, "write", real)
    assert main(["run", str(exp), "-o", str(full), "-j", "1", "--no-report"]) == 0
    assert "(2 reused from the store, 2 to compute)" in capsys.readouterr().err
    for name in ("samples.parquet", "cells.parquet"):
        assert (full / name).read_bytes() == (whole / name).read_bytes()


def test_a_fresh_run_stopped_early_counts_its_stored_cells_and_says_drop_fresh(tmp_path, capsys,
                                                                             monkeypatch):
    """A signal between a cell's commit and its read-back: the cell is stored and counted (it was
    left out of 'k of n cells are stored'); after --fresh the advice is to run again without it
    (the same command would ignore what was stored)."""
    from gnibench.suite.runs import store

    exp = tmp_path / "tiny.toml"
    exp.write_text(TINY)
    real = store.Store.read
    computed = []

    def read(self, key):
        if key in computed and len(computed) == 1:   # the read-back of the first cell stored
            computed.append("interrupted")
            raise KeyboardInterrupt
        return real(self, key)

    def write(self, key, part, empty, real_write=store.Store.write):
        real_write(self, key, part, empty)
        computed.append(key)

    monkeypatch.setattr(store.Store, "read", read)
    monkeypatch.setattr(store.Store, "write", write)
    code = main(["run", str(exp), "-o", str(tmp_path / "out"), "-j", "1", "--no-report",
                 "--fresh"])
    err = capsys.readouterr().err
    assert code == 130 and "1 of 4 cells are stored" in err, err
    assert "run it again without --fresh" in err
    assert len(list((tmp_path / "out" / "parts").glob("*.parquet"))) == 1


# ---- report and bench -------------------------------------------------------------------------

@pytest.fixture(scope="module")
def results(tmp_path_factory):
    d = tmp_path_factory.mktemp("results")
    (d / "tiny.toml").write_text(TINY)
    assert main(["run", str(d / "tiny.toml"), "-o", str(d / "out"), "-j", "1", "--no-report"]) == 0
    return d / "out"


def test_report_to_an_existing_file_or_a_read_only_place(results, tmp_path, capsys):
    taken = tmp_path / "site"
    taken.write_text("not a directory")
    for site, needle in ((taken, "not a directory"), (Path("/proc/site"), "cannot write")):
        code, _out, err = run(["report", str(results), "-o", str(site)], capsys)
        assert needle in one_error_line(code, err)
    assert taken.read_text() == "not a directory"


def test_disk_full_while_writing_a_report_page_is_one_line_naming_it(results, tmp_path, capsys,
                                                                    monkeypatch):
    """ENOSPC in a page of ``gnibench report``: one line naming the page, no half-written page
    (it was 'gnibench: error: No space left on device', naming nothing)."""
    real = Path.write_text

    def write_text(self, text, *a, **k):
        if self.name.startswith(".index.html"):
            real(self, text[:10], *a, **k)
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, text, *a, **k)

    monkeypatch.setattr(Path, "write_text", write_text)
    site = tmp_path / "site"
    code, _out, err = run(["report", str(results), "-o", str(site)], capsys)
    err = "\n".join(ln for ln in err.splitlines() if not ln.startswith("gnibench: report:"))
    assert str(site / "index.html") in one_error_line(code, err, status=1)
    assert not (site / "index.html").exists() and not list(site.glob(".index.html*"))


@pytest.mark.parametrize("damage", ["truncate", "garbage", "empty"])
def test_report_of_a_damaged_table_is_one_line(results, tmp_path, capsys, damage):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(results, copy)
    cells = copy / "cells.parquet"
    raw = cells.read_bytes()
    cells.write_bytes({"truncate": raw[: len(raw) // 2], "garbage": b"x" * 100,
                       "empty": b""}[damage])
    code, _out, err = run(["report", str(copy), "-o", str(tmp_path / "site")], capsys)
    assert "cells.parquet" in one_error_line(code, err)


def test_report_of_tables_of_another_program_is_one_line(tmp_path, capsys):
    """Parquet files under the tables' names but written by something else: a KeyError traceback
    (no 'method' column) before."""
    alien = tmp_path / "alien"
    alien.mkdir()
    for name in ("cells", "samples", "timings"):
        pd.DataFrame({"a": [1, 2]}).to_parquet(alien / f"{name}.parquet")
    code, _out, err = run(["report", str(alien), "-o", str(tmp_path / "site")], capsys)
    assert "not a gnibench table" in one_error_line(code, err)


def test_bench_storage_that_is_a_file_is_refused_before_timing(tmp_path, capsys, monkeypatch):
    from gnibench.suite.runs import bench

    def never(*a, **k):
        raise AssertionError("the benchmark ran before its storage was checked")

    monkeypatch.setattr(bench, "bench", never)
    storage = tmp_path / "bench"
    storage.write_text("a file")
    code, out, err = run(["bench", "--storage", str(storage)], capsys)
    assert "--storage" in one_error_line(code, err)
    code, out, err = run(["bench", "--steps", "1e14"], capsys)
    assert "GNIBENCH_MAX_STEPS" in one_error_line(code, err) and out == ""


# ---- verify --list --------------------------------------------------------------------------

def test_verify_list_speaks_json_and_refuses_run_options(capsys, tmp_path):
    code, out, err = run(["verify", "--list", "--format", "json"], capsys)
    assert code == 0 and err == ""
    rows = json.loads(out)
    assert rows and {"id", "expected", "citation"} <= set(rows[0])
    code, text, err = run(["verify", "--list"], capsys)
    assert code == 0 and [r["id"] for r in rows] == [ln.split()[0] for ln in text.splitlines()]
    for extra in (["-o", str(tmp_path / "x")], ["-j", "3"], ["--no-report"]):
        code, out, err = run(["verify", "--list", *extra], capsys)
        assert "does not apply with --list" in one_error_line(code, err)
    assert not (tmp_path / "x").exists()


# ---- standard streams -----------------------------------------------------------------------

@pytest.mark.parametrize("argv", [["list", "methods"], SOLVE[:-1] + ["20000"]])
def test_a_reader_that_stops_reading_ends_nothing(argv):
    """``gnibench ... | head -1``: the first line arrives, nothing else is said, exit 0."""
    p = subprocess.Popen([GNIBENCH, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    first = p.stdout.readline()
    p.stdout.close()
    err = p.stderr.read().decode()
    assert p.wait(timeout=300) == 0, err
    assert first and err == ""


def _closing(*fds):
    return lambda: [os.close(fd) for fd in fds]


def test_closed_standard_streams(tmp_path):
    """``>&-`` and ``2>&-``: a solve to a closed stdout is refused before work (exit 2; it was a
    traceback after the work), one with -o completes; a closed stderr is silence, the exit code
    still says what happened (a traceback at the end made every code 1)."""
    p = subprocess.run([GNIBENCH, *SOLVE], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       text=True, timeout=300, check=False, preexec_fn=_closing(1))
    assert "stdout is closed" in one_error_line(p.returncode, p.stderr)
    out = tmp_path / "x.csv"
    p = subprocess.run([GNIBENCH, *SOLVE, "-o", str(out)], stderr=subprocess.PIPE, text=True,
                       timeout=300, check=False, preexec_fn=_closing(1, 2))
    assert p.returncode == 0 and out.read_text().startswith("t,")
    p = subprocess.run([GNIBENCH, "solve", OSC, "rk4:h=-1", "--steps", "10"], timeout=300,
                       check=False, preexec_fn=_closing(2))
    assert p.returncode == 2


def test_a_run_goes_on_when_its_progress_reader_goes_away(tmp_path):
    """``gnibench run ... 2>&1 | head -1``: the run completes and writes its tables."""
    exp = tmp_path / "tiny.toml"
    exp.write_text(TINY)
    p = subprocess.Popen([GNIBENCH, "run", str(exp), "-o", str(tmp_path / "out"), "-j", "1",
                          "--no-report"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    assert p.stdout.readline().startswith(b"gnibench: tiny:")
    p.stdout.close()
    assert p.wait(timeout=300) == 0
    assert (tmp_path / "out" / "cells.parquet").is_file()
    assert len(pd.read_parquet(tmp_path / "out" / "cells.parquet")) == 4


@pytest.mark.parametrize("name", ["/dev/stdout", "-"])
def test_stdout_named_as_the_output_file_is_stdout(name):
    """``-o /dev/stdout`` (a symlink to the process's stdout, a pipe here) is stdout, as in most
    tools (before: refused with the hint "a regular file, e.g. /proc/<pid>/fd/pipe:[...]")."""
    done = subprocess.run([GNIBENCH, *SOLVE, "-o", name], capture_output=True, text=True,
                          check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0].startswith("t,") and len(done.stdout.splitlines()) == 22


def test_a_symlink_output_gets_a_hint_that_helps(tmp_path, capsys):
    link = tmp_path / "link"
    link.symlink_to("/dev/null")
    line = one_error_line(*run([*SOLVE, "-o", str(link)], capsys)[::2])
    assert "to write to stdout, leave out -o" in line and "/proc/" not in line
    other = tmp_path / "other"
    other.symlink_to(tmp_path / "real.csv")
    line = one_error_line(*run([*SOLVE, "-o", str(other)], capsys)[::2])
    assert f"allowed: its target, {tmp_path / 'real.csv'}" in line
