/* EasyLab host board: the command line.
 *
 * Options are rows of el_host_options[]: a name, an optional argument, a
 * help line and a handler that stores the value in el_host_settings (or in
 * the settings of the feature that owns the option). Both `--opt VALUE`
 * and `--opt=VALUE` are accepted; anything else (unknown options, stray
 * arguments, a flag given a value, a missing value, a non-repeatable
 * option given twice) is an error: exit status 2.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "host_internal.h"

#include <stdio.h>
#include <string.h>

el_host_settings_t el_host_settings;

/* ---- handlers ---- */

static bool opt_fast(const char *arg)
{
    (void)arg;
    el_host_settings.fast = true;
    return true;
}

static bool opt_duration(const char *arg)
{
    const char *why;
    if (!el_host_parse_duration(arg, &el_host_settings.duration_us, &why)) {
        el_host_error("--duration %s: %s", arg, why);
        return false;
    }
    el_host_settings.has_duration = true;
    return true;
}

static bool opt_stimulus(const char *arg)
{
    el_host_settings.stimulus_path = arg;
    return true;
}

static bool opt_trace(const char *arg)
{
    el_host_settings.trace_path = arg;
    return true;
}

static bool opt_trace_state(const char *arg)
{
    (void)arg;
    el_host_trace_state = true;
    return true;
}

static bool opt_nvram(const char *arg)
{
    el_host_settings.nvram_path = arg;
    return true;
}

static bool opt_help(const char *arg);

const el_host_option_t el_host_options[] = {
    {"--fast", NULL, "virtual time: instants follow each other at once (deterministic)", false, opt_fast},
    {"--duration", "T", "stop before logical time T (10s, 1.5s, 500ms, 250us, 2m, 1h); default: endless", false,
     opt_duration},
    {"--stimulus", "FILE.csv", "device `out` data from a CSV file: time_us, then data paths", false, opt_stimulus},
    {"--trace", "FILE.csv|FILE.vcd", "record every item and chart at each instant (CSV or VCD by extension)", false,
     opt_trace},
    {"--trace-state", NULL, "the trace also records the devices' `state` fields (DEVICE.FIELD, after the items)",
     false, opt_trace_state},
    {"--nvram", "FILE", "non-volatile storage in FILE (4096 bytes; default: in memory)", false, opt_nvram},
    {"--debug", "pty:LINK|tcp:PORT[,halt]", "serve the debug interface on a new pty (symlink LINK) or 127.0.0.1:PORT",
     false, el_host_opt_debug},
    {"--modbus-tcp", "PORT", "serve the model's Modbus TCP interface on 127.0.0.1:PORT (default: its port)", false,
     el_host_opt_modbus_tcp},
    {"--modbus-rtu", "pty:LINK", "serve the model's Modbus RTU interface on a new pty (symlink LINK; 8N1)", false,
     el_host_opt_modbus_rtu},
    {"--hmi", "pty:LINK", "the example HMI (get NAME / set NAME VALUE lines) on a new pty (symlink LINK)", false,
     el_host_opt_hmi},
    {"--link", "pty:LINK|tcp:PORT",
     "a remote-execution proxy's link to easylab remote: a new pty (symlink LINK) or 127.0.0.1:PORT", false,
     el_host_opt_link},
    {"--help", NULL, "show this help and exit", false, opt_help},
};
const size_t el_host_option_count = sizeof el_host_options / sizeof el_host_options[0];

static bool help_requested;

static bool opt_help(const char *arg)
{
    (void)arg;
    help_requested = true;
    return true;
}

static void print_usage(FILE *out)
{
    size_t i;
    fprintf(out, "usage: %s [OPTION]...\n", el_host_prog);
    fprintf(out, "Run the EasyLab model %s (program id 0x%08lx, tick %lu us) on the host board.\n\n",
            el_model_name, (unsigned long)el_program_id, (unsigned long)el_tick_us);
    fprintf(out, "Options (an option's value may also be given as --option=VALUE):\n");
    for (i = 0; i < el_host_option_count; i++) {
        const el_host_option_t *o = &el_host_options[i];
        char left[64];
        snprintf(left, sizeof left, "%s%s%s", o->name, o->arg_name ? " " : "", o->arg_name ? o->arg_name : "");
        if (strlen(left) <= 26u)
            fprintf(out, "  %-26s  %s\n", left, o->help);
        else
            fprintf(out, "  %s\n  %-26s  %s\n", left, "", o->help);
    }
    fprintf(out, "\nSIGINT and SIGTERM end the run cleanly (the trace is complete), exit status 0.\n"
                 "Exit status: 0 done, 1 I/O error during the run, 2 bad command line or input file.\n");
}

int el_host_parse_args(int argc, char **argv)
{
    unsigned char seen[sizeof el_host_options / sizeof el_host_options[0]];
    int a;

    memset(seen, 0, sizeof seen);
    memset(&el_host_settings, 0, sizeof el_host_settings);
    help_requested = false;
    for (a = 1; a < argc && argv != NULL; a++) {
        const char *word = argv[a], *eq, *value = NULL;
        size_t name_len, i;
        const el_host_option_t *o = NULL;

        if (word == NULL)
            break;
        if (word[0] != '-' || word[1] != '-' || word[2] == '\0') {
            el_host_error("unexpected argument '%s' (try --help)", word);
            return EL_HOST_ARGS_ERROR;
        }
        eq = strchr(word, '=');
        name_len = eq ? (size_t)(eq - word) : strlen(word);
        for (i = 0; i < el_host_option_count; i++)
            if (strlen(el_host_options[i].name) == name_len && strncmp(el_host_options[i].name, word, name_len) == 0)
                o = &el_host_options[i];
        if (o == NULL) {
            el_host_error("unknown option '%.*s' (try --help)", (int)name_len, word);
            return EL_HOST_ARGS_ERROR;
        }
        if (o->arg_name == NULL) {
            if (eq != NULL) {
                el_host_error("option %s takes no value", o->name);
                return EL_HOST_ARGS_ERROR;
            }
        } else if (eq != NULL) {
            value = eq + 1;
        } else if (a + 1 < argc && argv[a + 1] != NULL) {
            value = argv[++a];
        } else {
            el_host_error("option %s needs a value: %s %s", o->name, o->name, o->arg_name);
            return EL_HOST_ARGS_ERROR;
        }
        if (seen[o - el_host_options] && !o->repeatable) {
            el_host_error("option %s given more than once", o->name);
            return EL_HOST_ARGS_ERROR;
        }
        seen[o - el_host_options] = 1;
        if (!o->handle(value))
            return EL_HOST_ARGS_ERROR;
    }
    if (help_requested) {
        print_usage(stdout);
        fflush(stdout);
        return EL_HOST_ARGS_DONE;
    }
    return EL_HOST_ARGS_RUN;
}
