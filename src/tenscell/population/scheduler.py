"""Whether a Dask scheduler answers at an address: checked before a run creates anything (a study's ensemble, a
population of cells on a cluster)."""
from __future__ import annotations

from pathlib import Path

__all__ = ["reach_scheduler"]


def reach_scheduler(address: str, timeout_s: float = 3.0, flag: str = "--scheduler") -> None:
    """ValueError unless a Dask scheduler answers at ``address`` within ``timeout_s`` (s).

    Checked before anything is created: Dask's own wait for an absent scheduler is 30 s and comes after the
    work directory exists. A Dask peer writes its handshake as soon as a connection opens (a small message:
    its size and its number of frames, each 8 bytes little-endian, lead it); a port that accepts connections but does not speak Dask
    (a proxy, another service) is refused here rather than read as a huge frame later. Only tcp:// is
    checked this way; tls:// is only connected to, other protocols are left to Dask.
    """
    import json
    import socket
    import struct

    text = str(address).strip()
    where = f"{flag} {text}"
    if Path(text).is_file():
        try:
            text = str(json.loads(Path(text).read_text())["address"])
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise ValueError(f"{where}: not a Dask scheduler file (JSON with an 'address'; {type(err).__name__})") \
                from None
        where += f" (address {text})"
    scheme, _, body = text.rpartition("://")
    if scheme not in ("", "tcp", "tls"):
        return
    host, _, port = body.rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s) as conn:
            if scheme == "tls":
                return
            head = b""
            while len(head) < 16:
                chunk = conn.recv(16 - len(head))
                if not chunk:
                    break
                head += chunk
    except (OSError, ValueError) as err:
        reason = "no answer" if isinstance(err, TimeoutError) else (getattr(err, "strerror", None) or str(err))
        raise ValueError(f"{where}: no Dask scheduler reachable within {timeout_s:g} s ({reason})") from None
    size, frames = struct.unpack("<QQ", head) if len(head) == 16 else (0, 0)
    if not (16 <= size <= 1 << 20 and 1 <= frames <= 64):
        raise ValueError(f"{where}: something answers there, but not a Dask scheduler")
