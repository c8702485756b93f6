/* EasyLab host board: the debug protocol's board commands of local execution
 * (docs/protocol.md, "Replacing the model"): LOAD_BEGIN, LOAD_DATA and
 * LOAD_COMMIT receive a new model text, checked against its length and
 * CRC-16; the interpreter takes it (el_interp_take_load), checks and builds
 * it, and reports the outcome (el_interp_load_result), which LOAD_STATUS
 * returns. Linked into the interfaces library (host_interp.c) and the
 * debug server's fuzz target; every length and offset from the request is
 * checked before use.
 */
#include "el_debug.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define EL_LOAD_EXPORT __attribute__((visibility("default")))

EL_LOAD_EXPORT uint32_t el_interp_take_load(const uint8_t **text);
EL_LOAD_EXPORT void el_interp_load_result(uint8_t state, uint32_t program_id, const char *message);

#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER && defined(EL_DEBUG_BOARD_COMMANDS) && EL_DEBUG_BOARD_COMMANDS

#include "el_crc16.h"

static uint8_t *load_text;  /* malloc'd: its size comes from the request (at most EL_DBG_LOAD_MAX) */
static uint32_t load_size;
static uint8_t load_state = EL_DBG_LOAD_IDLE;
static uint32_t load_program_id;
static char load_message[EL_DBG_MAX_PAYLOAD];
static bool load_taken = true;

static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint16_t crc_of(const uint8_t *data, uint32_t size)
{
    uint16_t crc = EL_CRC16_INIT;
    while (size > 0u) {
        uint16_t n = size > 0xFFFFu ? 0xFFFFu : (uint16_t)size;
        crc = el_crc16_update(crc, data, n);
        data += n;
        size -= n;
    }
    return crc;
}

uint8_t el_debug_port_command(uint8_t cmd, const uint8_t *p, uint16_t n)
{
    switch (cmd) {
    case EL_DBG_CMD_LOAD_BEGIN: {
        uint32_t size;
        uint8_t *text;
        if (n != 4u)
            return EL_DBG_E_LENGTH;
        if (load_state == EL_DBG_LOAD_CHECKING)
            return EL_DBG_E_TX_BUSY;
        size = get_u32(p);
        if (size == 0u || size > EL_DBG_LOAD_MAX)
            return EL_DBG_E_VALUE;
        text = (uint8_t *)realloc(load_text, size);
        if (text == NULL)
            return EL_DBG_E_TOO_BIG;
        load_text = text;
        memset(load_text, 0, size);
        load_size = size;
        load_state = EL_DBG_LOAD_RECEIVING;
        load_message[0] = '\0';
        return EL_DBG_OK;
    }
    case EL_DBG_CMD_LOAD_DATA: {
        uint32_t at;
        if (n < 4u)
            return EL_DBG_E_LENGTH;
        if (load_state != EL_DBG_LOAD_RECEIVING)
            return EL_DBG_E_NO_TX;
        at = get_u32(p);
        if (at > load_size || (uint32_t)(n - 4u) > load_size - at)
            return EL_DBG_E_VALUE;
        memcpy(load_text + at, p + 4, (size_t)(n - 4u));
        return EL_DBG_OK;
    }
    case EL_DBG_CMD_LOAD_COMMIT:
        if (n != 6u)
            return EL_DBG_E_LENGTH;
        if (load_state != EL_DBG_LOAD_RECEIVING)
            return EL_DBG_E_NO_TX;
        if (get_u32(p) != load_size || crc_of(load_text, load_size) != ((uint16_t)p[4] | (uint16_t)(p[5] << 8)))
            return EL_DBG_E_VALUE; /* a chunk was lost or damaged: send again */
        load_state = EL_DBG_LOAD_CHECKING;
        load_taken = false;
        return EL_DBG_OK;
    case EL_DBG_CMD_LOAD_STATUS: {
        uint8_t head[5];
        if (n != 0u)
            return EL_DBG_E_LENGTH;
        head[0] = load_state;
        head[1] = (uint8_t)(load_program_id & 0xFFu);
        head[2] = (uint8_t)((load_program_id >> 8) & 0xFFu);
        head[3] = (uint8_t)((load_program_id >> 16) & 0xFFu);
        head[4] = (uint8_t)(load_program_id >> 24);
        (void)el_debug_put(head, 5u);
        /* As much of the message as fits (the client shows what came). */
        {
            size_t len = strlen(load_message), i;
            for (i = 0; i < len && el_debug_put((const uint8_t *)&load_message[i], 1u); i++) {
            }
        }
        return EL_DBG_OK;
    }
    default:
        return EL_DBG_E_UNKNOWN_CMD;
    }
}

/* A committed model text not yet taken: its size, and *text (valid until the
 * next LOAD_BEGIN, which cannot come while it is being checked); else 0. */
uint32_t el_interp_take_load(const uint8_t **text)
{
    if (load_taken || load_state != EL_DBG_LOAD_CHECKING)
        return 0u;
    load_taken = true;
    *text = load_text;
    return load_size;
}

/* The outcome of a model sent to this library (EL_DBG_LOAD_REFUSED), or of
 * the one that replaced the program (EL_DBG_LOAD_REPLACED, given to the new
 * library): what LOAD_STATUS reports. */
void el_interp_load_result(uint8_t state, uint32_t program_id, const char *message)
{
    load_state = state;
    load_program_id = program_id;
    snprintf(load_message, sizeof load_message, "%s", message != NULL ? message : "");
}

#else /* no debug server: no model can be sent */

uint32_t el_interp_take_load(const uint8_t **text)
{
    (void)text;
    return 0u;
}

void el_interp_load_result(uint8_t state, uint32_t program_id, const char *message)
{
    (void)state;
    (void)program_id;
    (void)message;
}

#endif
