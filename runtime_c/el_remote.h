/* EasyLab remote execution: the proxy's runtime (docs/remote.md).
 *
 * A proxy is firmware generated from the device model (proxy.c): the
 * devices, their data and the dispatch table of the tasks that use them,
 * with no application. The LET dispatcher (el_dispatch.c) runs it as any
 * firmware; the generated el_gen_* functions call this runtime, which
 * exchanges one frame per release instant with the host running the
 * application: UP (the device data read now) and DOWN (the device `in`
 * data each task released now publishes at its deadline). A value that has
 * not arrived by its deadline is an overrun: counted, the previous value
 * stays. Until START, after STOP and when the link ends, every device `in`
 * datum holds its safe value.
 *
 * Compiled into every firmware (runtime_c/ is), but only a proxy build
 * (-DEL_REMOTE_PROXY=1, easylab proxy) has any of it.
 */
#ifndef EL_REMOTE_H
#define EL_REMOTE_H

#include "el_types.h"
#include "el_remote_protocol.h"

/* One device datum in a frame: `size` bytes at `addr` (the published
 * value). `owner` is the device (out data) or the proxy task (in data). */
typedef struct {
    void *addr;
    uint16_t size;
    uint8_t owner;
} el_rmt_field_t;

/* ---- tables generated in proxy.c ---------------------------------------- */
extern const uint32_t el_rmt_device_model_id;
extern const uint32_t el_rmt_watchdog_ticks;       /* no valid frame for this long: safe values */
extern const uint8_t el_rmt_overrun_limit;          /* this many overruns in a row: safe values */
extern const uint8_t el_rmt_device_count_;          /* devices */
extern const uint32_t el_rmt_device_ids[];          /* per device: hash of its description */
extern const char *const el_rmt_device_paths[];
extern const uint32_t el_rmt_device_readers[];      /* per device: proxy tasks reading it (bits) */
extern const el_rmt_field_t el_rmt_out_fields[];    /* device out data: device order, port order */
extern const uint16_t el_rmt_out_count;
extern const el_rmt_field_t el_rmt_in_fields[];     /* device in data: task order, item order */
extern const uint16_t el_rmt_in_count;
extern const uint8_t el_rmt_safe[];                 /* safe values of the in fields, concatenated */
extern uint8_t el_rmt_staged[];                     /* received in values, same layout */
extern const uint16_t el_rmt_staged_size;

/* ---- called by proxy.c ---------------------------------------------------- */
void el_remote_boot(void);               /* safe values, then wait for START */
void el_remote_release(uint8_t task);    /* a proxy task is released now */
void el_remote_body(uint8_t task);       /* after the reads: UP, and in lock-step DOWN */
void el_remote_publish(uint8_t task);    /* the task's deadline: apply what arrived */
void el_remote_poll(void);               /* take received bytes (from el_idle) */
void el_remote_shutdown(void);           /* safe values */
/* A proxy task's overruns: its deadlines at which the host's values had
 * not come (the previous values held). The dispatcher's el_overruns of a
 * proxy count the proxy's own lateness, behind its clock, instead. */
uint16_t el_remote_overruns(uint8_t task);

/* ---- provided by the board (the host board: boards/host/host_remote.c) ---- */
uint16_t el_remote_port_read(uint8_t *buf, uint16_t max); /* received bytes, without waiting */
bool el_remote_port_write(const uint8_t *frame, uint16_t len);
void el_remote_port_end(void); /* the host stopped the session: end the run where the board can */
/* Whether the board wants the run to end (the host board: a SIGTERM or
 * SIGINT came): the proxy stops waiting for its host (START, a lock-step
 * DOWN) and the run ends at the next tick, safe values applied. Boards
 * that run until reset return false. */
bool el_remote_port_stopping(void);

#endif /* EL_REMOTE_H */
