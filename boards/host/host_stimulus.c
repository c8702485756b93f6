/* EasyLab host board: stimulus files and the simulated devices' reads.
 *
 * A stimulus file is CSV (no quoting; spaces and tabs around cells are
 * ignored; LF or CRLF line ends; a UTF-8 byte-order mark is skipped; blank
 * lines are skipped; lines are at most EL_HOST_LINE_MAX bytes):
 *
 *     time_us,sensor.raw,sensor.ok,cam.px[0],cam.px[1]
 *     0,100,1,,
 *     2500,120,,7,8
 *
 * - The header is `time_us` then device `out` data (el_items of kind
 *   EL_K_DEV_OUT), params or vars by name. An item with count n > 1 (a port with a rate)
 *   has a column per element, `name[0]` .. `name[n-1]` (the trace's column
 *   names), or a single column `name` that sets all n elements to the same
 *   value; a column may set no element that another column sets.
 * - Each row: a time in whole microseconds (non-decreasing), then one cell
 *   per column; an empty cell leaves the datum unchanged.
 * - Values: bool 0, 1, true or false; integers in decimal within the
 *   type's range; float32 as strtod reads it (also inf and nan), within
 *   float range; time as whole milliseconds (0 .. 4294967295).
 * - A device datum's value holds from its row's time on: el_sim_read(device)
 *   at logical time t writes the latest value of each of the device's
 *   columns whose row time is <= t. Rows with equal times apply in file
 *   order.
 * - A param's or var's value is written once, like a debug or service
 *   write, at the first instant at or after its row's time (el_port_inputs:
 *   after the outputs due then are published, before inputs are latched).
 *
 * Errors are reported as FILE:LINE: message and nothing is loaded.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "host_internal.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <ctype.h>
#include <string.h>

typedef union {
    bool b;
    int8_t i8;
    uint8_t u8;
    int16_t i16;
    uint16_t u16;
    int32_t i32;
    uint32_t u32;
    float f32;
} value_t;

typedef struct {
    uint16_t item;   /* index into el_items */
    uint16_t first;  /* first element set by the column */
    uint16_t n;      /* elements set: 1, or the item's count for `name` */
    bool set;        /* a value has applied (as of `cursor`) */
    value_t value;   /* the value that applies */
} column_t;

typedef struct {
    uint64_t time_us;
    uint32_t column;
    value_t value;
} event_t;

static column_t *columns;
static size_t column_count;
static event_t *events;
static size_t event_count, event_cap;
static size_t cursor;   /* events before it have applied */
static bool loaded;

static const char *stim_path;
static unsigned long stim_line;
static char line_buf[EL_HOST_LINE_MAX + 2u];
static char header_buf[EL_HOST_LINE_MAX + 2u]; /* the header, split into names */

