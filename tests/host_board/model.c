/* A hand-written stand-in for a generated model, ONLY to test the host
 * board (boards/host/): the el_model.h tables of a small model and a
 * minimal el_run loop in place of the runtime's dispatcher.
 *
 * Devices: 0 "sensor" (out: sensor.raw int16, sensor.ok bool),
 *          1 "cam" (out: cam.px uint8[3], cam.exposure float32),
 *          2 "motor" (in: motor.speed float32).
 * Each tick: read sensor and cam, compute, write motor, record the instant.
 *
 * Build options: -DFIXTURE_TICK_US=N (default 1000), -DFIXTURE_FIRST_TICK=N
 * (default 0). Environment: FIXTURE_OVERRUNS=N sets el_overruns[1] = N;
 * FIXTURE_REPORT=1 prints "ticks: N" (instants processed) and "last: T"
 * (the last tick processed, "-" for none) on stdout at the end;
 * FIXTURE_CAM_EVERY=N reads the cam device only at ticks that are
 * multiples of N (default 1: every tick).
 */
#include "el_types.h"
#include "el_model.h"
#include "el_port.h"
#include "el_board.h"

#include <stdio.h>
#include <stdlib.h>

#ifndef FIXTURE_TICK_US
#define FIXTURE_TICK_US 1000u
#endif
#ifndef FIXTURE_FIRST_TICK
#define FIXTURE_FIRST_TICK 0u
#endif

/* Published values. */
static float gain = 0.5f;            /* param */
static int16_t limit = 100;          /* param */
static uint32_t count;               /* var: tick / 2 */
static bool over;                    /* var: sensor.ok && sensor.raw > limit */
static int8_t delta;                 /* var: (int8) wrapping sensor.raw - 100 */
static uint16_t level;               /* var: cam.px[0] + cam.px[1] + cam.px[2] */
static el_time_t elapsed;            /* var: ms since the start, every 4 ticks */
static uint32_t boots;               /* var: runs so far, from nvram */
static int32_t neg;                  /* var: -count */
static int16_t sensor_raw;           /* device 0 out */
static bool sensor_ok;               /* device 0 out */
static uint8_t cam_px[3];            /* device 1 out, rate 3 */
static float cam_exposure;           /* device 1 out */
static float motor_speed;            /* device 2 in */

const char el_model_name[] = "fixture";
const uint32_t el_program_id = 0x12345678u;
const uint32_t el_tick_us = FIXTURE_TICK_US;
const uint32_t el_hyperperiod_ticks = 12u;
/* The fixture declares no Modbus interface (el_service.h). */
const uint8_t el_svc_modbus_links = 0u;

const el_item_t el_items[] = {
    {"gain", &gain, EL_T_F32, EL_K_PARAM, EL_NO_DEVICE, 1},
    {"limit", &limit, EL_T_I16, EL_K_PARAM, EL_NO_DEVICE, 1},
    {"count", &count, EL_T_U32, EL_K_VAR, EL_NO_DEVICE, 1},
    {"over", &over, EL_T_BOOL, EL_K_VAR, EL_NO_DEVICE, 1},
    {"delta", &delta, EL_T_I8, EL_K_VAR, EL_NO_DEVICE, 1},
    {"level", &level, EL_T_U16, EL_K_VAR, EL_NO_DEVICE, 1},
    {"elapsed", &elapsed, EL_T_TIME, EL_K_VAR, EL_NO_DEVICE, 1},
    {"boots", &boots, EL_T_U32, EL_K_VAR, EL_NO_DEVICE, 1},
    {"neg", &neg, EL_T_I32, EL_K_VAR, EL_NO_DEVICE, 1},
    {"sensor.raw", &sensor_raw, EL_T_I16, EL_K_DEV_OUT, 0, 1},
    {"sensor.ok", &sensor_ok, EL_T_BOOL, EL_K_DEV_OUT, 0, 1},
    {"cam.px", cam_px, EL_T_U8, EL_K_DEV_OUT, 1, 3},
    {"cam.exposure", &cam_exposure, EL_T_F32, EL_K_DEV_OUT, 1, 1},
    {"motor.speed", &motor_speed, EL_T_F32, EL_K_DEV_IN, 2, 1},
};
const uint16_t el_item_count = sizeof el_items / sizeof el_items[0];

