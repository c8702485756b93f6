"""The debug protocol on the host side (docs/protocol.md): constants,
framing (COBS, CRC-16/MODBUS, sequence numbers) and a client.

The constants are not written here: they are read at import time from the
C header that the firmware compiles, runtime_c/el_debug_protocol.h
(shipped as package data), so the two sides cannot drift apart
(tests/debug/test_protocol_constants.py checks it with pycparser).
"""

from __future__ import annotations

import random
import struct
import time
from dataclasses import dataclass, field
from types import SimpleNamespace

from .transport import FrameTransport, TransportError, TransportTimeout
from ..core.crc import crc16  # the frames' CRC (re-exported for the tests)

# ====================================================================== constants

# The one parser of runtime_c/el_debug_protocol.h, shared with the generator.
from ..codegen.debug import parse_protocol_header as parse_header  # noqa: E402
from ..codegen.debug import protocol_header_path as header_path  # noqa: E402

CONSTANTS: dict[str, int] = parse_header(header_path().read_text(encoding="utf-8"))
K = SimpleNamespace(**CONSTANTS)
"""The protocol's constants by their C names without ``EL_DBG_``: ``K.CMD_READ``."""

PROTOCOL_VERSION = K.PROTOCOL_VERSION

# Type names of the model language -> (EL_DBG_T_ value, struct format).
TYPES: dict[str, tuple[int, str]] = {
    "bool": (K.T_BOOL, "<B"), "int8": (K.T_I8, "<b"), "uint8": (K.T_U8, "<B"), "int16": (K.T_I16, "<h"),
    "uint16": (K.T_U16, "<H"), "int32": (K.T_I32, "<i"), "uint32": (K.T_U32, "<I"),
    "float32": (K.T_F32, "<f"), "time": (K.T_TIME, "<I"),
}
TYPE_NAMES = {code: name for name, (code, _) in TYPES.items()}
KIND_NAMES = {K.K_PARAM: "param", K.K_VAR: "var", K.K_DEV_OUT: "dev_out", K.K_DEV_IN: "dev_in",
              K.K_STATE: "state", K.K_STATUS: "status", K.K_DEV_STATE: "dev_state", K.K_CHART: "chart",
              K.K_STEP_TIME: "step_time", K.K_FIRED: "fired"}
PROBE_NAMES = {K.P_NONE: "none", K.P_INSTANT: "instant", K.P_TASK: "task", K.P_CHART: "chart", K.P_STEP: "step",
               K.P_TRANSITION: "transition", K.P_ACTOR: "actor", K.P_CHART_END: "chart end",
               K.P_CONDITION: "condition"}
# A conditional breakpoint's comparison (BP_WHEN): the console's operator -> EL_DBG_OP_.
OPS = {"==": K.OP_EQ, "!=": K.OP_NE, "<": K.OP_LT, "<=": K.OP_LE, ">": K.OP_GT, ">=": K.OP_GE}
OP_NAMES = {code: name for name, code in OPS.items()}
WHY_NAMES = {K.WHY_NONE: "", K.WHY_BREAK: "break", K.WHY_BREAKPOINT: "breakpoint", K.WHY_STEP: "step",
             K.WHY_START: "start"}
STEP_UNITS = {"task": K.STEP_TASK, "chart": K.STEP_CHART, "actor": K.STEP_ACTOR, "instant": K.STEP_INSTANT}
COUNTER_NAMES = ["frames", "bad_crc", "oversize", "truncated", "unknown", "errors", "duplicates", "seq_gaps",
                 "tx_dropped"]
ERRORS = {
    K.E_UNKNOWN_CMD: "unknown command",
    K.E_LENGTH: "bad request length",
    K.E_ID: "no such item, chart, step, transition, actor, task or breakpoint",
    K.E_READ_ONLY: "read-only",
    K.E_VALUE: "bad value or element",
    K.E_RANGE: "out of range",
    K.E_TOO_BIG: "the answer would not fit in one frame",
    K.E_QUEUE_FULL: "the queue is full",
    K.E_NO_TX: "no transaction",
    K.E_TX_BUSY: "a transaction is already open or not yet applied",
    K.E_NOT_HALTED: "the program is running (break first)",
    K.E_BP_FULL: "every breakpoint slot is in use",
    K.E_UNSUPPORTED: "the board cannot do that",
    K.E_FORCE_FULL: "every force slot is in use (a model gets more with `debug on ... force N`)",
}


def type_size(type_name: str) -> int:
    return struct.calcsize(TYPES[type_name][1])


