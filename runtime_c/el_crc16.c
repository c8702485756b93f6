/* EasyLab runtime: CRC-16/MODBUS, bitwise (no table: 8-bit targets are short
 * of flash, and frames are short). */
#include "el_crc16.h"

uint16_t el_crc16_update(uint16_t crc, const uint8_t *data, uint16_t len)
{
    uint16_t i;
    uint8_t bit;
    for (i = 0u; i < len; i++) {
        crc ^= data[i];
        for (bit = 0u; bit < 8u; bit++) {
            crc = (crc & 1u) != 0u ? (uint16_t)((crc >> 1) ^ 0xA001u) : (uint16_t)(crc >> 1);
        }
    }
    return crc;
}

uint16_t el_crc16(const uint8_t *data, uint16_t len)
{
    return el_crc16_update(EL_CRC16_INIT, data, len);
}
