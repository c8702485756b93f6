/* EasyLab AVR board, simulator harness: the chips on the I2C and SPI buses
 * (avr_chips.h).
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
 * it.
 */
#include "avr_chips.h"
#include "sim_chips.h"
#include "sim_model.h"
#include "host_internal.h"

#include "avr_ioport.h"
#include "avr_spi.h"
#include "avr_twi.h"
#include "sim_irq.h"
#include "sim_time.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* An EEPROM's write cycle (24LC256: 5 ms at the most). */
#define EEPROM_WRITE_US 5000u
/* A TMP102 measures -55 .. +150 degC. */
#define TEMP_MIN (-55 * 16)
#define TEMP_MAX (150 * 16)

enum { IDLE, WRITING, READING };

typedef struct {
    const sim_chip_t *spec;
    int state;           /* IDLE, or addressed for WRITING or READING */
    uint32_t index;      /* bytes written in this transaction */
    /* temperature sensor */
    uint8_t pointer;
    uint16_t reg[4];     /* temperature, configuration, T_LOW, T_HIGH */
    int32_t sixteenths;  /* the temperature */
    uint8_t byte_of_reg; /* the next byte of a register read: 0 MSB, 1 LSB */
    uint8_t written_hi;
    /* EEPROM */
    uint8_t *mem;
    uint32_t at;         /* the address pointer */
    uint8_t *page;       /* bytes of the page being written */
    bool *dirty;
    uint32_t page_base;
    avr_cycle_count_t busy_until;
    /* SPI EEPROM */
    bool selected;
    uint8_t command;
    uint8_t next_out;    /* what it shifts out during the next byte */
    bool write_enabled;  /* WEL */
} chip_t;

/* The 25LC256's instructions and status bits. */
#define SPI_READ 0x03u
#define SPI_WRITE 0x02u
#define SPI_WRDI 0x04u
#define SPI_RDSR 0x05u
#define SPI_WREN 0x06u
#define SPI_WIP 0x01u
#define SPI_WEL 0x02u

static avr_t *mcu;
static avr_irq_t *twi_in; /* the TWI's input: our answers */
static chip_t *chips;
static const char *chip_dir;

static void answer(uint8_t msg, uint8_t addr, uint8_t data)
{
    avr_raise_irq(twi_in, avr_twi_irq_msg(msg, addr, data));
}

/* ---- the temperature sensor ---- */

static bool extended(const chip_t *c)
{
    return (c->reg[1] & 0x0010u) != 0u; /* EM */
}

static uint16_t temperature_register(const chip_t *c)
{
    int32_t t = c->sixteenths;
    if (extended(c)) { /* 13 bits, then the EM flag in bit 0 */
        t = t < -4096 ? -4096 : t > 4095 ? 4095 : t;
        return (uint16_t)((uint16_t)((uint32_t)t << 3) | 1u);
    }
    t = t < -2048 ? -2048 : t > 2047 ? 2047 : t;
    return (uint16_t)((uint32_t)t << 4);
}

static void temp_write(chip_t *c, uint8_t b)
{
    if (c->index == 0u) {
        c->pointer = b & 3u;
        c->byte_of_reg = 0u;
    } else if (c->index == 1u) {
        c->written_hi = b;
    } else if (c->index == 2u && c->pointer != 0u) { /* the temperature register is read-only */
        c->reg[c->pointer] = (uint16_t)((uint16_t)c->written_hi << 8 | b);
    }
}

static uint8_t temp_read(chip_t *c)
{
    uint16_t r = c->pointer == 0u ? temperature_register(c) : c->reg[c->pointer];
    uint8_t b = c->byte_of_reg == 0u ? (uint8_t)(r >> 8) : (uint8_t)r;
    c->byte_of_reg ^= 1u;
    return b;
}

/* ---- the EEPROM ---- */

/* Byte k of a write: the address (most significant byte first), then data
 * into the page buffer. */
