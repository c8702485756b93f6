/* EasyLab simulator harnesses: the chips of one build on the simulated
 * buses (sim_chips.h), and what the chip-model API offers a chip
 * (el_chip.h). Shared by every simulator harness. */
#include "sim_chips.h"
#include "sim_harness.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* How many buses of each kind a board may have. */
#define SIM_BUSES 4u

typedef struct {
    el_chip_t chip;
    uint8_t *memory;
    size_t memory_size;
    /* The level the firmware last drove each of the device's pins to
     * (PIN_UNDRIVEN before the first): pin_edge reports the changes. */
    uint8_t *pin_level;
} chip_slot_t;

#define PIN_UNDRIVEN 0xFFu

static chip_slot_t *slots;
static const char *chip_dir;
/* A chip reported a problem (el_chip_error, a memory it cannot have). */
static bool chip_failed;
/* The chip addressed on each I2C bus since its last START (-1: none). */
static int32_t i2c_addressed[SIM_BUSES] = { -1, -1, -1, -1 };
/* The chip selected on each SPI bus (-1: none). */
static int32_t spi_selected[SIM_BUSES] = { -1, -1, -1, -1 };

static const el_chip_ops_t *ops_of(uint16_t k)
{
    return sim_chip_table[k].ops;
}

/* The chip's index in sim_chip_table. */
static uint16_t index_of(const el_chip_t *chip)
{
    return (uint16_t)((const chip_slot_t *)chip->harness - slots);
}

bool sim_chips_start(const char *dir)
{
    uint16_t k;
    chip_dir = dir;
    if (sim_chip_table_count == 0u)
        return true;
    slots = calloc(sim_chip_table_count, sizeof *slots);
    if (slots == NULL) {
        el_host_error("out of memory for the chip models");
        return false;
    }
    for (k = 0; k < sim_chip_table_count; k++) {
        const sim_chip_entry_t *e = &sim_chip_table[k];
        el_chip_t *c = &slots[k].chip;
        c->state = calloc(1, e->ops->state_size ? e->ops->state_size : 1u);
        if (c->state == NULL) {
            el_host_error("out of memory for the chip model of '%s'", e->device);
            return false;
        }
        c->device = e->device;
        c->bus = e->bus;
        c->address = e->address;
        c->cs = e->cs;
        c->cs_name = e->cs_name;
        c->value_count = e->value_count;
        c->value_names = e->value_names;
        c->pin_count = e->pin_count;
        c->pins = e->pins;
        c->harness = &slots[k];
        slots[k].pin_level = malloc(e->pin_count ? e->pin_count : 1u);
        if (slots[k].pin_level == NULL) {
            el_host_error("out of memory for the chip model of '%s'", e->device);
            return false;
        }
        memset(slots[k].pin_level, PIN_UNDRIVEN, e->pin_count ? e->pin_count : 1u);
    }
    /* Every chip's state is there before any reset runs (a chip's reset may
     * ask for its memory, which reports problems naming the device). */
    for (k = 0; k < sim_chip_table_count; k++)
        if (sim_chip_table[k].ops->reset != NULL)
            sim_chip_table[k].ops->reset(&slots[k].chip);
    return !chip_failed;
}

static void memory_path(const el_chip_t *c, char *out, size_t n)
{
    size_t i;
    snprintf(out, n, "%s/%s.bin", chip_dir, c->device);
    /* a nested device's path "a.b" stays one file name */
    for (i = strlen(chip_dir) + 1u; out[i] != '\0'; i++)
        if (out[i] == '/')
            out[i] = '_';
}

