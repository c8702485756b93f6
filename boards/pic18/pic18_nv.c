/* EasyLab PIC18 board: the data EEPROM (pic18_hw.h): 256 bytes on the
 * PIC18F4520, 1024 on the PIC18F4620 (EEADRH). A byte is programmed only
 * when it changes (about 4 ms each; the CPU waits with interrupts on, the
 * watchdog kicked); the required unlock sequence runs with interrupts off.
 */
#include "el_pic18.h"
#include "pic18_hw.h"

static void address(uint16_t a)
{
#if EL_PIC18_NV_SIZE > 256u
    EEADRH = (uint8_t)(a >> 8);
#endif
    EEADR = (uint8_t)a;
}

uint8_t el_pic18_eeprom_read(uint16_t a)
{
    address(a);
    EECON1 = 0x01u; /* EEPGD = 0, CFGS = 0 (data EEPROM), RD */
    return EEDATA;
}

void el_pic18_eeprom_update(uint16_t a, uint8_t value)
{
    uint8_t state;
    if (el_pic18_eeprom_read(a) == value) {
        return;
    }
    EEDATA = value;
    EECON1 = 0x04u; /* WREN */
    state = el_pic18_irq_save();
    EECON2 = 0x55u;
    EECON2 = 0xAAu;
    EECON1bits.WR = 1;
    el_pic18_irq_restore(state);
    while (EECON1bits.WR) {
        el_pic18_watchdog_kick();
    }
    EECON1bits.WREN = 0;
    PIR2bits.EEIF = 0;
}
