/* EasyLab runtime: the service interface's register map and its local API
 * (docs/service.md).
 *
 * The generator writes the map of a model's `service` params and vars into
 * service_tables.c (templates/service_tables.c.j2): one entry per item, in
 * declaration order (the entry's index is its *map id*, the "id" of
 * service_map.json), each with its register table and address, its type,
 * range and flags. The Modbus slave (el_modbus.h) and code linked into the
 * firmware (an HMI, a display: el_service_get / el_service_set) go through
 * the same checks here. Values are the published items of model.c: a write
 * takes effect at the next release of every task that reads the item
 * (tasks latch their inputs at release, docs/ir.md).
 *
 * Values cross this API as el_svc_value_t, always by pointer (some
 * compilers of the project's targets, sdcc, pass no unions by value): `.u`
 * for bool (0 or 1), uint8/16/32 and time (milliseconds), `.i` for
 * int8/16/32, `.f` for float32.
 *
 * Registers: 8- and 16-bit items take one 16-bit register (int8 sign-
 * extended, so -5 reads 0xFFFB); 32-bit integers, time and float32 take
 * two, the high word first at the lower address ("big-endian words",
 * ABCD; float32 as its IEEE 754 bits). bool items are coils (rw) or
 * discrete inputs (ro).
 *
 * No heap, no recursion, C99 (and C89 with a 16-bit int).
 */
#ifndef EL_SERVICE_H
#define EL_SERVICE_H

#include "el_types.h"

/* Generated tables carry this number; a mismatch is a compile error there. */
#define EL_SERVICE_VERSION 1

/* The four Modbus tables. */
#define EL_SVC_COIL 0u     /* bool, rw: read 01, write 05 / 15 */
#define EL_SVC_DISCRETE 1u /* bool, ro: read 02 */
#define EL_SVC_HOLDING 2u  /* numbers, rw: read 03, write 06 / 16 */
#define EL_SVC_INPUT 3u    /* numbers, ro: read 04 */
#define EL_SVC_TABLES 4u

/* Entry flags. */
#define EL_SVC_F_RW 0x01u      /* writable (service rw) */
#define EL_SVC_F_PERSIST 0x02u /* kept in non-volatile storage (el_persist.h) */
#define EL_SVC_F_RANGE 0x04u   /* lo..hi hold the model's range */

/* "No such item": what el_service_find returns for an unknown name. */
#define EL_SVC_NONE 0xFFFFu

/* Results. The numbers of the first three are the Modbus exception codes
 * the slave answers with. */
typedef uint8_t el_svc_status_t;
#define EL_SVC_OK 0u
#define EL_SVC_NO_ITEM 2u   /* no such map id (Modbus: illegal data address) */
#define EL_SVC_BAD_VALUE 3u /* outside the type or the range, NaN (Modbus: illegal data value) */
#define EL_SVC_STORAGE 4u   /* applied, but storing it failed (Modbus: server device failure) */
#define EL_SVC_READ_ONLY 5u /* a `service ro` item (local API; Modbus never sees it) */

typedef union {
    uint32_t u; /* bool (0/1), uint8, uint16, uint32, time */
    int32_t i;  /* int8, int16, int32 */
    float f;    /* float32 */
} el_svc_value_t;

/* One item of the map (generated, constant). */
typedef struct {
    const char *name; /* model path, "cal_gain" */
    void *addr;       /* its published value in model.c */
    uint32_t lo, hi;  /* EL_SVC_F_RANGE: the range as 32-bit patterns of the type
                       * (signed: two's complement, float32: IEEE bits) */
    uint16_t address; /* first register (or bit) in its table */
    uint16_t nv_key;  /* persist: CRC-16 of "name:type", stored in its records */
    uint16_t nv_slot; /* persist: index of its pair of records */
    uint8_t type;     /* EL_T_... (el_model.h) */
    uint8_t table;    /* EL_SVC_COIL ... EL_SVC_INPUT */
    uint8_t flags;    /* EL_SVC_F_... */
} el_svc_entry_t;

