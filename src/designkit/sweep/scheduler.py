"""A Dask scheduler given by address (``--scheduler``): the address read, the endpoint heard, within a deadline.

``dask.distributed`` connects in two stages: the connection (bounded by its ``timeout``), then the handshake,
where each side sends a length-prefixed message -- read without a deadline, and with a length taken on
trust.  An endpoint that accepts the connection and stays silent would hold the sweep for ever, and one
that answers other bytes (an SSH banner: ``SSH-2.0-`` read as a frame length is 3 EiB) makes Dask
allocate whatever its first eight bytes say.  So before a client is made, :func:`probe` opens one
connection with Dask's own ``distributed.comm.connect`` inside a deadline of its own, and refuses an
endpoint that does not complete Dask's handshake within :data:`CONNECT_TIMEOUT` seconds.

Protocols: ``tcp://`` (or a bare ``host:port``); ``tls://`` with the Dask TLS configuration
(``distributed.comm.tls.ca-file``, ``distributed.comm.tls.client.cert`` and ``.key``, e.g. from
``DASK_DISTRIBUTED__COMM__TLS__CA_FILE``), without which no TLS connection can be made.  Other
protocols (``ucx://``, ``inproc://``, ``ws://``) are refused naming ``--scheduler``.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

from designkit.errors import SpecError, short_repr

__all__ = ["CONNECT_TIMEOUT", "PROTOCOLS", "Endpoint", "endpoint", "probe"]

CONNECT_TIMEOUT = 5.0
"""Seconds within which a scheduler given by address must complete Dask's handshake (``--scheduler``)."""
CONNECT_SHARE = 0.8
"""Share of the deadline Dask's connection attempts (retried while refused) may take; the handshake has the rest."""
PROTOCOLS = ("tcp", "tls")
"""The protocols a sweep connects over."""
_TLS_KEYS = ("distributed.comm.tls.ca-file", "distributed.comm.tls.client.cert")


@dataclass(frozen=True)
class Endpoint:
    """A scheduler address as Dask reads it.

    Parameters
    ----------
    address : str
        ``protocol://host:port``.
    protocol : str
        One of :data:`PROTOCOLS`.
    security : distributed.Security or None
        The TLS settings of a ``tls://`` address (from the Dask configuration).
    """

    address: str
    protocol: str
    security: Any = None


def _refuse(scheduler: str, reason: str) -> SpecError:
    return SpecError("--scheduler", f"{short_repr(scheduler)}: {reason}")


def endpoint(scheduler: str) -> Endpoint:
    """Read ``scheduler`` (``tcp://host:port``, ``host:port`` or ``tls://host:port``) without connecting.

    Raises
    ------
    SpecError
        ``--scheduler``: not an address, a port out of range, a protocol other than :data:`PROTOCOLS`, or
        ``tls://`` without the Dask TLS configuration.
    """
    from distributed.comm.addressing import normalize_address, parse_address, parse_host_port

    if not isinstance(scheduler, str) or not scheduler.strip():
        raise _refuse(str(scheduler), "expected an address such as tcp://host:8786")
    protocol = scheduler.split("://", 1)[0] if "://" in scheduler else "tcp"
    if protocol not in PROTOCOLS:
        raise _refuse(scheduler, f"the {protocol[:20]}:// protocol is not supported; a sweep connects over "
                      "tcp:// (or tls:// with the Dask TLS configuration)")
    try:
        address = normalize_address(scheduler if "://" in scheduler else f"tcp://{scheduler}")
        _, location = parse_address(address)
        host, port = parse_host_port(location)
    except (ValueError, TypeError) as exc:
        raise _refuse(scheduler, f"not a scheduler address such as tcp://host:8786 ({exc})") from None
    if not host or not isinstance(port, int) or not 1 <= port <= 65535:
        raise _refuse(scheduler, "expected protocol://host:port with a port from 1 to 65535")
    security = None
    if protocol == "tls":
        import dask
        from distributed import Security

        missing = [k for k in _TLS_KEYS if not dask.config.get(k, None)]
        if missing:
            raise _refuse(scheduler, "tls:// needs the Dask TLS configuration (the cluster's CA certificate and a "
                          "client certificate): " + " and ".join(missing) + " not set (e.g. the environment "
                          "variables DASK_DISTRIBUTED__COMM__TLS__CA_FILE, "
                          "DASK_DISTRIBUTED__COMM__TLS__CLIENT__CERT and ..._CLIENT__KEY)")
        security = Security()
        try:
            security.get_connection_args("client")
        except (OSError, ValueError) as exc:  # ssl.SSLError is an OSError
            raise _refuse(scheduler, f"the Dask TLS configuration cannot be used: {type(exc).__name__}: "
                          f"{short_repr(str(exc))}") from None
    return Endpoint(address=address, protocol=protocol, security=security)


