/* EasyLab AVR board: non-volatile storage on the internal EEPROM.
 *
 * el_port_nv_read/write address the EEPROM byte for byte: offset 0 is
 * EEPROM address 0, EL_AVR_NV_SIZE bytes in all (1024 on the ATmega328P,
 * 4096 on the ATmega2560); an erased EEPROM reads 0xFF. Writes only
 * program the bytes that change (eeprom_update_block: about 3.4 ms per
 * changed byte, the CPU waits with interrupts on); the runtime's persist
 * layer double-buffers and checksums its records, so a reset in the middle
 * of a write loses at most that write.
 */
#include "avr_internal.h"
#include "el_port.h"

#include <avr/eeprom.h>

bool el_port_nv_read(uint16_t offset, void *data, uint16_t size)
{
    if ((uint32_t)offset + size > EL_AVR_NV_SIZE || (data == (void *)0 && size != 0u)) {
        return false;
    }
    if (size != 0u) {
        eeprom_read_block(data, (const void *)(uintptr_t)offset, size);
    }
    return true;
}

bool el_port_nv_write(uint16_t offset, const void *data, uint16_t size)
{
    if ((uint32_t)offset + size > EL_AVR_NV_SIZE || (data == (const void *)0 && size != 0u)) {
        return false;
    }
    if (size != 0u) {
        eeprom_update_block(data, (void *)(uintptr_t)offset, size);
    }
    return true;
}
