/* EasyLab std chip model (el_chip.h): a 24LC256-class I2C EEPROM at the
 * address 0x50..0x57 a device claims when its type brings no chip model of
 * its own (docs/boards.md, "Chip models").
 *
 * A two-byte address (most significant byte first), sequential reads
 * across the whole memory, page writes that wrap inside their page and are
 * programmed at the STOP, then a write cycle of 5 ms during which the chip
 * acknowledges nothing (drivers poll it). Its size and page are the
 * device's parameters `bytes` and `page` (std's I2cEepromLog), else a
 * 24LC256's: 32768 and 64. Its memory is el_chip_memory: erased (0xFF), or
 * kept in --chips DIR.
 */
#include "el_chip.h"

#include <string.h>

#define WRITE_CYCLE_US 5000u
#define MAX_PAGE 256u

typedef struct {
    uint8_t *mem;
    uint32_t size;       /* a power of two */
    uint32_t page;
    uint32_t at;         /* the address pointer */
    uint32_t index;      /* bytes written since the address */
    uint32_t page_base;
    bool writing;
    uint64_t busy_until; /* us */
    uint8_t buffer[MAX_PAGE];
    bool dirty[MAX_PAGE];
} eeprom_t;

static bool power_of_two(int64_t n)
{
    return n > 0 && (n & (n - 1)) == 0;
}

static void reset(el_chip_t *chip)
{
    eeprom_t *s = chip->state;
    int64_t size = el_chip_param(chip, "bytes", 32768), page = el_chip_param(chip, "page", 64);
    if (!power_of_two(size) || size > 0x10000 || !power_of_two(page) || page > (int64_t)MAX_PAGE || page > size) {
        el_chip_error(chip, "an I2C EEPROM of %lld bytes in pages of %lld: both powers of two, at most 65536 and "
                            "%u", (long long)size, (long long)page, MAX_PAGE);
        return;
    }
    s->size = (uint32_t)size;
    s->page = (uint32_t)page;
    s->mem = el_chip_memory(chip, s->size);
}

/* The STOP (or a repeated START) after data bytes: the page is programmed,
 * the chip busy for its write cycle. */
static void commit(el_chip_t *chip, eeprom_t *s)
{
    uint32_t k;
    if (!s->writing || s->index <= 2u || s->mem == NULL)
        return;
    for (k = 0; k < s->page; k++)
        if (s->dirty[k])
            s->mem[s->page_base + k] = s->buffer[k];
    s->busy_until = el_chip_now_us(chip) + WRITE_CYCLE_US;
}

static bool i2c_start(el_chip_t *chip, bool read)
{
    eeprom_t *s = chip->state;
    commit(chip, s);
    s->writing = false;
    if (s->mem == NULL || el_chip_now_us(chip) < s->busy_until)
        return false; /* in its write cycle: no acknowledge */
    s->writing = !read;
    s->index = 0u;
    return true;
}

static bool i2c_write(el_chip_t *chip, uint8_t b)
{
    eeprom_t *s = chip->state;
    if (s->index == 0u) {
        s->at = (uint32_t)b << 8;
    } else if (s->index == 1u) {
        s->at = (s->at | b) & (s->size - 1u);
        s->page_base = s->at - s->at % s->page;
        memset(s->dirty, 0, sizeof s->dirty);
    } else { /* into the page buffer; the address wraps inside the page */
        uint32_t off = s->at % s->page;
        s->buffer[off] = b;
        s->dirty[off] = true;
        s->at = s->page_base + (off + 1u) % s->page;
    }
    s->index++;
    return true;
}

static uint8_t i2c_read(el_chip_t *chip)
{
    eeprom_t *s = chip->state;
    uint8_t b = s->mem[s->at];
    s->at = (s->at + 1u) & (s->size - 1u);
    return b;
}

static void i2c_stop(el_chip_t *chip)
{
    eeprom_t *s = chip->state;
    commit(chip, s);
    s->writing = false;
}

const el_chip_ops_t EL_CHIP = {
    .name = "24lc256",
    .state_size = sizeof(eeprom_t),
    .reset = reset,
    .i2c_start = i2c_start,
    .i2c_write = i2c_write,
    .i2c_read = i2c_read,
    .i2c_stop = i2c_stop,
};