uint8_t *el_chip_memory(el_chip_t *chip, size_t size)
{
    chip_slot_t *s = chip->harness;
    FILE *f;
    char path[4096];
    if (s->memory != NULL) {
        if (size != s->memory_size) {
            el_chip_error(chip, "asked for %lu bytes of memory, then for %lu", (unsigned long)s->memory_size,
                          (unsigned long)size);
            return NULL;
        }
        return s->memory;
    }
    s->memory = malloc(size ? size : 1u);
    if (s->memory == NULL) {
        el_chip_error(chip, "out of memory for %lu bytes", (unsigned long)size);
        return NULL;
    }
    s->memory_size = size;
    memset(s->memory, 0xFF, size);
    if (chip_dir == NULL)
        return s->memory;
    memory_path(chip, path, sizeof path);
    f = fopen(path, "rb");
    if (f == NULL) {
        if (errno == ENOENT)
            return s->memory;
        el_host_error("--chips: cannot read %s: %s", path, strerror(errno));
        chip_failed = true;
        return NULL;
    }
    {
        size_t n = fread(s->memory, 1, size, f);
        int extra = fgetc(f);
        fclose(f);
        if (n != size || extra != EOF) {
            el_host_error("--chips: %s is not the %lu-byte memory of '%s'", path, (unsigned long)size, chip->device);
            chip_failed = true;
            return NULL;
        }
    }
    return s->memory;
}

bool sim_chips_finish(void)
{
    uint16_t k;
    bool ok = true;
    for (k = 0; k < sim_chip_table_count && slots != NULL; k++) {
        chip_slot_t *s = &slots[k];
        char path[4096];
        FILE *f;
        if (ops_of(k)->finish != NULL)
            ops_of(k)->finish(&s->chip);
        if (chip_dir == NULL || s->memory == NULL)
            continue;
        memory_path(&s->chip, path, sizeof path);
        f = fopen(path, "wb");
        if (f == NULL || fwrite(s->memory, 1, s->memory_size, f) != s->memory_size) {
            el_host_error("--chips: cannot write %s: %s", path, strerror(errno));
            ok = false;
        }
        if (f != NULL && fclose(f) != 0)
            ok = false;
    }
    return ok && !chip_failed; /* a chip's error during the run fails it */
}

bool sim_chips_value(uint16_t index, uint8_t k, const el_chip_value_t *value)
{
    const el_chip_ops_t *ops;
    if (index >= sim_chip_table_count)
        return true;
    ops = ops_of(index);
    return ops->value == NULL || ops->value(&slots[index].chip, k, value);
}

bool sim_chips_i2c_start(uint8_t bus, uint8_t address, bool read)
{
    uint16_t k;
    if (bus >= SIM_BUSES)
        return false;
    i2c_addressed[bus] = -1;
    for (k = 0; k < sim_chip_table_count; k++) {
        const sim_chip_entry_t *e = &sim_chip_table[k];
        if (e->kind != SIM_CHIP_I2C || e->bus != bus || e->address != address)
            continue;
        if (e->ops->i2c_start == NULL || !e->ops->i2c_start(&slots[k].chip, read))
            return false; /* there, but not acknowledging (an EEPROM's write cycle) */
        i2c_addressed[bus] = k;
        return true;
    }
    return false;
}

bool sim_chips_i2c_write(uint8_t bus, uint8_t byte)
{
    int32_t k = bus < SIM_BUSES ? i2c_addressed[bus] : -1;
    if (k < 0 || ops_of((uint16_t)k)->i2c_write == NULL)
        return false;
    return ops_of((uint16_t)k)->i2c_write(&slots[k].chip, byte);
}

uint8_t sim_chips_i2c_read(uint8_t bus)
{
    int32_t k = bus < SIM_BUSES ? i2c_addressed[bus] : -1;
    if (k < 0 || ops_of((uint16_t)k)->i2c_read == NULL)
        return 0xFFu; /* nobody drives SDA: the pull-up */
    return ops_of((uint16_t)k)->i2c_read(&slots[k].chip);
}

void sim_chips_i2c_stop(uint8_t bus)
{
    int32_t k = bus < SIM_BUSES ? i2c_addressed[bus] : -1;
    if (k >= 0 && ops_of((uint16_t)k)->i2c_stop != NULL)
        ops_of((uint16_t)k)->i2c_stop(&slots[k].chip);
    if (bus < SIM_BUSES)
        i2c_addressed[bus] = -1;
}

