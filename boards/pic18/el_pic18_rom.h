/* EasyLab PIC18 board: read-only tables, read before every portable file
 * (sdcc.py puts it in front of each, as the AVR board's el_avr_progmem.h).
 *
 * sdcc keeps `const` data in program memory and knows it: an access through
 * the object's own address is a table read (TBLRD). runtime_c/el_types.h's
 * default EL_ROM_READ_U16(p), a read through `const uint16_t *`, would make
 * the address a generic pointer and read through a library call; the
 * pointer as it is keeps what sdcc knows. */
#ifndef EL_PIC18_ROM_H
#define EL_PIC18_ROM_H

#define EL_ROM
#define EL_ROM_READ_U8(p) (*(p))
#define EL_ROM_READ_U16(p) (*(p))
#define EL_ROM_READ_U32(p) (*(p))
#define EL_ROM_READ_PTR(p) (*(p))

/* The PIC18 keeps the least significant byte first, as the debug wire
 * does: el_debug.c moves values as plain copies. */
#define EL_LITTLE_ENDIAN 1

#endif /* EL_PIC18_ROM_H */
