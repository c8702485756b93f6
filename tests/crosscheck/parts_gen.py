"""The parts random models are written for: pins a model may claim for
digital I/O, ADC channels, PWM pins and encoder pin pairs, chosen from each
board's board.toml so that no two kinds collide (a pin behind an ADC
channel, a UART or a bus is not offered as a digital pin)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Part:
    name: str
    board: str
    digital: tuple[str, ...]
    adc: tuple[int, ...]
    pwm: tuple[str, ...]
    encoder_pairs: tuple[tuple[str, str], ...]
    adc_max: int = 1023
    i2c: bool = False  # std's I2C devices on bus 0
    spi_cs: tuple[str, ...] = ()  # chip selects for std's SPI devices on bus 0


PARTS = {p.name: p for p in (
    # PA/PC/PL: plain ports; INT2..INT3 and INT6..INT7 for encoders (simavr
    # models pin-change interrupts on port B only, where the SPI bus is);
    # ADC 0..5 on PF0..PF5; PWM on timers 1, 3, 4; I2C on PD0/PD1, SPI on
    # PB0..PB3 with chip selects on PL4/PL5.
    Part("atmega2560", "avr",
         digital=("PA0", "PA1", "PA2", "PA3", "PC0", "PC1", "PC2", "PC3", "PL0", "PL1", "PL2"),
         adc=(0, 1, 2, 3, 4, 5), pwm=("PB5", "PB6", "PE3", "PH3"),
         encoder_pairs=(("PE6", "PE7"), ("PD2", "PD3")), i2c=True, spi_cs=("PL4", "PL5")),
    # ADC 6 and 7 have no digital pin; PD0/PD1 are the UART; PB3..PB5 SPI.
    Part("atmega328p", "avr",
         digital=("PD2", "PD4", "PD7", "PB0", "PC2", "PC3"),
         adc=(6, 7, 0, 1), pwm=("PD6", "PD5", "PB1", "PB2"),
         encoder_pairs=(("PC4", "PC5"),)),
    # AN0..AN3 on RA0..RA3; RB0..RB2 (INTn) and RB4..RB7 (change) for
    # encoders; CCP1/CCP2 on RC2/RC1; RC6/RC7 the EUSART.
    Part("pic18f4620", "pic18",
         digital=("RD0", "RD1", "RD2", "RD3", "RD4", "RD5", "RD6", "RD7", "RC0", "RC3"),
         adc=(0, 1, 2, 3), pwm=("RC2", "RC1"),
         encoder_pairs=(("RB1", "RB2"), ("RB4", "RB5"))),
    # The F16's MB90F543: port 0..3 digital, AN0..AN7 on port 5, PPG on
    # port 7, INT0..INT7 on port 6.
    Part("mb90f543", "f16",
         digital=("P00", "P01", "P02", "P03", "P10", "P11", "P12", "P13"),
         adc=(0, 1, 2, 3), pwm=("P70", "P71", "P72"),
         encoder_pairs=(("P60", "P61"), ("P62", "P63"))),
)}
