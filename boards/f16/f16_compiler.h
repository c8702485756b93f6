/* EasyLab f16 board: the compiler's own words, and only here.
 *
 * Softune's fcc907s (the Makefile of a build defines EL_F16_FCC907S) has
 * interrupt functions (`__interrupt`) and intrinsics for the CPU's
 * interrupt flag (`__DI`, `__EI`) and level mask (`__set_il`). Every other
 * compiler that reads the board's files is a proxy check (gcc -std=c89,
 * clang for MSP430, clang-tidy, sdcc): for them an interrupt function is a
 * plain function and the intrinsics are functions the proxies' own
 * hardware layer defines, so the same sources pass through them all.
 *
 * The vector table (generated el_f16_vectors.c) uses fcc907s's
 * `#pragma intvect`, which no macro can carry in C89: its pragmas stand
 * under `#if defined(EL_F16_FCC907S)` there.
 */
#ifndef F16_COMPILER_H
#define F16_COMPILER_H

#if defined(EL_F16_FCC907S)
#define EL_F16_ISR(name) __interrupt void name(void)
#define EL_F16_DISABLE_IRQ() __DI()
#define EL_F16_ENABLE_IRQ() __EI()
#define EL_F16_SET_ILM(level) __set_il(level)
#else
#define EL_F16_ISR(name) void name(void)
void el_f16_proxy_disable_irq(void);
void el_f16_proxy_enable_irq(void);
void el_f16_proxy_set_ilm(uint8_t level);
#define EL_F16_DISABLE_IRQ() el_f16_proxy_disable_irq()
#define EL_F16_ENABLE_IRQ() el_f16_proxy_enable_irq()
#define EL_F16_SET_ILM(level) el_f16_proxy_set_ilm(level)
#endif

#endif /* F16_COMPILER_H */
