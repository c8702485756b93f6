/* EasyLab runtime: CRC-16/MODBUS (polynomial 0xA001 reflected, initial value
 * 0xFFFF), used by the Modbus RTU framing and the debug protocol's frames.
 * "123456789" gives 0x4B37; the CRC over a frame followed by its CRC (low
 * byte first) is 0. */
#ifndef EL_CRC16_H
#define EL_CRC16_H

#include "el_types.h"

#define EL_CRC16_INIT 0xFFFFu

/* Continue a CRC over `len` bytes. */
uint16_t el_crc16_update(uint16_t crc, const uint8_t *data, uint16_t len);

/* The CRC of `len` bytes. */
uint16_t el_crc16(const uint8_t *data, uint16_t len);

/* el_crc16_update from a table: faster, 512 bytes more (el_crc16.c). */
uint16_t el_crc16_fast(uint16_t crc, const uint8_t *data, uint16_t len);

/* el_crc16_fast of one byte (a receiver's running CRC). */
uint16_t el_crc16_fast_byte(uint16_t crc, uint8_t byte);

#endif /* EL_CRC16_H */
