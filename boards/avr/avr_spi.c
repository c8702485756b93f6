/* EasyLab AVR board: the SPI bus spi[0], master (runtime_c/el_bus.h;
 * docs/boards.md, "Buses").
 *
 * A transfer is done in place, byte after byte, polling SPIF: at the
 * board's clock (EL_AVR_SPI_HZ, from board.toml: 4 MHz, F_CPU / 4) a byte
 * takes 2 us, less than an interrupt per byte would cost; a transfer of n
 * bytes takes n * 8 / EL_AVR_SPI_HZ seconds and a few cycles a byte. The
 * SS pin is an output (in master mode an SS input pulled low would make
 * the SPI a slave); a chip select is any pin (struct el_pin: PINx, then
 * DDRx and PORTx at the next two addresses, as on every AVR port).
 */
#include "avr_internal.h"

#if defined(EL_AVR_SPI) && EL_AVR_SPI

#include "el_bus.h"
#include "el_board.h"

static bool spi_on;

static void spi_start(void)
{
    EL_AVR_SPI_DDR |= EL_AVR_SPI_OUTPUTS; /* SCK, MOSI and SS out; MISO in */
    EL_AVR_SPI_PORT |= EL_AVR_SPI_SS;     /* SS high: selects nothing of its own */
    SPCR = (uint8_t)(_BV(SPE) | _BV(MSTR) | EL_AVR_SPI_SPR);
    SPSR = EL_AVR_SPI_2X;
    spi_on = true;
}

el_bus_status_t el_spi_open(uint8_t bus, const el_pin_t *cs)
{
    if (bus != 0u || cs == 0) {
        return EL_BUS_ERROR;
    }
    if (!spi_on) {
        spi_start();
    }
    cs->pin[2] |= cs->mask; /* PORTx: high, selects nothing */
    cs->pin[1] |= cs->mask; /* DDRx: an output */
    return EL_BUS_DONE;
}

el_bus_status_t el_spi_transfer(uint8_t bus, const el_pin_t *cs, uint8_t mode, const uint8_t *tx, uint8_t *rx,
                                uint16_t len)
{
    uint16_t i;
    if (el_spi_open(bus, cs) != EL_BUS_DONE) {
        return EL_BUS_ERROR;
    }
    SPCR = (uint8_t)((SPCR & (uint8_t)~(_BV(CPOL) | _BV(CPHA))) | (uint8_t)((mode & 3u) << CPHA));
    cs->pin[2] &= (uint8_t)~cs->mask; /* selected */
    for (i = 0u; i < len; i++) {
        uint8_t in;
        SPDR = tx != 0 ? tx[i] : 0xFFu;
        while ((SPSR & _BV(SPIF)) == 0u) {
        }
        in = SPDR;
        if (rx != 0) {
            rx[i] = in;
        }
    }
    cs->pin[2] |= cs->mask;
    return EL_BUS_DONE;
}

#else
typedef int el_avr_spi_unused_t; /* ISO C wants something here */
#endif /* EL_AVR_SPI */
