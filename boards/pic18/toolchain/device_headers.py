"""Device headers and device libraries for sdcc's pic16 port, generated
from gputils' assembler include files (``p18f4520.inc``): Microchip's own
C headers are non-free and Debian's sdcc ships none.

For each part it writes ``pic18fNNNN.h`` (what ``<pic18fregs.h>`` includes
for ``-p18fNNNN``: every special function register as an ``__sfr`` at its
address and, where the include file names its bits, a ``NAMEbits`` union
of bit fields, as Microchip's and sdcc's own headers have them) and
``pic18fNNNN.c`` (their definitions, which ``build.sh`` compiles and
archives as ``libdev18fNNNN.lib``, the library sdcc links for the part).

Usage: python3 device_headers.py INC_DIR OUT_DIR PART...   (PART: 18f4520)
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

_EQU = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)\s+EQU\s+H'([0-9A-Fa-f]+)'")
_BITS = re.compile(r"^;-+\s*([A-Za-z0-9_]+) Bits\s*-+")
# Registers start at the access bank's SFR area of every PIC18.
_SFR_FIRST = 0xF60
# Bytes of data EEPROM by part: libsdcc's generic pointers reach the EEPROM
# through __eeprom_gptrget/put, which a device library maps onto the 8-bit
# or 16-bit address routines.
EEPROM_BYTES = {"18f4520": 256, "18f4620": 1024}


def parse(text: str) -> tuple[dict[str, int], dict[str, list[dict[int, str]]]]:
    """(register -> address, register -> groups of bit names by position)
    of one include file."""
    registers: dict[str, int] = {}
    bits: dict[str, list[dict[int, str]]] = {}
    section = "registers"
    current: dict[int, str] = {}
    for raw in text.splitlines():
        line = raw.strip()
        if line.startswith(";") and ("Configuration Bits" in line or "RAM Definitions" in line):
            section = "done"
            continue
        m = _BITS.match(line)
        if m:
            section = m.group(1)
            current = {}
            bits.setdefault(section, []).append(current)
            continue
        if section == "done":
            continue
        m = _EQU.match(line)
        if m is None:
            if line == "" and section != "registers" and current:
                current = {}
                bits[section].append(current)
            continue
        name, value = m.group(1), int(m.group(2), 16)
        if section == "registers":
            if value >= _SFR_FIRST:
                registers[name] = value
        elif value < 8 and value not in current:
            current[value] = name
    return registers, {reg: [g for g in groups if g] for reg, groups in bits.items()}


def _bits_union(reg: str, groups: list[dict[int, str]]) -> list[str]:
    """typedef union { struct { unsigned NAME:1; ... }; ... } __REGbits_t;
    a name used by an earlier group of the union is left unnamed."""
    used: set[str] = set()
    lines = ["typedef union {"]
    for group in groups:
        fields = []
        for pos in range(8):
            name = group.get(pos)
            if name is None or name in used:
                fields.append("        unsigned :1;")
            else:
                used.add(name)
                fields.append(f"        unsigned {name}:1;")
        lines += ["    struct {", *fields, "    };"]
    lines.append(f"}} __{reg}bits_t;")
    return lines


def render(part: str, text: str) -> tuple[str, str]:
    """(header, definitions) of one part from its include file's text."""
    registers, bits = parse(text)
    guard = f"__PIC{part.upper()}_H__"
    head = [f"/* PIC{part.upper()}: special function registers for sdcc's pic16 port, generated from gputils'",
            f" * p{part}.inc by EasyLab's boards/pic18/toolchain/device_headers.py. Do not edit. */",
            f"#ifndef {guard}", f"#define {guard}", ""]
    body = [f"/* PIC{part.upper()}: definitions of the special function registers (device_headers.py). */",
            f"#include <pic{part}.h>", ""]
    for reg, addr in sorted(registers.items(), key=lambda kv: (kv[1], kv[0])):
        head.append(f"extern __at(0x{addr:04X}) __sfr {reg};")
        body.append(f"__at(0x{addr:04X}) __sfr {reg};")
        if reg in bits and bits[reg]:
            head += _bits_union(reg, bits[reg])
            head.append(f"extern __at(0x{addr:04X}) volatile __{reg}bits_t {reg}bits;")
            body.append(f"__at(0x{addr:04X}) volatile __{reg}bits_t {reg}bits;")
    head += ["", f"#endif /* {guard} */", ""]
    width = 8 if EEPROM_BYTES[part] <= 256 else 16
    body += ["", f"/* Generic pointers into the {EEPROM_BYTES[part]} bytes of data EEPROM: libsdcc's {width}-bit "
             "address routines. */"]
    for op in ("get", "put"):
        for n in range(1, 5):
            body.append(f"extern int __eeprom{width}_gptr{op}{n};")
            body.append(f"void __eeprom_gptr{op}{n}(void) __naked {{ __asm goto ___eeprom{width}_gptr{op}{n} "
                        "__endasm; }")
    return "\n".join(head), "\n".join(body) + "\n"


def main(argv: list[str]) -> int:
    if len(argv) < 4:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    inc_dir, out_dir = Path(argv[1]), Path(argv[2])
    out_dir.mkdir(parents=True, exist_ok=True)
    for part in argv[3:]:
        inc = inc_dir / f"p{part}.inc"
        try:
            text = inc.read_text(encoding="latin-1")
        except OSError as err:
            print(f"device_headers.py: cannot read {inc}: {err.strerror} (Debian package: gputils)", file=sys.stderr)
            return 1
        header, source = render(part, text)
        (out_dir / f"pic{part}.h").write_text(header, encoding="ascii")
        (out_dir / f"pic{part}.c").write_text(source, encoding="ascii")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