static void eeprom_write(chip_t *c, uint32_t k, uint8_t b)
{
    uint32_t size = c->spec->bytes, page = c->spec->page;
    if (k == 0u) {
        c->at = (uint32_t)b << 8;
    } else if (k == 1u) {
        c->at = (c->at | b) & (size - 1u);
        c->page_base = c->at - c->at % page;
        memset(c->dirty, 0, page * sizeof *c->dirty);
    } else { /* into the page buffer; the address wraps inside the page */
        uint32_t off = c->at % page;
        c->page[off] = b;
        c->dirty[off] = true;
        c->at = c->page_base + (off + 1u) % page;
    }
}

static uint8_t eeprom_read(chip_t *c)
{
    uint8_t b = c->mem[c->at];
    c->at = (c->at + 1u) & (c->spec->bytes - 1u);
    return b;
}

/* STOP (I2C) or the chip select's rise (SPI) after data bytes: the page is
 * written, the chip busy for a while. */
static void eeprom_commit(chip_t *c, uint32_t address_bytes)
{
    uint32_t k;
    if (c->index <= address_bytes)
        return;
    for (k = 0; k < c->spec->page; k++)
        if (c->dirty[k])
            c->mem[c->page_base + k] = c->page[k];
    c->busy_until = mcu->cycle + avr_usec_to_cycles(mcu, EEPROM_WRITE_US);
}

/* ---- the SPI EEPROM ---- */

static uint8_t spi_status(const chip_t *c)
{
    return (uint8_t)((mcu->cycle < c->busy_until ? SPI_WIP : 0u) | (c->write_enabled ? SPI_WEL : 0u));
}

static void spi_select(struct avr_irq_t *irq, uint32_t value, void *param)
{
    chip_t *c = (chip_t *)param;
    (void)irq;
    if (value == 0u) { /* selected: an instruction comes */
        c->selected = true;
        c->index = 0u;
        c->command = 0u;
        c->next_out = 0xFFu;
        return;
    }
    if (!c->selected)
        return;
    c->selected = false;
    if (c->command == SPI_WRITE && c->write_enabled) { /* the write cycle starts */
        eeprom_commit(c, 3u);
        if (c->index > 3u)
            c->write_enabled = false;
    } else if (c->command == SPI_WREN && c->index > 0u) {
        c->write_enabled = true;
    } else if (c->command == SPI_WRDI && c->index > 0u) {
        c->write_enabled = false;
    }
}

/* One byte in from the master; returns the byte shifted out meanwhile. */
static uint8_t spi_exchange(chip_t *c, uint8_t in)
{
    uint8_t out = c->next_out;
    bool busy = mcu->cycle < c->busy_until;
    c->next_out = 0xFFu;
    if (c->index == 0u) {
        c->command = busy && in != SPI_RDSR ? 0u : in; /* in its write cycle it only answers RDSR */
    } else if (c->command == SPI_READ || c->command == SPI_WRITE) {
        if (c->index <= 2u || c->command == SPI_WRITE) { /* the address, then a WRITE's data */
            if (c->index <= 2u || c->write_enabled)
                eeprom_write(c, c->index - 1u, in);
            if (c->index == 2u && c->command == SPI_READ)
                c->next_out = c->mem[c->at];
        } else { /* READ: the next byte */
            c->at = (c->at + 1u) & (c->spec->bytes - 1u);
            c->next_out = c->mem[c->at];
        }
    }
    if (c->command == SPI_RDSR)
        c->next_out = spi_status(c);
    c->index++;
    return out;
}

static void on_spi(struct avr_irq_t *irq, uint32_t value, void *param)
{
    uint16_t i;
    uint8_t out = 0xFFu; /* nothing selected: the line stays high */
    (void)irq;
    (void)param;
    bool std_selected = false;
    uint8_t user;
    for (i = 0; i < sim_chip_count; i++)
        if (chips[i].spec->kind == SIM_CHIP_SPI_EEPROM && chips[i].selected) {
            out = spi_exchange(&chips[i], (uint8_t)value);
            std_selected = true;
        }
    /* The chip models a model brings (sim/sim_chips.c): 0xFF when none is selected. */
    user = sim_chips_spi_byte(0u, (uint8_t)value);
    if (!std_selected)
        out = user;
    avr_raise_irq(avr_io_getirq(mcu, AVR_IOCTL_SPI_GETIRQ(0), SPI_IRQ_INPUT), out);
}

