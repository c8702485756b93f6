/* EasyLab AVR board: read-only tables in flash.
 *
 * Read before every C file of an AVR build (`-include el_avr_progmem.h` in
 * board.toml), so that runtime_c/el_types.h finds EL_ROM and the
 * EL_ROM_READ_ macros defined before it falls back to plain reads: the
 * dispatch table, the task deadlines and actors' tables (Pt100Linearize)
 * stay in flash and are read with LPM.
 */
#ifndef EL_AVR_PROGMEM_H
#define EL_AVR_PROGMEM_H

#include <avr/pgmspace.h>

#define EL_ROM PROGMEM
#define EL_ROM_READ_U8(p) pgm_read_byte(p)
#define EL_ROM_READ_U16(p) pgm_read_word(p)
#define EL_ROM_READ_U32(p) pgm_read_dword(p)
#define EL_ROM_READ_PTR(p) pgm_read_ptr(p)

#endif /* EL_AVR_PROGMEM_H */
