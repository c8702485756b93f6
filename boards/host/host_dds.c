/* EasyLab host board: a node's DDS topics (see host_dds.h).
 *
 * Exports: reliable, keep-last, transient-local writers (a reader that
 * joins late and asks for it gets the last samples); the model calls
 * el_port_export() at the instant an export has a value (ir/dds.py decides
 * when). Channels over DDS: reliable, keep-all, transient-local, so that no
 * token is lost; the output end's tokens are written at the instant they
 * are published, the input end gets a sample at the first instant at or
 * after its stamp + the link's delay. Every sample's source timestamp is
 * the logical time of the instant that wrote it, in nanoseconds, so a
 * subscriber sees the model's instants whatever the wall clock did.
 *
 * In lock-step (--fast) a channel's writer waits for its reader before the
 * run, the reader waits at each instant for the publications due by then,
 * and the writer waits for its acks at the end, each at most
 * EASYLAB_DDS_TIMEOUT_MS (20 s); in real time nothing waits and a late
 * sample leaves the release tardy. */
#include "host_dds.h"
#include "host_internal.h"
#include "el_port.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static bool write_failed; /* a failed write is reported once */
static bool overflowed;   /* so is a full input end */
static bool gave_up;      /* a lock-step wait timed out: reported once, no more waits */

static dds_duration_t timeout(void)
{
    const char *env = getenv("EASYLAB_DDS_TIMEOUT_MS");
    long ms = env != NULL ? atol(env) : 20000L;
    return DDS_MSECS(ms > 0 ? ms : 20000L);
}

static dds_qos_t *make_qos(uint8_t role)
{
    dds_qos_t *qos = dds_create_qos();
    if (qos == NULL)
        return NULL;
    dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
    if (role == EL_DDS_EXPORT) {
        dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
        dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, el_dds_history_depth);
        /* as many samples for late joiners as the history holds (the default keeps one) */
        dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, el_dds_history_depth, DDS_LENGTH_UNLIMITED,
                                    DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
    } else {
        dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, timeout());
        dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
        dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_ALL, 0, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED,
                                    DDS_LENGTH_UNLIMITED);
    }
    return qos;
}

/* Lock-step: a channel's writer meets its reader before the run. */
static bool wait_for_reader(const el_dds_topic_t *e, dds_entity_t writer)
{
    dds_publication_matched_status_t matched;
    dds_time_t end = dds_time() + timeout();
    do {
        if (dds_get_publication_matched_status(writer, &matched) < 0)
            return false;
        if (matched.current_count > 0)
            return true;
        dds_sleepfor(DDS_MSECS(2));
    } while (dds_time() < end);
    fprintf(stderr, "%s: DDS: no reader of '%s' came: its values are not carried\n", el_host_prog, e->topic);
    return true;
}

static bool open_row(uint8_t k)
{
    const el_dds_topic_t *e = &el_dds_topics[k];
    dds_entity_t topic, endpoint;
    dds_qos_t *qos;
    uint8_t j;

    el_dds_participants[k] = 0;
    el_dds_last_us[k] = -1;
    for (j = 0u; j < k; j++) {
        if (el_dds_topics[j].domain == e->domain) {
            el_dds_participants[k] = el_dds_participants[j];
            break;
        }
    }
    if (el_dds_participants[k] == 0)
        el_dds_participants[k] = dds_create_participant((dds_domainid_t)e->domain, NULL, NULL);
    if (el_dds_participants[k] < 0) {
        fprintf(stderr, "%s: DDS: cannot join domain %u: %s\n", el_host_prog, (unsigned)e->domain,
                dds_strretcode(el_dds_participants[k]));
        el_dds_participants[k] = 0;
        return false;
    }
    qos = make_qos(e->role);
    if (qos == NULL) {
        fprintf(stderr, "%s: DDS: no memory for the QoS\n", el_host_prog);
        return false;
    }
    topic = dds_create_topic(el_dds_participants[k], e->type, e->topic, qos, NULL);
    if (topic < 0)
        endpoint = topic;
    else if (e->role == EL_DDS_CHANNEL_IN)
        endpoint = dds_create_reader(el_dds_participants[k], topic, qos, NULL);
    else
        endpoint = dds_create_writer(el_dds_participants[k], topic, qos, NULL);
    dds_delete_qos(qos);
    el_dds_endpoints[k] = endpoint;
    if (endpoint < 0) {
        fprintf(stderr, "%s: DDS: cannot %s topic '%s': %s\n", el_host_prog,
                e->role == EL_DDS_CHANNEL_IN ? "subscribe to" : "publish", e->topic, dds_strretcode(endpoint));
        return false;
    }
    return true;
}

