"""Reaching a Dask scheduler: its address checked, and its first message read and decoded with a bound
before Dask's own client connects (which allocates whatever a server's first bytes say)."""

from __future__ import annotations

import contextlib
import socket
import struct
import time
from importlib.util import find_spec

from excite_cli.errors import ExciteError

#: How long to wait for a Dask scheduler to answer [s].
CONNECT_TIMEOUT = 10.0
#: Largest first message a Dask scheduler may announce on a new connection (its handshake, a few
#: hundred bytes) [bytes].
HANDSHAKE_BYTES = 1 << 20


def require_distributed() -> None:
    """That Dask's ``distributed`` is installed (the ``cluster`` extra: only a run on a scheduler needs it).

    Raises:
        ExciteError: (``optimizer.scheduler``) it is not.
    """
    if find_spec("distributed") is None:
        raise ExciteError(
            "optimizer.scheduler",
            "needs Dask's distributed package, which is not installed",
            expected="the cluster extra: pip install 'excite[cluster]' (make install has it)",
        )


def check_scheduler(address: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """That a Dask scheduler listens at ``address`` (``[tcp://]host:port``), asked with a bound before
    Dask's client is: a scheduler's first message on a new connection is its handshake, framed as
    distributed frames every message over TCP (``distributed/comm/tcp.py``: an unsigned 64-bit count of
    the bytes that follow, then the frames, ``protocol.utils.pack_frames``), which decodes
    (``protocol.loads``) to a dict. The client allocates whatever another server's first bytes happen
    to say (3 EiB was seen) and fails on bytes it cannot unpack, so the whole message is read here
    within ``timeout`` seconds in all (a server that trickles a byte at a time is cut off at the bound)
    and decoded by distributed itself. A ``tls://`` address needs the client's certificates in Dask's
    own configuration (``distributed.comm.tls``: its CA file and the client's certificate and key,
    distributed's ``Security``), from which Dask's client takes its TLS context; with them it is left to
    Dask, without them refused.

    Raises:
        ExciteError: (``optimizer.scheduler``) distributed is not installed (:func:`require_distributed`),
            a ``tls://`` address without the certificates Dask needs for it, nothing listens there, the
            server's first message is not
            whole within ``timeout`` [s], announces more than :data:`HANDSHAKE_BYTES`, or is no Dask
            handshake.
    """
    require_distributed()
    scheme, _, rest = address.rpartition("://")
    if scheme == "tls":
        _check_tls(address)
    if scheme not in ("", "tcp"):
        return
    host, _, port = rest.rpartition(":")
    deadline = time.monotonic() + timeout
    try:
        connection = socket.create_connection((host.strip("[]"), int(port)), timeout=timeout)
    except OSError as exc:
        raise ExciteError("optimizer.scheduler", f"cannot reach the Dask scheduler at {address}: {exc}") from None
    with connection:
        head = _receive(connection, 8, deadline)
        size = struct.unpack("Q", head)[0] if len(head) == 8 else 0
        body = _receive(connection, size, deadline) if 0 < size <= HANDSHAKE_BYTES else b""
    if len(head) == 8 and not 0 < size <= HANDSHAKE_BYTES:
        problem = "its first bytes are no Dask handshake"
    elif len(head) < 8 or len(body) < size:
        problem = f"its first message did not come whole within {timeout:g} s"
    elif not _is_handshake(body):
        problem = "its first bytes are no Dask handshake"
    else:
        return
    raise ExciteError(
        "optimizer.scheduler",
        f"the server at {address} is not a Dask scheduler: {problem}",
        address,
        "the address of a Dask scheduler (dask scheduler prints it)",
    )


def _check_tls(address: str) -> None:
    """That Dask's configuration gives its client a TLS context for ``address`` (a ``tls://`` one).

    Raises:
        ExciteError: (``optimizer.scheduler``) it does not (Dask would fail with a bare ``TypeError``).
    """
    from distributed.security import Security

    try:
        context = Security().get_connection_args("client").get("ssl_context")
    except Exception as exc:  # certificate files that do not exist or do not parse
        raise ExciteError("optimizer.scheduler", f"Dask's TLS configuration cannot be used: {exc}") from None
    if context is None:
        raise ExciteError(
            "optimizer.scheduler",
            f"{address} is a TLS address, and Dask's configuration gives its client no certificates",
            address,
            "distributed.comm.tls.ca-file, .client.cert and .client.key set in Dask's configuration "
            "(or DASK_DISTRIBUTED__COMM__TLS__CA_FILE and the like), or a tcp:// address",
        )


def _receive(connection: socket.socket, count: int, deadline: float) -> bytes:
    """Up to ``count`` bytes from ``connection``, as many as come before ``deadline`` (``time.monotonic``)
    or before the server closes or resets the connection."""
    received = b""
    with contextlib.suppress(OSError):  # a timeout or a reset: what came is judged
        while len(received) < count and (left := deadline - time.monotonic()) > 0:
            connection.settimeout(left)
            chunk = connection.recv(min(count - len(received), 65_536))
            if not chunk:
                break
            received += chunk
    return received


def _is_handshake(body: bytes) -> bool:
    """Whether ``body`` (a framed message without its length) unpacks into whole frames that distributed
    decodes to a dict, as a scheduler's handshake does."""
    from distributed.protocol import loads
    from distributed.protocol.utils import unpack_frames

    try:
        frames, missing = unpack_frames(body, partial=True)
        return not missing and isinstance(loads(frames), dict)
    except Exception:  # whatever garbage makes distributed's own decoders raise (struct, msgpack, ...)
        return False
