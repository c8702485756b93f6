/* EasyLab PIC18 board: sdcc's start-up code, the board's own (builds link
 * with --no-crt).
 *
 * C wants static data that is not initialised to start at zero. sdcc's
 * crt0i copies initialised data but clears nothing; crt0iz clears RAM up
 * to 0xEFF, which the PIC18F4520 lacks (and gpsim stops there) and which
 * on the PIC18F4620 stops short of 0xF7F. This one clears the part's RAM
 * from 0x000 to EL_PIC18_RAM_LAST (el_pic18_kept, the byte after it, keeps
 * a request across a reset), then copies the initialised data by gplink's
 * table `_cinit` (entries of source, destination and size) and calls
 * main(). MPLAB XC8 brings its own start-up code: this file is sdcc's only.
 */
#include "el_pic18.h"
#include "pic18_hw.h"

#if defined(__SDCC)

extern int stack_end; /* the top of the software stack (the linker script's STACK) */
extern __code struct {
    uint16_t entries; /* then entries of source, destination, size (32 bits each) */
} cinit;              /* made by gplink */
extern void main(void);

/* gplink makes _cinit only for programs with initialised data: this
 * variable makes sure there is some. */
uint8_t el_pic18_started = 1u;

void el_pic18_startup(void) __naked;

/* The reset vector. */
void el_pic18_entry(void) __naked __interrupt 0
{
    __asm
        goto    _el_pic18_startup
    __endasm;
}

/* Scratch while copying (access RAM, sdcc's temporaries .registers: nothing
 * lives there yet): 0x00..0x02 source, 0x03..0x04 bytes left, 0x05..0x06
 * entries left, 0x07..0x09 the table pointer at the next entry. */
void el_pic18_startup(void) __naked
{
    __asm
        extern  _main                   ; named only here: sdcc declares only what C code uses
        lfsr    1, _stack_end
        lfsr    2, _stack_end
        clrf    _TBLPTRU, 0
        bsf     _EECON1, 7, 0           ; EEPGD: table reads from program memory
        bcf     _EECON1, 6, 0           ; CFGS

        ; clear EL_PIC18_RAM_LAST down to 0x000 (a 0xFF at 0x000 ends the loop)
        lfsr    0, EL_PIC18_RAM_LAST
        setf    0x00, 0
el_pic18_clear:
        clrf    _POSTDEC0, 0
        movf    0x00, w, 0
        bnz     el_pic18_clear

        ; the initialised data
        movlw   low(_cinit)
        movwf   _TBLPTRL, 0
        movlw   high(_cinit)
        movwf   _TBLPTRH, 0
        movlw   upper(_cinit)
        movwf   _TBLPTRU, 0
        tblrd*+
        movff   _TABLAT, 0x05
        tblrd*+
        movff   _TABLAT, 0x06
el_pic18_entry_next:
        movf    0x05, w, 0
        iorwf   0x06, w, 0
        bz      el_pic18_done
        tblrd*+                         ; source: 24 bits of 32
        movff   _TABLAT, 0x00
        tblrd*+
        movff   _TABLAT, 0x01
        tblrd*+
        movff   _TABLAT, 0x02
        tblrd*+
        tblrd*+                         ; destination: 16 bits of 32, into FSR0
        movff   _TABLAT, _FSR0L
        tblrd*+
        movff   _TABLAT, _FSR0H
        tblrd*+
        tblrd*+
        tblrd*+                         ; size: 16 bits of 32
        movff   _TABLAT, 0x03
        tblrd*+
        movff   _TABLAT, 0x04
        tblrd*+
        tblrd*+
        movff   _TBLPTRL, 0x07
        movff   _TBLPTRH, 0x08
        movff   _TBLPTRU, 0x09
        movff   0x00, _TBLPTRL
        movff   0x01, _TBLPTRH
        movff   0x02, _TBLPTRU
el_pic18_copy:
        movf    0x03, w, 0
        iorwf   0x04, w, 0
        bz      el_pic18_copied
        tblrd*+
        movff   _TABLAT, _POSTINC0
        movlw   1
        subwf   0x03, f, 0
        movlw   0
        subwfb  0x04, f, 0
        bra     el_pic18_copy
el_pic18_copied:
        movff   0x07, _TBLPTRL
        movff   0x08, _TBLPTRH
        movff   0x09, _TBLPTRU
        movlw   1
        subwf   0x05, f, 0
        movlw   0
        subwfb  0x06, f, 0
        bra     el_pic18_entry_next
el_pic18_done:
        call    _main
el_pic18_end:
        bra     el_pic18_end
    __endasm;
}

#endif
