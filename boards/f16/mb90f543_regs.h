/* EasyLab f16 board: the MB90F543's registers that the port uses.
 *
 * The MB90F543 is an F2MC-16LX of the MB90540/545 series (two CAN
 * controllers, 128 KB flash, 6 KB RAM). Addresses are those of Fujitsu's
 * I/O map for the series (IO-Wizard's mb90540.asm, V4.3); each block names
 * the chapter of the "MB90540/545 Series Hardware Manual" that describes
 * its bits. Bit positions below follow those chapters as this board reads
 * them; nothing on the machines that build EasyLab can run an F2MC-16, so
 * they are unchecked there: docs/boards.md ("The F16 board") lists what to
 * compare with the manual before a first run.
 *
 * Every register lies in the I/O area of bank 00, reached through a
 * volatile pointer (no compiler keyword).
 */
#ifndef MB90F543_REGS_H
#define MB90F543_REGS_H

#include "el_types.h"

/* Through size_t: an integer as wide as a pointer for every compiler that
 * reads this (16 bits on the part, 64 on the host's proxy check). */
#define EL_F16_REG8(addr) (*(volatile uint8_t *)(size_t)(addr))
#define EL_F16_REG16(addr) (*(volatile uint16_t *)(size_t)(addr))

/* ---- Chapter "I/O Ports": port data (PDRn) and direction (DDRn, 1 = output) */
#define EL_F16_PDR(port) EL_F16_REG8(0x0000u + (port))   /* PDR0..PDRA: 0x00..0x0A */
#define EL_F16_DDR(port) EL_F16_REG8(0x0010u + (port))   /* DDR0..DDRA: 0x10..0x1A */
#define EL_F16_ADER EL_F16_REG8(0x001Bu)                  /* port 5: 1 = analog input ANn */

/* ---- Chapter "UART1": the serial interface with a dedicated baud rate
 * generator (SMR1, SCR1, SIDR1/SODR1, SSR1, U1CDCR). UART0 (UMC0, USR0,
 * URD0 at 0x20..0x23) is a different circuit the board does not drive. */
#define EL_F16_SMR1 EL_F16_REG8(0x0024u)
#define EL_F16_SMR_SOE 0x01u     /* serial data output on SOT1 */
#define EL_F16_SMR_CS_SHIFT 3u   /* CS2..CS0: the transfer clock (000..011: machine clock / div / (208 << cs)) */
#define EL_F16_SMR_MD_ASYNC 0x00u /* MD1..MD0 = 00: asynchronous, normal */
#define EL_F16_SCR1 EL_F16_REG8(0x0025u)
#define EL_F16_SCR_TXE 0x01u
#define EL_F16_SCR_RXE 0x02u
#define EL_F16_SCR_REC 0x04u     /* write 0: clear the receive error flags */
#define EL_F16_SCR_CL8 0x10u     /* 8 data bits */
#define EL_F16_SCR_P_EVEN 0x00u  /* with PEN: even parity; P = 1: odd */
#define EL_F16_SCR_P_ODD 0x40u
#define EL_F16_SCR_PEN 0x80u
#define EL_F16_SIDR1 EL_F16_REG8(0x0026u) /* read: received byte */
#define EL_F16_SODR1 EL_F16_REG8(0x0026u) /* write: byte to send */
#define EL_F16_SSR1 EL_F16_REG8(0x0027u)
#define EL_F16_SSR_TIE 0x01u
#define EL_F16_SSR_RIE 0x02u
#define EL_F16_SSR_TDRE 0x08u
#define EL_F16_SSR_RDRF 0x10u
#define EL_F16_SSR_FRE 0x20u
#define EL_F16_SSR_ORE 0x40u
#define EL_F16_SSR_PE 0x80u
#define EL_F16_U1CDCR EL_F16_REG8(0x0028u)
#define EL_F16_CDCR_MD 0x80u     /* prescaler on; DIV3..DIV0 = div - 1 */

/* ---- Chapter "DTP/External Interrupt Circuit": INT0..INT7 */
#define EL_F16_ENIR EL_F16_REG8(0x0030u)   /* bit n: INTn enabled */
#define EL_F16_EIRR EL_F16_REG8(0x0031u)   /* bit n: INTn requested (write 0 to clear) */
#define EL_F16_ELVR EL_F16_REG16(0x0032u)  /* bits 2n+1..2n: 10 rising, 11 falling edge */
#define EL_F16_ELVR_RISING 2u
#define EL_F16_ELVR_FALLING 3u

