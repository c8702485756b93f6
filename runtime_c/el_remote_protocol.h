/* EasyLab remote execution: every constant of the link protocol between a
 * host running the application and the proxy on the target (docs/remote.md).
 *
 * The single source of the protocol's numbers: the proxy (el_remote.c)
 * includes it; the Python host side (generator/remote/protocol.py) parses
 * the `#define EL_RMT_NAME <integer literal>` lines at import time. Keep
 * every definition on one line of that form. Frames use the debug
 * protocol's framing (COBS, 0x00 delimiter, CRC-16/MODBUS: docs/protocol.md).
 */
#ifndef EL_REMOTE_PROTOCOL_H
#define EL_REMOTE_PROTOCOL_H

#define EL_RMT_PROTOCOL_VERSION 1u

/* Decoded frame: cmd u8, instant u32, payload, CRC-16 (2). */
#define EL_RMT_HEADER 5u
#define EL_RMT_TRAILER 2u
/* Largest decoded frame either side accepts. */
#define EL_RMT_MAX_FRAME 250u
#define EL_RMT_MAX_PAYLOAD 243u
/* A proxy's own buffers hold the largest frames of its device model only
 * (generated el_remote_config.h: EL_RMT_RX_FRAME, EL_RMT_TX_FRAME, computed
 * by generator/remote/device_model.py from these payloads). */

/* Fixed parts of payloads (bytes). */
#define EL_RMT_HELLO_ANSWER 7u  /* version u8, device-model id u32, device count u8, state u8 */
#define EL_RMT_DEVICE_ANSWER 5u /* index u8, device id u32; the path follows */
#define EL_RMT_UP_STATE 1u      /* UP: the state byte before the device data */
#define EL_RMT_DOWN_MASK 4u     /* DOWN: the task mask u32 before the device data */

/* ---- host -> proxy ------------------------------------------------------ */
#define EL_RMT_CMD_HELLO 0x01u
#define EL_RMT_CMD_DEVICE 0x02u
#define EL_RMT_CMD_START 0x03u
#define EL_RMT_CMD_STOP 0x04u
#define EL_RMT_CMD_DOWN 0x11u
#define EL_RMT_CMD_COUNTERS 0x05u

/* ---- proxy -> host ------------------------------------------------------ */
/* An answer's command byte is the request's with this bit set. */
#define EL_RMT_RESPONSE 0x80u
#define EL_RMT_CMD_UP 0x10u

/* START's mode byte. */
#define EL_RMT_MODE_REAL_TIME 0u
#define EL_RMT_MODE_LOCK_STEP 1u

/* Counters of COUNTERS' answer (u16 each, in this order). */
#define EL_RMT_COUNTER_FRAMES 0u
#define EL_RMT_COUNTER_BAD_CRC 1u
#define EL_RMT_COUNTER_MALFORMED 2u
#define EL_RMT_COUNTER_STALE 3u
#define EL_RMT_COUNTER_OVERRUNS 4u
#define EL_RMT_COUNTER_WATCHDOG 5u
#define EL_RMT_COUNTER_COUNT 6u

/* Proxy states (COUNTERS' answer, first byte). */
#define EL_RMT_STATE_SAFE 0u
#define EL_RMT_STATE_RUNNING 1u
/* UP's state byte also has this bit when the proxy built the frame after
 * its instant's tick had passed (real time): its CPU is behind its clock. */
#define EL_RMT_STATE_BEHIND 0x80u

#endif /* EL_REMOTE_PROTOCOL_H */
