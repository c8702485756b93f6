/* EasyLab host board: a node's DDS topics (docs/distribution.md, "DDS"):
 * its exports, and its ends of channels over DDS links.
 *
 * Built only into a node with either, with libddsc: the build generates
 * their IDL from the IR, compiles it with idlc (el_dds_types.c/.h) and
 * prints the table below (el_dds_table.c). */
#ifndef HOST_DDS_H
#define HOST_DDS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dds/dds.h"

enum {
    EL_DDS_EXPORT,      /* written by el_port_export (an export's index is its row) */
    EL_DDS_CHANNEL_OUT, /* the tokens of a channel's output end, written when published */
    EL_DDS_CHANNEL_IN   /* pushed into a channel's input end when due */
};

typedef struct {
    const char *topic;                   /* rt/<model>/<node>/<name> */
    const dds_topic_descriptor_t *type;  /* idlc's descriptor of its ROS 2 type */
    uint32_t domain;                     /* the DDS domain of its link */
    uint8_t role;                        /* EL_DDS_... */
    void *sample;                        /* its sample, of idlc's struct */
    void *data;                          /* the sample's `data` field */
    size_t size;                         /* bytes of `data` */
    uint16_t values;                     /* values in `data` */
    /* a channel's end (el_chN_pull, el_chN_push); NULL elsewhere */
    uint16_t (*pull)(void *tokens, uint16_t n);
    uint16_t (*push)(const void *tokens, uint16_t n);
    /* EL_DDS_CHANNEL_IN: a sample stamped d is pushed at the first instant
     * >= d + delay_us; the producer publishes at first_us + k * period_us */
    uint64_t delay_us, first_us, period_us;
} el_dds_topic_t;

extern const el_dds_topic_t el_dds_topics[];
extern const uint8_t el_dds_topic_count;
extern const int32_t el_dds_history_depth; /* keep-last depth of every export */
extern dds_entity_t el_dds_participants[];  /* one per row; shared by the rows of one domain */
extern dds_entity_t el_dds_endpoints[];     /* the row's writer or reader */
extern int64_t el_dds_last_us[];            /* EL_DDS_CHANNEL_IN: the stamp last pushed (-1: none) */

/* Join each row's domain and create its topic and writer or reader; in
 * lock-step (--fast) wait until each channel's writer meets its reader.
 * False (and a message) if DDS fails. */
bool el_host_dds_start(void);
/* At each instant before the releases: write the tokens the channels' output
 * ends got, push the samples due into the input ends (in lock-step after
 * waiting for every publication due). */
void el_host_dds_inputs(uint64_t now_us);
/* Delete every participant (a channel's writer first waits for its acks). */
void el_host_dds_stop(void);

#endif /* HOST_DDS_H */
