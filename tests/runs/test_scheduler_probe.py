"""``--scheduler ADDRESS``: a peer that is not a Dask scheduler fails in one line, within the
timeout for the whole exchange, before the output directory exists (issue 18, Dask cases)."""
from __future__ import annotations

import contextlib
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError

pytest.importorskip("distributed")
from gnibench.suite.runs.scheduler import probe

SAFETY = 60.0
GNIBENCH = str(Path(sys.executable).with_name("gnibench"))


class Peer:
    """A TCP server on localhost that accepts and then says ``reply`` (or nothing)."""

    def __init__(self, reply: bytes | None):
        self.reply, self.connections = reply, []
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.connections.append(conn)
            self._on_connect(conn)

    def _on_connect(self, conn):
        if self.reply is not None:
            conn.sendall(self.reply)

    def close(self):
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_RDWR)   # wakes the thread blocked in accept (Linux)
        self.sock.close()
        for c in self.connections:
            c.close()


@pytest.fixture
def peer(request):
    p = Peer(request.param)
    yield p
    p.close()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("peer", [None], indirect=True)
def test_a_peer_that_never_answers_fails_within_the_timeout(peer):
    t0 = time.monotonic()
    with pytest.raises(UserError, match="sent nothing"):
        probe(peer.address, timeout=1.0)
    assert time.monotonic() - t0 < SAFETY


@pytest.mark.parametrize("peer", [b"HTTP/1.0 200 OK\r\nContent-Type: text/html\r\n\r\nhello\n",
                                  b"\xff" * 64], indirect=True)
def test_a_server_of_another_protocol_is_not_a_scheduler(peer, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["run", "quick", "-o", str(out), "--executor", "dask", "--scheduler",
                 peer.address])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "Dask" in err[0], err
    assert not out.exists()


class LinePeer(Peer):
    """A server of a line-based protocol (Redis, SMTP): it answers only once the client has sent
    a line."""

    def _on_connect(self, conn):
        threading.Thread(target=self._answer, args=(conn,), daemon=True).start()

    def _answer(self, conn):
        got = b""
        with contextlib.suppress(OSError):
            while b"\n" not in got:
                chunk = conn.recv(4096)
                if not chunk:
                    return
                got += chunk
            conn.sendall(b"-ERR unknown command\r\n")


def test_servers_that_wait_for_the_client_are_told_at_once():
    """The probe waited for the peer to speak first: an HTTP server, waiting for a request, took
    the whole timeout ("sent nothing within 10 s"). The probe now sends Dask's handshake first
    (both ends of a Dask connection send theirs at once), whose last key ends a line: such a
    server answers, and the answer is not Dask's (the timeout, 60 s here, is never reached)."""
    from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

    class Quiet(BaseHTTPRequestHandler):
        def log_message(self, *args):
            pass

    http = ThreadingHTTPServer(("127.0.0.1", 0), Quiet)
    # a connection select() reported can be gone before accept() (an asynchronous network
    # error: Linux accept(2), NOTES), and a blocking accept then waits for the next one: it hung
    # serve_forever, and http.shutdown() with it, forever (seen once, a full run slowed by a
    # sampling profiler). Non-blocking, as accept(2) advises: socketserver ignores the
    # BlockingIOError and polls again
    http.socket.setblocking(False)
    threading.Thread(target=http.serve_forever, daemon=True).start()
    line = LinePeer(None)
    try:
        for address in (f"tcp://127.0.0.1:{http.server_address[1]}", line.address):
            with pytest.raises(UserError, match="does not speak Dask's protocol"):
                probe(address, timeout=SAFETY)
    finally:
        http.shutdown()
        http.server_close()
        line.close()


def test_the_probe_sends_a_handshake_dask_can_read():
    """What the probe sends first is one framed message that distributed decodes as a handshake
    (distributed/comm/tcp.py: the 8-byte length, then the frames)."""
    import struct

    from distributed.protocol import loads
    from distributed.protocol.utils import unpack_frames
    from gnibench.suite.runs.scheduler import _handshake

    data = _handshake()
    (length,) = struct.unpack("<Q", data[:8])
    assert length == len(data) - 8
    info = loads(unpack_frames(data[8:]))
    assert {"compression", "python", "pickle-protocol"} <= set(info)


def test_a_closed_port_fails_at_once_and_creates_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    address = f"tcp://127.0.0.1:{_free_port()}"
    code = main(["run", "quick", "-o", str(out), "--executor", "dask", "--scheduler", address])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "cannot connect" in err[0], err
    assert not out.exists()


