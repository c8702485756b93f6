/* EasyLab local execution: the runner of the interpreter's plans
 * (generator/interp/runner.py, docs/local.md "How it works").
 *
 * The interpreter turns a program into plans once: lists of operations (an
 * actor firing through its plug-in, a copy between items, task copies and
 * edges, a channel's ring and a task's staging array, the bookkeeping of a
 * release and of a deadline), one list per dataflow and one per instant of
 * the dispatch table. el_run_ops runs one list (the Python side calls it
 * between its own work); el_run_instants runs instant after instant of the
 * table for as long as no instant needs Python.
 *
 * No heap, no recursion: a CALL runs a dataflow's list, which calls nothing
 * further. Rings and staging arrays are bounds-checked: a fault stops the
 * runner with its cause in the cursor, which the Python side reports.
 *
 * Multi-core runs (`easylab run --cores N`, docs/multicore.md): a PARALLEL
 * operation runs a job, one list per core, on the calling thread (core 0)
 * and worker threads (cores 1..), started once and asleep between jobs.
 * The lists order themselves across cores by WAIT and SIGNAL on per-firing
 * flags holding the job's epoch (release/acquire), as the host board's
 * threads do; the job returns once every core is done.
 */
#include <pthread.h>
#include <sched.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

#define EL_RUNNER_EXPORT __attribute__((visibility("default")))

typedef void (*el_plugin_step_t)(void *state, const void *const *inputs, void *const *outputs,
                                 const void *const *params);

/* A channel: a ring of tokens (the Python side may enlarge `data`). */
typedef struct {
    uint8_t *data;
    uint32_t capacity; /* tokens */
    uint32_t head;     /* the oldest token */
    uint32_t count;
    uint32_t size; /* bytes per token */
} el_ring_t;

/* A task's staging array of one channel: the tokens taken at its release
 * (or to push at its deadline), and the next one a channel node moves. */
typedef struct {
    uint8_t *data;
    uint32_t tokens;
    uint32_t cursor;
    uint32_t size; /* bytes per token */
} el_stage_t;

/* One operation; which fields it uses depends on its kind. */
typedef struct el_op {
    uint16_t kind;
    uint8_t src_type, dst_type; /* WIDEN, READ, WRITE: the types (EL_T_*) of src and dst */
    uint32_t count;
    el_plugin_step_t fn;
    void *object;
    const void *const *inputs;
    void *const *outputs;
    const void *const *params;
    void *dst;
    const void *src;
} el_op_t;

enum {
    EL_OP_FIRE = 1,    /* fn(object: the instance's state, inputs, outputs, params) */
    EL_OP_COPY = 2,    /* count bytes from src to dst */
    EL_OP_CALL = 3,    /* the count operations at src (a list that calls nothing) */
    EL_OP_PUSH = 4,    /* the stage src's tokens to the end of the ring object */
    EL_OP_TAKE = 5,    /* the stage dst filled from the front of the ring object; its cursor to 0 */
    EL_OP_REWIND = 6,  /* the stage object's cursor to 0 */
    EL_OP_READ = 7,    /* the stage object's token at its cursor to dst (if any, widened); count 1: then advance */
    EL_OP_WRITE = 8,   /* src's token to the stage object at its cursor (widened), advance */
    EL_OP_PUBLISH = 9, /* the uint8 flag object clear: skip the count operations after; set: clear it */
    EL_OP_PENDING = 10, /* the uint8 flag object set */
    EL_OP_RELEASE = 11, /* the uint64 counter object + 1, the uint64 at dst the time */
    EL_OP_WIDEN = 12,   /* count values from src to dst, widened from src_type to dst_type */
    EL_OP_PARALLEL = 13, /* the job object (el_job_t) on its cores; done when every core is */
    EL_OP_WAIT = 14,    /* in a job's list: until the uint64 flag object holds the epoch of the job src */
    EL_OP_SIGNAL = 15   /* in a job's list: the uint64 flag object := the epoch of the job src */
};

/* Value types, in the interpreter's order (runner.py, TYPES). */
enum { EL_T_BOOL, EL_T_INT8, EL_T_UINT8, EL_T_INT16, EL_T_UINT16, EL_T_INT32, EL_T_UINT32, EL_T_FLOAT32, EL_T_TIME,
       EL_T_COUNT };

static const uint8_t el_type_size[EL_T_COUNT] = {sizeof(uint8_t), 1u, 1u, 2u, 2u, 4u, 4u, sizeof(float), 4u};

