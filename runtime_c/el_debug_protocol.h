/* EasyLab debug protocol: every constant of docs/protocol.md, once.
 *
 * This header is the single source of the protocol's numbers. The C debug
 * server (el_debug.c) includes it; the Python host tools read it at import
 * time (host_tools/debug_protocol.py parses the `#define EL_DBG_... N`
 * lines; tests/debug/test_protocol_constants.py checks the two against each
 * other with pycparser). Keep every definition on one line, of the form
 * `#define EL_DBG_NAME <integer literal>` (decimal or hex, optional u/U):
 * the Python side reads nothing else. Do not reuse a number once released;
 * change EL_DBG_PROTOCOL_VERSION when a meaning changes.
 */
#ifndef EL_DEBUG_PROTOCOL_H
#define EL_DEBUG_PROTOCOL_H

/* ---- the protocol ------------------------------------------------------ */
#define EL_DBG_PROTOCOL_VERSION 3u

/* Largest decoded frame (sequence number, command, payload, CRC), bytes.
 * The encoded frame adds at most 1 + ceil(n / 254) COBS bytes and the 0x00
 * delimiter. */
#define EL_DBG_MAX_FRAME 160u
/* Bytes around the payload in a decoded frame: seq, cmd, CRC (2). */
#define EL_DBG_HEADER 2u
#define EL_DBG_TRAILER 2u
/* Largest payload of a request or response. */
#define EL_DBG_MAX_PAYLOAD 156u
/* Requests the host may have in flight: the server answers in order, one
 * at a time. */
#define EL_DBG_WINDOW 1u
/* The frame delimiter on the wire (COBS removes it from frames). */
#define EL_DBG_DELIMITER 0u
/* A response's command byte is the request's with this bit set. */
#define EL_DBG_RESPONSE 0x80u

/* ---- requests (command byte) ------------------------------------------- */
#define EL_DBG_CMD_HELLO 0x01u
#define EL_DBG_CMD_GET_PROGRAM_ID 0x02u
#define EL_DBG_CMD_GET_FLAGS 0x03u
#define EL_DBG_CMD_GET_COUNTERS 0x04u
#define EL_DBG_CMD_ITEM_INFO 0x05u
#define EL_DBG_CMD_READ 0x10u
#define EL_DBG_CMD_WRITE 0x11u
#define EL_DBG_CMD_FORCE 0x12u       /* u16 id, u16 element, value: held at every instant until released */
#define EL_DBG_CMD_RELEASE 0x13u     /* u16 id (NONE16: all), u16 element */
#define EL_DBG_CMD_FORCE_LIST 0x14u  /* -> u8 n, n x (u16 id, u16 element, u8 size, value) */
#define EL_DBG_CMD_TX_BEGIN 0x20u
#define EL_DBG_CMD_TX_COMMIT 0x21u
#define EL_DBG_CMD_TX_ABORT 0x22u
#define EL_DBG_CMD_TX_RESULT 0x23u
#define EL_DBG_CMD_GET_STACK 0x28u
#define EL_DBG_CMD_RUN 0x30u
#define EL_DBG_CMD_BREAK 0x31u
#define EL_DBG_CMD_STEP 0x32u
#define EL_DBG_CMD_RESET 0x33u
#define EL_DBG_CMD_BP_SET 0x40u
#define EL_DBG_CMD_BP_CLEAR 0x41u
#define EL_DBG_CMD_BP_LIST 0x42u
#define EL_DBG_CMD_BP_WHEN 0x43u     /* u16 id, u16 element, u8 op, value -> u8 slot: a conditional breakpoint */
/* Board commands: answered by boards that have them (local execution),
 * EL_DBG_E_UNKNOWN_CMD by the others (every firmware). */
#define EL_DBG_CMD_BOARD_FIRST 0x50u
#define EL_DBG_CMD_BOARD_LAST 0x5Fu
#define EL_DBG_CMD_LOAD_BEGIN 0x50u   /* u32 length: a new model text follows */
#define EL_DBG_CMD_LOAD_DATA 0x51u    /* u32 offset, then bytes of the text */
#define EL_DBG_CMD_LOAD_COMMIT 0x52u  /* u32 length, u16 CRC-16: check the text, replace the model */
#define EL_DBG_CMD_LOAD_STATUS 0x53u  /* -> u8 state, u32 program id, message (UTF-8) */

