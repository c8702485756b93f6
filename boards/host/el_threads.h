/* EasyLab host board: the threads of a multi-core build (docs/multicore.md).
 *
 * Threads are created once, at boot; the dispatcher's thread is core 0.
 * A job is run by every core at once (el_threads_run), each core doing its
 * part (el_gen_core_job, generated); within a job, a core waits for a
 * firing of another core by its flag, which holds the epoch of the
 * iteration that ran it. No locks around data, no heap: C11 atomics,
 * release on the writer's side and acquire on the reader's, order
 * everything; an idle core sleeps on a condition variable.
 * Compiled only into multi-core builds (EL_THREADS). */
#ifndef EL_THREADS_H
#define EL_THREADS_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "el_dispatch.h"

typedef atomic_uint_least32_t el_mc_flag_t;

void el_threads_start(uint8_t cores); /* create the other cores' threads */
void el_threads_run(uint8_t job);     /* every core runs its part of the job; returns when all are done */
void el_threads_stop(void);           /* end and join the threads */
void el_mc_post(el_mc_flag_t *flag, uint32_t epoch);
void el_mc_wait(el_mc_flag_t *flag, uint32_t epoch);

/* Generated (model.c). */
void el_gen_core_job(uint8_t job, uint8_t el_core);
void el_gen_bodies(el_task_mask_t released); /* the tasks released now, a group on its cores */

#endif
