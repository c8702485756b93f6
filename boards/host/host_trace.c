/* EasyLab host board: traces.
 *
 * At each el_port_instant(tick) the trace records every item of el_items
 * (an item with count n > 1 as n columns) and every chart's step activity,
 * at logical time tick * el_tick_us microseconds.
 *
 * CSV (`--trace F.csv`): a header `time_us,` then the item names in
 * el_items order (`name[0]` .. `name[n-1]` for count n > 1), then
 * `CHART.active` per chart (with --trace-state, the devices' state fields,
 * `DEVICE.FIELD` of el_host_state_items, come between the items and the
 * charts); a row per instant at which any value differs
 * from the previous row (the first instant always gives a row). Values:
 * bool 0/1, integers in decimal, float32 as %.9g (exact round trip; every
 * NaN as "nan": its sign depends on the compiler, not on the model),
 * time as integer milliseconds, chart activity as the names of the active
 * steps in step order joined by `+` (empty when none is active).
 *
 * VCD (`--trace F.vcd`, opens in GTKWave): `$timescale 1us`, one
 * `$scope module` named after the model holding every signal under its
 * model path: bool as a 1-bit wire, integers as wires of their width (signed
 * ones in two's complement), time as a 32-bit wire of milliseconds,
 * float32 as `real`, each chart as `CHART.active`, a wire of step_count bits
 * with bit i set when step i is active (charts without steps are left out).
 * Elements of count n > 1 items are named `name(i)` in VCD (GTKWave reads
 * a trailing `[i]` as a bit index). `$dumpvars` gives every value at the
 * first instant; after it only changes are written, under `#time` lines.
 * At the end a last `#time` marks the end of the last traced tick.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "host_internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define COL_CHART 0xFFu

typedef struct {
    uint16_t index;   /* into el_items (el_host_state_items for `state`), or el_charts for COL_CHART */
    bool state;       /* a device's state field (--trace-state) */
    uint16_t elem;    /* element of a count > 1 item */
    uint8_t type;     /* EL_T_..., or COL_CHART */
    bool indexed;     /* count > 1: the column of one element */
    size_t width;     /* bytes in the snapshot */
    size_t off;       /* offset in the snapshot */
    char id[8];       /* VCD identifier code */
} tcol_t;

enum { FMT_CSV, FMT_VCD };

bool el_host_trace_state;

static FILE *out;
static int fmt;
static const char *trace_path;
static int write_errno;   /* first write error, reported once */
static tcol_t *cols;
static size_t ncols;
static unsigned char *snap_prev, *snap_cur;
static size_t snap_size;
static bool have_prev;
static uint64_t last_tick;

static void release(void)
{
    free(cols);
    free(snap_prev);
    free(snap_cur);
    cols = NULL;
    snap_prev = snap_cur = NULL;
    ncols = snap_size = 0;
    have_prev = false;
}

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix), i;
    if (n <= m)
        return false;
    for (i = 0; i < m; i++) {
        char c = s[n - m + i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != suffix[i])
            return false;
    }
    return true;
}

/* ---- columns and snapshots ---- */

/* The devices' state fields traced: none unless --trace-state (and the
 * program has the table, host_ranges.c). */
static uint16_t state_count(void)
{
    if (!el_host_trace_state || &el_host_state_item_count == NULL || el_host_state_items == NULL)
        return 0u;
    return el_host_state_item_count;
}

static const el_item_t *item_of(const tcol_t *t)
{
    return t->state ? &el_host_state_items[t->index] : &el_items[t->index];
}

static bool build_columns(void)
{
    size_t n = el_chart_count, k = 0, off = 0;
    uint16_t i, e, states = state_count();
    uint8_t c;
    int pass;

    for (i = 0; i < el_item_count; i++)
        n += el_items[i].count;
    for (i = 0; i < states; i++)
        n += el_host_state_items[i].count;
    cols = calloc(n ? n : 1u, sizeof *cols);
    if (cols == NULL)
        return false;
    /* The items, then the devices' state fields, then the charts. */
    for (pass = 0; pass < 2; pass++) {
        const el_item_t *table = pass == 0 ? el_items : el_host_state_items;
        uint16_t count = pass == 0 ? el_item_count : states;
        for (i = 0; i < count; i++)
            for (e = 0; e < table[i].count; e++) {
                tcol_t *t = &cols[k++];
                t->index = i;
                t->state = pass == 1;
                t->elem = e;
                t->type = table[i].type;
                t->indexed = table[i].count > 1u;
                t->width = t->type == EL_T_BOOL ? 1u : el_host_type_size(t->type);
            }
    }
    for (c = 0; c < el_chart_count; c++) {
        tcol_t *t = &cols[k++];
        t->index = c;
        t->type = COL_CHART;
        t->width = el_charts[c].step_count;
    }
    ncols = n;
    for (k = 0; k < ncols; k++) {
        size_t code = k;
        char *p = cols[k].id;
        cols[k].off = off;
        off += cols[k].width;
        do { /* base 94 over the printable characters '!' .. '~' */
            *p++ = (char)('!' + code % 94u);
            code /= 94u;
        } while (code != 0u && p < cols[k].id + sizeof cols[k].id - 1);
        *p = '\0';
    }
    snap_size = off;
    snap_prev = malloc(snap_size ? snap_size : 1u);
    snap_cur = malloc(snap_size ? snap_size : 1u);
    return snap_prev != NULL && snap_cur != NULL;
}

