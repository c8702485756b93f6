/* EasyLab PIC18 board: the compiler's keywords behind macros, for the
 * board's hardware files only (pic18_hw.c, pic18_uart.c, pic18_nv.c,
 * pic18_startup.c). The portable files (the runtime, generated code, the
 * port's portable part, the drivers) use none of them.
 *
 * sdcc (the board's compiler here) and Microchip's MPLAB XC8 name the
 * special function registers alike (PORTB, LATBbits.LATB5, PIR1bits.TMR2IF:
 * sdcc's from the board's generated device headers, XC8's from <xc.h>),
 * and both take `#pragma config NAME = VALUE`. What differs is here
 * (docs/boards.md, "MPLAB XC8").
 */
#ifndef EL_PIC18_H
#define EL_PIC18_H

#include <stdint.h>
#include <stdbool.h>

#if defined(__SDCC)

#include <pic18fregs.h>

/* The interrupt handler at the high-priority vector (0x08): with IPEN
 * clear every interrupt comes here. */
#define EL_PIC18_ISR(name) void name(void) __interrupt(1)
#define EL_PIC18_CLRWDT() __asm clrwdt __endasm
#define EL_PIC18_NOP() __asm nop __endasm
#define EL_PIC18_RESET() __asm reset __endasm
#define EL_PIC18_SLEEP() __asm sleep __endasm
/* A variable at a fixed RAM address. */
#define EL_PIC18_ABSOLUTE(declaration, address) __at(address) declaration

#elif defined(__XC8) || defined(__XC)

#include <xc.h>

#define EL_PIC18_ISR(name) void __interrupt(high_priority) name(void)
#define EL_PIC18_CLRWDT() CLRWDT()
#define EL_PIC18_NOP() NOP()
#define EL_PIC18_RESET() RESET()
#define EL_PIC18_SLEEP() SLEEP()
#define EL_PIC18_ABSOLUTE(declaration, address) declaration __at(address)

#else
#error "EasyLab's PIC18 board knows sdcc and MPLAB XC8 (docs/boards.md)"
#endif

#endif /* EL_PIC18_H */
