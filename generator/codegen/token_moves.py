"""C that moves a dataflow's tokens between its buffers, its actors and
its task's items: linear copies and circular buffers (runtime_c/
el_dispatch.h's EL_COPY, EL_RING_GET, EL_RING_PUT)."""

from __future__ import annotations


def ring_get(ring: str, size: int, dst: str, n: int) -> str:
    """C taking ``n`` tokens from a circular buffer into ``dst``. One token
    is an assignment, not a loop, and a one-token ring's index never moves:
    8-bit compilers (sdcc) spend much of a dataflow's code and of their own
    time on loops of one."""
    if n != 1:
        return f"EL_RING_GET({ring}, {ring}_rd, {size}u, {dst}, {n}u);"
    if size == 1:
        return f"({dst})[0] = {ring}[{ring}_rd];"
    return f"({dst})[0] = {ring}[{ring}_rd]; {ring}_rd = (uint16_t)({ring}_rd + 1u == {size}u ? 0u : {ring}_rd + 1u);"


def ring_put(ring: str, size: int, src: str, n: int) -> str:
    """C putting ``n`` tokens of ``src`` into a circular buffer (as ``ring_get``)."""
    if n != 1:
        return f"EL_RING_PUT({ring}, {ring}_wr, {size}u, {src}, {n}u);"
    if size == 1:
        return f"{ring}[{ring}_wr] = ({src})[0];"
    return f"{ring}[{ring}_wr] = ({src})[0]; {ring}_wr = (uint16_t)({ring}_wr + 1u == {size}u ? 0u : {ring}_wr + 1u);"


def copy_tokens(dst: str, src: str, n: int) -> str:
    """C copying ``n`` tokens (one: an assignment)."""
    return f"({dst})[0] = ({src})[0];" if n == 1 else f"EL_COPY({dst}, {src}, {n}u);"