static void stim_error(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

static void stim_error(const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s:%lu: ", stim_path, stim_line);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

void el_host_stimulus_free(void)
{
    free(columns);
    free(events);
    columns = NULL;
    events = NULL;
    column_count = event_count = event_cap = cursor = 0;
    loaded = false;
}

/* ---- reading lines ---- */

enum { LINE_OK, LINE_EOF, LINE_TOO_LONG, LINE_NUL, LINE_IO };

/* One line into line_buf without its line end; *len its length. */
static int read_line(FILE *f, size_t *len)
{
    size_t n = 0;
    int ch;
    bool any = false, nul = false;

    while ((ch = getc(f)) != EOF) {
        any = true;
        if (ch == '\n')
            break;
        if (ch == '\0')
            nul = true;
        if (n == EL_HOST_LINE_MAX + 1u)
            return LINE_TOO_LONG;
        line_buf[n++] = (char)ch;
    }
    if (ferror(f))
        return LINE_IO;
    if (!any)
        return LINE_EOF;
    if (n > 0 && line_buf[n - 1] == '\r')
        n--;
    if (n > EL_HOST_LINE_MAX)
        return LINE_TOO_LONG;
    line_buf[n] = '\0';
    *len = n;
    return nul ? LINE_NUL : LINE_OK;
}

static bool is_blank(char c)
{
    return c == ' ' || c == '\t';
}

/* Split line_buf in place at commas into `cells` (room for `max`), each
 * trimmed of spaces and tabs; returns the number of cells (may exceed
 * `max`: then only `max` were stored). */
static size_t split_cells(char *s, char **cells, size_t max)
{
    size_t n = 0;
    for (;;) {
        char *end = strchr(s, ',');
        char *stop = end ? end : s + strlen(s);
        char *a = s, *b = stop;
        while (a < b && is_blank(*a))
            a++;
        while (b > a && is_blank(b[-1]))
            b--;
        *b = '\0';
        if (n < max)
            cells[n] = a;
        n++;
        if (end == NULL)
            return n;
        s = end + 1;
    }
}

static size_t count_cells(const char *s)
{
    size_t n = 1;
    for (; *s; s++)
        if (*s == ',')
            n++;
    return n;
}

/* ---- the header ---- */

bool (*el_host_stimulus_reads)(uint16_t item);
const char *el_host_stimulus_unread_why = "";

static void list_valid_columns(void)
{
    uint16_t i;
    bool first = true;
    fprintf(stderr, "  valid columns: time_us");
    for (i = 0; i < el_item_count; i++) {
        const el_item_t *it = &el_items[i];
        if (it->kind == EL_K_DEV_IN || (el_host_stimulus_reads != NULL && !el_host_stimulus_reads(i)))
            continue;
        if (it->count == 1u)
            fprintf(stderr, ", %s", it->name);
        else
            fprintf(stderr, ", %s (or %s[0] .. %s[%u])", it->name, it->name, it->name, (unsigned)(it->count - 1u));
        first = false;
    }
    if (first)
        fprintf(stderr, " (the model has no device `out` data, params or vars)");
    fputc('\n', stderr);
}

static const char *kind_name(uint8_t kind)
{
    switch (kind) {
    case EL_K_PARAM: return "a param";
    case EL_K_VAR: return "a var";
    case EL_K_DEV_IN: return "a device `in` datum";
    default: return "a device `out` datum";
    }
}

static int find_item(const char *name, size_t len)
{
    uint16_t i;
    for (i = 0; i < el_item_count; i++)
        if (strlen(el_items[i].name) == len && strncmp(el_items[i].name, name, len) == 0)
            return (int)i;
    return -1;
}

/* Resolve one header cell into `col`; false after reporting. */
static bool resolve_column(const char *name, column_t *col)
{
    size_t len = strlen(name);
    int item = find_item(name, len);
    unsigned long index = 0;
    bool indexed = false;

    if (len == 0u) {
        stim_error("empty column name");
        list_valid_columns();
        return false;
    }
    if (item < 0 && name[len - 1] == ']') {
        const char *lb = strrchr(name, '[');
        const char *p;
        if (lb != NULL && lb + 1 < name + len - 1) {
            for (p = lb + 1; p < name + len - 1 && *p >= '0' && *p <= '9'; p++)
                if (index <= 65535u)
                    index = index * 10u + (unsigned long)(*p - '0');
            if (p == name + len - 1) {
                item = find_item(name, (size_t)(lb - name));
                indexed = item >= 0;
            }
        }
    }
    if (item < 0) {
        stim_error("unknown column '%s'", name);
        list_valid_columns();
        return false;
    }
    if (el_items[item].kind == EL_K_DEV_IN) {
        stim_error("column '%s': %s is %s; device `out` data, params and vars can be given a stimulus", name,
                   el_items[item].name, kind_name(el_items[item].kind));
        list_valid_columns();
        return false;
    }
    if (el_host_stimulus_reads != NULL && !el_host_stimulus_reads((uint16_t)item)) {
        stim_error("column '%s': nothing in this program reads it: %s", name, el_host_stimulus_unread_why);
        list_valid_columns();
        return false;
    }
    if (indexed && (el_items[item].count == 1u || index >= el_items[item].count)) {
        stim_error("column '%s': %s has %u element%s", name, el_items[item].name, (unsigned)el_items[item].count,
                   el_items[item].count == 1u ? " (no index)" : "s");
        list_valid_columns();
        return false;
    }
    col->item = (uint16_t)item;
    col->first = indexed ? (uint16_t)index : 0u;
    col->n = indexed ? 1u : el_items[item].count;
    col->set = false;
    return true;
}

/* ---- values ---- */

/* An optional sign then decimal digits only. */
static bool is_integer(const char *s)
{
    if (*s == '-' || *s == '+')
        s++;
    if (*s == '\0')
        return false;
    for (; *s; s++)
        if (*s < '0' || *s > '9')
            return false;
    return true;
}

/* A decimal integer (is_integer) within [lo, hi]. */
static bool parse_integer(const char *s, long long lo, long long hi, long long *out)
{
    char *end;
    long long v;
    errno = 0;
    v = strtoll(s, &end, 10);
    if (*end != '\0' || errno == ERANGE || v < lo || v > hi)
        return false;
    *out = v;
    return true;
}

/* Parse `s` as a value of `type` into *v; false after reporting. */
static bool parse_value(const char *s, uint8_t type, const char *column, value_t *v)
{
    static const struct {
        long long lo, hi;
    } range[] = {
        {0, 1}, {INT8_MIN, INT8_MAX}, {0, UINT8_MAX}, {INT16_MIN, INT16_MAX}, {0, UINT16_MAX},
        {INT32_MIN, INT32_MAX}, {0, UINT32_MAX}, {0, 0}, {0, UINT32_MAX},
    };
    long long n;

    if (type == EL_T_BOOL) {
        if (strcmp(s, "1") == 0 || strcmp(s, "true") == 0)
            v->b = true;
        else if (strcmp(s, "0") == 0 || strcmp(s, "false") == 0)
            v->b = false;
        else {
            stim_error("bad value '%s' for column '%s' (bool: 0, 1, true or false)", s, column);
            return false;
        }
        return true;
    }
    if (type == EL_T_F32) {
        char *end;
        double d;
        errno = 0;
        /* strtod skips leading white space (\v, \f, \r): the grammar has none. */
        d = isspace((unsigned char)*s) ? 0.0 : strtod(s, &end);
        if (isspace((unsigned char)*s) || end == s || *end != '\0') {
            stim_error("bad number '%s' for column '%s' (float32)", s, column);
            return false;
        }
        /* Above FLT_MAX but below FLT_MAX + half an ulp rounds to FLT_MAX
         * (so %.9g of FLT_MAX, 3.40282347e+38, reads back). */
        if ((errno == ERANGE && fabs(d) > 1.0) ||
            (!isinf(d) && fabs(d) >= (double)FLT_MAX + ldexp(1.0, 103))) {
            stim_error("value '%s' out of range for column '%s' (float32: magnitude at most %.9g)", s, column,
                       (double)FLT_MAX);
            return false;
        }
        if (!isinf(d) && !isnan(d) && fabs(d) > (double)FLT_MAX)
            d = d < 0 ? -(double)FLT_MAX : (double)FLT_MAX;
        v->f32 = (float)d;
        return true;
    }
    if (!is_integer(s)) {
        stim_error("bad number '%s' for column '%s' (%s%s)", s, column, el_host_type_name(type),
                   type == EL_T_TIME ? ": whole milliseconds" : ": a decimal integer");
        return false;
    }
    if (!parse_integer(s, range[type].lo, range[type].hi, &n)) {
        stim_error("value %s out of range for column '%s' (%s: %lld .. %lld)", s, column, el_host_type_name(type),
                   range[type].lo, range[type].hi);
        return false;
    }
    switch (type) {
    case EL_T_I8: v->i8 = (int8_t)n; break;
    case EL_T_U8: v->u8 = (uint8_t)n; break;
    case EL_T_I16: v->i16 = (int16_t)n; break;
    case EL_T_U16: v->u16 = (uint16_t)n; break;
    case EL_T_I32: v->i32 = (int32_t)n; break;
    default: v->u32 = (uint32_t)n; break; /* EL_T_U32, EL_T_TIME */
    }
    return true;
}

/* A value as a double, to compare with a declared range. */
static double as_double(const value_t *v, uint8_t type)
{
    switch (type) {
    case EL_T_BOOL: return v->b ? 1.0 : 0.0;
    case EL_T_I8: return v->i8;
    case EL_T_U8: return v->u8;
    case EL_T_I16: return v->i16;
    case EL_T_U16: return v->u16;
    case EL_T_I32: return v->i32;
    case EL_T_F32: return (double)v->f32;
    default: return v->u32; /* EL_T_U32, EL_T_TIME */
    }
}

/* Whether `v` of column `col` lies within its item's declared range (as
 * the debug interface checks a write); false after reporting. */
static bool within_range(const char *cell, const column_t *col, const char *column, const value_t *v)
{
    uint16_t k;
    const el_item_t *it = &el_items[col->item];
    if (&el_host_range_count == NULL || el_host_ranges == NULL)
        return true;
    for (k = 0; k < el_host_range_count; k++) {
        const el_host_range_t *r = &el_host_ranges[k];
        double d;
        if (r->item != col->item)
            continue;
        d = as_double(v, it->type);
        if (d >= r->lo && d <= r->hi) /* NaN is outside */
            return true;
        if (it->type == EL_T_F32)
            stim_error("value %s out of range for column '%s' (the declared range of %s: %.9g .. %.9g)", cell,
                       column, it->name, r->lo, r->hi);
        else
            stim_error("value %s out of range for column '%s' (the declared range of %s: %.0f .. %.0f)", cell,
                       column, it->name, r->lo, r->hi);
        return false;
    }
    return true;
}

static bool parse_time(const char *s, uint64_t *t)
{
    const char *p;
    char *end;
    unsigned long long v;
    if (*s == '\0')
        return false;
    for (p = s; *p; p++)
        if (*p < '0' || *p > '9')
            return false;
    errno = 0;
    v = strtoull(s, &end, 10);
    if (errno == ERANGE || *end != '\0')
        return false;
    *t = (uint64_t)v;
    return true;
}

static bool add_event(uint64_t time_us, size_t column, const value_t *value)
{
    if (event_count == event_cap) {
        size_t cap = event_cap ? event_cap * 2u : 256u;
        event_t *grown;
        if (event_cap >= EL_HOST_STIMULUS_MAX_EVENTS) {
            stim_error("more than %lu values: stimulus too big", (unsigned long)EL_HOST_STIMULUS_MAX_EVENTS);
            return false;
        }
        if (cap > EL_HOST_STIMULUS_MAX_EVENTS)
            cap = EL_HOST_STIMULUS_MAX_EVENTS;
        grown = realloc(events, cap * sizeof *events);
        if (grown == NULL) {
            stim_error("out of memory");
            return false;
        }
        events = grown;
        event_cap = cap;
    }
    events[event_count].time_us = time_us;
    events[event_count].column = (uint32_t)column;
    events[event_count].value = *value;
    event_count++;
    return true;
}

/* ---- loading ---- */

static bool load(FILE *f)
{
    char **cells = NULL, **names = NULL;
    size_t ncols = 0, len, i, j;
    bool have_header = false, ok = false, have_time = false;
    uint64_t last_time = 0;
    int r;

    stim_line = 0;
    for (;;) {
        char *text;
        stim_line++;
        r = read_line(f, &len);
        if (r == LINE_EOF)
            break;
        if (r == LINE_IO) {
            stim_error("read error: %s", strerror(errno));
            goto done;
        }
        if (r == LINE_TOO_LONG) {
            stim_error("line longer than %u bytes", (unsigned)EL_HOST_LINE_MAX);
            goto done;
        }
        if (r == LINE_NUL) {
            stim_error("NUL byte in line (not a text file?)");
            goto done;
        }
        text = line_buf;
        if (stim_line == 1u && strncmp(text, "\xEF\xBB\xBF", 3) == 0)
            text += 3;
        for (i = 0; is_blank(text[i]); i++)
            ;
        if (text[i] == '\0')
            continue;

        if (!have_header) {
            ncols = count_cells(text);
            cells = malloc(ncols * sizeof *cells);
            names = malloc(ncols * sizeof *names);
            columns = malloc(ncols * sizeof *columns); /* [0] unused: time_us */
            if (cells == NULL || names == NULL || columns == NULL) {
                stim_error("out of memory");
                goto done;
            }
            memcpy(header_buf, text, strlen(text) + 1u);
            split_cells(header_buf, names, ncols);
            if (strcmp(names[0], "time_us") != 0) {
                stim_error("the first column must be time_us, not '%s'", names[0]);
                goto done;
            }
            for (i = 1; i < ncols; i++) {
                if (!resolve_column(names[i], &columns[i]))
                    goto done;
                for (j = 1; j < i; j++)
                    if (columns[j].item == columns[i].item && columns[j].first < columns[i].first + columns[i].n &&
                        columns[i].first < columns[j].first + columns[j].n) {
                        stim_error("columns '%s' and '%s' set the same datum", names[j], names[i]);
                        goto done;
                    }
            }
            column_count = ncols;
            have_header = true;
            continue;
        }

        {
            size_t n = count_cells(text);
            uint64_t t;
            if (n != ncols) {
                stim_error("%lu cells, expected %lu as in the header", (unsigned long)n, (unsigned long)ncols);
                goto done;
            }
            split_cells(text, cells, ncols);
            if (!parse_time(cells[0], &t)) {
                stim_error("bad time '%s' (time_us: whole microseconds, 0 or more)", cells[0]);
                goto done;
            }
            if (have_time && t < last_time) {
                stim_error("time %s is before the previous row's time %llu (times must not decrease)", cells[0],
                           (unsigned long long)last_time);
                goto done;
            }
            have_time = true;
            last_time = t;
            for (i = 1; i < ncols; i++) {
                value_t v;
                if (cells[i][0] == '\0')
                    continue;
                memset(&v, 0, sizeof v);
                if (!parse_value(cells[i], el_items[columns[i].item].type, names[i], &v) ||
                    !within_range(cells[i], &columns[i], names[i], &v))
                    goto done;
                if (!add_event(t, i, &v))
                    goto done;
            }
        }
    }
    if (!have_header) {
        stim_line = 1;
        stim_error("empty file: the first line must be the header time_us,DATUM,...");
        goto done;
    }
    ok = true;
done:
    free(cells);
    free(names);
    return ok;
}

bool el_host_stimulus_load(const char *path)
{
    FILE *f;
    bool ok;

    el_host_stimulus_free();
    stim_path = path;
    f = fopen(path, "r");
    if (f == NULL) {
        el_host_error("cannot read stimulus %s: %s", path, strerror(errno));
        return false;
    }
    ok = load(f);
    fclose(f);
    if (!ok) {
        el_host_stimulus_free();
        return false;
    }
    loaded = true;
    return true;
}

/* ---- the simulated reads ---- */

static void store(const column_t *col)
{
    const el_item_t *it = &el_items[col->item];
    size_t size = el_host_type_size(it->type);
    size_t k;
    for (k = 0; k < col->n; k++)
        memcpy((unsigned char *)it->addr + (size_t)(col->first + k) * size, &col->value, size);
}

/* Apply the events due by `now`: params and vars are written as they come
 * (an interface write), device data are remembered for their next read. */
static void advance(uint64_t now)
{
    for (; cursor < event_count && events[cursor].time_us <= now; cursor++) {
        column_t *col = &columns[events[cursor].column];
        col->value = events[cursor].value;
        col->set = true;
        if (el_items[col->item].kind != EL_K_DEV_OUT)
            store(col);
    }
}

void el_host_stimulus_inputs(void)
{
    if (loaded)
        advance(el_host_now_us());
}

bool el_host_stimulus_event(size_t index, uint64_t *time_us, uint16_t *item, uint16_t *first, uint16_t *n,
                            void *value)
{
    const column_t *col;
    if (!loaded || index >= event_count)
        return false;
    col = &columns[events[index].column];
    *time_us = events[index].time_us;
    *item = col->item;
    *first = col->first;
    *n = col->n;
    memcpy(value, &events[index].value, el_host_type_size(el_items[col->item].type));
    return true;
}

void el_sim_read(uint8_t device)
{
    size_t c;

    if (!loaded || device >= el_device_count)
        return;
    advance(el_host_now_us());
    for (c = 1; c < column_count; c++) {
        const column_t *col = &columns[c];
        if (!col->set || el_items[col->item].kind != EL_K_DEV_OUT || el_items[col->item].device != device)
            continue;
        store(col);
    }
}

void el_sim_sample(uint8_t device)
{
    uint16_t i;

    if (device >= el_device_count)
        return;
    for (i = 0; i < el_item_count; i++) {
        const el_item_t *it = &el_items[i];
        if (it->kind == EL_K_DEV_OUT && it->device == device)
            memset(it->addr, 0, el_host_type_size(it->type) * it->count); /* 0, false, 0.0f */
    }
    el_sim_read(device);
}
