/* EasyLab host board: a node's DDS exports (see host_dds.h).
 *
 * Every export has a reliable, keep-last, transient-local writer on its
 * topic. The model
 * calls el_port_export() at the instant the export has a value (ir/dds.py
 * decides when); the sample's source timestamp is that instant's logical
 * time in nanoseconds, so a subscriber sees the model's instants whatever
 * the wall clock did. */
#include "host_dds.h"
#include "host_internal.h"
#include "el_port.h"

#include <stdio.h>
#include <string.h>

static bool write_failed; /* a failed write is reported once */

bool el_host_dds_start(void)
{
    dds_qos_t *qos;
    uint8_t k, j;
    bool ok = true;

    qos = dds_create_qos();
    if (qos == NULL) {
        fprintf(stderr, "%s: DDS: no memory for the QoS\n", el_host_prog);
        return false;
    }
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, el_dds_history_depth);
    /* A reader that joins late (discovery takes a few ms) and asks for it
     * gets the last samples; ROS 2's volatile readers match as well. */
    dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
    /* as many samples for them as the history holds (the default keeps one) */
    dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, el_dds_history_depth, DDS_LENGTH_UNLIMITED,
                                DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
    for (k = 0u; k < el_dds_export_count && ok; k++) {
        const el_dds_export_t *e = &el_dds_exports[k];
        dds_entity_t topic;
        el_dds_participants[k] = 0;
        for (j = 0u; j < k; j++) {
            if (el_dds_exports[j].domain == e->domain) {
                el_dds_participants[k] = el_dds_participants[j];
                break;
            }
        }
        if (el_dds_participants[k] == 0) {
            el_dds_participants[k] = dds_create_participant((dds_domainid_t)e->domain, NULL, NULL);
        }
        if (el_dds_participants[k] < 0) {
            fprintf(stderr, "%s: DDS: cannot join domain %u: %s\n", el_host_prog, (unsigned)e->domain,
                    dds_strretcode(el_dds_participants[k]));
            el_dds_participants[k] = 0;
            ok = false;
            break;
        }
        topic = dds_create_topic(el_dds_participants[k], e->type, e->topic, qos, NULL);
        el_dds_writers[k] = topic < 0 ? topic : dds_create_writer(el_dds_participants[k], topic, qos, NULL);
        if (el_dds_writers[k] < 0) {
            fprintf(stderr, "%s: DDS: cannot publish topic '%s': %s\n", el_host_prog, e->topic,
                    dds_strretcode(el_dds_writers[k]));
            ok = false;
        }
    }
    dds_delete_qos(qos);
    write_failed = false;
    if (!ok)
        el_host_dds_stop();
    return ok;
}

void el_host_dds_stop(void)
{
    uint8_t k, j;
    for (k = 0u; k < el_dds_export_count; k++) {
        bool first = el_dds_participants[k] > 0; /* the first export of its participant deletes it */
        for (j = 0u; j < k && first; j++)
            first = el_dds_participants[j] != el_dds_participants[k];
        if (first)
            (void)dds_delete(el_dds_participants[k]); /* its topics and writers with it */
    }
    for (k = 0u; k < el_dds_export_count; k++)
        el_dds_participants[k] = el_dds_writers[k] = 0;
}

void el_port_export(uint8_t index, const void *values)
{
    const el_dds_export_t *e;
    dds_return_t r;

    if (index >= el_dds_export_count || el_dds_writers[index] <= 0)
        return;
    e = &el_dds_exports[index];
    memcpy(e->data, values, e->size);
    r = dds_write_ts(el_dds_writers[index], e->sample, (dds_time_t)(el_host_now_us() * 1000u));
    if (r != DDS_RETCODE_OK && !write_failed) {
        write_failed = true;
        fprintf(stderr, "%s: DDS: writing topic '%s' failed: %s\n", el_host_prog, e->topic, dds_strretcode(r));
    }
}
