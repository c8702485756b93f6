/* EasyLab host board: a node's DDS exports (docs/distribution.md, "DDS").
 *
 * Built only into a node with exports, with libddsc: the build generates
 * the exports' IDL from the IR, compiles it with idlc (el_dds_types.c/.h)
 * and prints the table below (el_dds_table.c). */
#ifndef HOST_DDS_H
#define HOST_DDS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dds/dds.h"

typedef struct {
    const char *topic;                   /* rt/<model>/<node>/<name> */
    const dds_topic_descriptor_t *type;  /* idlc's descriptor of its ROS 2 type */
    uint32_t domain;                     /* the DDS domain of its link */
    void *sample;                        /* its sample, of idlc's struct */
    void *data;                          /* the sample's `data` field */
    size_t size;                         /* bytes of `data`: the export's values */
} el_dds_export_t;

extern const el_dds_export_t el_dds_exports[];
extern const uint8_t el_dds_export_count;
extern const int32_t el_dds_history_depth; /* keep-last depth of every writer */
extern dds_entity_t el_dds_participants[];  /* one per export; shared by exports of one domain */
extern dds_entity_t el_dds_writers[];

/* Join each export's domain and create its topic and writer; false (and a
 * message) if DDS fails. */
bool el_host_dds_start(void);
/* Delete every participant (a writer first waits for its readers' acks). */
void el_host_dds_stop(void);

#endif /* HOST_DDS_H */