/* ---- the bus ---- */

/* The chip models a model brings (sim/sim_chips.c) on the same messages:
 * the one addressed since the last START, if it acknowledged. */
static bool user_addressed;

static void user_chips_on_bus(avr_twi_msg_irq_t m)
{
    if (m.u.twi.msg & TWI_COND_STOP) {
        if (user_addressed)
            sim_chips_i2c_stop(0u);
        user_addressed = false;
    }
    if (m.u.twi.msg & TWI_COND_START) {
        user_addressed = sim_chips_i2c_start(0u, (uint8_t)(m.u.twi.addr >> 1), (m.u.twi.addr & 1u) != 0u);
        if (user_addressed)
            answer(TWI_COND_ACK, m.u.twi.addr, 1u);
        return;
    }
    if (!user_addressed)
        return;
    if (m.u.twi.msg & TWI_COND_WRITE) {
        if (sim_chips_i2c_write(0u, m.u.twi.data))
            answer(TWI_COND_ACK, m.u.twi.addr, 1u);
    } else if (m.u.twi.msg & TWI_COND_READ) {
        answer(TWI_COND_READ, m.u.twi.addr, sim_chips_i2c_read(0u));
    }
}

/* A chip select of a chip model: its level as the port drives it. */
static void user_chip_select(struct avr_irq_t *irq, uint32_t value, void *param)
{
    const sim_chip_entry_t *e = (const sim_chip_entry_t *)param;
    (void)irq;
    sim_chips_spi_select(e->bus, e->cs, value == 0u);
}

static void on_bus(struct avr_irq_t *irq, uint32_t value, void *param)
{
    avr_twi_msg_irq_t m;
    uint16_t i;
    (void)irq;
    (void)param;
    m.u.v = value;
    user_chips_on_bus(m);
    for (i = 0; i < sim_chip_count; i++) {
        chip_t *c = &chips[i];
        bool eeprom = c->spec->kind == SIM_CHIP_EEPROM;
        if (c->spec->kind == SIM_CHIP_SPI_EEPROM)
            continue;
        if (m.u.twi.msg & TWI_COND_STOP) {
            if (c->state == WRITING && eeprom)
                eeprom_commit(c, 2u);
            c->state = IDLE;
        }
        if (m.u.twi.msg & TWI_COND_START) {
            bool us = (m.u.twi.addr >> 1) == c->spec->address;
            if (c->state == WRITING && eeprom && !us)
                eeprom_commit(c, 2u);
            c->state = IDLE;
            if (!us || (eeprom && mcu->cycle < c->busy_until))
                continue; /* not addressed, or in its write cycle: no acknowledge */
            c->state = (m.u.twi.addr & 1u) ? READING : WRITING;
            c->index = 0u;
            c->byte_of_reg = 0u;
            answer(TWI_COND_ACK, m.u.twi.addr, 1u);
            continue;
        }
        if (c->state == WRITING && (m.u.twi.msg & TWI_COND_WRITE)) {
            if (eeprom)
                eeprom_write(c, c->index, m.u.twi.data);
            else
                temp_write(c, m.u.twi.data);
            c->index++;
            answer(TWI_COND_ACK, m.u.twi.addr, 1u);
        } else if (c->state == READING && (m.u.twi.msg & TWI_COND_READ)) {
            answer(TWI_COND_READ, m.u.twi.addr, eeprom ? eeprom_read(c) : temp_read(c));
        }
    }
}

static void image_path(const chip_t *c, char *out, size_t n)
{
    if (c->spec->kind == SIM_CHIP_SPI_EEPROM)
        snprintf(out, n, "%s/spi%u-P%c%u.bin", chip_dir, (unsigned)c->spec->bus, c->spec->port,
                 (unsigned)c->spec->address);
    else
        snprintf(out, n, "%s/i2c%u-0x%02x.bin", chip_dir, (unsigned)c->spec->bus, (unsigned)c->spec->address);
}

