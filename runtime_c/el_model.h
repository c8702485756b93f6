/* EasyLab runtime: the description of a generated model that boards and
 * tools walk (data, not code): its items, devices, charts and timing.
 *
 * The generator emits these tables in model.c; the host board uses them
 * for stimulus files and traces, the debug server for reads and writes.
 */
#ifndef EL_MODEL_H
#define EL_MODEL_H

#include "el_types.h"

/* Value types of items (docs/ir.md). */
enum {
    EL_T_BOOL = 0,
    EL_T_I8 = 1,
    EL_T_U8 = 2,
    EL_T_I16 = 3,
    EL_T_U16 = 4,
    EL_T_I32 = 5,
    EL_T_U32 = 6,
    EL_T_F32 = 7,
    EL_T_TIME = 8 /* uint32_t milliseconds */
};

/* What an item is. */
enum {
    EL_K_PARAM = 0,   /* a param: written through the interfaces only */
    EL_K_VAR = 1,     /* a var */
    EL_K_DEV_OUT = 2, /* device -> application datum: produced by read() */
    EL_K_DEV_IN = 3,  /* application -> device datum: consumed by write() */
    EL_K_DEV_STATE = 4 /* a device's `state` field (the host board's traced state, never in el_items) */
};

#define EL_NO_DEVICE 0xFFu

/* One traced / addressable item. `addr` points at the published (global)
 * value; `count` values of the type lie there (a device port's rate). */
typedef struct {
    const char *name;   /* model path: "temperature", "sensor.raw" */
    void *addr;
    uint8_t type;       /* EL_T_... */
    uint8_t kind;       /* EL_K_... */
    uint8_t device;     /* index into el_devices for device data, else EL_NO_DEVICE */
    uint16_t count;
} el_item_t;

/* One primitive device. */
typedef struct {
    const char *path;   /* "robot.drive.m1" */
    const char *driver; /* "motor" */
} el_device_t;

/* One chart: the published activity of its steps (1 = active), as of the
 * deadline of its task's latest activation. */
typedef struct {
    const char *name;                /* "Cylinder"; traced as "Cylinder.active" */
    uint8_t step_count;
    const char *const *step_names;
    const uint8_t *active;           /* step_count flags */
} el_chart_t;

extern const char el_model_name[];
extern const uint32_t el_program_id;
extern const uint32_t el_tick_us;          /* one logical tick, in microseconds */
extern const uint32_t el_hyperperiod_ticks;
extern const el_item_t el_items[];
extern const uint16_t el_item_count;
extern const el_device_t el_devices[];
extern const uint8_t el_device_count;
extern const el_chart_t el_charts[];
extern const uint8_t el_chart_count;

/* Per-task lateness: how often a task finished after its deadline. */
extern uint16_t el_overruns[];
extern const uint8_t el_task_count;
extern const char *const el_task_names[];

#endif /* EL_MODEL_H */
