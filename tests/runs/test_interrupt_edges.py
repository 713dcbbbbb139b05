"""Interruptions at the edges of a command (issue 43 item 4): a signal that a library turns into
another error, and a hard exit while a results directory is locked.

Each test sends its signal from inside the process at a chosen point (a deterministic hook),
never after a delay.
"""
from __future__ import annotations

import subprocess
import sys

import pytest

SAFETY = 300.0

# A library catches the KeyboardInterrupt of a SIGINT and raises another error from it, as a C
# extension's module init does (pandas: "SystemError: ... returned a result with an exception
# set", seen when the signal came while the tables' writer first imported pandas).
TURNED_IN_THE_COMMAND = """
import os, signal, sys
from gnibench.suite.cli import entry, main

def command(a):
    try:
        os.kill(os.getpid(), signal.{sig})
        signal.pause()
    except KeyboardInterrupt as e:
        raise SystemError("<class '__pyx_defaults'> returned a result with an exception set") from e

main._list = command
sys.argv = ["gnibench", "list", "methods"]
entry.main()
"""

# The same during the console script's own imports (before the command's handlers).
TURNED_IN_THE_IMPORTS = """
import os, signal, sys
from gnibench.suite.cli import entry

class Finder:                   # the command line's module is imported: the signal comes, and
    def find_spec(self, name, path=None, target=None):      # its import fails from it
        if name == "gnibench.suite.cli.main":
            try:
                os.kill(os.getpid(), signal.SIGINT)
                signal.pause()
            except KeyboardInterrupt as e:
                raise SystemError("returned a result with an exception set") from e
        return None

sys.meta_path.insert(0, Finder())
entry.main()
"""


@pytest.mark.parametrize("sig,code,line", [("SIGINT", 130, "gnibench: interrupted"),
                                           ("SIGTERM", 143, "gnibench: terminated")])
def test_an_interrupt_turned_into_another_error_is_the_interrupt(sig, code, line):
    out = subprocess.run([sys.executable, "-c", TURNED_IN_THE_COMMAND.format(sig=sig)],
                         check=False, capture_output=True, text=True, timeout=SAFETY)
    assert (out.returncode, out.stderr.strip()) == (code, line), out.stderr[-3000:]


def test_an_interrupt_turned_into_another_error_during_the_imports_is_the_interrupt():
    out = subprocess.run([sys.executable, "-c", TURNED_IN_THE_IMPORTS], check=False,
                         capture_output=True, text=True, timeout=SAFETY)
    assert (out.returncode, out.stderr.strip()) == (130, "gnibench: interrupted"), \
        out.stderr[-3000:]


AN_ERROR_AFTER_THE_INTERRUPT = """
import os, signal, sys
from gnibench.suite.cli import entry, main

def command(a):
    try:
        os.kill(os.getpid(), signal.SIGINT)
        signal.pause()
    except KeyboardInterrupt:
        pass                    # handled: what follows is not raised from it
    raise SystemError("a bug of ours")

main._list = command
sys.argv = ["gnibench", "list", "methods"]
entry.main()
"""


def test_an_error_of_its_own_after_an_interrupt_is_not_hidden():
    """Only an error raised while the interrupt propagates is taken for it: a bug stays one."""
    out = subprocess.run([sys.executable, "-c", AN_ERROR_AFTER_THE_INTERRUPT], check=False,
                         capture_output=True, text=True, timeout=SAFETY)
    assert out.returncode == 1 and "SystemError: a bug of ours" in out.stderr, out.stderr[-3000:]


# A run holds its results directory's lock while the main thread is in numba (here: a frame of a
# module named numba.*), where a signal is only marked pending: the watchdog ends the process
# after GRACE (the "hard exit").
HARD_EXIT_HOLDING_A_LOCK = """
import sys
from gnibench.suite.cli import signals
from gnibench.suite.runs.lock import DirectoryLock

with signals.handling():
    DirectoryLock(sys.argv[1]).acquire()
    exec("print('locked', flush=True)\\nwhile True:\\n    pass", {"__name__": "numba.compiling"})
"""


def test_a_hard_exit_empties_the_lock_so_the_next_run_takes_it_silently(tmp_path, capsys):
    """A Ctrl-C during a cold compile of ``gnibench run -j 1`` ended it at once, as designed,
    but left ``pid N`` in the lock: the next run warned "left locked by pid N, which is gone
    (killed?); lock taken over" after an orderly interrupt."""
    import signal

    from gnibench.suite.runs.lock import DirectoryLock

    proc = subprocess.Popen([sys.executable, "-c", HARD_EXIT_HOLDING_A_LOCK, str(tmp_path)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "locked"
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=SAFETY)
    err = proc.stderr.read()
    assert proc.returncode == 130 and "while compiling" in err, err
    assert (tmp_path / ".lock").read_text() == ""
    lock = DirectoryLock(tmp_path)
    lock.acquire()
    lock.release()
    assert "warning" not in capsys.readouterr().err


# The command's handling has ended (its handlers are restored to the console script's early
# ones) and a SIGTERM comes before the process ends.
SIGTERM_AS_THE_HANDLING_ENDS = """
import os, signal, sys
from gnibench.suite.cli import entry, signals

real = signals.watch_signals

def watch(on):                  # called as handling() ends, its handlers already restored
    real(on)
    if not on:
        os.kill(os.getpid(), signal.SIGTERM)

signals.watch_signals = watch
sys.argv = ["gnibench", "list", "metrics"]
entry.main()
"""


def test_a_sigterm_as_the_handling_ends_is_named_terminated_with_exit_143():
    """Seen: ``kill -TERM`` as ``gnibench verify`` printed its last line gave "gnibench:
    interrupted" and exit code 130 (the early handler saw it, the message read the command's)."""
    out = subprocess.run([sys.executable, "-c", SIGTERM_AS_THE_HANDLING_ENDS], check=False,
                         capture_output=True, text=True, timeout=SAFETY)
    assert (out.returncode, out.stderr.strip()) == (143, "gnibench: terminated"), out.stderr


def test_an_interrupt_after_every_cell_was_stored_says_to_finish(tmp_path, monkeypatch):
    """The line of an interrupt while the last tables were written said "run the same command
    again to compute the rest" with every cell stored."""
    import io

    from gnibench.suite.runs import runner

    exp = tmp_path / "two.toml"
    exp.write_text('name = "two"\ntitle = "Two cells"\nreference = "[HLW] (2.2)"\nsteps = 10\n'
                   '[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["rk4"]\nvary.h = [0.1, 0.2]\n')
    real, raised = runner.Consolidator.flush, []

    def flush(self, done):
        if len(done) == 2 and not raised:         # a write with both cells stored: a Ctrl-C
            raised.append(True)
            raise KeyboardInterrupt
        return real(self, done)

    monkeypatch.setattr(runner.Consolidator, "flush", flush)
    log = io.StringIO()
    with pytest.raises(KeyboardInterrupt):
        runner.run_experiment(str(exp), tmp_path / "out", jobs=1, log=log)
    assert "2 of 2 cells are stored" in log.getvalue()
    assert "run the same command again to finish" in log.getvalue(), log.getvalue()