/* ---- Chapter "8/10-bit A/D Converter" */
#define EL_F16_ADCS0 EL_F16_REG8(0x0034u)  /* MD1..0 (7..6), ANS2..0 start (5..3), ANE2..0 end (2..0) */
#define EL_F16_ADCS1 EL_F16_REG8(0x0035u)  /* BUSY (7), INT (6), INTE (5), PAUS (4), STS1..0 (3..2), STRT (1) */
#define EL_F16_ADCS1_BUSY 0x80u
#define EL_F16_ADCS1_INT 0x40u
#define EL_F16_ADCS1_STRT 0x02u
#define EL_F16_ADCR EL_F16_REG16(0x0036u)  /* D9..D0; S10 (15) = 0: 10-bit results */

/* ---- Chapter "8/16-bit PPG Timer": four units (PPG0/1 .. PPG6/7) */
#define EL_F16_PPGC(ch) EL_F16_REG8(0x0038u + 4u * ((ch) / 2u) + ((ch) % 2u)) /* PPGC0..PPGC7 */
#define EL_F16_PPG_CLK(ch) EL_F16_REG8(0x003Au + 4u * ((ch) / 2u))          /* PPG01..PPG67 */
#define EL_F16_PPGC_PEN 0x80u   /* counting */
#define EL_F16_PPGC_PE 0x20u    /* pulse on the pin */
#define EL_F16_PPGC_EVEN_RESERVED 0x07u /* PPGCn (even n): bits 2..0 are written 1 */
#define EL_F16_PPGC_ODD_RESERVED 0x01u  /* PPGCn (odd n): bit 0 is written 1; MD1..0 (2..1) = 00: 8-bit x 2 */
#define EL_F16_PPG_CLK_DIV16 0x90u /* PCS2..0 (7..5) and PCM2..0 (4..2) = 100: machine clock / 16 */
#define EL_F16_PRLL(ch) EL_F16_REG8(0x3900u + 2u * (ch))      /* counts low */
#define EL_F16_PRLH(ch) EL_F16_REG8(0x3901u + 2u * (ch))      /* counts high */

/* ---- Chapter "16-bit Reload Timer": timer 0 runs the LET tick */
#define EL_F16_TMCSR0 EL_F16_REG16(0x0050u)
#define EL_F16_TMR0 EL_F16_REG16(0x0052u)   /* read: the count (down) */
#define EL_F16_TMRLR0 EL_F16_REG16(0x0052u) /* write: the reload value */
#define EL_F16_TMCSR_TRG 0x0001u
#define EL_F16_TMCSR_CNTE 0x0002u
#define EL_F16_TMCSR_UF 0x0004u
#define EL_F16_TMCSR_INTE 0x0008u
#define EL_F16_TMCSR_RELD 0x0010u
#define EL_F16_TMCSR_CSL_SHIFT 10u /* CSL1..0: machine clock / 2, / 8, / 32 */

/* ---- Chapter "Low-Power Consumption Mode": LPMCR (writing RST = 0 resets
 * the part: a proxy's STOP) */
#define EL_F16_LPMCR EL_F16_REG8(0x00A0u)
#define EL_F16_LPMCR_TMD 0x08u  /* 0 would enter the watch mode: keep it 1 */

/* ---- Chapter "Clocks": CKSCR selects the PLL multiplier */
#define EL_F16_CKSCR EL_F16_REG8(0x00A1u)
#define EL_F16_CKSCR_MCM 0x40u  /* 1: the main clock runs (PLL not yet locked) */
#define EL_F16_CKSCR_MCS 0x04u  /* 0: the PLL clock */
#define EL_F16_CKSCR_CS_MASK 0x03u /* CS1..0: multiplier - 1 */

/* ---- Chapter "Interrupts": ICR00..ICR15, one per pair of vectors from #11 */
#define EL_F16_ICR(n) EL_F16_REG8(0x00B0u + (n))
#define EL_F16_ICR_OF_VECTOR(v) (((v) - 11u) / 2u)

#endif /* MB90F543_REGS_H */
