/* EasyLab host board: an example HMI linked into the firmware, a user of
 * the local service API (runtime_c/el_service.h, docs/service.md "HMI").
 *
 *   --hmi pty:LINK   a pseudo-terminal, LINK a symlink to it, speaking one
 *                    line per request and one line per reply:
 *
 *   get NAME          -> ok NAME VALUE
 *   set NAME VALUE    -> ok NAME VALUE      (the value it now holds)
 *   list              -> ok NAME NAME ...   (every service item)
 *   anything else     -> error syntax
 *
 * Errors: `error unknown NAME`, `error read-only NAME` (a `service ro`
 * item), `error range NAME` (outside its type or range: nothing changed),
 * `error value NAME` (not a value of its type), `error storage NAME` (a
 * persist param applied but not stored), `error line too long` (over
 * HMI_LINE_MAX bytes). Values: bool 0/1 (also true/false on input),
 * integers in decimal, float32 as %.9g, time in milliseconds. Lines end
 * with LF (a CR before it is ignored). Requests are served between
 * instants, like Modbus requests, and go through the same checks.
 *
 * The runtime is linked by `easylab build` (which defines EL_DEBUG or
 * EL_RELEASE); the board's own test fixture (tests/host_board) has no
 * runtime, and there only the option remains, saying so.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "host_internal.h"

#include <stdio.h>
#include <string.h>

#if defined(EL_DEBUG) || defined(EL_RELEASE)

#include "el_service.h"

#include <errno.h>
#include <stdlib.h>
#include <unistd.h>

#define HMI_LINE_MAX 200u

static int hmi_fd = -1, hmi_keep = -1;
static char line[HMI_LINE_MAX + 1u];
static size_t line_len;
static bool line_too_long;

static void reply(const char *text)
{
    size_t len = strlen(text);
    const char *p = text;
    while (len > 0u) {
        ssize_t n = write(hmi_fd, p, len);
        if (n <= 0) {
            if (n < 0 && errno == EINTR)
                continue;
            return; /* nobody reads: the reply is lost */
        }
        p += n;
        len -= (size_t)n;
    }
}

static void format_value(uint8_t type, el_svc_value_t v, char *buf, size_t cap)
{
    switch (type) {
    case EL_T_I8:
    case EL_T_I16:
    case EL_T_I32: snprintf(buf, cap, "%ld", (long)v.i); break;
    case EL_T_F32: snprintf(buf, cap, "%.9g", (double)v.f); break;
    default: snprintf(buf, cap, "%lu", (unsigned long)v.u); break;
    }
}

/* Parse a value of `type`: 0 fine, 1 not a value, 2 outside the type. */
static int parse_value(uint8_t type, const char *text, el_svc_value_t *v)
{
    char *end;
    errno = 0;
    if (text[0] == '\0')
        return 1;
    switch (type) {
    case EL_T_BOOL:
        if (strcmp(text, "1") == 0 || strcmp(text, "true") == 0)
            v->u = 1u;
        else if (strcmp(text, "0") == 0 || strcmp(text, "false") == 0)
            v->u = 0u;
        else
            return 1;
        return 0;
    case EL_T_I8:
    case EL_T_I16:
    case EL_T_I32: {
        long long x = strtoll(text, &end, 10);
        if (*end != '\0')
            return 1;
        if (errno != 0 || x < -2147483647LL - 1 || x > 2147483647LL)
            return 2;
        v->i = (int32_t)x; /* narrower types: el_service_set checks */
        return 0;
    }
    case EL_T_F32: {
        float f = strtof(text, &end);
        if (*end != '\0')
            return 1;
        v->f = f; /* NaN, infinities, out of range: el_service_set says */
        return 0;
    }
    default: {
        unsigned long long x;
        if (text[0] == '-')
            return 2;
        x = strtoull(text, &end, 10);
        if (*end != '\0')
            return 1;
        if (errno != 0 || x > 0xFFFFFFFFULL)
            return 2;
        v->u = (uint32_t)x;
        return 0;
    }
    }
}

static void serve_line(char *text)
{
    char out[HMI_LINE_MAX + 64u], value_text[48];
    char *words[4];
    size_t n = 0;
    char *p = text;
    uint16_t id;
    el_svc_value_t v;
    const el_svc_entry_t *e;

    while (n < 4u) {
        while (*p == ' ' || *p == '\t')
            *p++ = '\0';
        if (*p == '\0')
            break;
        words[n++] = p;
        while (*p != '\0' && *p != ' ' && *p != '\t')
            p++;
    }
    if (n == 1u && strcmp(words[0], "list") == 0) {
        uint16_t i, count = el_service_count();
        reply("ok");
        for (i = 0; i < count; i++) {
            reply(" ");
            reply(el_service_entry(i)->name);
        }
        reply("\n");
        return;
    }
    if (!((n == 2u && strcmp(words[0], "get") == 0) || (n == 3u && strcmp(words[0], "set") == 0))) {
        reply("error syntax\n");
        return;
    }
    id = el_service_find(words[1]);
    e = el_service_entry(id);
    if (e == NULL) {
        snprintf(out, sizeof out, "error unknown %s\n", words[1]);
        reply(out);
        return;
    }
    if (n == 3u) {
        el_svc_status_t st;
        int parsed = parse_value(e->type, words[2], &v);
        if (parsed == 1) {
            snprintf(out, sizeof out, "error value %s\n", e->name);
            reply(out);
            return;
        }
        st = parsed == 2 ? EL_SVC_BAD_VALUE : el_service_set(id, &v);
        if (st != EL_SVC_OK) {
            snprintf(out, sizeof out, "error %s %s\n",
                     st == EL_SVC_READ_ONLY ? "read-only" : st == EL_SVC_STORAGE ? "storage" : "range", e->name);
            reply(out);
            return;
        }
    }
    (void)el_service_get(id, &v);
    format_value(e->type, v, value_text, sizeof value_text);
    snprintf(out, sizeof out, "ok %s %s\n", e->name, value_text);
    reply(out);
}

static void hmi_readable(int fd, short revents, void *ctx)
{
    char buf[256];
    ssize_t n, i;
    (void)revents;
    (void)ctx;
    n = read(fd, buf, sizeof buf);
    for (i = 0; i < n; i++) {
        char c = buf[i];
        if (c == '\n') {
            if (line_too_long)
                reply("error line too long\n");
            else {
                if (line_len > 0u && line[line_len - 1u] == '\r')
                    line_len--;
                line[line_len] = '\0';
                serve_line(line);
            }
            line_len = 0;
            line_too_long = false;
        } else if (line_len < HMI_LINE_MAX) {
            line[line_len++] = c;
        } else {
            line_too_long = true;
        }
    }
}

bool el_host_opt_hmi(const char *arg)
{
    if (strncmp(arg, "pty:", 4) != 0) {
        el_host_error("--hmi %s: give pty:LINK (a pseudo-terminal with a symlink LINK to it)", arg);
        return false;
    }
    hmi_fd = el_host_make_pty("--hmi", arg + 4, &hmi_keep);
    return hmi_fd >= 0 && el_host_watch_fd(hmi_fd, hmi_readable, NULL);
}

#else /* the board's test fixture: no runtime */

bool el_host_opt_hmi(const char *arg)
{
    (void)arg;
    el_host_error("--hmi: this program has no service interface");
    return false;
}

#endif
