"""The PIC18 board's MCUs, as board.toml describes them ([mcu.NAME])."""

from __future__ import annotations

from dataclasses import dataclass, field

from easylab.board.resources import Part

PORTS = "ABCDE"


@dataclass
class Mcu:
    """One MCU of board.toml."""

    name: str
    title: str
    gpsim: str  # gpsim's processor type
    programmer_part: str
    flash: int
    ram: int
    eeprom: int
    pins: list[str]
    uart: dict[int, list[str]]
    adc: dict[int, str]
    pwm: dict[str, int]  # pin -> CCP module
    ext_int: dict[str, int]  # pin -> INTn
    change: list[str]  # PORTB's interrupt on change
    unavailable: dict[str, str] = field(default_factory=dict)
    # sdcc's software stack (arguments, saved registers, the interrupt
    # handler's context), at the top of RAM below el_pic18_kept.
    stack: int = 384
    i2c: dict[int, list[str]] = field(default_factory=dict)  # the MSSP as I2C: bus 0 -> (SDA, SCL)
    spi: dict[int, list[str]] = field(default_factory=dict)  # the MSSP as SPI: bus 0 -> (SCK, SDO, SDI)

    @property
    def device(self) -> str:
        """sdcc's -p name: 18f4520."""
        return self.name.removeprefix("pic")

    @property
    def ram_last(self) -> int:
        """The last byte of RAM that start-up clears (el_pic18_kept is the next)."""
        return self.ram - 2

    @property
    def stack_bottom(self) -> int:
        """The software stack's lowest byte (it ends at ram_last)."""
        return self.ram_last + 1 - self.stack

    def aliases(self) -> dict[str, str]:
        """PB5 for RB5: the port-and-bit names other boards use."""
        return {"P" + p[1:]: p for p in self.pins + list(self.unavailable) if p.startswith("R")}

    def part(self) -> Part:
        """The MCU's resources for the shared claim check."""
        return Part(self.name, self.pins, self.uart, self.adc, dict(self.pwm), set(self.ext_int) | set(self.change),
                    self.unavailable, {}, network=False, pwm_source="CCP output",
                    no_interrupt="which has neither an external interrupt (INT0..INT2 on RB0..RB2) nor PORTB's "
                                 "interrupt on change (RB4..RB7)",
                    i2c=self.i2c, spi=self.spi, aliases=self.aliases(),
                    bus_modules={**{("i2c", n): "MSSP" for n in self.i2c}, **{("spi", n): "MSSP" for n in self.spi}})


def pin_code(pin: str) -> int:
    """The hardware layer's pin number (port << 3 | bit) of RB5 and the like."""
    return PORTS.index(pin[1]) << 3 | int(pin[2])


def read_mcus(table: dict) -> dict[str, Mcu]:
    """board.toml's [mcu.*] tables by MCU name."""
    out = {}
    for name, m in table.items():
        out[name] = Mcu(name, m.get("title", name), m["gpsim"], m["programmer_part"], int(m["flash"]), int(m["ram"]),
                        int(m["eeprom"]), list(m["pins"]), {int(k): list(v) for k, v in m.get("uart", {}).items()},
                        {int(k): str(v) for k, v in m.get("adc", {}).items()},
                        {str(k): int(v) for k, v in m.get("pwm", {}).items()},
                        {str(k): int(v) for k, v in m.get("int", {}).items()}, list(m.get("change", [])),
                        dict(m.get("unavailable", {})), int(m.get("stack", 384)),
                        {int(k): list(v) for k, v in m.get("i2c", {}).items()},
                        {int(k): list(v) for k, v in m.get("spi", {}).items()})
    return out