bool el_host_dds_start(void)
{
    uint8_t k;
    write_failed = overflowed = gave_up = false;
    for (k = 0u; k < el_dds_topic_count; k++) {
        if (!open_row(k)) {
            el_host_dds_stop();
            return false;
        }
    }
    for (k = 0u; k < el_dds_topic_count && el_host_settings.fast; k++)
        if (el_dds_topics[k].role == EL_DDS_CHANNEL_OUT && !wait_for_reader(&el_dds_topics[k], el_dds_endpoints[k]))
            return false;
    return true;
}

void el_host_dds_stop(void)
{
    uint8_t k, j;
    for (k = 0u; k < el_dds_topic_count; k++)
        if (el_dds_topics[k].role == EL_DDS_CHANNEL_OUT && el_dds_endpoints[k] > 0)
            (void)dds_wait_for_acks(el_dds_endpoints[k], timeout()); /* the consumer's last tokens */
    for (k = 0u; k < el_dds_topic_count; k++) {
        bool first = el_dds_participants[k] > 0; /* the first row of its participant deletes it */
        for (j = 0u; j < k && first; j++)
            first = el_dds_participants[j] != el_dds_participants[k];
        if (first)
            (void)dds_delete(el_dds_participants[k]); /* its topics, writers and readers with it */
    }
    for (k = 0u; k < el_dds_topic_count; k++)
        el_dds_participants[k] = el_dds_endpoints[k] = 0;
}

static void write_row(uint8_t k, uint64_t now_us)
{
    const el_dds_topic_t *e = &el_dds_topics[k];
    dds_return_t r = dds_write_ts(el_dds_endpoints[k], e->sample, (dds_time_t)(now_us * 1000u));
    if (r != DDS_RETCODE_OK && !write_failed) {
        write_failed = true;
        fprintf(stderr, "%s: DDS: writing topic '%s' failed: %s\n", el_host_prog, e->topic, dds_strretcode(r));
    }
}

void el_port_export(uint8_t index, const void *values)
{
    if (index >= el_dds_topic_count || el_dds_endpoints[index] <= 0)
        return;
    memcpy(el_dds_topics[index].data, values, el_dds_topics[index].size);
    write_row(index, el_host_now_us());
}

/* Push the samples of input row k due by now, oldest first (one writer:
 * they come in the order of their stamps). */
static void push_due(uint8_t k, uint64_t now_us)
{
    const el_dds_topic_t *e = &el_dds_topics[k];
    void *samples[1];
    dds_sample_info_t info;
    samples[0] = e->sample;
    while (dds_read_mask(el_dds_endpoints[k], samples, &info, 1, 1, DDS_ANY_STATE) > 0) {
        uint64_t stamp = info.valid_data ? (uint64_t)info.source_timestamp / 1000u : 0u;
        if (info.valid_data && stamp + e->delay_us > now_us)
            break; /* the oldest is not due yet */
        (void)dds_take_mask(el_dds_endpoints[k], samples, &info, 1, 1, DDS_ANY_STATE);
        if (!info.valid_data)
            continue; /* the writer's end: no value */
        if (e->push(e->data, e->values) < e->values && !overflowed) {
            overflowed = true;
            fprintf(stderr, "%s: DDS: the input end of '%s' is full: tokens dropped\n", el_host_prog, e->topic);
        }
        el_dds_last_us[k] = (int64_t)stamp;
    }
}

/* The stamp of the last publication due by now (-1: none yet). */
static int64_t last_due(const el_dds_topic_t *e, uint64_t now_us)
{
    if (now_us < e->first_us + e->delay_us)
        return -1;
    return (int64_t)(e->first_us + (now_us - e->delay_us - e->first_us) / e->period_us * e->period_us);
}

void el_host_dds_inputs(uint64_t now_us)
{
    uint8_t k;
    for (k = 0u; k < el_dds_topic_count; k++) {
        const el_dds_topic_t *e = &el_dds_topics[k];
        if (e->role == EL_DDS_CHANNEL_OUT) {
            while (e->pull(e->data, e->values) == e->values)
                write_row(k, now_us);
        }
    }
    for (k = 0u; k < el_dds_topic_count; k++) {
        const el_dds_topic_t *e = &el_dds_topics[k];
        dds_time_t end;
        if (e->role != EL_DDS_CHANNEL_IN)
            continue;
        push_due(k, now_us);
        if (!el_host_settings.fast || gave_up)
            continue;
        end = dds_time() + timeout();
        while (el_dds_last_us[k] < last_due(e, now_us)) {
            if (dds_time() >= end) {
                gave_up = true;
                fprintf(stderr, "%s: DDS: no sample on '%s' for the instant at %llu us: the run goes on without "
                        "waiting\n", el_host_prog, e->topic, (unsigned long long)now_us);
                break;
            }
            dds_sleepfor(DDS_USECS(200));
            push_due(k, now_us);
        }
    }
}
