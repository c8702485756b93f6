"""CRC-16/MODBUS in Python, as runtime_c/el_crc16.c computes it: the map
builder (persist keys), the debug client and the tests use this one."""


def crc16(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/MODBUS of ``data`` (polynomial 0xA001 reflected), continuing
    from ``crc``; ``crc16(b"123456789") == 0x4B37``."""
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc
