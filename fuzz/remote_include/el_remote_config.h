/* The remote fuzz target's frame sizes (what easylab proxy generates as
 * el_remote_config.h, DeviceModel.frame_sizes): by default those of the
 * fuzz model (fuzz/remote_fuzz_model.c), so that every frame longer than
 * the model's goes through the decoder's oversize path;
 * -DEL_FUZZ_LARGEST_FRAMES=1 gives the protocol's largest (and 32 tasks) instead. */
#ifndef EL_REMOTE_CONFIG_H
#define EL_REMOTE_CONFIG_H
#if defined(EL_FUZZ_LARGEST_FRAMES) && EL_FUZZ_LARGEST_FRAMES
#define EL_RMT_RX_FRAME EL_RMT_MAX_FRAME
#define EL_RMT_TX_FRAME EL_RMT_MAX_FRAME
#define EL_RMT_TASKS 32u
#else
#define EL_RMT_RX_FRAME 14u /* DOWN of both tasks: header 5, mask 4, speed 2, on 1, CRC 2 */
#define EL_RMT_TX_FRAME 24u /* COUNTERS' answer: header 5, state 1, 6 counters and 2 tasks' overruns u16, CRC 2 */
#define EL_RMT_TASKS 2u
#endif
#endif