/* Copy the current values into snap_cur, canonical so that equal bytes
 * mean equal printed values (bool as 0/1, one NaN per sign). */
static void take_snapshot(void)
{
    size_t k;
    for (k = 0; k < ncols; k++) {
        const tcol_t *t = &cols[k];
        unsigned char *dst = snap_cur + t->off;
        if (t->type == COL_CHART) {
            const el_chart_t *ch = &el_charts[t->index];
            uint8_t s;
            for (s = 0; s < ch->step_count; s++)
                dst[s] = ch->active[s] != 0u;
        } else {
            const el_item_t *it = item_of(t);
            size_t size = el_host_type_size(t->type);
            const unsigned char *src = (const unsigned char *)it->addr + (size_t)t->elem * size;
            if (t->type == EL_T_BOOL) {
                size_t b;
                dst[0] = 0;
                for (b = 0; b < size; b++)
                    if (src[b] != 0u)
                        dst[0] = 1;
            } else if (t->type == EL_T_F32) {
                float f;
                memcpy(&f, src, sizeof f);
                if (isnan(f))
                    f = signbit(f) ? -NAN : NAN;
                memcpy(dst, &f, sizeof f);
            } else {
                memcpy(dst, src, size);
            }
        }
    }
}

/* The integer value of a snapshot cell, as two's complement bits for the
 * signed types; *is_signed tells how to print it. */
static uint32_t cell_bits(const tcol_t *t, const unsigned char *cell, bool *is_signed)
{
    int8_t i8;
    int16_t i16;
    int32_t i32;
    uint16_t u16;
    uint32_t u32;
    *is_signed = false;
    switch (t->type) {
    case EL_T_I8: memcpy(&i8, cell, 1); *is_signed = true; return (uint32_t)(int32_t)i8;
    case EL_T_I16: memcpy(&i16, cell, 2); *is_signed = true; return (uint32_t)(int32_t)i16;
    case EL_T_I32: memcpy(&i32, cell, 4); *is_signed = true; return (uint32_t)i32;
    case EL_T_U16: memcpy(&u16, cell, 2); return u16;
    case EL_T_U32:
    case EL_T_TIME: memcpy(&u32, cell, 4); return u32;
    default: return cell[0]; /* bool, uint8 */
    }
}

static unsigned bit_width(uint8_t type)
{
    switch (type) {
    case EL_T_BOOL: return 1;
    case EL_T_I8:
    case EL_T_U8: return 8;
    case EL_T_I16:
    case EL_T_U16: return 16;
    default: return 32;
    }
}

/* ---- CSV ---- */

static void csv_header(void)
{
    size_t k;
    fputs("time_us", out);
    for (k = 0; k < ncols; k++) {
        const tcol_t *t = &cols[k];
        if (t->type == COL_CHART)
            fprintf(out, ",%s.active", el_charts[t->index].name);
        else if (t->indexed)
            fprintf(out, ",%s[%u]", item_of(t)->name, (unsigned)t->elem);
        else
            fprintf(out, ",%s", item_of(t)->name);
    }
    fputc('\n', out);
}

static void csv_row(uint64_t time_us)
{
    size_t k;
    fprintf(out, "%llu", (unsigned long long)time_us);
    for (k = 0; k < ncols; k++) {
        const tcol_t *t = &cols[k];
        const unsigned char *cell = snap_cur + t->off;
        fputc(',', out);
        if (t->type == COL_CHART) {
            const el_chart_t *ch = &el_charts[t->index];
            uint8_t s;
            bool first = true;
            for (s = 0; s < ch->step_count; s++)
                if (cell[s]) {
                    if (!first)
                        fputc('+', out);
                    fputs(ch->step_names[s], out);
                    first = false;
                }
        } else if (t->type == EL_T_F32) {
            float f;
            memcpy(&f, cell, sizeof f);
            if (isnan(f))
                fputs("nan", out); /* the sign of a NaN depends on the compiler, not the model */
            else
                fprintf(out, "%.9g", (double)f);
        } else {
            bool is_signed;
            uint32_t v = cell_bits(t, cell, &is_signed);
            if (is_signed)
                fprintf(out, "%ld", (long)(int32_t)v);
            else
                fprintf(out, "%lu", (unsigned long)v);
        }
    }
    fputc('\n', out);
}

/* ---- VCD ---- */

/* A VCD reference: no whitespace or control characters. */
static void vcd_name(const char *s)
{
    for (; *s; s++)
        fputc((unsigned char)*s <= ' ' || (unsigned char)*s > '~' ? '_' : *s, out);
}