/* Why a runner stopped before its end. */
enum { EL_RUN_OK = 0, EL_RUN_RING_FULL = 1, EL_RUN_RING_EMPTY = 2, EL_RUN_STAGE = 3, EL_RUN_NESTED = 4, EL_RUN_BAD_OP = 5,
       EL_RUN_THREADS = 6, /* a worker thread could not be started */
       EL_RUN_GAVE_UP = 7  /* a core stopped waiting because another one faulted (not a fault of its own) */
};

/* The dispatch table: instant i runs ops[first[i] .. first[i + 1]). */
typedef struct {
    const el_op_t *ops;
    const uint32_t *first;
    const uint64_t *tick;   /* instant i's tick in the hyperperiod */
    const uint8_t *native;  /* 1: the instant runs here entirely; 0: it needs Python */
    uint32_t instants;
    uint64_t hyperperiod; /* ticks */
    uint64_t tick_us;
} el_table_t;

/* Where a run is: the next instant, the time of the one being run (the last
 * one run, afterwards), and a fault. */
typedef struct {
    uint64_t base; /* the current hyperperiod's first tick */
    uint64_t now_us;
    uint32_t index; /* the next instant of the table */
    uint32_t error; /* EL_RUN_* */
    const void *error_at; /* the ring or stage at fault */
} el_cursor_t;

/* Cores of a job: --cores is 1 to 64. */
#define EL_MAX_CORES 64u

/* A parallel job: per core, the operations it runs in order (firings,
 * copies, channel moves, WAIT and SIGNAL; no CALL, PUBLISH or PARALLEL). */
typedef struct {
    uint32_t cores;
    uint32_t failed; /* set by a core at a fault: the others' waits give up */
    uint64_t epoch;  /* raised at each run: what a flag holds once its firing ran in this run */
    const el_op_t *const *lists;
    const uint32_t *counts;
    el_cursor_t *cursors; /* per core: its fault */
} el_job_t;

EL_RUNNER_EXPORT uint32_t el_run_ops(const el_op_t *ops, uint32_t count, el_cursor_t *cursor);
EL_RUNNER_EXPORT uint64_t el_run_instants(const el_table_t *table, el_cursor_t *cursor, uint64_t before_us,
                                          uint64_t max_instants, uint64_t max_ops);

/* An integer of type `type` at p (bool, time and float32 never widen, so
 * they are never read here). */
static int64_t load_integer(const uint8_t *p, uint8_t type)
{
    switch (type) {
    case EL_T_INT8: { int8_t v; memcpy(&v, p, sizeof v); return v; }
    case EL_T_UINT8: { uint8_t v; memcpy(&v, p, sizeof v); return v; }
    case EL_T_INT16: { int16_t v; memcpy(&v, p, sizeof v); return v; }
    case EL_T_UINT16: { uint16_t v; memcpy(&v, p, sizeof v); return v; }
    case EL_T_INT32: { int32_t v; memcpy(&v, p, sizeof v); return v; }
    default: { uint32_t v; memcpy(&v, p, sizeof v); return v; }
    }
}

/* The C assignment of an integer to type `type` at p: the widenings of
 * edges (docs/language.md: integers into integers whose range holds theirs,
 * 8- and 16-bit integers into float32), which are exact. */
static void store_integer(uint8_t *p, uint8_t type, int64_t value)
{
    switch (type) {
    case EL_T_INT8: { int8_t v = (int8_t)value; memcpy(p, &v, sizeof v); break; }
    case EL_T_UINT8: { uint8_t v = (uint8_t)value; memcpy(p, &v, sizeof v); break; }
    case EL_T_INT16: { int16_t v = (int16_t)value; memcpy(p, &v, sizeof v); break; }
    case EL_T_UINT16: { uint16_t v = (uint16_t)value; memcpy(p, &v, sizeof v); break; }
    case EL_T_INT32: { int32_t v = (int32_t)value; memcpy(p, &v, sizeof v); break; }
    case EL_T_FLOAT32: { float v = (float)value; memcpy(p, &v, sizeof v); break; }
    default: { uint32_t v = (uint32_t)value; memcpy(p, &v, sizeof v); break; }
    }
}

/* n bytes from src to dst; the sizes of single values inline. */
static void copy_bytes(void *dst, const void *src, size_t n)
{
    switch (n) {
    case 1u: memmove(dst, src, 1u); break;
    case 2u: memmove(dst, src, 2u); break;
    case 4u: memmove(dst, src, 4u); break;
    case 8u: memmove(dst, src, 8u); break;
    default: memmove(dst, src, n); break;
    }
}

