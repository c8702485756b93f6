/* EasyLab runtime: the Modbus slave (docs/service.md, "Modbus").
 *
 * Function codes 01 read coils, 02 read discrete inputs, 03 read holding
 * registers, 04 read input registers, 05 write single coil, 06 write single
 * register, 15 write multiple coils, 16 write multiple registers, 43/14
 * read device identification, over the register map of el_service.h.
 * Requests are validated in the specification's order: an unsupported
 * function gives exception 01; a malformed length, a quantity or byte count
 * out of range, or a coil value other than 0x0000/0xFF00 gives 03; an
 * address range not entirely in the map (or cutting a 32-bit item in a
 * write) gives 02; a value outside its item's type or range gives 03 and
 * changes nothing; a persist param that could not be stored gives 04.
 *
 * Three layers, none using the heap, recursion or anything outside these
 * files, el_service.c and el_crc16.c:
 *
 *  - el_mb_pdu: one request PDU -> its response PDU (in place allowed);
 *  - RTU: a receiver state machine fed byte by byte and told of the 3.5-
 *    character silences that end frames (el_mb_rtu_byte, el_mb_rtu_silence,
 *    el_mb_rtu_reply: an MCU port calls the first from its receive
 *    interrupt and the second from the t3.5 timer it restarts at every
 *    byte), or driven by el_mb_rtu_poll through a port that hands out bytes
 *    and silence marks (the host board);
 *  - TCP: the MBAP framing over byte streams (el_mb_tcp_adu_length,
 *    el_mb_tcp_reply), or el_mb_tcp_poll over a port that keeps one stream
 *    per connection.
 *
 * Engine state and buffers are the caller's (the generated
 * service_tables.c allocates them only for the interfaces a model has).
 */
#ifndef EL_MODBUS_H
#define EL_MODBUS_H

#include "el_types.h"
#include "el_modbus_port.h" /* EL_MB_NONE, EL_MB_SILENCE */

/* Sizes of the specification. */
#define EL_MB_PDU_MAX 253u     /* function code + data */
#define EL_MB_RTU_ADU_MAX 256u /* unit + PDU + CRC */
#define EL_MB_MBAP 7u          /* transaction, protocol, length, unit */
#define EL_MB_TCP_ADU_MAX 260u /* MBAP + PDU */

/* Exception codes. */
#define EL_MB_EX_ILLEGAL_FUNCTION 0x01u
#define EL_MB_EX_ILLEGAL_ADDRESS 0x02u
#define EL_MB_EX_ILLEGAL_VALUE 0x03u
#define EL_MB_EX_DEVICE_FAILURE 0x04u

/* Quantity limits of the specification. */
#define EL_MB_MAX_READ_BITS 2000u
#define EL_MB_MAX_READ_REGS 125u
#define EL_MB_MAX_WRITE_BITS 1968u
#define EL_MB_MAX_WRITE_REGS 123u

/* Device identification objects (43/14), conformity level 0x83. */
#define EL_MB_ID_VENDOR 0x00u       /* "EasyLab" */
#define EL_MB_ID_PRODUCT_CODE 0x01u /* the model's name */
#define EL_MB_ID_REVISION 0x02u     /* EasyLab's version */
#define EL_MB_ID_PRODUCT_NAME 0x04u /* the model's title */
#define EL_MB_ID_MODEL_NAME 0x05u   /* the model's name */
#define EL_MB_ID_PROGRAM 0x80u      /* the program id, "0x1234abcd" (extended) */

/* Handle one request PDU (`len` bytes: function code and data) against the
 * map of el_service_map(). Writes the response PDU to `resp` (at least
 * EL_MB_PDU_MAX bytes; it may be `req` itself) and returns its length. A
 * broadcast request executes writes and returns 0: no reply, not even an
 * exception. */
uint16_t el_mb_pdu(const uint8_t *req, uint16_t len, uint8_t *resp, bool broadcast);

/* ---- RTU ---------------------------------------------------------------- */

#define EL_MB_RTU_EARLY 0x01u    /* no character timing: see el_mb_rtu_init */
#define EL_MB_RTU_OVERFLOW 0x02u /* more than EL_MB_RTU_ADU_MAX bytes: drop the frame */
#define EL_MB_RTU_READY 0x04u    /* a frame waits for el_mb_rtu_reply */