/* What el_persist.c remembers of one persist item (generated, zeroed). */
typedef struct {
    uint32_t value;  /* the value stored last (32-bit pattern) */
    uint16_t seq;    /* sequence number of the current copy */
    uint8_t current; /* 0: copy A, 1: copy B, EL_PERSIST_NO_COPY: none is valid */
} el_svc_nv_t;

/* The whole map of a model (generated). */
typedef struct {
    const el_svc_entry_t *entries; /* by map id */
    uint16_t count;
    const uint16_t *order;              /* map ids sorted by table, then address */
    uint16_t first[EL_SVC_TABLES];      /* where each table starts in `order` */
    uint16_t size[EL_SVC_TABLES];       /* entries of each table */
    el_svc_nv_t *nv;                    /* one per persist item */
    uint16_t nv_count;
    uint16_t nv_base;                   /* first byte used in el_port_nv_* */
    /* Device identification (Modbus 43/14). */
    const char *vendor;   /* "EasyLab" */
    const char *model;    /* the model's name */
    const char *title;    /* the model's title (or its name) */
    const char *version;  /* EasyLab version that generated the firmware */
    const char *program;  /* the program id, "0x1234abcd" */
    uint32_t program_id;
} el_svc_map_t;

/* The Modbus interfaces the model declares (generated in service_tables.c),
 * so that a board's command line can refuse to serve one the model lacks. */
#define EL_SVC_LINK_RTU 0x01u
#define EL_SVC_LINK_TCP 0x02u
extern const uint8_t el_svc_modbus_links;

/* Use `map` from now on and load the persisted params (el_persist_load).
 * Called once at boot by the generated interface glue, before the first
 * release. */
void el_service_init(const el_svc_map_t *map);

/* The map in use (null before el_service_init). */
const el_svc_map_t *el_service_map(void);

/* Number of items; map ids are 0 .. count-1. */
uint16_t el_service_count(void);

/* The map id of a model path, or EL_SVC_NONE. */
uint16_t el_service_find(const char *name);

/* The entry of a map id, or null. */
const el_svc_entry_t *el_service_entry(uint16_t id);

/* The current (published) value. EL_SVC_NO_ITEM for an unknown id. */
el_svc_status_t el_service_get(uint16_t id, el_svc_value_t *value);

/* Check a value for an item without writing it: the item exists
 * (EL_SVC_NO_ITEM), the value fits its type and range, a float32 is finite
 * (EL_SVC_BAD_VALUE). Writability is the caller's business. */
el_svc_status_t el_service_check(uint16_t id, const el_svc_value_t *value);

/* Write a value: the checks of el_service_check, EL_SVC_READ_ONLY for a
 * `service ro` item; then the published value changes and a persist param
 * is stored if it changed (EL_SVC_STORAGE if storing failed: the value is
 * applied nonetheless). Nothing changes when a check fails. */
el_svc_status_t el_service_set(uint16_t id, const el_svc_value_t *value);

/* Write without the read-only check (the Modbus slave: its tables already
 * tell writable from read-only items). Same other checks. */
el_svc_status_t el_service_write(uint16_t id, const el_svc_value_t *value);

/* Registers of an item: 0 for bool (a bit), 1 for 8/16-bit, 2 for 32-bit
 * integers, time and float32. */
uint8_t el_service_regs(uint8_t type);

/* An item's value as its registers (high word first). */
void el_service_to_regs(uint8_t type, const el_svc_value_t *value, uint16_t regs[2]);

/* Registers back to a value; EL_SVC_BAD_VALUE when they hold no value of
 * the type (int8 outside -128..127, uint8 above 255, a NaN or infinite
 * float32). The range is checked by el_service_check. */
el_svc_status_t el_service_from_regs(uint8_t type, const uint16_t regs[2], el_svc_value_t *value);

/* A value as the 32-bit pattern stored by el_persist (bool 0/1, integers
 * sign- or zero-extended, float32 IEEE bits), and back. */
uint32_t el_service_bits(uint8_t type, const el_svc_value_t *value);
void el_service_from_bits(uint8_t type, uint32_t bits, el_svc_value_t *value);

#endif /* EL_SERVICE_H */
