/* EasyLab AVR board, simulator harness: simavr's buses to the chips'
 * dispatch (avr_chips.h; sim/sim_chips.c runs the chip models).
 *
 * simavr 1.6's TWI talks to the chips through IRQ messages: at each
 * address byte the master raises a START message carrying the address and
 * its R/W bit, then one WRITE message per byte written and one READ
 * message per byte it wants, and STOP at the end. A chip acknowledges an
 * address or a written byte by answering with an ACK message at once (no
 * answer is a NACK) and gives a read byte by answering with a READ message.
 * Its SPI raises each byte the master sends (100 us after SPDR is written,
 * whatever the clock); the selected chip answers at once with the byte it
 * shifts out meanwhile. A chip select is the pin's level as the port drives
 * it; the harness numbers pins (port letter - 'A') << 3 | bit.
 *
 * The pins a chip's device claims: after each write of the firmware to
 * their port's PORTx, DDRx or PINx, the level of each of them that is an output
 * goes to sim_chips_pin_driven (which reports the changes to the chip).
 * A chip's bytes on a UART and the levels it drives are avr_sim.c's
 * (sim_board_uart_receive, sim_board_pin_drive).
 */
#include "avr_chips.h"
#include "sim_chips.h"
#include "sim_model.h"

#include "avr_ioport.h"
#include "avr_spi.h"
#include "avr_twi.h"
#include "sim_io.h"
#include "sim_irq.h"
#include "sim_time.h"

#include <stdlib.h>

static avr_t *mcu;
static avr_irq_t *twi_in; /* the TWI's input: the chips' answers */
/* The level of each SPI chip's chip select as last seen (1: not selected),
 * by index into sim_chip_table. */
static uint8_t *cs_level;

static void answer(uint8_t msg, uint8_t addr, uint8_t data)
{
    avr_raise_irq(twi_in, avr_twi_irq_msg(msg, addr, data));
}

static void on_twi(struct avr_irq_t *irq, uint32_t value, void *param)
{
    avr_twi_msg_irq_t m;
    (void)irq;
    (void)param;
    m.u.v = value;
    if (m.u.twi.msg & TWI_COND_STOP)
        sim_chips_i2c_stop(0u);
    if (m.u.twi.msg & TWI_COND_START) {
        if (sim_chips_i2c_start(0u, (uint8_t)(m.u.twi.addr >> 1), (m.u.twi.addr & 1u) != 0u))
            answer(TWI_COND_ACK, m.u.twi.addr, 1u);
        return;
    }
    if (m.u.twi.msg & TWI_COND_WRITE) {
        if (sim_chips_i2c_write(0u, m.u.twi.data))
            answer(TWI_COND_ACK, m.u.twi.addr, 1u);
    } else if (m.u.twi.msg & TWI_COND_READ) {
        answer(TWI_COND_READ, m.u.twi.addr, sim_chips_i2c_read(0u));
    }
}

static void on_spi(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    avr_raise_irq(avr_io_getirq(mcu, AVR_IOCTL_SPI_GETIRQ(0), SPI_IRQ_INPUT), sim_chips_spi_byte(0u, (uint8_t)value));
}

static void on_chip_select(struct avr_irq_t *irq, uint32_t value, void *param)
{
    uint16_t k = (uint16_t)(uintptr_t)param;
    uint8_t level = (uint8_t)(value & 1u);
    (void)irq;
    if (level == cs_level[k]) /* the port wrote the pin's level again */
        return;
    cs_level[k] = level;
    sim_chips_spi_select(sim_chip_table[k].bus, sim_chip_table[k].cs, level == 0u);
}

uint16_t avr_port_addr(char port)
{
    if (port >= 'H') /* PORTH and up live in the extended I/O space */
        return (uint16_t)(0x102u + 3u * (uint16_t)(port - 'H' - (port > 'I' ? 1 : 0)));
    return (uint16_t)(0x22u + 3u * (uint16_t)(port - 'A'));
}

/* A write to PORTx, DDRx or PINx of a port with chip pins (param: the letter). */
static void on_port_write(struct avr_irq_t *irq, uint32_t value, void *param)
{
    char port = (char)(uintptr_t)param;
    avr_ioport_state_t state;
    uint16_t k;
    uint8_t j;
    (void)irq;
    (void)value;
    if (avr_ioctl(mcu, AVR_IOCTL_IOPORT_GETSTATE(port), &state) != 0)
        return;
    for (k = 0; k < sim_chip_table_count; k++) {
        for (j = 0; j < sim_chip_table[k].pin_count; j++) {
            uint16_t pin = sim_chip_table[k].pins[j];
            uint8_t bit = (uint8_t)(1u << (pin & 7u));
            if ((pin >> 3) == (uint16_t)(port - 'A') && (state.ddr & bit) != 0u)
                sim_chips_pin_driven(pin, (state.port & bit) != 0u);
        }
    }
}

/* Watch the ports of the chips' pins (each port once). */
static void watch_chip_pins(void)
{
    uint32_t watched = 0u; /* by port: bit (letter - 'A') */
    uint16_t k, offset;
    uint8_t j;
    for (k = 0; k < sim_chip_table_count; k++) {
        for (j = 0; j < sim_chip_table[k].pin_count; j++) {
            uint16_t n = sim_chip_table[k].pins[j] >> 3;
            char port = (char)('A' + n);
            uint16_t addr = avr_port_addr(port);
            if (n >= 32u || (watched & (1ul << n)) != 0u)
                continue;
            watched |= 1ul << n;
            /* PORTx, DDRx below it, PINx below that (a 1 written there toggles PORTx's bit) */
            for (offset = 0u; offset < 3u; offset++)
                avr_irq_register_notify(avr_iomem_getirq(mcu, (uint16_t)(addr - offset), NULL, AVR_IOMEM_IRQ_ALL),
                                        on_port_write, (void *)(uintptr_t)port);
        }
    }
}

bool avr_chips_attach(avr_t *avr)
{
    uint16_t k;
    mcu = avr;
    cs_level = calloc(sim_chip_table_count ? sim_chip_table_count : 1u, 1u);
    if (cs_level == NULL) {
        el_host_error("out of memory for the chips' selects");
        return false;
    }
    twi_in = avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0), TWI_IRQ_INPUT);
    if (twi_in != NULL)
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0), TWI_IRQ_OUTPUT), on_twi, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_SPI_GETIRQ(0), SPI_IRQ_OUTPUT), on_spi, NULL);
    for (k = 0; k < sim_chip_table_count; k++) {
        const sim_chip_entry_t *e = &sim_chip_table[k];
        if (e->kind != SIM_CHIP_SPI)
            continue;
        cs_level[k] = 1u;
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('A' + (e->cs >> 3)), e->cs & 7u),
                                on_chip_select, (void *)(uintptr_t)k);
    }
    watch_chip_pins();
    return true;
}