typedef struct {
    uint8_t buf[EL_MB_RTU_ADU_MAX]; /* the frame received, then the reply */
    uint16_t len;
    uint16_t crc;   /* running CRC of buf[0..len): 0 when the frame ends with its CRC */
    uint8_t unit;   /* our unit id, 1..247 */
    uint8_t flags;  /* EL_MB_RTU_... */
    uint32_t frames;     /* frames answered or executed (statistics) */
    uint32_t bad_frames; /* frames dropped: CRC, overflow, too short */
} el_mb_rtu_t;

/* Start a receiver for unit `unit`. `early`: a port without character
 * timing (a pty, a USB CDC link) also ends a frame as soon as its bytes
 * form a request of the length its function code implies (a CRC-valid
 * frame of at least 4 bytes for unknown codes) whose CRC holds; ports with
 * a t3.5 timer pass false and end frames only at silences. */
void el_mb_rtu_init(el_mb_rtu_t *rtu, uint8_t unit, bool early);

/* A received byte. True when a frame is complete (early mode); the bytes
 * that come while a frame waits for its reply are dropped. */
bool el_mb_rtu_byte(el_mb_rtu_t *rtu, uint8_t byte);

/* The 3.5-character silence after the last byte: the bytes so far form a
 * frame. True when there is one (at least one byte). */
bool el_mb_rtu_silence(el_mb_rtu_t *rtu);

/* Handle the complete frame: check its length, CRC and unit (ours, or 0 for
 * a broadcast), run the request. Returns the length of the reply ADU now
 * in rtu->buf, CRC included (0: nothing to send), and gets the receiver
 * ready for the next frame. */
uint16_t el_mb_rtu_reply(el_mb_rtu_t *rtu);

/* A port that hands out what it received, one event at a time. */
typedef struct {
    int16_t (*getc)(void);                          /* a byte 0..255, EL_MB_SILENCE or EL_MB_NONE */
    void (*send)(const uint8_t *adu, uint16_t len); /* transmit a reply (copied or sent before returning) */
} el_mb_rtu_port_t;

/* Take what the port has (at most two frames' worth of events per call),
 * answer complete frames. */
void el_mb_rtu_poll(el_mb_rtu_t *rtu, const el_mb_rtu_port_t *port);

/* ---- TCP ---------------------------------------------------------------- */

#define EL_MB_TCP_BAD (-1)

/* The length of the ADU at the head of a stream from its first `avail`
 * bytes: 0 until the MBAP header (7 bytes) is there, EL_MB_TCP_BAD for a
 * header the stream cannot recover from (protocol id not 0, length field
 * outside 2..254: close the connection), else MBAP + PDU bytes: read
 * exactly that many, then the next ADU starts. */
int16_t el_mb_tcp_adu_length(const uint8_t *head, uint16_t avail);

/* Handle one complete ADU of `len` bytes in `adu` (at least
 * EL_MB_TCP_ADU_MAX bytes): returns the length of the reply ADU written
 * in place. Any unit id is answered (and echoed); a TCP server never
 * treats unit 0 as a broadcast. 0 when `len` disagrees with the header. */
uint16_t el_mb_tcp_reply(uint8_t *adu, uint16_t len);

/* A port with one byte stream per connection slot 0..conns-1. */
typedef struct {
    /* Copy up to n received bytes of `conn` without consuming them; 0 when
     * there are none or the slot is unused. */
    uint16_t (*peek)(uint8_t conn, uint8_t *buf, uint16_t n);
    void (*consume)(uint8_t conn, uint16_t n);
    /* Send a reply; false when it could not be (the connection is gone). */
    bool (*send)(uint8_t conn, const uint8_t *adu, uint16_t len);
    void (*close)(uint8_t conn); /* drop a connection that lost the framing */
    uint8_t conns;
} el_mb_tcp_port_t;

/* Answer the complete requests waiting on every connection (at most 8 per
 * connection per call); `buf` holds EL_MB_TCP_ADU_MAX bytes. */
void el_mb_tcp_poll(const el_mb_tcp_port_t *port, uint8_t *buf);

#endif /* EL_MODBUS_H */