/* count values of type `from` at src to dst as type `to`; false for an
 * unknown type. */
static bool move_values(void *dst, uint8_t to, const void *src, uint8_t from, uint32_t count)
{
    uint32_t i;
    if (from >= EL_T_COUNT || to >= EL_T_COUNT) {
        return false;
    }
    if (from == to) {
        copy_bytes(dst, src, (size_t)count * el_type_size[from]);
        return true;
    }
    for (i = 0u; i < count; i++) {
        store_integer((uint8_t *)dst + (size_t)i * el_type_size[to], to,
                      load_integer((const uint8_t *)src + (size_t)i * el_type_size[from], from));
    }
    return true;
}

static uint32_t fault(el_cursor_t *cursor, uint32_t error, const void *at)
{
    cursor->error = error;
    cursor->error_at = at;
    return error;
}

static uint32_t ring_push(el_ring_t *ring, const el_stage_t *stage)
{
    uint32_t i;
    if (stage->tokens > ring->capacity - ring->count) {
        return EL_RUN_RING_FULL;
    }
    for (i = 0u; i < stage->tokens; i++) {
        uint32_t at = (ring->head + ring->count) % ring->capacity;
        memcpy(ring->data + (size_t)at * ring->size, stage->data + (size_t)i * ring->size, ring->size);
        ring->count++;
    }
    return EL_RUN_OK;
}

static uint32_t ring_take(el_ring_t *ring, el_stage_t *stage)
{
    uint32_t i;
    if (stage->tokens > ring->count) {
        return EL_RUN_RING_EMPTY;
    }
    for (i = 0u; i < stage->tokens; i++) {
        memcpy(stage->data + (size_t)i * ring->size, ring->data + (size_t)ring->head * ring->size, ring->size);
        ring->head = (ring->head + 1u) % ring->capacity;
        ring->count--;
    }
    stage->cursor = 0u;
    return EL_RUN_OK;
}

/* A channel node's move between the stage's token at its cursor and an
 * edge: READ (dst, or none: src and dst NULL) or WRITE (src). */
static uint32_t stage_move(el_stage_t *stage, const el_op_t *op, int advance)
{
    uint8_t *token;
    if (stage->cursor >= stage->tokens) {
        return EL_RUN_STAGE;
    }
    token = stage->data + (size_t)stage->cursor * stage->size;
    if (op->dst != NULL && !move_values(op->dst, op->dst_type, token, op->src_type, 1u)) {
        return EL_RUN_BAD_OP;
    }
    if (op->src != NULL && !move_values(token, op->dst_type, op->src, op->src_type, 1u)) {
        return EL_RUN_BAD_OP;
    }
    if (advance) {
        stage->cursor++;
    }
    return EL_RUN_OK;
}

/* A core's wait: spin a while (the other core is usually about to finish),
 * then give the processor away, then nap: more threads than free
 * processors stay correct, only slower. */
static void pause_for(uint32_t *spins)
{
    static const struct timespec nap = {0, 20000};
    (*spins)++;
    if (*spins > 2000u) {
        nanosleep(&nap, NULL);
    } else if (*spins > 200u) {
        sched_yield();
    }
}

static uint32_t wait_for(const uint64_t *flag, el_job_t *job)
{
    uint32_t spins = 0u;
    while (__atomic_load_n(flag, __ATOMIC_ACQUIRE) != job->epoch) {
        if (__atomic_load_n(&job->failed, __ATOMIC_ACQUIRE) != 0u) {
            return EL_RUN_GAVE_UP;
        }
        pause_for(&spins);
    }
    return EL_RUN_OK;
}

/* One operation that neither jumps nor runs other lists; its error. */
static uint32_t run_leaf(const el_op_t *op, el_cursor_t *cursor)
{
    switch (op->kind) {
    case EL_OP_FIRE:
        op->fn(op->object, op->inputs, op->outputs, op->params);
        return EL_RUN_OK;
    case EL_OP_COPY:
        copy_bytes(op->dst, op->src, op->count);
        return EL_RUN_OK;
    case EL_OP_WIDEN:
        return move_values(op->dst, op->dst_type, op->src, op->src_type, op->count) ? EL_RUN_OK : EL_RUN_BAD_OP;
    case EL_OP_PUSH:
        return ring_push((el_ring_t *)op->object, (const el_stage_t *)op->src);
    case EL_OP_TAKE:
        return ring_take((el_ring_t *)op->object, (el_stage_t *)op->dst);
    case EL_OP_REWIND:
        ((el_stage_t *)op->object)->cursor = 0u;
        return EL_RUN_OK;
    case EL_OP_READ:
        return stage_move((el_stage_t *)op->object, op, op->count != 0u);
    case EL_OP_WRITE:
        return stage_move((el_stage_t *)op->object, op, 1);
    case EL_OP_PENDING:
        *(uint8_t *)op->object = 1u;
        return EL_RUN_OK;
    case EL_OP_RELEASE:
        (*(uint64_t *)op->object)++;
        *(uint64_t *)op->dst = cursor->now_us;
        return EL_RUN_OK;
    case EL_OP_WAIT:
        return wait_for((const uint64_t *)op->object, (el_job_t *)op->src);
    case EL_OP_SIGNAL:
        __atomic_store_n((uint64_t *)op->object, ((const el_job_t *)op->src)->epoch, __ATOMIC_RELEASE);
        return EL_RUN_OK;
    default:
        return EL_RUN_BAD_OP;
    }
}

