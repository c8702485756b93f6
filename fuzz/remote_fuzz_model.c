/* The remote fuzz target's proxy model: the tables proxy.c would have for
 * a device model of two devices and two proxy tasks (templates/proxy.c.j2)
 * and the dispatcher's symbols el_remote.c uses.
 *
 *   device sensor: out raw uint16, out window int16 rate 2  (read by both tasks)
 *   device drive:  in speed int16 (task 0), in on bool (task 1)
 *   task 0 every tick, task 1 every second tick (deadline 2 ticks)
 *
 * UP payload: state u8, raw u16, window 2 x i16 (7 bytes). DOWN payload:
 * mask u32, then speed i16 (bit 0) and on u8 (bit 1). Safe values:
 * speed -7, on true (declared, not zero: applying them is visible). */
#include "el_remote.h"
#include "el_model.h"

static uint16_t raw;
static int16_t window[2];
static int16_t speed = -7;
static bool on = true;

const uint32_t el_rmt_device_model_id = 0x5AFE0001UL;
const uint32_t el_rmt_watchdog_ticks = 8UL;
const uint8_t el_rmt_overrun_limit = 3u;
const uint8_t el_rmt_device_count_ = 2u;
const uint32_t el_rmt_device_ids[2] = { 0x11111111UL, 0x22222222UL };
const char *const el_rmt_device_paths[2] = { "sensor", "drive" };
const uint32_t el_rmt_device_readers[2] = { 0x00000003UL, 0x00000000UL };
const el_rmt_field_t el_rmt_out_fields[2] = {
    { (void *)&raw, 2u, 0u },
    { (void *)window, 4u, 0u },
};
const uint16_t el_rmt_out_count = 2u;
const el_rmt_field_t el_rmt_in_fields[2] = {
    { (void *)&speed, 2u, 0u },
    { (void *)&on, 1u, 1u },
};
const uint16_t el_rmt_in_count = 2u;
const uint8_t el_rmt_safe[3] = { 0xf9u, 0xffu, 0x01u };
uint8_t el_rmt_staged[3];
const uint16_t el_rmt_staged_size = 3u;

uint16_t el_overruns[2];
const uint8_t el_task_count = 2u; /* COUNTERS' answer carries each task's overruns */

void fuzz_model_reset(void);
void fuzz_model_reset(void)
{
    el_overruns[0] = 0u;
    el_overruns[1] = 0u;
    speed = 0;
    on = false;
}

/* The device `in` data hold their safe values (checked after STOP). */
bool fuzz_model_safe(void);
bool fuzz_model_safe(void)
{
    return speed == -7 && on;
}

/* A device read: the out data change at every read. */
void fuzz_model_read(uint32_t tick);
void fuzz_model_read(uint32_t tick)
{
    raw = (uint16_t)tick;
    window[0] = (int16_t)(tick & 0x7FFFu);
    window[1] = (int16_t)-window[0];
}
