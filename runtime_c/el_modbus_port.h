/* EasyLab runtime: what a board that serves Modbus provides (optional part
 * of the port interface; docs/service.md, "Porting").
 *
 * Only the generated service_tables.c of a model with a `modbus rtu` or
 * `modbus tcp` interface calls these, so boards without Modbus need
 * nothing. The runtime's slave (el_modbus.c) never calls a board directly:
 * the generated glue hands these functions to el_mb_rtu_poll and
 * el_mb_tcp_poll through their port structures, from
 * el_gen_interfaces_poll (el_idle: between instants).
 */
#ifndef EL_MODBUS_PORT_H
#define EL_MODBUS_PORT_H

#include "el_types.h"

/* ---- RTU on a UART ---- */

/* Receive events besides bytes 0..255 (el_port_mb_rtu_getc). */
#define EL_MB_NONE (-1)    /* nothing more for now */
#define EL_MB_SILENCE (-2) /* a t3.5 silence after the last byte */

#define EL_MB_PARITY_NONE 0u
#define EL_MB_PARITY_EVEN 1u
#define EL_MB_PARITY_ODD 2u

/* What el_port_mb_rtu_open answers. */
#define EL_MB_PORT_OFF 0u     /* not served (the host board without --modbus-rtu) */
#define EL_MB_PORT_TIMED 1u   /* served; el_port_mb_rtu_getc reports real t3.5 silences */
#define EL_MB_PORT_UNTIMED 2u /* served, without character timing (a pty): frames may
                               * also end early (el_mb_rtu_init's `early`) */

/* Open UART `uart` for the model's `modbus rtu` interface: baud rate,
 * parity (EL_MB_PARITY_...), our unit id. */
uint8_t el_port_mb_rtu_open(uint8_t uart, uint32_t baud, uint8_t parity, uint8_t unit);

/* The next receive event: a byte 0..255, EL_MB_SILENCE once after the last
 * byte of a burst when 3.5 character times passed without another (1.75 ms
 * above 19200 baud), or EL_MB_NONE. An MCU port fills a ring from its
 * receive interrupt and puts the silence mark from the t3.5 timer that
 * every received byte restarts. */
int16_t el_port_mb_rtu_getc(void);

/* Transmit a reply frame (on RS-485: release the driver on transmit
 * complete). The bytes are copied or sent before returning. */
void el_port_mb_rtu_send(const uint8_t *adu, uint16_t len);

/* ---- TCP ---- */

/* Listen for the model's `modbus tcp` interface on `port`; returns the
 * number of connection slots (0: not served). */
uint8_t el_port_mb_tcp_open(uint16_t port);

/* The streams of the connection slots (see el_mb_tcp_port_t). */
uint16_t el_port_mb_tcp_peek(uint8_t conn, uint8_t *buf, uint16_t n);
void el_port_mb_tcp_consume(uint8_t conn, uint16_t n);
bool el_port_mb_tcp_send(uint8_t conn, const uint8_t *adu, uint16_t len);
void el_port_mb_tcp_close(uint8_t conn);

#endif /* EL_MODBUS_PORT_H */
