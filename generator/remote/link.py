"""The host's end of the link to a proxy (docs/remote.md): connecting
(HELLO until the proxy answers, then the device-model check), starting,
one UP and one DOWN frame per release instant, stopping."""

from __future__ import annotations

import struct
import time

from ..host_tools.transport import FrameTransport, TransportError, TransportTimeout
from . import protocol as P
from .device_model import DeviceModel
from .protocol import K

HELLO_EVERY_S = 0.2  # opening a serial port resets many boards: HELLO again until one answers
CONNECT_S = 5.0
ANSWER_S = 1.0


class RemoteError(Exception):
    """The link cannot be used; the message is one line naming the target."""


class NoAnswer(RemoteError):
    """Nothing answered HELLO in time."""


class OtherDeviceModel(RemoteError):
    """The proxy was built from another device model."""


class Misframed(RemoteError):
    """Bytes come from the proxy, but no valid frame: the two ends of the
    link are at different baud rates, most likely."""


# Damaged frames in a row (no good one between them) that end a session as
# misframed: a link at the right baud rate damages one now and then, never
# so many in a row.
MISFRAMED_IN_A_ROW = 8


class Link:
    """A connected proxy at ``url`` (anything pyserial opens: a device path,
    a pty, ``socket://host:port``) for ``model``."""

    def __init__(self, url: str, model: DeviceModel, baudrate: int = 115200):
        self.url = url
        self.model = model
        self.baudrate = baudrate
        try:
            self.transport = FrameTransport.open(url, baudrate)
        except TransportError as err:
            raise RemoteError(str(err)) from None
        self.frames_in = 0
        self.dropped = 0  # frames with a bad CRC, COBS or length
        self.dropped_in_a_row = 0  # since the last good frame
        self.lock_step = False
        # The latest COUNTERS answer that came while waiting for another frame (ask_counters).
        self.latest_counters: dict | None = None

    def close(self) -> None:
        self.transport.close()

    def poll(self, on: bool) -> None:
        """Wait for frames by polling the link (realtime.polls_its_link)."""
        self.transport.poll(on)

    # ------------------------------------------------------------ frames

    def _send(self, cmd: int, instant: int, payload: bytes = b"") -> None:
        try:
            self.transport.send(P.encode(cmd, instant, payload))
        except TransportError as err:
            raise RemoteError(str(err)) from None

    def _receive(self, cmd: int, timeout: float) -> tuple[int, bytes] | None:
        """(instant, payload) of the next good frame with ``cmd``, or None
        after ``timeout`` seconds; damaged frames are dropped and counted."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            try:
                wire = self.transport.recv(left)
            except TransportTimeout:
                return None
            except TransportError as err:
                raise RemoteError(str(err)) from None
            if not wire:
                continue
            frame = P.decode(wire)
            if frame is None:
                self.dropped += 1
                self.dropped_in_a_row += 1
                if self.dropped_in_a_row >= MISFRAMED_IN_A_ROW:
                    raise self.misframed()
                continue
            self.frames_in += 1
            self.dropped_in_a_row = 0
            if frame[0] == cmd:
                return frame[1], frame[2]
            if frame[0] == K.CMD_COUNTERS | K.RESPONSE:
                self.latest_counters = _counters(frame[2])

    def misframed(self) -> Misframed:
        """The error of a link whose bytes from the proxy do not frame at
        this baud rate (the link's statistics: damaged frames and bytes
        since the last good frame)."""
        seen = (f"{self.dropped_in_a_row} damaged frame{'s' if self.dropped_in_a_row != 1 else ''} in a row"
                if self.dropped_in_a_row else f"{self.transport.bytes_in} bytes")
        since = "no valid frame yet" if self.frames_in == 0 else "no valid frame since"
        return Misframed(f"{self.url}: the proxy's bytes do not frame at {self.baudrate} baud ({seen}, {since}): "
                         f"the proxy runs at another baud rate, most likely; give `easylab proxy` and "
                         f"`easylab remote` the same --baud")

    def _request(self, cmd: int, payload: bytes = b"", timeout: float = ANSWER_S) -> bytes:
        self._send(cmd, 0, payload)
        answer = self._receive(cmd | K.RESPONSE, timeout)
        if answer is None:
            raise NoAnswer(f"{self.url}: the proxy stopped answering")
        return answer[1]

    # ------------------------------------------------------------ session

    def connect(self, timeout: float = CONNECT_S) -> None:
        """HELLO until the proxy answers, then check its device model."""
        deadline = time.monotonic() + timeout
        answer = None
        while answer is None and time.monotonic() < deadline:
            self._send(K.CMD_HELLO, 0)
            answer = self._receive(K.CMD_HELLO | K.RESPONSE, HELLO_EVERY_S)
        if answer is None:
            if self.frames_in == 0 and (self.dropped or self.transport.bytes_in):  # bytes came, no frame
                raise self.misframed()
            raise NoAnswer(f"{self.url}: no proxy answers (no valid HELLO answer within {timeout:g} s)")
        body = answer[1]
        if len(body) < 7:
            raise RemoteError(f"{self.url}: a malformed HELLO answer")
        version, model_id, devices = body[0], struct.unpack_from("<I", body, 1)[0], body[5]
        if version != K.PROTOCOL_VERSION:
            raise OtherDeviceModel(f"{self.url}: the proxy speaks protocol version {version}, this host "
                                   f"{K.PROTOCOL_VERSION}: rebuild and flash the proxy (easylab proxy)")
        if model_id != self.model.id:
            raise OtherDeviceModel(f"{self.url}: the proxy runs another device model (0x{model_id:08x}, this "
                                   f"model's is 0x{self.model.id:08x}): {self._differences(devices)}; rebuild "
                                   "and flash the proxy (easylab proxy)")

    def _differences(self, count: int) -> str:
        theirs = {}
        for index in range(count):
            body = self._request(K.CMD_DEVICE, bytes([index]))
            theirs[body[5:].decode("utf-8", "replace")] = struct.unpack_from("<I", body, 1)[0]
        ours = {d.path: h for d, h in zip(self.model.devices, self.model.device_ids)}
        parts = []
        if only := [p for p in theirs if p not in ours]:
            parts.append("only in the proxy: " + ", ".join(only))
        if only := [p for p in ours if p not in theirs]:
            parts.append("only in the model: " + ", ".join(only))
        if differ := [p for p in ours if p in theirs and theirs[p] != ours[p]]:
            parts.append("different: " + ", ".join(differ))
        return "; ".join(parts) or "the devices are the same, the instants at which tasks read or write them differ"

    def start(self, lock_step: bool) -> None:
        self.lock_step = lock_step
        self._request(K.CMD_START, bytes([K.MODE_LOCK_STEP if lock_step else K.MODE_REAL_TIME]))

    def stop(self) -> None:
        """The proxy applies its safe values (and a host-board proxy ends)."""
        self._request(K.CMD_STOP)

    def counters(self) -> dict:
        """The proxy's counters (waits for the answer; other frames meanwhile are dropped)."""
        return _counters(self._request(K.CMD_COUNTERS))

    def ask_counters(self) -> None:
        """Ask for the counters without waiting: the answer lands in
        ``latest_counters`` while the host waits for its next UP frame."""
        self._send(K.CMD_COUNTERS, 0)

    def up(self, tick: int, timeout: float) -> bytes:
        """The device data the proxy read at ``tick`` (lock-step: waits)."""
        while True:
            frame = self._receive(K.CMD_UP, timeout)
            if frame is None:
                if self.dropped_in_a_row:
                    raise self.misframed()
                raise NoAnswer(f"{self.url}: no device data from the proxy for instant {tick} within {timeout:g} s")
            instant, payload = frame
            if instant == tick & 0xFFFFFFFF:
                return payload
            if instant > tick & 0xFFFFFFFF:
                raise RemoteError(f"{self.url}: the proxy is at instant {instant}, the host at {tick}")

    def down(self, tick: int, mask: int, payload: bytes) -> None:
        self._send(K.CMD_DOWN, tick, struct.pack("<I", mask) + payload)


COUNTER_NAMES = ("frames", "bad_crc", "malformed", "stale", "overruns", "watchdog")


def _counters(body: bytes) -> dict:
    """A COUNTERS answer: the link's counters by name, and ``tasks``, the
    overruns of each proxy task (task order)."""
    if len(body) < 1 + 2 * K.COUNTER_COUNT:
        raise RemoteError(f"a COUNTERS answer of {len(body)} bytes")
    link = struct.unpack_from(f"<{K.COUNTER_COUNT}H", body, 1)
    tasks = (len(body) - 1 - 2 * K.COUNTER_COUNT) // 2
    per_task = list(struct.unpack_from(f"<{tasks}H", body, 1 + 2 * K.COUNTER_COUNT)) if tasks > 0 else []
    return {**dict(zip(COUNTER_NAMES, link)), "tasks": per_task}