def encode_value(type_name: str, value) -> bytes:
    return struct.pack(TYPES[type_name][1], int(value) if type_name != "float32" else float(value))


def decode_value(type_name: str, data: bytes):
    (v,) = struct.unpack(TYPES[type_name][1], data)
    return bool(v) if type_name == "bool" else v


# ====================================================================== framing




def cobs_encode(data: bytes) -> bytes:
    """COBS without the delimiter (the C encoder's exact output)."""
    out = bytearray([0])
    code_at, code = 0, 1
    for b in data:
        if b == 0:
            out[code_at] = code
            code_at, code = len(out), 1
            out.append(0)
        else:
            out.append(b)
            code += 1
            if code == 0xFF:
                out[code_at] = code
                code_at, code = len(out), 1
                out.append(0)
    out[code_at] = code
    return bytes(out)


def cobs_decode(data: bytes) -> bytes:
    out = bytearray()
    i = 0
    while i < len(data):
        code = data[i]
        if code == 0 or i + code > len(data):
            raise ValueError("bad COBS")
        out += data[i + 1:i + code]
        i += code
        if code != 0xFF and i < len(data):
            out.append(0)
    return bytes(out)


def encode_frame(seq: int, cmd: int, payload: bytes = b"") -> bytes:
    """A request as it goes on the wire: COBS(seq, cmd, payload, CRC) 0x00."""
    body = bytes([seq & 0xFF, cmd & 0xFF]) + bytes(payload)
    crc = crc16(body)
    return cobs_encode(body + bytes([crc & 0xFF, crc >> 8])) + b"\x00"


def decode_frame(wire: bytes) -> tuple[int, int, bytes] | None:
    """(seq, cmd, payload) of a frame without its delimiter, or None when it
    is damaged."""
    try:
        raw = cobs_decode(wire)
    except ValueError:
        return None
    if len(raw) < 4 or crc16(raw[:-2]) != raw[-2] | (raw[-1] << 8):
        return None
    return raw[0], raw[1], raw[2:-2]


def max_encoded(n: int) -> int:
    """Bytes on the wire for a decoded frame of n bytes (COBS, delimiter)."""
    return n + 1 + n // 254 + 1


# ====================================================================== client


class DebugError(Exception):
    """The firmware answered a request with an error status."""

    def __init__(self, status: int, what: str = ""):
        self.status = status
        text = ERRORS.get(status, f"error {status}")
        super().__init__(f"{what}: {text}" if what else text)


class ProtocolError(TransportError):
    """The other side does not speak this protocol (or this version)."""


@dataclass
class Hello:
    version: int
    max_frame: int
    window: int
    program_id: int
    item_count: int
    actor_count: int
    chart_count: int
    task_count: int
    tx_max: int
    write_queue: int
    bp_max: int
    value_max: int
    force_slots: int  # forced elements the server holds (0: built without forcing)
    cond_slots: int  # conditional breakpoints (0: built without them)


@dataclass
class Location:
    kind: int
    a: int
    b: int

    @property
    def kind_name(self) -> str:
        return PROBE_NAMES.get(self.kind, str(self.kind))


@dataclass
class Flags:
    status: int
    halted: bool
    why: str
    location: Location
    breakpoint: int | None
    tick: int
    writes_pending: int
    tx_entries: int

    @property
    def tx_open(self) -> bool:
        return bool(self.status & K.S_TX_OPEN)


@dataclass
class Stack:
    tick: int
    halted: bool
    why: str
    location: Location
    breakpoint: int | None
    task: int | None
    actor: int | None
    charts: list[list[int | None]] = field(default_factory=list)  # per chart: the step of each slot


@dataclass
class Breakpoint:
    slot: int
    kind: int
    a: int
    b: int
    hits: int
    op: int | None = None  # a conditional breakpoint (kind P_CONDITION: a = item, b = element): EL_DBG_OP_
    value: bytes = b""  # its constant, 4 bytes little-endian (the item's size used)


@dataclass
class Forced:
    """A forced element (FORCE_LIST): its item, element and value's bytes."""

    item: int
    elem: int
    value: bytes


LOAD_STATES = {K.LOAD_IDLE: "idle", K.LOAD_RECEIVING: "receiving", K.LOAD_CHECKING: "checking",
               K.LOAD_REPLACED: "replaced", K.LOAD_REFUSED: "refused"}


@dataclass
class LoadStatus:
    """LOAD_STATUS: ``state`` (idle, receiving, checking, replaced,
    refused), the program id once replaced, and the message (why refused)."""

    state: str
    program_id: int
    message: str