void sim_chips_spi_select(uint8_t bus, uint16_t cs, bool selected)
{
    uint16_t k;
    if (bus >= SIM_BUSES)
        return;
    for (k = 0; k < sim_chip_table_count; k++) {
        const sim_chip_entry_t *e = &sim_chip_table[k];
        if (e->kind != SIM_CHIP_SPI || e->bus != bus || e->cs != cs)
            continue;
        if (selected)
            spi_selected[bus] = k;
        else if (spi_selected[bus] == (int32_t)k)
            spi_selected[bus] = -1;
        if (e->ops->spi_select != NULL)
            e->ops->spi_select(&slots[k].chip, selected);
    }
}

uint8_t sim_chips_spi_byte(uint8_t bus, uint8_t mosi)
{
    int32_t k = bus < SIM_BUSES ? spi_selected[bus] : -1;
    if (k < 0 || ops_of((uint16_t)k)->spi_byte == NULL)
        return 0xFFu; /* an idle MISO, pulled up */
    return ops_of((uint16_t)k)->spi_byte(&slots[k].chip, mosi);
}

void sim_chips_uart_byte(uint8_t uart, uint8_t byte)
{
    uint16_t k;
    for (k = 0; k < sim_chip_table_count; k++)
        if (sim_chip_table[k].kind == SIM_CHIP_UART && sim_chip_table[k].bus == uart && ops_of(k)->uart_byte != NULL)
            ops_of(k)->uart_byte(&slots[k].chip, byte);
}

/* Which of chip k's pins `pin` is, or -1 when its device does not claim it. */
static int pin_index(uint16_t k, uint16_t pin)
{
    uint8_t j;
    for (j = 0; j < sim_chip_table[k].pin_count; j++)
        if (sim_chip_table[k].pins[j] == pin)
            return j;
    return -1;
}

void sim_chips_pin_driven(uint16_t pin, bool level)
{
    uint16_t k;
    for (k = 0; k < sim_chip_table_count; k++) {
        int j = pin_index(k, pin);
        if (j < 0 || slots[k].pin_level[j] == (uint8_t)level)
            continue;
        slots[k].pin_level[j] = (uint8_t)level;
        if (ops_of(k)->pin_edge != NULL)
            ops_of(k)->pin_edge(&slots[k].chip, pin, level);
    }
}

int64_t el_chip_param(const el_chip_t *chip, const char *name, int64_t otherwise)
{
    const sim_chip_entry_t *e = &sim_chip_table[index_of(chip)];
    uint8_t k;
    for (k = 0; k < e->param_count; k++)
        if (strcmp(e->param_names[k], name) == 0)
            return e->param_values[k];
    return otherwise;
}

uint64_t el_chip_now_us(const el_chip_t *chip)
{
    (void)chip;
    return sim_board_now_us();
}

void el_chip_uart_send(el_chip_t *chip, uint8_t byte)
{
    if (sim_chip_table[index_of(chip)].kind != SIM_CHIP_UART) {
        el_chip_error(chip, "sent 0x%02x on a UART, but its device claims none", (unsigned)byte);
        return;
    }
    sim_board_uart_receive(chip->bus, byte);
}

void el_chip_pin_drive(el_chip_t *chip, uint16_t pin, bool level)
{
    if (pin_index(index_of(chip), pin) < 0) {
        el_chip_error(chip, "drove pin %u, which its device does not claim", (unsigned)pin);
        return;
    }
    sim_board_pin_drive(pin, level);
}

void el_chip_error(const el_chip_t *chip, const char *format, ...)
{
    char text[512];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    chip_failed = true;
    el_host_error("%s (chip model): %s", chip->device, text);
    /* the run ends at the harness's next chance, failed */
    sim_stop = true;
    sim_exit_status = SIM_EXIT_RUN;
}
