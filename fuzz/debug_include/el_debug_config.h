/* The fuzz target's stand-in for the generated el_debug_config.h. */
#ifndef EL_DEBUG_CONFIG_H
#define EL_DEBUG_CONFIG_H
#define EL_DEBUG_SERVER 1
#endif
