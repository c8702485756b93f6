/* EasyLab PIC18 board: what generated code sees of it.
 *
 * Device code calls el_drv_<driver>_<handler>(&el_dev<id>) (open, start,
 * read, write, stop, close). el_pic18_devices.h, generated for each build,
 * defines each device el_dev<id> as a `static const` description (its
 * pins, channel or CCP module and the addresses of its data) and includes
 * the drivers' headers (drivers/), whose handlers call the hardware layer
 * (pic18_hw.h). All of it is portable C: model.c goes through the board's
 * 64-bit lowering (lower64.py) like every portable file.
 */
#ifndef EL_BOARD_H
#define EL_BOARD_H

#include "el_types.h"

#define EL_BOARD_PIC18 1
#define EL_BOARD_NAME "pic18"

/* The runtime's entry point (runtime_c/el_dispatch.c); main() calls it. */
void el_run(int argc, char **argv);

#include "pic18_hw.h"         /* struct el_pin: a chip select (runtime_c/el_bus.h) */
#include "el_pic18_devices.h" /* generated: el_dev<id> and the drivers */

#endif /* EL_BOARD_H */
