/* EasyLab host board: a profiling build times every actor firing
 * (`easylab analyze --cores N --profile`, docs/multicore.md). At exit the
 * profile goes to the file named by EASYLAB_PROFILE, one line per actor
 * instance: "dataflow.instance firings nanoseconds". */
#ifndef EL_PROFILE_H
#define EL_PROFILE_H

#include <stdint.h>

void el_prof_begin(void);
void el_prof_end(uint16_t instance);

/* Generated (model.c). */
extern const uint16_t el_prof_count;
extern const char *const el_prof_names[];
extern uint64_t el_prof_ns[];
extern uint32_t el_prof_firings[];

#endif
