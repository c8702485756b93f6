"""Byte transports for the host tools: anything pyserial's ``serial_for_url``
opens (device paths, ptys, ``socket://host:port``, ``loop://``), split into
frames at a delimiter byte.

Failures become :class:`TransportError` with a one-line message (a missing
port, an unplugged adapter, a closed socket), never a pyserial traceback.
"""

from __future__ import annotations

import os
import socket
import time

import serial

try:
    from termios import error as _TermiosError  # tcdrain on a pty whose other side closed
except ImportError:  # not POSIX
    class _TermiosError(Exception):
        pass

_PORT_ERRORS = (serial.SerialException, OSError, _TermiosError)


class TransportError(Exception):
    """The port cannot be opened or went away; the message is one line."""


class TransportTimeout(TransportError):
    """Nothing (complete) arrived in time."""


def open_port(url: str, baudrate: int = 115200, timeout: float = 0.05):
    """Open ``url`` with pyserial (8N1, no flow control)."""
    try:
        port = serial.serial_for_url(url, baudrate=baudrate, timeout=timeout, write_timeout=2.0,
                                     do_not_open=True)
        port.open()
        _no_delay(port)
        return port
    except (*_PORT_ERRORS, ValueError) as err:
        raise TransportError(f"cannot open {url}: {_reason(err)}") from None


def _no_delay(port) -> None:
    """A TCP link sends each frame at once: Nagle's algorithm would hold a
    small frame until the peer acknowledges the last (up to its delayed
    acknowledgement, tens of milliseconds: a 1 ms deadline missed)."""
    sock = getattr(port, "_socket", None)  # pyserial's socket:// port
    if sock is not None:
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except OSError:
            pass  # not a TCP socket


def _reason(err: Exception) -> str:
    text = str(err)
    if isinstance(err, OSError) and err.strerror:
        text = err.strerror
    # pyserial says "[Errno 2] could not open port X: [Errno 2] No such file or directory: 'X'"
    if "No such file or directory" in text:
        return "no such device or file"
    if "Connection refused" in text:
        return "connection refused (nothing listens there)"
    return text.splitlines()[0] if text else type(err).__name__


class FrameTransport:
    """Frames delimited by one byte (0x00) over a pyserial port."""

    def __init__(self, port, url: str, delimiter: int = 0):
        self.port = port
        self.url = url
        self.delimiter = bytes([delimiter])
        self._buf = bytearray()
        self.bytes_out = 0
        self.bytes_in = 0
        self.polling = False
        self._blocking_timeout = port.timeout

    @classmethod
    def open(cls, url: str, baudrate: int = 115200) -> "FrameTransport":
        return cls(open_port(url, baudrate), url)

    def send(self, data: bytes) -> None:
        """Hand ``data`` to the operating system whole (not waiting for it
        to leave: tcdrain on a pty may wait a kernel tick, 4 ms, which is a
        1 ms deadline missed)."""
        try:
            self.port.write(data)
            self.bytes_out += len(data)
        except _PORT_ERRORS as err:
            raise TransportError(f"lost the connection to {self.url}: {_reason(err)}") from None

    def poll(self, on: bool) -> None:
        """Wait for bytes by polling the port, yielding the CPU between
        looks (``on``), or by sleeping in the kernel until they come: a
        process asleep on an idle machine may be woken milliseconds after
        its bytes came (docs/remote.md, "Real time at 1 kHz")."""
        self.polling = on
        self.port.timeout = 0 if on else self._blocking_timeout

    def discard_input(self) -> None:
        """Forget bytes received so far (stale responses)."""
        self._buf.clear()
        try:
            self.port.reset_input_buffer()
        except _PORT_ERRORS:
            pass

    def recv(self, timeout: float) -> bytes:
        """The bytes of the next frame, without its delimiter (possibly
        empty: an empty frame between two delimiters)."""
        deadline = time.monotonic() + timeout
        while True:
            at = self._buf.find(self.delimiter)
            if at >= 0:
                frame = bytes(self._buf[:at])
                del self._buf[:at + 1]
                return frame
            if time.monotonic() >= deadline:
                raise TransportTimeout(f"no answer from {self.url} within {timeout:g} s")
            try:
                if self.polling:  # a timeout of 0: what is there, at once (a closed port still raises)
                    chunk = self.port.read(4096)
                else:
                    waiting = self.port.in_waiting
                    chunk = self.port.read(max(1, min(waiting, 4096)))
            except _PORT_ERRORS as err:
                raise TransportError(f"lost the connection to {self.url}: {_reason(err)}") from None
            if chunk:
                self.bytes_in += len(chunk)
                self._buf += chunk
            elif self.polling:
                os.sched_yield()

    def close(self) -> None:
        try:
            self.port.close()
        except _PORT_ERRORS:
            pass
