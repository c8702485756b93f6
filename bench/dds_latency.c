/* DDS publish-to-receive latency on one machine (bench/bench_distribution.py): the
 * exports' transport, libddsc with their QoS (reliable, keep-last 10) and
 * their type (std_msgs::msg::dds_::Int16_, compiled by idlc; the build
 * defines EL_DDS_DEPTH, the exports' history depth).
 *
 *   dds_latency pub DOMAIN COUNT PERIOD_US   waits for a reader, then writes
 *                                            COUNT samples, one per period,
 *                                            stamped with CLOCK_MONOTONIC
 *   dds_latency sub DOMAIN COUNT             prints "ready", then each
 *                                            sample's latency in ns, until
 *                                            COUNT or 2 s without one
 * Both processes read the same CLOCK_MONOTONIC. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dds/dds.h"
#include "el_dds_types.h"

#define TOPIC "rt/bench/pc/latency"

static dds_time_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (dds_time_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static int fail(const char *what, dds_return_t r)
{
    fprintf(stderr, "dds_latency: %s: %s\n", what, dds_strretcode(r));
    return 1;
}

static int publish(dds_entity_t participant, dds_entity_t topic, const dds_qos_t *qos, long count, long period_us)
{
    dds_entity_t writer = dds_create_writer(participant, topic, qos, NULL);
    dds_publication_matched_status_t matched;
    std_msgs_msg_dds__Int16_ sample;
    struct timespec next;
    long i;

    if (writer < 0)
        return fail("writer", writer);
    do { /* a sample before the reader matches would be lost */
        dds_sleepfor(DDS_MSECS(5));
        if (dds_get_publication_matched_status(writer, &matched) < 0)
            return 1;
    } while (matched.current_count == 0);
    dds_sleepfor(DDS_MSECS(100));
    clock_gettime(CLOCK_MONOTONIC, &next);
    for (i = 0; i < count; i++) {
        dds_return_t r;
        next.tv_nsec += period_us * 1000L;
        while (next.tv_nsec >= 1000000000L) {
            next.tv_nsec -= 1000000000L;
            next.tv_sec++;
        }
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) != 0) {
        }
        sample.data = (int16_t)i;
        r = dds_write_ts(writer, &sample, now_ns());
        if (r != DDS_RETCODE_OK)
            return fail("write", r);
    }
    dds_sleepfor(DDS_MSECS(500)); /* the last samples' acks */
    return 0;
}

static int subscribe(dds_entity_t participant, dds_entity_t topic, const dds_qos_t *qos, long count)
{
    dds_entity_t reader = dds_create_reader(participant, topic, qos, NULL);
    dds_entity_t waitset = dds_create_waitset(participant);
    dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
    long got = 0;

    if (reader < 0 || waitset < 0 || condition < 0)
        return fail("reader", reader < 0 ? reader : waitset < 0 ? waitset : condition);
    (void)dds_waitset_attach(waitset, condition, 0);
    printf("ready\n");
    fflush(stdout);
    while (got < count) {
        std_msgs_msg_dds__Int16_ sample;
        void *samples[1] = {&sample};
        dds_sample_info_t info;
        /* the publisher waits for this reader: 30 s for the first sample,
         * then the end of the run is 2 s without one (lost ones: keep-last) */
        dds_return_t n = dds_waitset_wait(waitset, NULL, 0, got == 0 ? DDS_SECS(30) : DDS_SECS(2));
        if (n <= 0) {
            if (got == 0) {
                fprintf(stderr, "dds_latency: no sample in 30 s\n");
                return 1;
            }
            break;
        }
        while (dds_take(reader, samples, &info, 1, 1) > 0) {
            dds_time_t at = now_ns();
            if (!info.valid_data)
                continue;
            printf("%lld\n", (long long)(at - info.source_timestamp));
            got++;
        }
    }
    fflush(stdout);
    return 0;
}

int main(int argc, char **argv)
{
    dds_entity_t participant, topic;
    dds_qos_t *qos;
    int rc;

    if (argc < 4 || (strcmp(argv[1], "pub") == 0 && argc < 5)) {
        fprintf(stderr, "usage: dds_latency pub DOMAIN COUNT PERIOD_US | sub DOMAIN COUNT\n");
        return 2;
    }
    participant = dds_create_participant((dds_domainid_t)atoi(argv[2]), NULL, NULL);
    if (participant < 0)
        return fail("participant", participant);
    qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, EL_DDS_DEPTH);
    topic = dds_create_topic(participant, &std_msgs_msg_dds__Int16__desc, TOPIC, qos, NULL);
    if (topic < 0)
        return fail("topic", topic);
    if (strcmp(argv[1], "pub") == 0)
        rc = publish(participant, topic, qos, atol(argv[3]), atol(argv[4]));
    else
        rc = subscribe(participant, topic, qos, atol(argv[3]));
    dds_delete_qos(qos);
    dds_delete(participant);
    return rc;
}
