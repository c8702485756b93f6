"""The remote link's frames on the host side (docs/remote.md): constants
read from runtime_c/el_remote_protocol.h (their single source), and the
debug protocol's framing (COBS, 0x00 delimiter, CRC-16/MODBUS) around
``cmd u8, instant u32, payload``."""

from __future__ import annotations

import re
import struct
from types import SimpleNamespace

from ..core.crc import crc16
from ..core.paths import runtime_dir
from ..host_tools.debug_protocol import cobs_decode, cobs_encode  # the debug protocol's framing

_DEFINE = re.compile(r"^\s*#\s*define\s+EL_RMT_(\w+)\s+\(?(0[xX][0-9A-Fa-f]+|\d+)[uUlL]*\)?\s*(?:/\*.*)?$")


def parse_header(text: str) -> dict[str, int]:
    """``{NAME: value}`` of every ``#define EL_RMT_NAME <integer>`` line."""
    return {m.group(1): int(m.group(2), 0) for m in map(_DEFINE.match, text.splitlines()) if m}


K = SimpleNamespace(**parse_header((runtime_dir() / "el_remote_protocol.h").read_text(encoding="utf-8")))
"""The protocol's constants by their C names without ``EL_RMT_``."""

_HEAD = struct.Struct("<BI")


def encode(cmd: int, instant: int, payload: bytes = b"") -> bytes:
    """A frame as it goes on the wire."""
    body = _HEAD.pack(cmd, instant & 0xFFFFFFFF) + payload
    crc = crc16(body)
    return cobs_encode(body + bytes([crc & 0xFF, crc >> 8])) + b"\x00"


def decode(wire: bytes) -> tuple[int, int, bytes] | None:
    """(cmd, instant, payload) of a frame without its delimiter, or None
    when it is damaged (COBS, length or CRC)."""
    try:
        raw = cobs_decode(wire)
    except ValueError:
        return None
    if len(raw) < K.HEADER + K.TRAILER or len(raw) > K.MAX_FRAME or crc16(raw[:-2]) != raw[-2] | (raw[-1] << 8):
        return None
    cmd, instant = _HEAD.unpack_from(raw)
    return cmd, instant, raw[K.HEADER:-2]


def wire_bytes(payload: int) -> int:
    """Bytes on the wire of a frame with ``payload`` bytes (header, CRC,
    COBS overhead, delimiter)."""
    n = K.HEADER + payload + K.TRAILER
    return n + 1 + n // 254 + 1