def _handshake(ep: Endpoint, timeout: float) -> tuple[dict | None, BaseException | None]:
    """``(remote handshake, None)`` or ``(None, the exception)`` of one connection to ``ep`` within ``timeout`` s."""
    import asyncio

    from distributed.comm import connect

    args = ep.security.get_connection_args("client") if ep.security is not None else {}

    async def talk() -> dict:
        # the connection's own retries end first (OSError "Timed out trying to connect": nothing listening), the
        # deadline over the handshake after (TimeoutError: connected, then silent)
        comm = await connect(ep.address, timeout=CONNECT_SHARE * timeout, **args)
        try:
            return dict(comm.remote_info)
        finally:
            comm.abort()

    async def bounded() -> dict:
        return await asyncio.wait_for(talk(), timeout)

    try:
        return asyncio.run(bounded()), None
    except BaseException as exc:  # noqa: BLE001 - whatever the endpoint made Dask raise (MemoryError included)
        return None, exc


def probe(ep: Endpoint, timeout: float = CONNECT_TIMEOUT) -> dict:
    """Complete Dask's handshake with ``ep`` within ``timeout`` seconds; its handshake message.

    The connection is made on a thread of its own (its own event loop, so a caller with a running loop, a
    notebook, is not disturbed) and dropped once the scheduler has answered.

    Raises
    ------
    SpecError
        ``--scheduler``: nothing listening, silent past ``timeout``, or answering bytes that are not Dask's
        handshake.
    """
    box: list[tuple[dict | None, BaseException | None]] = []
    worker = threading.Thread(target=lambda: box.append(_handshake(ep, timeout)), daemon=True,
                              name="designkit-scheduler-probe")
    worker.start()
    worker.join(timeout + 1.0)
    if not box:  # the loop did not even honour its own deadline: give up on it (a daemon thread)
        raise _refuse(ep.address, f"no answer from a Dask scheduler within {timeout:g} s")
    info, exc = box[0]
    if exc is None and isinstance(info, dict) and {"compression", "python"} <= set(info):
        return info
    if isinstance(exc, TimeoutError):  # asyncio's deadline (asyncio.TimeoutError is TimeoutError)
        reason = (f"the endpoint accepted the connection but did not answer as a Dask scheduler within "
                  f"{timeout:g} s")
    elif isinstance(exc, OSError) and "Timed out trying to connect" in str(exc):
        reason = f"nothing answered at this address within {timeout:g} s (no scheduler listening)"
    elif exc is None or isinstance(exc, MemoryError | ValueError | TypeError | EOFError | OSError | KeyError):
        what = "" if exc is None else f" ({type(exc).__name__})"
        reason = f"the endpoint answered, but not with Dask's handshake{what}: not a Dask scheduler"
    else:
        reason = f"cannot connect to a Dask scheduler here ({type(exc).__name__}: {short_repr(str(exc))})"
    raise _refuse(ep.address, reason)