const el_device_t el_devices[] = {
    {"sensor", "analog_in"},
    {"cam", "camera"},
    {"motor", "motor"},
};
const uint8_t el_device_count = 3;

static const char *const cyl_steps[] = {"Idle", "Extending", "Holding"};
static uint8_t cyl_active[3];
const el_chart_t el_charts[] = {
    {"Cyl", 3, cyl_steps, cyl_active},
};
const uint8_t el_chart_count = 1;

uint16_t el_overruns[2];
const uint8_t el_task_count = 2;
const char *const el_task_names[] = {"control", "logger"};

static void compute(uint64_t tick)
{
    uint8_t s;
    count = (uint32_t)(tick / 2u);
    neg = EL_WRAP_NEG(int32_t, uint32_t, count);
    over = sensor_ok && sensor_raw > limit;
    delta = (int8_t)(uint8_t)((uint16_t)sensor_raw - 100u);
    level = (uint16_t)(cam_px[0] + cam_px[1] + cam_px[2]);
    if (tick % 4u == 0u)
        elapsed = (el_time_t)(tick * el_tick_us / 1000u);
    motor_speed = gain * (float)sensor_raw;
    /* Chart: Idle for 3 ticks, Extending for 3, Holding for 3, none for 3;
     * Extending and Holding together at the last tick of Extending. */
    for (s = 0; s < 3u; s++)
        cyl_active[s] = 0;
    s = (uint8_t)((tick / 3u) % 4u);
    if (s < 3u)
        cyl_active[s] = 1;
    if (s == 1u && tick % 3u == 2u)
        cyl_active[2] = 1;
}

/* The runtime's idle hook (el_dispatch.h), which the board calls between
 * instants: nothing to serve in this fixture. */
void el_idle(void);
void el_idle(void)
{
}

void el_run(int argc, char **argv)
{
    uint64_t tick, processed = 0;
    uint8_t nv[4];
    el_irq_state_t a, b;
    const char *ov = getenv("FIXTURE_OVERRUNS");
    const char *every = getenv("FIXTURE_CAM_EVERY");
    uint64_t cam_every = every != NULL && atoi(every) > 0 ? (uint64_t)atoi(every) : 1u;

    if (!el_port_init(argc, argv))
        return;
    /* nvram: a boot counter in bytes 0..3 (erased: 0xFFFFFFFF = none). */
    if (el_port_nv_read(0, nv, 4)) {
        boots = (uint32_t)nv[0] | (uint32_t)nv[1] << 8 | (uint32_t)nv[2] << 16 | (uint32_t)nv[3] << 24;
        boots = boots == 0xFFFFFFFFu ? 1u : boots + 1u;
        nv[0] = (uint8_t)boots;
        nv[1] = (uint8_t)(boots >> 8);
        nv[2] = (uint8_t)(boots >> 16);
        nv[3] = (uint8_t)(boots >> 24);
        (void)el_port_nv_write(0, nv, 4);
    }
    if (ov != NULL)
        el_overruns[1] = (uint16_t)atoi(ov);
    el_sim_open(0);
    el_sim_open(1);
    el_sim_open(2);
    el_sim_start(0);
    el_sim_start(1);
    el_sim_start(2);
    for (tick = FIXTURE_FIRST_TICK;; tick++) {
        if (!el_port_wait_tick((uint32_t)tick))
            break;
        a = el_port_irq_save();
        b = el_port_irq_save();
        el_port_irq_restore(b);
        el_port_irq_restore(a);
        el_port_inputs(tick);
        el_sim_read(0);
        if (tick % cam_every == 0u)
            el_sim_read(1);
        compute(tick);
        el_sim_write(2);
        (void)el_port_real_tick();
        el_port_instant(tick);
        processed++;
    }
    if (getenv("FIXTURE_REPORT") != NULL) {
        printf("ticks: %llu\n", (unsigned long long)processed);
        if (processed > 0u)
            printf("last: %llu\n", (unsigned long long)(tick - 1u));
        else
            printf("last: -\n");
    }
    el_sim_stop(0);
    el_sim_close(0);
    el_port_shutdown();
}
