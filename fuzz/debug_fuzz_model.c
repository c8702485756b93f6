/* The fuzz target's model: debug tables as debug_tables.c would have them
 * (every type, an array item, ranges, read-only items, charts, actors) and
 * the runtime symbols the server uses. */
#include "el_debug.h"
#include "el_model.h"

#include <string.h>

static bool b0;
static int8_t i8;
static uint8_t u8;
static int16_t i16 = 5;
static uint16_t u16;
static int32_t i32;
static uint32_t u32;
static float f32;
static uint32_t t32 = 2000u;
static int16_t arr[3];
static bool dev_in;
static struct { int32_t integral; int16_t window[4]; } actor0;
static uint8_t slots0[1] = {0xFFu};
static uint8_t slots1[2] = {0u, 2u};

const el_dbg_range_t el_dbg_ranges[3] EL_ROM = {
    { { .i = -100L }, { .i = 100L } },
    { { .f = -1.5f }, { .f = 2.5f } },
    { { .u = 100UL }, { .u = 10000UL } },
};

const el_dbg_item_t el_dbg_items[14] EL_ROM = {
    { (void *)&b0, 1u, EL_DBG_NONE16, EL_DBG_T_BOOL, EL_DBG_K_VAR, EL_DBG_F_READ | EL_DBG_F_WRITE },
    { (void *)&i8, 1u, EL_DBG_NONE16, EL_DBG_T_I8, EL_DBG_K_VAR, EL_DBG_F_READ | EL_DBG_F_WRITE },
    { (void *)&u8, 1u, EL_DBG_NONE16, EL_DBG_T_U8, EL_DBG_K_PARAM, EL_DBG_F_READ | EL_DBG_F_WRITE },
    { (void *)&i16, 1u, 0u, EL_DBG_T_I16, EL_DBG_K_PARAM, EL_DBG_F_READ | EL_DBG_F_WRITE | EL_DBG_F_RANGE },
    { (void *)&u16, 1u, EL_DBG_NONE16, EL_DBG_T_U16, EL_DBG_K_DEV_OUT, EL_DBG_F_READ | EL_DBG_F_WRITE },
    { (void *)&i32, 1u, EL_DBG_NONE16, EL_DBG_T_I32, EL_DBG_K_VAR, EL_DBG_F_READ | EL_DBG_F_WRITE },
    { (void *)&u32, 1u, EL_DBG_NONE16, EL_DBG_T_U32, EL_DBG_K_VAR, EL_DBG_F_READ },
    { (void *)&f32, 1u, 1u, EL_DBG_T_F32, EL_DBG_K_PARAM, EL_DBG_F_READ | EL_DBG_F_WRITE | EL_DBG_F_RANGE },
    { (void *)&t32, 1u, 2u, EL_DBG_T_TIME, EL_DBG_K_PARAM, EL_DBG_F_READ | EL_DBG_F_WRITE | EL_DBG_F_RANGE },
    { (void *)arr, 3u, EL_DBG_NONE16, EL_DBG_T_I16, EL_DBG_K_DEV_OUT, EL_DBG_F_READ | EL_DBG_F_WRITE },
    { (void *)&dev_in, 1u, EL_DBG_NONE16, EL_DBG_T_BOOL, EL_DBG_K_DEV_IN, EL_DBG_F_READ },
    { (void *)&actor0.integral, 1u, EL_DBG_NONE16, EL_DBG_T_I32, EL_DBG_K_STATE, EL_DBG_F_READ | EL_DBG_F_WRITE },
    { (void *)actor0.window, 4u, EL_DBG_NONE16, EL_DBG_T_I16, EL_DBG_K_STATE, EL_DBG_F_READ | EL_DBG_F_WRITE },
    { (void *)&u32, 1u, EL_DBG_NONE16, EL_DBG_T_U32, EL_DBG_K_VAR, EL_DBG_F_READ | EL_DBG_F_WRITE },
};
const uint16_t el_dbg_item_count = 14u;
const uint16_t el_dbg_actor_count = 3u; /* actor0 and two stateless ones */
const el_dbg_chart_t el_dbg_charts[2] EL_ROM = {
    { slots0, 1u, 3u, 2u },
    { slots1, 2u, 4u, 3u },
};
const uint8_t el_dbg_chart_count = 2u;

const uint32_t el_program_id = 0xC0FFEE01UL;
const uint8_t el_task_count = 3u;

uint64_t el_now_tick(void)
{
    return 42u;
}

void fuzz_model_reset(void);
void fuzz_model_reset(void)
{
    i16 = 5;
    t32 = 2000u;
    memset(arr, 0, sizeof arr);
}