static void vcd_header(void)
{
    size_t k;
    fprintf(out, "$comment EasyLab trace of model %s, program id 0x%08lx, tick %lu us $end\n", el_model_name,
            (unsigned long)el_program_id, (unsigned long)el_tick_us);
    fputs("$timescale 1us $end\n$scope module ", out);
    vcd_name(el_model_name[0] ? el_model_name : "model");
    fputs(" $end\n", out);
    for (k = 0; k < ncols; k++) {
        const tcol_t *t = &cols[k];
        if (t->type == COL_CHART) {
            if (t->width == 0u)
                continue;
            fprintf(out, "$var wire %u %s ", (unsigned)t->width, t->id);
            vcd_name(el_charts[t->index].name);
            fputs(".active", out);
        } else {
            if (t->type == EL_T_F32)
                fprintf(out, "$var real 64 %s ", t->id);
            else
                fprintf(out, "$var wire %u %s ", bit_width(t->type), t->id);
            vcd_name(item_of(t)->name);
            if (t->indexed)
                fprintf(out, "(%u)", (unsigned)t->elem);
        }
        fputs(" $end\n", out);
    }
    fputs("$upscope $end\n$enddefinitions $end\n", out);
}

static void vcd_value(const tcol_t *t, const unsigned char *cell)
{
    unsigned w, b;
    if (t->type == COL_CHART) {
        w = (unsigned)t->width;
        if (w == 0u)
            return;
        if (w == 1u) {
            fprintf(out, "%c%s\n", cell[0] ? '1' : '0', t->id);
            return;
        }
        fputc('b', out);
        for (b = w; b-- > 0;)
            fputc(cell[b] ? '1' : '0', out);
    } else if (t->type == EL_T_F32) {
        float f;
        memcpy(&f, cell, sizeof f);
        if (isnan(f))
            fputs("rnan", out);
        else
            fprintf(out, "r%.9g", (double)f);
    } else if (t->type == EL_T_BOOL) {
        fprintf(out, "%c%s\n", cell[0] ? '1' : '0', t->id);
        return;
    } else {
        bool is_signed;
        uint32_t v = cell_bits(t, cell, &is_signed);
        w = bit_width(t->type);
        fputc('b', out);
        for (b = w; b-- > 0;)
            fputc((v >> b) & 1u ? '1' : '0', out);
    }
    fprintf(out, " %s\n", t->id);
}

/* ---- the interface ---- */

bool el_host_trace_open(const char *path)
{
    el_host_trace_close();
    if (ends_with(path, ".csv"))
        fmt = FMT_CSV;
    else if (ends_with(path, ".vcd"))
        fmt = FMT_VCD;
    else {
        el_host_error("--trace %s: unknown trace format (give a .csv or a .vcd file)", path);
        return false;
    }
    if (!build_columns()) {
        el_host_error("out of memory for the trace");
        release();
        return false;
    }
    out = fopen(path, "w");
    if (out == NULL) {
        el_host_error("cannot write trace %s: %s", path, strerror(errno));
        release();
        return false;
    }
    setvbuf(out, NULL, _IOFBF, 65536u);
    trace_path = path;
    write_errno = 0;
    if (fmt == FMT_CSV)
        csv_header();
    else
        vcd_header();
    return true;
}

static void check_write(void)
{
    if (write_errno == 0 && ferror(out)) {
        write_errno = errno ? errno : EIO;
        el_host_error("error writing trace %s: %s", trace_path, strerror(write_errno));
    }
}

void el_host_trace_instant(uint64_t tick)
{
    uint64_t time_us;
    size_t k;

    if (out == NULL)
        return;
    errno = 0;
    take_snapshot();
    time_us = tick * (uint64_t)el_tick_us;
    if (fmt == FMT_CSV) {
        if (!have_prev || memcmp(snap_prev, snap_cur, snap_size) != 0)
            csv_row(time_us);
    } else if (!have_prev) {
        fprintf(out, "#%llu\n$dumpvars\n", (unsigned long long)time_us);
        for (k = 0; k < ncols; k++)
            vcd_value(&cols[k], snap_cur + cols[k].off);
        fputs("$end\n", out);
    } else {
        bool stamped = false;
        for (k = 0; k < ncols; k++) {
            const tcol_t *t = &cols[k];
            if (t->width == 0u || memcmp(snap_prev + t->off, snap_cur + t->off, t->width) == 0)
                continue;
            if (!stamped) {
                fprintf(out, "#%llu\n", (unsigned long long)time_us);
                stamped = true;
            }
            vcd_value(t, snap_cur + t->off);
        }
    }
    {
        unsigned char *swap = snap_prev;
        snap_prev = snap_cur;
        snap_cur = swap;
    }
    have_prev = true;
    last_tick = tick;
    check_write();
}

bool el_host_trace_close(void)
{
    bool ok;
    if (out == NULL)
        return true;
    if (fmt == FMT_VCD && have_prev)
        fprintf(out, "#%llu\n", (unsigned long long)((last_tick + 1u) * (uint64_t)el_tick_us));
    errno = 0;
    if (fflush(out) != 0 || ferror(out))
        check_write();
    if (fclose(out) != 0 && write_errno == 0) {
        write_errno = errno ? errno : EIO;
        el_host_error("error writing trace %s: %s", trace_path, strerror(write_errno));
    }
    out = NULL;
    ok = write_errno == 0;
    release();
    return ok;
}