/* Where a fault of `op` is reported: the ring or stage, else the operation. */
static const void *fault_at(const el_op_t *op, uint32_t error)
{
    return error == EL_RUN_BAD_OP || error == EL_RUN_GAVE_UP ? (const void *)op : op->object;
}

/* One core's list of a job; at a fault the other cores stop waiting. */
static void run_core(el_job_t *job, uint32_t core)
{
    const el_op_t *op = job->lists[core];
    const el_op_t *end = op + job->counts[core];
    el_cursor_t *cursor = &job->cursors[core];
    for (; op != end; op++) {
        uint32_t error = run_leaf(op, cursor);
        if (error != EL_RUN_OK) {
            fault(cursor, error, fault_at(op, error));
            __atomic_store_n(&job->failed, 1u, __ATOMIC_RELEASE);
            return;
        }
    }
}

/* The worker threads (cores 1 ..): a job is posted by raising the sequence
 * under the lock (they sleep on the condition variable between jobs, which
 * guards the sleep, never data: an idle model costs nothing); each says it
 * is done through its counter. One job at a time in a process. */
static pthread_mutex_t el_pool_post = PTHREAD_MUTEX_INITIALIZER;
static pthread_mutex_t el_pool_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t el_pool_wake = PTHREAD_COND_INITIALIZER;
static el_job_t *el_pool_job;
static uint32_t el_pool_cores;    /* of the job posted last */
static uint64_t el_pool_sequence; /* jobs posted */
static uint32_t el_pool_workers;  /* threads started: cores 1 .. el_pool_workers */
static uint64_t el_pool_done[EL_MAX_CORES]; /* per core: the last job it finished */

static void *worker(void *arg)
{
    uint32_t core = (uint32_t)(uintptr_t)arg;
    uint64_t seen;
    pthread_mutex_lock(&el_pool_lock);
    seen = el_pool_done[core]; /* the sequence when it was started */
    pthread_mutex_unlock(&el_pool_lock);
    for (;;) {
        el_job_t *job;
        uint32_t cores;
        pthread_mutex_lock(&el_pool_lock);
        while (el_pool_sequence == seen) {
            pthread_cond_wait(&el_pool_wake, &el_pool_lock);
        }
        seen = el_pool_sequence;
        job = el_pool_job;
        cores = el_pool_cores;
        pthread_mutex_unlock(&el_pool_lock);
        if (core < cores) {
            run_core(job, core);
            __atomic_store_n(&el_pool_done[core], seen, __ATOMIC_RELEASE);
        }
    }
    return NULL;
}

/* A forked child has none of the parent's workers: it starts its own. */
static void forget_workers(void)
{
    el_pool_workers = 0u;
    pthread_mutex_init(&el_pool_post, NULL);
    pthread_mutex_init(&el_pool_lock, NULL);
    pthread_cond_init(&el_pool_wake, NULL);
}

/* The workers a job of `cores` cores needs, started if not yet (under the
 * pool's lock). */
static bool start_workers(uint32_t cores)
{
    static bool fork_handled = false;
    if (!fork_handled && el_pool_workers + 1u < cores) {
        if (pthread_atfork(NULL, NULL, forget_workers) != 0) {
            return false;
        }
        fork_handled = true;
    }
    while (el_pool_workers + 1u < cores) {
        pthread_t thread;
        uint32_t core = el_pool_workers + 1u;
        el_pool_done[core] = el_pool_sequence;
        if (pthread_create(&thread, NULL, worker, (void *)(uintptr_t)core) != 0) {
            return false;
        }
        pthread_detach(thread);
        el_pool_workers = core;
    }
    return true;
}

