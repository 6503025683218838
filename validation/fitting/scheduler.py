"""A Dask scheduler address (``--scheduler``), checked before any work and probed under one
deadline.

:func:`check_scheduler_address` refuses what no scheduler can be reached at, without touching
the network: a protocol other than ``tcp://``, ``tls://`` (with certificates in dask's
configuration) or an installed ``ucx://``; ``inproc://`` (it connects only inside one Python
process); no host; a port outside 1-65535.  A privileged port (below 1024) that refuses the
connection is refused at once (no scheduler runs there).

:func:`probe_scheduler` then connects and asks the scheduler who it is, all of it under one
deadline.  ``dask.distributed.Client(address, timeout=T)`` alone does not do that: its ``T``
bounds the TCP connection, but distributed's handshake after it (``comm.connect`` reads the
peer's handshake without a timeout) waits for ever on a port that accepts and never answers, and
a port that answers garbage makes it read a frame length of exabytes (``MemoryError``).
"""

from __future__ import annotations

import asyncio
import os
import re
import socket
import threading

__all__ = ["SchedulerError", "check_scheduler_address", "probe_scheduler"]

#: the protocols a scheduler on another process or machine is reached by (ucx only if installed)
PROTOCOLS = ("tcp", "tls", "ucx")

_HOST_PORT = re.compile(r"^(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.\-]*)(?::(\d*))?$")


class SchedulerError(ValueError):
    """No dask.distributed scheduler can be used at the address given (``--scheduler``): the
    address is the user's input (the command line turns it into ``error: ...``, exit 2)."""


def _refuse(address, reason):
    raise SchedulerError(f"scheduler {address!r}: {reason}")


def _protocol_installed(scheme):
    from distributed.comm import registry  # dask.distributed (heavy): loaded only for a cluster

    try:
        registry.get_backend(scheme)
    except ValueError:
        return False
    return True


def _tls_problem():
    """Why ``tls://`` cannot connect with dask's configuration, or ``None``."""
    import dask.config  # dask (heavy): loaded only for a cluster

    files = {
        "distributed.comm.tls.ca-file": dask.config.get("distributed.comm.tls.ca-file", None),
        "distributed.comm.tls.client.cert": dask.config.get("distributed.comm.tls.client.cert", None),
    }
    for key, path in files.items():
        if not path:
            return (
                f"tls:// needs certificates, and dask's configuration has no {key} "
                "(set it, and distributed.comm.tls.client.key, in ~/.config/dask or DASK_* variables)"
            )
        if not os.path.isfile(path):
            return f"tls:// certificate {key} = {path!r}: no such file"
    return None


def check_scheduler_address(address) -> str:
    """``address`` as ``PROTOCOL://HOST:PORT`` (``tcp://`` when no protocol is given), or
    :class:`SchedulerError` saying why no scheduler can be reached at it.  Nothing is sent."""

    if not isinstance(address, str) or not address.strip():
        _refuse(address, "no address; give [PROTOCOL://]HOST:PORT, e.g. tcp://10.0.0.5:8786")
    scheme, sep, rest = address.partition("://")
    scheme, rest = (scheme.lower(), rest) if sep else ("tcp", address)
    if scheme == "inproc":
        _refuse(address, "inproc:// connects only within one Python process; use tcp://HOST:PORT")
    if scheme not in PROTOCOLS:
        _refuse(address, f"unknown protocol {scheme}://; use tcp://, tls:// (with certificates) or ucx://")
    if scheme == "ucx" and not _protocol_installed("ucx"):
        _refuse(address, "ucx:// is not installed here (pip install distributed-ucxx); use tcp://")
    m = _HOST_PORT.match(rest)
    if m is None:
        _refuse(address, "not HOST:PORT (e.g. tcp://10.0.0.5:8786)")
    host, port = m.group(1), m.group(2)
    if not host:
        _refuse(address, "no host (e.g. tcp://10.0.0.5:8786)")
    if not port:
        _refuse(address, "no port (a scheduler listens on 8786 by default: tcp://HOST:8786)")
    if not 1 <= int(port) <= 65535:
        _refuse(address, f"port {int(port)} is outside 1-65535")
    if scheme == "tls":
        problem = _tls_problem()
        if problem:
            _refuse(address, problem)
    return f"{scheme}://{host}:{int(port)}"


async def _identity(address, timeout, connection_args):
    from distributed.comm import connect  # dask.distributed (heavy): loaded only for a cluster

    comm = await connect(address, timeout=timeout, **connection_args)
    try:
        await comm.write({"op": "identity", "reply": True})
        return await comm.read()
    finally:
        comm.abort()


def _in_own_loop(coro_fn, timeout):
    """``coro_fn()`` run to completion, or cancelled at ``timeout`` s, in a thread with its own
    event loop (so it neither needs nor disturbs the caller's); its result or exception."""
    box = {}

    def run():
        try:
            box["value"] = asyncio.run(asyncio.wait_for(coro_fn(), timeout))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller, whatever it is
            box["error"] = exc

    t = threading.Thread(target=run, name="scheduler-probe", daemon=True)
    t.start()
    t.join(timeout + 5.0)  # wait_for has cancelled it by then; a margin for the cancellation
    if t.is_alive():
        box["error"] = TimeoutError()
    return box


def _privileged_closed(address, timeout):
    """Refuse at once a privileged port (below 1024) where nothing listens: no scheduler runs
    there (distributed's connect would retry a refused connection until the deadline)."""
    scheme, _, rest = address.partition("://")
    host, _, port = rest.rpartition(":")
    if scheme not in ("tcp", "tls") or int(port) >= 1024:
        return
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except ConnectionRefusedError:
        _refuse(address, f"port {port} is a privileged port (below 1024) and nothing listens there")
    except OSError:
        pass  # unreachable or slow: the probe says so under its deadline


def probe_scheduler(address, timeout, connection_args=None) -> dict:
    """The scheduler's identity at ``address`` (a checked address), asked under one deadline of
    ``timeout`` s for the connection, the handshake and the reply; :class:`SchedulerError` when
    nothing answers in time or what answers is not a dask.distributed scheduler."""

    _privileged_closed(address, timeout)
    box = _in_own_loop(lambda: _identity(address, timeout, connection_args or {}), timeout)
    exc = box.get("error")
    if isinstance(exc, TimeoutError):
        _refuse(address, f"no dask.distributed scheduler answered within {timeout:g} s")
    if isinstance(exc, OSError):  # refused, unreachable, reset
        _refuse(address, f"no dask.distributed scheduler answered within {timeout:g} s ({exc})")
    if exc is not None:  # garbage: a frame of exabytes (MemoryError), undecodable bytes
        _refuse(address, f"something answered, but not a dask.distributed scheduler ({type(exc).__name__})")
    info = box["value"]
    if not isinstance(info, dict) or info.get("type") != "Scheduler":
        kind = info.get("type") if isinstance(info, dict) else type(info).__name__
        _refuse(address, f"answered as {kind!r}, not as a dask.distributed scheduler")
    return info