/* ---- status: the first payload byte of every response ------------------ */
#define EL_DBG_OK 0u
#define EL_DBG_E_UNKNOWN_CMD 1u  /* no such command */
#define EL_DBG_E_LENGTH 2u       /* payload too short or too long for the command */
#define EL_DBG_E_ID 3u           /* no such item, chart, step, transition, actor, task or breakpoint */
#define EL_DBG_E_READ_ONLY 4u    /* the item cannot be written */
#define EL_DBG_E_VALUE 5u        /* bad value (bool not 0/1), element or argument out of range */
#define EL_DBG_E_RANGE 6u        /* value outside the item's declared range */
#define EL_DBG_E_TOO_BIG 7u      /* the response would exceed EL_DBG_MAX_FRAME */
#define EL_DBG_E_QUEUE_FULL 8u   /* the transaction or write queue is full */
#define EL_DBG_E_NO_TX 9u        /* commit/abort/result without an open or committed transaction */
#define EL_DBG_E_TX_BUSY 10u     /* begin while a transaction is open or not yet applied */
#define EL_DBG_E_NOT_HALTED 11u  /* step needs a halted program */
#define EL_DBG_E_BP_FULL 12u     /* every breakpoint slot is in use */
#define EL_DBG_E_UNSUPPORTED 13u /* the board cannot do it (reset without a way to reset) */
#define EL_DBG_E_FORCE_FULL 14u  /* every force slot is in use (or the build has none) */

/* ---- sizes of the server (reported by HELLO) --------------------------- */
#define EL_DBG_TX_MAX 24u        /* entries of one transaction (reads and writes) */
#define EL_DBG_WRITE_QUEUE 8u    /* single writes waiting for the next instant */
#define EL_DBG_BP_MAX 8u         /* breakpoints */
#define EL_DBG_VALUE_MAX 4u      /* bytes of one element of any type */
#define EL_DBG_FORCE_MAX 8u      /* forced elements */
#define EL_DBG_COND_MAX 4u       /* conditional breakpoints (slots BP_SLOTS .. BP_SLOTS + COND_SLOTS - 1) */

/* ---- item kinds (EL_K_... of el_model.h, plus actor state, the links'
 * read-only fault counters, docs/ir.md "Status items", and the read-only
 * state of devices running the model's handlers) ------------------------ */
#define EL_DBG_K_PARAM 0u
#define EL_DBG_K_VAR 1u
#define EL_DBG_K_DEV_OUT 2u
#define EL_DBG_K_DEV_IN 3u
#define EL_DBG_K_STATE 4u
#define EL_DBG_K_STATUS 5u
#define EL_DBG_K_DEV_STATE 6u
#define EL_DBG_K_CHART 7u        /* a chart's active steps: per slot, its step's id (NONE8: none), read-only */
#define EL_DBG_K_STEP_TIME 8u    /* a step's time (ms since its last entry, as its guards see it), read-only */
#define EL_DBG_K_FIRED 9u        /* the transition a chart fired last (its id; NONE8/NONE16: none yet), read-only */

/* ---- item types (EL_T_... of el_model.h) ------------------------------- */
#define EL_DBG_T_BOOL 0u
#define EL_DBG_T_I8 1u
#define EL_DBG_T_U8 2u
#define EL_DBG_T_I16 3u
#define EL_DBG_T_U16 4u
#define EL_DBG_T_I32 5u
#define EL_DBG_T_U32 6u
#define EL_DBG_T_F32 7u
#define EL_DBG_T_TIME 8u

/* ---- item flags --------------------------------------------------------- */
#define EL_DBG_F_READ 0x01u
#define EL_DBG_F_WRITE 0x02u
#define EL_DBG_F_RANGE 0x04u     /* writes are checked against a range */

/* ---- transaction entry operations (TX_RESULT) --------------------------- */
#define EL_DBG_OP_READ 0u
#define EL_DBG_OP_WRITE 1u

/* ---- when a write or commit takes effect -------------------------------- */
#define EL_DBG_QUEUED 0u         /* at the inputs step of the next instant */
#define EL_DBG_APPLIED 1u        /* now: the program is halted at an instant */

/* ---- probe points (breakpoints, halt locations) ------------------------- */
#define EL_DBG_P_NONE 0u
#define EL_DBG_P_INSTANT 1u      /* an instant, after its inputs (a = b = 0) */
#define EL_DBG_P_TASK 2u         /* a task's activation starts (a = task) */
#define EL_DBG_P_CHART 3u        /* a chart evolution starts (a = chart) */
#define EL_DBG_P_STEP 4u         /* a step was activated (a = chart, b = step) */
#define EL_DBG_P_TRANSITION 5u   /* a transition fires (a = chart, b = transition) */
#define EL_DBG_P_ACTOR 6u        /* an actor fires (a = actor instance) */
/* A chart evolution ended, its steps entered and its runs done (a = chart):
 * where STEP_CHART halts; not a breakpoint's point (BP_SET: E_ID). */