# HELLO's fields up to VALUE_MAX; the slots of forcing and conditional breakpoints follow (2 x u8) when the
# server has either.
HELLO_FORMAT = "<BHBIHHBBBBBB"


class DebugClient:
    """Requests and responses over a FrameTransport, one at a time.

    A request that gets no answer in ``timeout`` seconds is sent again with
    the same sequence number (``retries`` times): the firmware answers a
    repeated request from its cache instead of running it twice. Responses
    with another sequence number (late answers to earlier requests) are
    dropped."""

    def __init__(self, transport: FrameTransport, timeout: float = 1.0, retries: int = 2):
        self.t = transport
        self.timeout = timeout
        self.retries = retries
        self.seq = random.randrange(256)
        self.hello_info: Hello | None = None
        self.round_trips = 0

    @classmethod
    def open(cls, url: str, timeout: float = 1.0, baudrate: int = 115200) -> "DebugClient":
        return cls(FrameTransport.open(url, baudrate), timeout)

    def close(self) -> None:
        self.t.close()

    # -------------------------------------------------------------- requests

    def request(self, cmd: int, payload: bytes = b"", what: str = "", check: bool = True) -> bytes:
        """Send one request; the response's payload after the status byte.
        Raises DebugError for an error status (when ``check``)."""
        self.seq = (self.seq + 1) & 0xFF
        frame = encode_frame(self.seq, cmd, payload)
        if len(frame) > max_encoded(self.max_frame):
            raise DebugError(K.E_TOO_BIG, what or "request")
        for attempt in range(self.retries + 1):
            self.t.send(frame)
            self.round_trips += 1
            try:
                body = self._await(cmd)
            except TransportTimeout:
                if attempt == self.retries:
                    raise
                continue
            if check and body[0] != K.OK:
                raise DebugError(body[0], what)
            return body[1:] if check else body
        raise AssertionError("unreachable")

    def _await(self, cmd: int) -> bytes:
        import time
        deadline = time.monotonic() + self.timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TransportTimeout(f"no answer from {self.t.url} within {self.timeout:g} s")
            wire = self.t.recv(left)
            if not wire:
                continue
            frame = decode_frame(wire)
            if frame is None:
                continue
            seq, rcmd, body = frame
            if seq != self.seq or rcmd != (cmd | K.RESPONSE) or not body:
                continue  # a late answer to an earlier request, or noise
            return body

    @property
    def max_frame(self) -> int:
        return self.hello_info.max_frame if self.hello_info else K.MAX_FRAME

    # -------------------------------------------------------------- the functions

    def hello(self) -> Hello:
        self.t.discard_input()
        body = self.request(K.CMD_HELLO, what="hello")
        if len(body) < 1 or body[0] != PROTOCOL_VERSION:
            older = bool(body) and body[0] < PROTOCOL_VERSION
            raise ProtocolError(f"{self.t.url} speaks debug protocol version {body[0] if body else '?'}, "
                                f"this tool version {PROTOCOL_VERSION}"
                                + (": the firmware is older (no force, no conditional breakpoints); rebuild it "
                                   "with this easylab" if older else ""))
        # the slots of forcing and conditional breakpoints: absent from a server without either
        fixed = struct.calcsize(HELLO_FORMAT)
        fields = struct.unpack_from(HELLO_FORMAT, body) + (tuple(body[fixed:fixed + 2]) if len(body) >= fixed + 2
                                                           else (0, 0))
        self.hello_info = Hello(*fields)
        return self.hello_info

    def hello_again(self, timeout: float = 5.0) -> Hello:
        """HELLO, asked until the firmware answers within ``timeout`` s: a
        firmware restarted by RESET answers once its receiver is on again."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                time.sleep(0.05)
                return self.hello()
            except TransportTimeout:
                if time.monotonic() >= deadline:
                    raise

    def program_id(self) -> int:
        return struct.unpack("<I", self.request(K.CMD_GET_PROGRAM_ID, what="getProgramId"))[0]

    @staticmethod
    def _location(body: bytes, at: int) -> tuple[bool, str, Location, int | None]:
        halted, why, kind, a, b, bp = struct.unpack_from("<BBBHHB", body, at)
        return bool(halted), WHY_NAMES.get(why, str(why)), Location(kind, a, b), None if bp == 0xFF else bp

    def flags(self) -> Flags:
        body = self.request(K.CMD_GET_FLAGS, what="getFlags")
        halted, why, loc, bp = self._location(body, 1)
        tick, wq, txn = struct.unpack_from("<IBB", body, 9)
        return Flags(body[0], halted, why, loc, bp, tick, wq, txn)

    def counters(self) -> dict[str, int]:
        body = self.request(K.CMD_GET_COUNTERS, what="counters")
        n = body[0]
        values = struct.unpack_from(f"<{n}H", body, 1)
        return {COUNTER_NAMES[i] if i < len(COUNTER_NAMES) else f"c{i}": v for i, v in enumerate(values)}

    def item_info(self, item: int) -> dict:
        body = self.request(K.CMD_ITEM_INFO, struct.pack("<H", item), what=f"item {item}")
        type_code, kind, flags, count = struct.unpack_from("<BBBH", body)
        tname = TYPE_NAMES.get(type_code, str(type_code))
        info = {"id": item, "type": tname, "kind": KIND_NAMES.get(kind, str(kind)), "count": count,
                "flags": [n for bit, n in ((K.F_READ, "read"), (K.F_WRITE, "write"), (K.F_RANGE, "range"))
                          if flags & bit]}
        if flags & K.F_RANGE and tname in TYPES:
            # Bounds are 32-bit: int32 for signed types, float for float32, uint32 otherwise.
            fmt = "<ff" if tname == "float32" else "<ii" if tname in ("int8", "int16", "int32") else "<II"
            info["range"] = list(struct.unpack_from(fmt, body, 5))
        return info

    def read_raw(self, ids: list[int]) -> bytes:
        return self.request(K.CMD_READ, b"".join(struct.pack("<H", i) for i in ids), what="read")

    def read(self, items: list[tuple[int, str, int]]) -> list:
        """Values of items given as (id, type name, count); several requests
        when the answers do not fit in one frame. A count > 1 gives a list."""
        out: list = []
        budget = self.max_frame - 3 - 2
        batch: list[tuple[int, str, int]] = []
        used = 0
        for it in items + [None]:
            size = type_size(it[1]) * it[2] if it else 0
            if it is None or (batch and (used + size > budget or 2 * (len(batch) + 1) > budget)):
                if batch:
                    data = self.read_raw([b[0] for b in batch])
                    at = 0
                    for _id, tname, count in batch:
                        sz = type_size(tname)
                        vals = [decode_value(tname, data[at + k * sz:at + (k + 1) * sz]) for k in range(count)]
                        out.append(vals if count > 1 else vals[0])
                        at += sz * count
                batch, used = [], 0
            if it is not None:
                batch.append(it)
                used += size
        return out

    def write(self, item: int, type_name: str, value, elem: int = 0, what: str = "") -> int:
        """Write one element; returns K.APPLIED or K.QUEUED."""
        body = self.request(K.CMD_WRITE, struct.pack("<HH", item, elem) + encode_value(type_name, value),
                            what=what or f"write {item}")
        return body[0]

    def tx_begin(self) -> None:
        self.request(K.CMD_TX_BEGIN, what="tx begin")

    def tx_commit(self) -> tuple[int, bytes]:
        """(K.APPLIED or K.QUEUED, the read values when applied)."""
        body = self.request(K.CMD_TX_COMMIT, what="tx commit")
        return body[0], body[1:]

    def tx_abort(self) -> None:
        self.request(K.CMD_TX_ABORT, what="tx abort")

    def tx_result(self) -> tuple[int, bytes]:
        """(state: 0 none, 1 open, 2 committed, 3 applied; the read values)."""
        body = self.request(K.CMD_TX_RESULT, what="tx result")
        return body[0], body[1:]

    def stack(self) -> Stack:
        body = self.request(K.CMD_GET_STACK, what="stack")
        tick = struct.unpack_from("<I", body)[0]
        halted, why, loc, bp = self._location(body, 4)
        task, actor, nch = struct.unpack_from("<BHB", body, 12)
        at = 16
        charts = []
        for _ in range(nch):
            ns = body[at]
            charts.append([None if s == 0xFF else s for s in body[at + 1:at + 1 + ns]])
            at += 1 + ns
        return Stack(tick, halted, why, loc, bp, None if task == 0xFF else task, None if actor == 0xFFFF else actor,
                     charts)

    def run(self) -> None:
        self.request(K.CMD_RUN, what="run")

    def halt(self) -> None:
        self.request(K.CMD_BREAK, what="break")

    def step(self, unit: str = "task") -> None:
        self.request(K.CMD_STEP, bytes([STEP_UNITS[unit]]), what=f"step {unit}")

    def reset(self, halt: bool = False) -> None:
        self.request(K.CMD_RESET, bytes([K.RESET_HALT if halt else 0]), what="reset")

    # -------------------------------------------------------------- model replacement (local execution)

    def load_status(self) -> "LoadStatus":
        """LOAD_STATUS: where a model sent with :meth:`send_model` is."""
        body = self.request(K.CMD_LOAD_STATUS, what="load status")
        state, program_id = struct.unpack_from("<BI", body)
        return LoadStatus(LOAD_STATES.get(state, str(state)), program_id, body[5:].decode("utf-8", "replace"))

    def send_model(self, text: bytes) -> None:
        """Send a model's text (LOAD_BEGIN, LOAD_DATA in chunks that fill a
        frame, LOAD_COMMIT with its length and CRC-16): the interpreter
        checks it and replaces the running program at an instant. Targets
        that cannot (every firmware) answer E_UNKNOWN_CMD."""
        self.request(K.CMD_LOAD_BEGIN, struct.pack("<I", len(text)), what="load")
        chunk = self.max_frame - K.HEADER - K.TRAILER - 4
        for at in range(0, len(text), chunk):
            self.request(K.CMD_LOAD_DATA, struct.pack("<I", at) + text[at:at + chunk], what="load data")
        self.request(K.CMD_LOAD_COMMIT, struct.pack("<IH", len(text), crc16(text)), what="load commit")

    def replace_model(self, text: bytes, timeout: float = 120.0) -> "LoadStatus":
        """Send a model and wait until it runs (``replaced``) or is refused
        (``refused``, with the first error); the status."""
        import time
        self.send_model(text)
        deadline = time.monotonic() + timeout
        while True:
            try:
                status = self.load_status()
            except TransportTimeout:  # the links moving to the new program's server: ask again
                status = None
            if status is not None and status.state in ("replaced", "refused"):
                return status
            if time.monotonic() > deadline:
                raise TransportTimeout(f"the model was not checked within {timeout:g} s")
            time.sleep(0.05)

    def bp_set(self, kind: int, a: int, b: int = 0) -> int:
        return self.request(K.CMD_BP_SET, struct.pack("<BHH", kind, a, b), what="break at")[0]

    def bp_clear(self, slot: int | None = None) -> None:
        self.request(K.CMD_BP_CLEAR, bytes([0xFF if slot is None else slot]), what="delete")

    def bp_when(self, item: int, type_name: str, op: str, value, elem: int = 0) -> int:
        """A conditional breakpoint: halt at the instant where ``item[elem]
        OP value`` turns true; returns its slot."""
        return self.request(K.CMD_BP_WHEN, struct.pack("<HHB", item, elem, OPS[op]) + encode_value(type_name, value),
                            what="break when")[0]

    def bp_list(self) -> list[Breakpoint]:
        """Every breakpoint; conditional ones (kind P_CONDITION) carry their
        comparison."""
        body = self.request(K.CMD_BP_LIST, what="breakpoints")
        out, at = [], 1
        for _ in range(body[0]):
            bp = Breakpoint(*struct.unpack_from("<BBHHH", body, at))
            at += 8
            if bp.kind == K.P_CONDITION:
                bp.op, bp.value = body[at], bytes(body[at + 1:at + 1 + K.VALUE_MAX])
                at += 1 + K.VALUE_MAX
            out.append(bp)
        return out

    def force(self, item: int, type_name: str, value, elem: int = 0, what: str = "") -> int:
        """Hold one element at ``value`` every instant until released;
        returns K.APPLIED (halted at an instant) or K.QUEUED (from the next
        instant)."""
        body = self.request(K.CMD_FORCE, struct.pack("<HH", item, elem) + encode_value(type_name, value),
                            what=what or f"force {item}")
        return body[0]

    def release(self, item: int | None = None, elem: int = 0) -> None:
        """Release one forced element, or every one (``item`` None)."""
        self.request(K.CMD_RELEASE, struct.pack("<HH", K.NONE16 if item is None else item, elem), what="release")

    def forced(self) -> list[Forced]:
        """The forced elements (FORCE_LIST)."""
        body = self.request(K.CMD_FORCE_LIST, what="forced")
        out, at = [], 1
        for _ in range(body[0]):
            item, elem, size = struct.unpack_from("<HHB", body, at)
            out.append(Forced(item, elem, bytes(body[at + 5:at + 5 + size])))
            at += 5 + size
        return out
