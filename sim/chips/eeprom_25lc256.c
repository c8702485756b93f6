/* EasyLab std chip model (el_chip.h): a 25LC256-class SPI EEPROM behind
 * the chip select of std's SpiEepromLog (docs/boards.md, "Chip models").
 *
 * SPI mode 0. READ, WRITE (after WREN; two address bytes, page writes
 * wrapping inside their page, programmed when the chip select rises, then
 * a write cycle of 5 ms with WIP set, during which it answers RDSR only),
 * RDSR (WIP, WEL), WREN, WRDI. Size and page: the device's `bytes` and
 * `page`. Its memory is el_chip_memory: erased (0xFF), or kept in
 * --chips DIR.
 */
#include "el_chip.h"

#include <string.h>

#define WRITE_CYCLE_US 5000u
#define MAX_PAGE 256u

#define CMD_WRITE 0x02u
#define CMD_READ 0x03u
#define CMD_WRDI 0x04u
#define CMD_RDSR 0x05u
#define CMD_WREN 0x06u
#define SR_WIP 0x01u
#define SR_WEL 0x02u

typedef struct {
    uint8_t *mem;
    uint32_t size;
    uint32_t page;
    bool selected;
    uint8_t command;
    uint32_t index;      /* bytes since the chip select fell */
    uint32_t at;
    uint32_t page_base;
    uint8_t next_out;    /* what it shifts out during the next byte */
    bool write_enabled;  /* WEL */
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
        el_chip_error(chip, "an SPI EEPROM of %lld bytes in pages of %lld: both powers of two, at most 65536 and "
                            "%u", (long long)size, (long long)page, MAX_PAGE);
        return;
    }
    s->size = (uint32_t)size;
    s->page = (uint32_t)page;
    s->mem = el_chip_memory(chip, s->size);
}

static bool busy(const el_chip_t *chip, const eeprom_t *s)
{
    return el_chip_now_us(chip) < s->busy_until;
}

static void spi_select(el_chip_t *chip, bool selected)
{
    eeprom_t *s = chip->state;
    uint32_t k;
    if (selected) { /* an instruction comes */
        s->selected = true;
        s->index = 0u;
        s->command = 0u;
        s->next_out = 0xFFu;
        return;
    }
    if (!s->selected)
        return;
    s->selected = false;
    if (s->command == CMD_WRITE && s->write_enabled && s->index > 3u && s->mem != NULL) {
        for (k = 0; k < s->page; k++) /* the write cycle starts */
            if (s->dirty[k])
                s->mem[s->page_base + k] = s->buffer[k];
        s->busy_until = el_chip_now_us(chip) + WRITE_CYCLE_US;
        s->write_enabled = false;
    } else if (s->command == CMD_WREN && s->index > 0u) {
        s->write_enabled = true;
    } else if (s->command == CMD_WRDI && s->index > 0u) {
        s->write_enabled = false;
    }
}

/* An address byte (k 0, 1) or a WRITE's data byte into the page buffer. */
static void take(eeprom_t *s, uint32_t k, uint8_t b)
{
    if (k == 0u) {
        s->at = (uint32_t)b << 8;
    } else if (k == 1u) {
        s->at = (s->at | b) & (s->size - 1u);
        s->page_base = s->at - s->at % s->page;
        memset(s->dirty, 0, sizeof s->dirty);
    } else {
        uint32_t off = s->at % s->page;
        s->buffer[off] = b;
        s->dirty[off] = true;
        s->at = s->page_base + (off + 1u) % s->page;
    }
}

static uint8_t spi_byte(el_chip_t *chip, uint8_t in)
{
    eeprom_t *s = chip->state;
    uint8_t out = s->next_out;
    s->next_out = 0xFFu;
    if (s->mem == NULL)
        return 0xFFu;
    if (s->index == 0u) {
        s->command = busy(chip, s) && in != CMD_RDSR ? 0u : in; /* in its write cycle it only answers RDSR */
    } else if (s->command == CMD_READ || s->command == CMD_WRITE) {
        if (s->index <= 2u || s->command == CMD_WRITE) { /* the address, then a WRITE's data */
            if (s->index <= 2u || s->write_enabled)
                take(s, s->index - 1u, in);
            if (s->index == 2u && s->command == CMD_READ)
                s->next_out = s->mem[s->at];
        } else { /* READ: the next byte */
            s->at = (s->at + 1u) & (s->size - 1u);
            s->next_out = s->mem[s->at];
        }
    }
    if (s->command == CMD_RDSR)
        s->next_out = (uint8_t)((busy(chip, s) ? SR_WIP : 0u) | (s->write_enabled ? SR_WEL : 0u));
    s->index++;
    return out;
}

const el_chip_ops_t EL_CHIP = {
    .name = "25lc256",
    .state_size = sizeof(eeprom_t),
    .reset = reset,
    .spi_select = spi_select,
    .spi_byte = spi_byte,
};
