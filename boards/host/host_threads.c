/* EasyLab host board: the threads of a multi-core build (el_threads.h). */
#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "el_threads.h"

#define EL_MAX_CORES 64u
#define EL_JOB_STOP 0xFFu
/* Waiting: spin this many times, then yield the processor, then sleep: a
 * wait inside an iteration is short. The wait for the next job may last a
 * whole period: after the yields an idle core sleeps on a condition
 * variable until a job is posted (the mutex guards only that sleep, no
 * data). */
#define EL_SPINS 256u
#define EL_YIELDS 4096u
/* A core between jobs yields for this long after its last job before it
 * sleeps: a model whose jobs come every few milliseconds keeps its cores
 * awake (a sleeping core takes a wake-up latency at every job, up to
 * milliseconds on a virtual machine); an idle model lets them sleep. */
#define EL_IDLE_NS 4000000L

static pthread_t el_threads[EL_MAX_CORES];
static uint8_t el_core_count = 1u;
static uint8_t el_job;                             /* written before el_go is raised */
static atomic_uint_least32_t el_go;                /* the sequence number of the job posted last */
static atomic_uint_least32_t el_done[EL_MAX_CORES]; /* per core: the sequence number of its last job done */
static atomic_uint_least32_t el_sleepers;          /* cores asleep (or going to sleep) on el_wake */
static pthread_mutex_t el_sleep_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t el_wake = PTHREAD_COND_INITIALIZER;

static void el_pause(uint32_t round)
{
    if (round < EL_SPINS) {
        return;
    }
    if (round < EL_YIELDS) {
        (void)sched_yield();
    } else {
        struct timespec nap = { 0, 20000L };
        (void)nanosleep(&nap, NULL);
    }
}

static void el_wait_equal(atomic_uint_least32_t *word, uint32_t value)
{
    uint32_t round = 0u;
    while ((uint32_t)atomic_load_explicit(word, memory_order_acquire) != value) {
        el_pause(round < UINT32_MAX ? round++ : round);
    }
}

/* The next job's sequence number: spin and yield a while, then sleep
 * until el_post wakes the core. el_go and el_sleepers are sequentially
 * consistent: either el_post sees this core among the sleepers, or this
 * core sees the new job before it sleeps. */
static int64_t el_ns_since(const struct timespec *start)
{
    struct timespec now;
    (void)clock_gettime(CLOCK_MONOTONIC, &now);
    return (int64_t)(now.tv_sec - start->tv_sec) * 1000000000 + (int64_t)(now.tv_nsec - start->tv_nsec);
}

static uint32_t el_next_job(uint32_t seen)
{
    uint32_t round;
    uint32_t now;
    struct timespec idle_since;
    (void)clock_gettime(CLOCK_MONOTONIC, &idle_since);
    for (round = 0u;; round++) {
        now = (uint32_t)atomic_load_explicit(&el_go, memory_order_acquire);
        if (now != seen) {
            return now;
        }
        if (round < EL_SPINS) {
            continue;
        }
        if ((round & 63u) == 0u && el_ns_since(&idle_since) > EL_IDLE_NS) {
            break;
        }
        (void)sched_yield();
    }
    (void)pthread_mutex_lock(&el_sleep_lock);
    (void)atomic_fetch_add(&el_sleepers, 1u);
    while ((now = (uint32_t)atomic_load(&el_go)) == seen) {
        (void)pthread_cond_wait(&el_wake, &el_sleep_lock);
    }
    (void)atomic_fetch_sub(&el_sleepers, 1u);
    (void)pthread_mutex_unlock(&el_sleep_lock);
    return now;
}

/* Post job number ``seq`` (el_job written before), waking sleeping cores. */
static void el_post(uint32_t seq)
{
    atomic_store(&el_go, seq);
    if (atomic_load(&el_sleepers) != 0u) {
        (void)pthread_mutex_lock(&el_sleep_lock);
        (void)pthread_cond_broadcast(&el_wake);
        (void)pthread_mutex_unlock(&el_sleep_lock);
    }
}

static void *el_worker(void *arg)
{
    uint8_t core = (uint8_t)(uintptr_t)arg;
    uint32_t seen = 0u;
    for (;;) {
        seen = el_next_job(seen);
        if (el_job == EL_JOB_STOP) {
            return NULL;
        }
        el_gen_core_job(el_job, core);
        atomic_store_explicit(&el_done[core], seen, memory_order_release);
    }
}

void el_threads_start(uint8_t cores)
{
    uint8_t c;
    if (cores > EL_MAX_CORES) {
        cores = EL_MAX_CORES;
    }
    for (c = 1u; c < cores; c++) {
        if (pthread_create(&el_threads[c], NULL, el_worker, (void *)(uintptr_t)c) != 0) {
            fprintf(stderr, "easylab: cannot start the thread of core %u\n", (unsigned)c);
            exit(1);
        }
        el_core_count = (uint8_t)(c + 1u);
    }
}

void el_threads_run(uint8_t job)
{
    uint32_t seq;
    uint8_t c;
    el_job = job;
    seq = (uint32_t)atomic_load_explicit(&el_go, memory_order_relaxed) + 1u;
    el_post(seq);
    el_gen_core_job(job, 0u);
    for (c = 1u; c < el_core_count; c++) {
        el_wait_equal(&el_done[c], seq);
    }
}

void el_threads_stop(void)
{
    uint8_t c;
    if (el_core_count < 2u) {
        return;
    }
    el_job = EL_JOB_STOP;
    el_post((uint32_t)atomic_load_explicit(&el_go, memory_order_relaxed) + 1u);
    for (c = 1u; c < el_core_count; c++) {
        (void)pthread_join(el_threads[c], NULL);
    }
    el_core_count = 1u;
}

void el_mc_post(el_mc_flag_t *flag, uint32_t epoch)
{
    atomic_store_explicit(flag, epoch, memory_order_release);
}

void el_mc_wait(el_mc_flag_t *flag, uint32_t epoch)
{
    el_wait_equal(flag, epoch);
}