#define EL_DBG_P_CHART_END 7u
/* A conditional breakpoint's condition became true (a = item, b = element):
 * after the instant's device reads and forced values, before its tasks are
 * released; set with BP_WHEN, not BP_SET. */
#define EL_DBG_P_CONDITION 8u

/* ---- conditional breakpoints: the comparison (BP_WHEN) ------------------ */
#define EL_DBG_OP_EQ 0u
#define EL_DBG_OP_NE 1u
#define EL_DBG_OP_LT 2u
#define EL_DBG_OP_LE 3u
#define EL_DBG_OP_GT 4u
#define EL_DBG_OP_GE 5u

/* ---- step units (STEP request) ------------------------------------------ */
#define EL_DBG_STEP_TASK 2u      /* to the start of the next task activation */
#define EL_DBG_STEP_CHART 7u     /* to the end of the next chart evolution (P_CHART_END): the steps it entered */
#define EL_DBG_STEP_ACTOR 6u     /* to the next actor firing */
#define EL_DBG_STEP_INSTANT 1u   /* to the next instant */

/* ---- why the program is halted (GET_FLAGS, GET_STACK) ------------------- */
#define EL_DBG_WHY_NONE 0u
#define EL_DBG_WHY_BREAK 1u      /* the BREAK request */
#define EL_DBG_WHY_BREAKPOINT 2u
#define EL_DBG_WHY_STEP 3u
#define EL_DBG_WHY_START 4u      /* halted at start (host: --debug ...,halt; reset with halt) */

/* ---- program status flags (GET_FLAGS) ------------------------------------ */
#define EL_DBG_S_HALTED 0x01u
#define EL_DBG_S_TX_OPEN 0x02u
#define EL_DBG_S_TX_COMMITTED 0x04u  /* committed, not yet applied */
#define EL_DBG_S_TX_APPLIED 0x08u    /* applied: TX_RESULT has its reads */
#define EL_DBG_S_WRITES_PENDING 0x10u
#define EL_DBG_S_HALT_PENDING 0x20u  /* BREAK or STEP under way */
#define EL_DBG_S_FORCED 0x40u        /* at least one element is forced (FORCE_LIST names them) */

/* ---- RESET flags ---------------------------------------------------------- */
#define EL_DBG_RESET_HALT 0x01u  /* halt at the first instant after the reset */

/* ---- model replacement (LOAD_STATUS state) ------------------------------- */
#define EL_DBG_LOAD_IDLE 0u       /* nothing sent */
#define EL_DBG_LOAD_RECEIVING 1u  /* LOAD_BEGIN came; LOAD_DATA fills the text */
#define EL_DBG_LOAD_CHECKING 2u   /* committed: being checked and built */
#define EL_DBG_LOAD_REPLACED 3u   /* running since an instant; the id is the new program's */
#define EL_DBG_LOAD_REFUSED 4u    /* refused (the message says why); the old program runs on */
#define EL_DBG_LOAD_MAX 1048576u  /* longest model text, bytes */

/* ---- counters (GET_COUNTERS: uint16 each, saturating, in this order) ----- */
#define EL_DBG_C_FRAMES 0u       /* good requests */
#define EL_DBG_C_BAD_CRC 1u      /* dropped: CRC mismatch */
#define EL_DBG_C_OVERSIZE 2u     /* dropped: longer than EL_DBG_MAX_FRAME */
#define EL_DBG_C_TRUNCATED 3u    /* dropped: shorter than a header and CRC, or bad COBS */
#define EL_DBG_C_UNKNOWN 4u      /* answered EL_DBG_E_UNKNOWN_CMD */
#define EL_DBG_C_ERRORS 5u       /* answered with any other error */
#define EL_DBG_C_DUPLICATES 6u   /* repeated requests answered from the cache */
#define EL_DBG_C_SEQ_GAPS 7u     /* a request's seq was not the previous one + 1 */
#define EL_DBG_C_TX_DROPPED 8u   /* responses the transport could not take */
#define EL_DBG_C_COUNT 9u

/* ---- no such thing ------------------------------------------------------- */
#define EL_DBG_NONE8 0xFFu
#define EL_DBG_NONE16 0xFFFFu

#endif /* EL_DEBUG_PROTOCOL_H */
