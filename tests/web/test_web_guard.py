"""The request guard shared by the service panel and the online mode
(host_tools/web_guard.py), on its own: addresses over drawn IPv4 and IPv6
addresses and ports (their servers' tests exercise it over HTTP)."""

from __future__ import annotations

import pytest
from hypothesis import given, strategies as st

from easylab.host_tools.web_guard import ListenError, host_name, is_loopback, make_guard, parse_listen

ADDRESSES = st.one_of(st.ip_addresses(v=4), st.ip_addresses(v=6))
PORTS = st.integers(0, 65535)


def bracketed(address) -> str:
    return f"[{address}]" if address.version == 6 else str(address)


@given(address=ADDRESSES, port=PORTS)
def test_listen_addresses_and_host_headers_come_back_with_what_they_name(address, port):
    assert parse_listen(f"{bracketed(address)}:{port}") == (str(address), port)
    assert host_name(f"{bracketed(address)}:{port}") == str(address)
    assert host_name(bracketed(address)) == str(address)
    assert is_loopback(str(address)) == address.is_loopback


@given(address=ADDRESSES, token=st.none() | st.from_regex(r"[A-Za-z0-9._~-]{8,128}", fullmatch=True))
def test_a_token_off_loopback_and_whenever_one_is_given(address, token):
    guard = make_guard(str(address), token, "easylab_test")
    assert guard.loopback == address.is_loopback
    assert guard.token == token if token is not None else (guard.token is None) == address.is_loopback
    assert guard.csrf and guard.csrf != guard.token


@pytest.mark.parametrize("text", ["8080", "host.example:80", "127.0.0.1:70000", "[::1]", "::1:80"])
def test_a_listen_address_it_cannot_use_is_refused_with_why(text):
    with pytest.raises(ListenError, match="--listen"):
        parse_listen(text)


def test_a_token_of_other_characters_is_refused():
    with pytest.raises(ListenError, match="--token"):
        make_guard("127.0.0.1", "short", "easylab_test")
    assert is_loopback("localhost") and is_loopback("[::1]") and not is_loopback("evil.example")
