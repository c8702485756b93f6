/* EasyLab f16 board: what generated code sees (model.c includes this after
 * the runtime's headers).
 *
 * A build for the part: every device is a constant description for its
 * driver (generated el_f16_devices.h; drivers/el_f16_drivers.h). On the
 * 16-bit proxy (EL_F16_PROXY) devices are simulated as on the host board,
 * their `out` data coming from the stimulus (proxy/f16p_sim.c).
 */
#ifndef EL_BOARD_H
#define EL_BOARD_H

#include "el_types.h"

#define EL_BOARD_F16 1
#define EL_BOARD_NAME "f16"

/* The runtime's entry point (runtime_c/el_dispatch.c). */
void el_run(int argc, char **argv);

#if defined(EL_F16_PROXY)
void el_sim_open(uint8_t device);
void el_sim_close(uint8_t device);
void el_sim_start(uint8_t device);
void el_sim_stop(uint8_t device);
void el_sim_read(uint8_t device);
void el_sim_write(uint8_t device);
#else
#include "el_f16_devices.h"
#endif

#endif /* EL_BOARD_H */