@pytest.mark.parametrize("address", ["tcp://[::1", "tcp://127.0.0.1:notaport", "inproc://nowhere",
                                     "tcp://name.invalid:8786"])
def test_malformed_or_unknown_addresses(address):
    with pytest.raises(UserError, match="bad scheduler="):
        probe(address, timeout=5.0)


def test_a_real_scheduler_answers():
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        info = probe(cluster.scheduler_address, timeout=10.0)
    assert info["type"] == "Scheduler"



@pytest.mark.parametrize("peer", [b"\x10" + b"\x00" * 7 + b"\x00" * 16], indirect=True)
def test_a_peer_with_a_plausible_length_and_garbage_is_one_line(peer, tmp_path):
    """The first 8 bytes pass as a handshake's length; distributed then fails to decode the
    frames and logged CRITICAL with a traceback on stderr beside the probe's line (a separate
    process: pytest captures the logging of this one)."""
    out = tmp_path / "out"
    p = subprocess.run([GNIBENCH, "run", "quick", "-o", str(out), "--executor", "dask",
                        "--scheduler", peer.address], capture_output=True, text=True,
                       timeout=SAFETY, check=False)
    err = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(err) == 1 and err[0].startswith("gnibench: error:"), err
    assert not out.exists()


def test_a_local_cluster_beside_a_taken_port_8787_says_nothing(tmp_path):
    """The LocalCluster's HTTP server went to Dask's default port 8787 and, that port taken by
    another cluster, warned on stderr: a Dask run now says only its own lines."""
    taken = socket.socket()
    try:
        taken.bind(("127.0.0.1", 8787))
        taken.listen(1)
    except OSError:
        pass                             # taken already: the case itself
    exp = tmp_path / "tiny.toml"
    exp.write_text('name = "tiny"\ntitle = "Tiny"\nreference = "[HLW] (2.2)"\nsteps = 20\n'
                   '[[cells]]\nproblems = ["harmonic-oscillator"]\nmethods = ["rk4:h=0.1"]\n')
    try:
        p = subprocess.run([GNIBENCH, "run", str(exp), "-o", str(tmp_path / "out"),
                            "--executor", "dask", "-j", "1", "--no-report"],
                           capture_output=True, text=True, timeout=300, check=False)
    finally:
        taken.close()
    assert p.returncode == 0, p.stderr
    assert all(ln.startswith(("gnibench:", "[")) for ln in p.stderr.splitlines()), p.stderr


def _children(pid: int) -> list[tuple[int, str]]:
    found = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        with contextlib.suppress(OSError):
            for child in (task / "children").read_text().split():
                with contextlib.suppress(OSError):
                    found.append((int(child), Path(f"/proc/{child}/cmdline").read_bytes()
                                  .replace(b"\0", b" ").decode()))
    return found


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs Linux /proc")
def test_the_local_cluster_failing_to_start_is_one_line(tmp_path):
    """The fork server of the local Dask cluster killed while the cluster starts: one gnibench
    line and exit code 1 (before: 158 lines of Dask's tracebacks and no line of ours); killed
    too late to matter, the run completes."""
    import os
    import signal

    exp = tmp_path / "tiny.toml"
    exp.write_text('name = "tiny"\ntitle = "t"\nreference = "r"\nsteps = 40\n[[cells]]\n'
                   'problems = ["kepler-2d", "pendulum"]\nmethods = ["rk4"]\n'
                   'vary.h = [0.05, 0.1]\n')
    proc = subprocess.Popen([sys.executable, "-m", "gnibench.suite.cli.entry", "run", str(exp),
                             "-o", str(tmp_path / "out"), "--executor", "dask", "-j", "2",
                             "--no-report"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    deadline = time.monotonic() + 120
    killed = False
    while proc.poll() is None and time.monotonic() < deadline and not killed:
        for pid, cmd in _children(proc.pid):
            if "multiprocessing.forkserver" in cmd:
                os.kill(pid, signal.SIGKILL)
                killed = True
        time.sleep(0.02)
    out, err = proc.communicate(timeout=300)
    assert "Traceback" not in err, err
    if proc.returncode == 0:
        assert (tmp_path / "out" / "cells.parquet").is_file()
        return
    assert proc.returncode == 1, err
    lines = [ln for ln in err.splitlines() if ln.startswith("gnibench:")]
    assert lines[-1].startswith("gnibench: error: the local Dask cluster could not start"), err
    assert not [ln for ln in err.splitlines() if " - ERROR - " in ln], err