/* A PARALLEL operation: the job on its cores, the caller's thread as core 0;
 * the first fault (by core) goes to the cursor. */
static uint32_t run_job(el_job_t *job, el_cursor_t *cursor)
{
    uint32_t core;
    uint64_t sequence;
    if (job->cores < 1u || job->cores > EL_MAX_CORES) {
        return fault(cursor, EL_RUN_BAD_OP, job);
    }
    pthread_mutex_lock(&el_pool_post);
    job->epoch++;
    job->failed = 0u;
    for (core = 0u; core < job->cores; core++) {
        job->cursors[core].error = EL_RUN_OK;
        job->cursors[core].now_us = cursor->now_us;
    }
    pthread_mutex_lock(&el_pool_lock);
    if (!start_workers(job->cores)) {
        pthread_mutex_unlock(&el_pool_lock);
        pthread_mutex_unlock(&el_pool_post);
        return fault(cursor, EL_RUN_THREADS, job);
    }
    sequence = ++el_pool_sequence;
    el_pool_job = job;
    el_pool_cores = job->cores;
    pthread_cond_broadcast(&el_pool_wake);
    pthread_mutex_unlock(&el_pool_lock);
    run_core(job, 0u);
    for (core = 1u; core < job->cores; core++) {
        uint32_t spins = 0u;
        while (__atomic_load_n(&el_pool_done[core], __ATOMIC_ACQUIRE) != sequence) {
            pause_for(&spins);
        }
    }
    pthread_mutex_unlock(&el_pool_post);
    for (core = 0u; core < job->cores; core++) {
        const el_cursor_t *c = &job->cursors[core];
        if (c->error != EL_RUN_OK && c->error != EL_RUN_GAVE_UP) {
            return fault(cursor, c->error, c->error_at);
        }
    }
    return EL_RUN_OK;
}

uint32_t el_run_ops(const el_op_t *ops, uint32_t count, el_cursor_t *cursor)
{
    const el_op_t *op = ops;
    const el_op_t *end = ops + count;
    const el_op_t *back = NULL; /* where a CALL returns to, and the end of that list */
    const el_op_t *back_end = NULL;
    uint32_t error = EL_RUN_OK;

    for (;;) {
        if (op == end) {
            if (back == NULL) {
                return EL_RUN_OK;
            }
            op = back;
            end = back_end;
            back = NULL;
            continue;
        }
        switch (op->kind) {
        case EL_OP_CALL:
            if (back != NULL) {
                return fault(cursor, EL_RUN_NESTED, op);
            }
            back = op + 1;
            back_end = end;
            end = (const el_op_t *)op->src + op->count;
            op = (const el_op_t *)op->src;
            continue;
        case EL_OP_PUBLISH:
            if ((size_t)(end - op - 1) < op->count) {
                return fault(cursor, EL_RUN_BAD_OP, op);
            }
            if (*(uint8_t *)op->object == 0u) {
                op += op->count; /* not released since its last deadline: nothing to publish */
            } else {
                *(uint8_t *)op->object = 0u;
            }
            break;
        case EL_OP_PARALLEL:
            error = run_job((el_job_t *)op->object, cursor);
            if (error != EL_RUN_OK) {
                return error;
            }
            break;
        case EL_OP_WAIT:
        case EL_OP_SIGNAL: /* only in a job's lists */
            return fault(cursor, EL_RUN_BAD_OP, op);
        default:
            error = run_leaf(op, cursor);
            if (error != EL_RUN_OK) {
                return fault(cursor, error, fault_at(op, error));
            }
            break;
        }
        op++;
    }
}

uint64_t el_run_instants(const el_table_t *table, el_cursor_t *cursor, uint64_t before_us, uint64_t max_instants,
                         uint64_t max_ops)
{
    uint64_t done = 0u;
    uint64_t ops_run = 0u;

    while (done < max_instants && ops_run < max_ops) {
        uint32_t i = cursor->index;
        uint64_t time_us = (cursor->base + table->tick[i]) * table->tick_us;
        uint32_t count = table->first[i + 1u] - table->first[i];
        if (!table->native[i] || time_us >= before_us) {
            break;
        }
        cursor->now_us = time_us;
        if (el_run_ops(table->ops + table->first[i], count, cursor) != EL_RUN_OK) {
            break;
        }
        ops_run += count;
        done++;
        cursor->index = i + 1u;
        if (cursor->index == table->instants) {
            cursor->index = 0u;
            cursor->base += table->hyperperiod;
        }
    }
    return done;
}