bool sim_chips_init(avr_t *avr, const char *dir)
{
    uint16_t i;
    mcu = avr;
    chip_dir = dir;
    /* The SPI bus answers 0xFF (an idle MISO, pulled up) at a chip select
     * nothing answers, with chips or without (docs/boards.md). */
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_SPI_GETIRQ(0), SPI_IRQ_OUTPUT), on_spi, NULL);
    for (i = 0; i < sim_chip_table_count; i++)
        if (sim_chip_table[i].kind == SIM_CHIP_SPI)
            avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('A' + (sim_chip_table[i].cs >> 3)),
                                                  sim_chip_table[i].cs & 7u),
                                    user_chip_select, (void *)&sim_chip_table[i]);
    if (sim_chip_count == 0u && sim_chip_table_count == 0u)
        return true;
    chips = calloc(sim_chip_count ? sim_chip_count : 1u, sizeof *chips);
    if (chips == NULL)
        return false;
    twi_in = avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0), TWI_IRQ_INPUT);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0), TWI_IRQ_OUTPUT), on_bus, NULL);
    for (i = 0; i < sim_chip_count; i++) {
        chip_t *c = &chips[i];
        c->spec = &sim_chips[i];
        if (c->spec->kind == SIM_CHIP_SPI_EEPROM)
            avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(c->spec->port), c->spec->address),
                                    spi_select, c);
        if (c->spec->kind == SIM_CHIP_TEMPERATURE) {
            c->reg[1] = 0x60A0u; /* the TMP102's power-on configuration */
            c->reg[2] = 0x4B00u; /* 75 degC */
            c->reg[3] = 0x5000u; /* 80 degC */
            continue;
        }
        c->mem = malloc(c->spec->bytes);
        c->page = malloc(c->spec->page);
        c->dirty = calloc(c->spec->page, sizeof *c->dirty);
        if (c->mem == NULL || c->page == NULL || c->dirty == NULL)
            return false;
        memset(c->mem, 0xFF, c->spec->bytes);
        if (dir != NULL) {
            char path[4096];
            FILE *f;
            image_path(c, path, sizeof path);
            f = fopen(path, "rb");
            if (f == NULL && errno != ENOENT) {
                el_host_error("--chips: cannot read %s: %s", path, strerror(errno));
                return false;
            }
            if (f != NULL) {
                size_t n = fread(c->mem, 1, c->spec->bytes, f);
                int extra = fgetc(f);
                fclose(f);
                if (n != c->spec->bytes || extra != EOF) {
                    el_host_error("--chips: %s is not the memory of a %lu-byte EEPROM", path,
                                  (unsigned long)c->spec->bytes);
                    return false;
                }
            }
        }
    }
    return true;
}

bool sim_chips_temperature(uint8_t bus, uint8_t address, int32_t sixteenths, const char *what)
{
    uint16_t i;
    for (i = 0; i < sim_chip_count; i++) {
        chip_t *c = &chips[i];
        if (c->spec->bus != bus || c->spec->address != address || c->spec->kind != SIM_CHIP_TEMPERATURE)
            continue;
        if (sixteenths < TEMP_MIN || sixteenths > TEMP_MAX) {
            el_host_error("%s = %ld at %llu us: the temperature sensor at i2c[%u] 0x%02x measures -55 .. 150 degC "
                          "(-880 .. 2400 sixteenths)", what, (long)sixteenths, (unsigned long long)el_host_now_us(),
                          (unsigned)bus, (unsigned)address);
            return false;
        }
        c->sixteenths = sixteenths;
    }
    return true;
}

bool sim_chips_save(void)
{
    uint16_t i;
    bool ok = true;
    if (chip_dir == NULL)
        return true;
    for (i = 0; i < sim_chip_count; i++) {
        chip_t *c = &chips[i];
        char path[4096];
        FILE *f;
        if (c->spec->kind == SIM_CHIP_TEMPERATURE)
            continue;
        image_path(c, path, sizeof path);
        f = fopen(path, "wb");
        if (f == NULL || fwrite(c->mem, 1, c->spec->bytes, f) != c->spec->bytes) {
            el_host_error("--chips: cannot write %s: %s", path, strerror(errno));
            ok = false;
        }
        if (f != NULL && fclose(f) != 0)
            ok = false;
    }
    return ok;
}
