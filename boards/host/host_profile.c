/* EasyLab host board: the timer of a profiling build (el_profile.h). */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "el_profile.h"

#define EL_PROF_CALIBRATION 1000u

static uint64_t el_prof_started;
static uint64_t el_prof_overhead; /* ns of an empty begin/end pair, taken off every firing */
static int el_prof_ready;

static uint64_t el_prof_now(void)
{
    struct timespec t;
    (void)clock_gettime(CLOCK_MONOTONIC, &t);
    return (uint64_t)t.tv_sec * 1000000000u + (uint64_t)t.tv_nsec;
}

static void el_prof_dump(void)
{
    const char *path = getenv("EASYLAB_PROFILE");
    FILE *out;
    uint16_t i;
    if (path == NULL || (out = fopen(path, "w")) == NULL) {
        return;
    }
    for (i = 0u; i < el_prof_count; i++) {
        fprintf(out, "%s %lu %llu\n", el_prof_names[i], (unsigned long)el_prof_firings[i],
                (unsigned long long)el_prof_ns[i]);
    }
    (void)fclose(out);
}

static void el_prof_setup(void)
{
    uint64_t start = el_prof_now();
    uint32_t k;
    for (k = 0u; k < EL_PROF_CALIBRATION; k++) {
        (void)el_prof_now();
        (void)el_prof_now();
    }
    el_prof_overhead = (el_prof_now() - start) / EL_PROF_CALIBRATION / 2u;
    el_prof_ready = 1;
    (void)atexit(el_prof_dump);
}

void el_prof_begin(void)
{
    if (!el_prof_ready) {
        el_prof_setup();
    }
    el_prof_started = el_prof_now();
}

void el_prof_end(uint16_t instance)
{
    uint64_t spent = el_prof_now() - el_prof_started;
    el_prof_ns[instance] += spent > el_prof_overhead ? spent - el_prof_overhead : 0u;
    el_prof_firings[instance]++;
}
