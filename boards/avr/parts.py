"""The AVR board's MCUs, as board.toml describes them ([mcu.NAME])."""

from __future__ import annotations

from dataclasses import dataclass, field

from easylab.board.resources import Part


@dataclass
class Mcu:
    """One MCU of board.toml."""

    name: str
    title: str
    flash: int
    bootloader: int
    ram: int
    eeprom: int
    avrdude_part: str
    programmer: str
    upload_baud: int
    pins: list[str]
    pcint_groups: list[list[str]]
    ext_int: dict[str, int]
    uart: dict[int, list[str]]
    adc: dict[int, str]
    pwm: dict[str, tuple[int, str]]
    reserved_pwm: dict[str, str]
    wide_timers: list[int]
    unavailable: dict[str, str] = field(default_factory=dict)
    i2c: dict[int, list[str]] = field(default_factory=dict)  # the TWI: bus 0 -> (SDA, SCL)
    spi: dict[int, list[str]] = field(default_factory=dict)  # bus 0 -> (SCK, MOSI, MISO, SS)

    @property
    def small(self) -> bool:
        return self.ram <= 2048

    def part(self) -> Part:
        """The MCU's resources for the shared claim check: Timer2 runs the
        LET tick, so its compare outputs are no PWM; an encoder needs a
        pin-change or an external interrupt on each pin."""
        interrupt = set(self.ext_int) | {p for group in self.pcint_groups for p in group if p != "-"}
        reserved = {pin: f"({output}) belongs to Timer2, which runs the LET tick on this board"
                    for pin, output in self.reserved_pwm.items()}
        return Part(self.name, self.pins, self.uart, self.adc, dict(self.pwm), interrupt, self.unavailable, reserved,
                    network=False, pwm_source="timer output",
                    no_interrupt="which has neither a pin-change nor an external interrupt",
                    i2c=self.i2c, spi=self.spi)


def read_mcus(table: dict) -> dict[str, Mcu]:
    """board.toml's [mcu.*] tables by MCU name."""
    out = {}
    for name, m in table.items():
        out[name] = Mcu(name, m.get("title", name), int(m["flash"]), int(m.get("bootloader", 0)), int(m["ram"]),
                        int(m["eeprom"]), m["avrdude_part"], m["programmer"], int(m.get("upload_baud", 115200)),
                        list(m["pins"]), [list(g) for g in m.get("pcint_groups", [])],
                        {k: int(v) for k, v in m.get("int", {}).items()},
                        {int(k): list(v) for k, v in m.get("uart", {}).items()},
                        {int(k): str(v) for k, v in m.get("adc", {}).items()},
                        {k: (int(v[0]), str(v[1])) for k, v in m.get("pwm", {}).items()},
                        dict(m.get("reserved_pwm", {})), [int(t) for t in m.get("sixteen_bit_timers", [])],
                        dict(m.get("unavailable", {})),
                        {int(k): list(v) for k, v in m.get("i2c", {}).items()},
                        {int(k): list(v) for k, v in m.get("spi", {}).items()})
    return out
