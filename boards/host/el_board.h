/* EasyLab host board (POSIX): what generated code and main.c see of it.
 *
 * The host board runs generated firmware as a Linux process. Every device
 * driver is simulated: at a device's read time the generated code calls
 * el_sim_read(device), which copies the stimulus values of the device's
 * `out` data (el_items entries of kind EL_K_DEV_OUT) into the published
 * data; at its write time it calls el_sim_write(device) (the trace records
 * the `in` data). Command line, stimulus and trace formats: README.md.
 */
#ifndef EL_BOARD_H
#define EL_BOARD_H

#include "el_types.h"

#define EL_BOARD_HOST 1
#define EL_BOARD_NAME "host"

/* Size in bytes of the non-volatile store (el_port_nv_read/write): the
 * size of the --nvram file, and of the in-memory store without one. */
#define EL_HOST_NV_SIZE 4096u

/* Exit statuses of the host process. */
#define EL_HOST_EXIT_OK 0      /* run ended (--duration, SIGINT, SIGTERM), or --help */
#define EL_HOST_EXIT_IO 1      /* an I/O error during the run (trace write failed) */
#define EL_HOST_EXIT_USAGE 2   /* bad command line or input file: nothing was run */

/* Simulated devices: `device` is an index into el_devices. Indices out of
 * range are ignored. open/close/start/stop do nothing on the host. */
void el_sim_open(uint8_t device);
void el_sim_close(uint8_t device);
void el_sim_start(uint8_t device);
void el_sim_stop(uint8_t device);
/* The device is read at the instant being processed (the tick last given
 * to el_port_wait_tick): copy into every `out` datum of the device that
 * has a stimulus column the latest stimulus value whose time is <= the
 * instant's time. Data without a column keep their value. */
void el_sim_read(uint8_t device);
/* The device's `in` data were just published. Nothing to do on the host. */
void el_sim_write(uint8_t device);
/* Before the host handlers of a device whose type brings them from the
 * model's folder read it (docs/language.md, "Device handlers"): every
 * `out` datum of the device takes the stimulus value due at the instant
 * being processed, or its initial value when the stimulus has none yet, so
 * that a simulation handler computes its data from the stimulus. */
void el_sim_sample(uint8_t device);

/* The runtime's entry point (runtime_c/el_dispatch.c). */
void el_run(int argc, char **argv);

/* The process exit status once el_run has returned (EL_HOST_EXIT_...). */
int el_host_exit_status(void);

#endif /* EL_BOARD_H */
