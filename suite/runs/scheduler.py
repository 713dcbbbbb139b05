"""Checking ``--scheduler ADDRESS`` before anything is created: is a Dask scheduler answering there?

``distributed.Client(address, timeout=...)`` bounds only the TCP connection: its handshake waits
without a limit for a peer that accepts and never answers (measured: 62 s), and takes the first
8 bytes a non-Dask server sends (``HTTP/1.0``) as the length of a message ("Unable to allocate
3.07 EiB"). :func:`probe` asks the peer who it is within one deadline for the whole exchange, in
three steps, each failing with one line:

1. a TCP connection (``tcp://`` addresses): refused or unreachable at once;
2. Dask's handshake, sent by the probe, and the first 8 bytes the peer sends. Both ends of a Dask
   connection send their handshake as soon as it is made, then read the other's
   (``distributed/comm/core.py``: ``connect`` and ``Listener.on_connection``), each a framed
   message: a little-endian length followed by that many bytes (``comm/tcp.py``). Sending ours
   first costs a Dask peer nothing, and a server that waits for its client to speak (HTTP)
   answers at once, usually with an error (before, it took the whole timeout). Silence, a
   closed connection, or a length no handshake has (> 64 MiB: someone else's protocol, e.g.
   ``HTTP/1.0``) is not a Dask scheduler;
3. a Dask connection (``distributed.comm.connect``) and an ``identity`` request, whose answer
   must be a scheduler's.

All of it (name resolution included) runs in a daemon thread joined with the deadline, so nothing
in it can hang the command.
"""
from __future__ import annotations

import contextlib
import contextvars
import logging
import pickle
import socket
import struct
import sys
import threading
import time

from gnibench.suite.foundation.errors import UserError, named

TIMEOUT = 10.0                  # seconds for the whole exchange
MAX_HANDSHAKE = 64 * 2 ** 20    # a Dask handshake is a few hundred bytes


def _bad(address: str, why: str) -> UserError:
    return UserError(f"bad {named('--scheduler', repr(address))}: {why}; allowed: the address of a running Dask "
                     f"scheduler, e.g. tcp://127.0.0.1:8786")


def _handshake() -> bytes:
    """Dask's handshake as ``distributed.comm.connect`` sends it over TCP: the framed msgpack of
    ``Comm.handshake_info()`` (compression, Python version, pickle protocol), plus one key of our
    own, which the peer ignores (it reads only the pickle protocol and the compression). Its
    value ends in CRLF: the end of a line for line-based protocols (HTTP, SMTP), whose servers
    then answer instead of waiting for the rest of a request."""
    from distributed.protocol import dumps
    from distributed.protocol.utils import pack_frames

    info = {"compression": None, "python": tuple(sys.version_info)[:3],
            "pickle-protocol": pickle.HIGHEST_PROTOCOL, "gnibench": "probe\r\n"}
    body = pack_frames(dumps(info))
    return struct.pack("<Q", len(body)) + body


def _tcp_first_bytes(address: str, host: str, port: int, deadline: float) -> None:
    try:
        sock = socket.create_connection((host, port), timeout=max(deadline - time.monotonic(),
                                                                  0.1))
    except TimeoutError:
        raise _bad(address, f"no connection within {TIMEOUT:g} s") from None
    except OSError as e:
        raise _bad(address, f"cannot connect ({e.strerror or e})") from None
    with sock:
        try:
            sock.sendall(_handshake())
        except TimeoutError:
            raise _bad(address, f"the peer took nothing within {TIMEOUT:g} s "
                                f"(not a Dask scheduler?)") from None
        except OSError as e:
            raise _bad(address, f"the connection failed ({e.strerror or e})") from None
        head = b""
        while len(head) < 8:
            sock.settimeout(max(deadline - time.monotonic(), 0.01))
            try:
                chunk = sock.recv(8 - len(head))
            except TimeoutError:
                raise _bad(address, f"the peer accepted but sent nothing within {TIMEOUT:g} s "
                                    f"(not a Dask scheduler?)") from None
            except OSError as e:
                raise _bad(address, f"the connection failed ({e.strerror or e})") from None
            if not chunk:
                raise _bad(address, "the peer closed the connection (not a Dask scheduler?)")
            head += chunk
    (length,) = struct.unpack("<Q", head)
    if not 0 < length <= MAX_HANDSHAKE:
        raise _bad(address, f"the peer does not speak Dask's protocol (it sent {head[:8]!r})")


async def _identity(address: str, timeout: float) -> dict:
    from distributed.comm import connect

    comm = await connect(address, timeout=timeout)
    try:
        await comm.write({"op": "identity", "reply": True})
        return await comm.read()
    finally:
        comm.abort()


def _in_thread(fn, seconds: float):
    box: dict = {}

    def target():
        try:
            box["value"] = fn()
        except BaseException as e:  # noqa: BLE001 - carried to the caller
            box["error"] = e

    # the caller's context (errors.EDGE: a message names the option as the caller gave it)
    context = contextvars.copy_context()
    thread = threading.Thread(target=context.run, args=(target,), name="gnibench-scheduler-probe",
                              daemon=True)
    thread.start()
    thread.join(seconds)
    if thread.is_alive():
        raise TimeoutError
    if "error" in box:
        raise box["error"]
    return box["value"]


@contextlib.contextmanager
def _quiet_dask_logs():
    """distributed logs a message it cannot decode as CRITICAL, with a traceback, on stderr (a
    peer that sends a plausible length and then garbage): the probe's one line says it all."""
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        logger.setLevel(level)


def probe(address: str, timeout: float = TIMEOUT) -> dict:
    """The scheduler's identity, or a one-line UserError within ``timeout`` seconds."""
    import asyncio

    from distributed.comm.addressing import parse_address, parse_host_port

    address = address.strip()
    if "://" not in address:
        address = f"tcp://{address}"
    try:
        scheme, loc = parse_address(address)
        host, port = parse_host_port(loc) if scheme in ("tcp", "tls") else (None, None)
    except (ValueError, TypeError) as e:
        raise _bad(address, str(e)) from None
    deadline = time.monotonic() + timeout

    def ask():             # name resolution included: nothing here may outlast the deadline
        if scheme == "tcp":
            _tcp_first_bytes(address, host, int(port), deadline)
        left = max(deadline - time.monotonic(), 0.1)
        return asyncio.run(asyncio.wait_for(_identity(address, left), left))

    try:
        with _quiet_dask_logs():
            info = _in_thread(ask, timeout + 0.5)
    except TimeoutError:
        raise _bad(address, f"no Dask answer within {timeout:g} s") from None
    except UserError:
        raise
    except Exception as e:  # noqa: BLE001 - MemoryError, protocol errors: not a scheduler
        raise _bad(address, f"no Dask scheduler answers there ({type(e).__name__})") from None
    if not isinstance(info, dict) or info.get("type") != "Scheduler":
        kind = info.get("type") if isinstance(info, dict) else type(info).__name__
        raise _bad(address, f"it is not a Dask scheduler (it says: {kind})")
    return info
