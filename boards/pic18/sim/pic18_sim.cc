/* EasyLab PIC18 board: the gpsim harness (docs/boards.md, "The PIC18
 * board", "Simulation").
 *
 * Runs a firmware built with `easylab build --board pic18 --sim` in gpsim
 * (Debian's libgpsim) with the host board's command line where it makes
 * sense, so that one stimulus gives one trace on every board (what every
 * harness shares is sim/sim_harness.c):
 *
 *   NAME-sim [--fast] [--duration T] [--cycles N] [--stimulus S.csv]
 *            [--trace T.csv|T.vcd] [--pins P.csv|P.vcd] [--nvram FILE]
 *            [--uart0 pty:LINK|tcp:PORT|file:PATH|null] [--wait] [--halt]
 *            [--cod FILE] [--report] [--help]
 *
 * How it watches the firmware: gpsim keeps a register object per data
 * address; the harness puts its own object in front of a few of them
 * (HookRegister), which passes every access on and tells the harness of
 * writes, in the middle of the instruction, the CPU stopped:
 * - el_pic18_sim_mark (RAM, found in the link map): the firmware's
 *   boot (after a RESET too) and instants (pic18_port.c). At the inputs mark the stimulus due is applied
 *   (params and vars into RAM, device data onto the pins and the ADC);
 *   while encoder edges are on their way el_pic18_sim_busy stays nonzero and
 *   the firmware waits. At the instant mark the items are read from RAM and
 *   traced with the host board's own trace code.
 *   At each inputs mark the guard at the bottom of sdcc's software stack
 *   is checked: a stack that ran out ends the run with an error.
 * - TXREG: each byte the EUSART is given goes to the link of uart0 and to
 *   the chip models on uart0 (sim/sim_chips.h).
 * - EECON1 (the PIC18F4620): gpsim's data EEPROM reads ignore EEADRH; the
 *   harness completes them (map_eeadrh, eeprom_read_fix).
 * - LATA..LATE, TRISA..TRISE, CCPR1L, CCP1CON, CCPR2L, CCP2CON, PR2: the
 *   traced pins' levels and PWM duties (--pins), stamped with the cycle
 *   (a duty PWM_SETTLE_CYCLES after a CCP write: it spans two registers);
 *   the chip selects of the SPI's chips; the levels the firmware drives
 *   the pins of the chips' devices to (chip_pins_update).
 * - SSPCON1, SSPCON2, SSPSTAT, SSPADD, SSPBUF are not gpsim's at all: the
 *   harness plays the MSSP and the chips on its buses (sim/sim_chips.h;
 *   "the MSSP" below).
 * Bytes from the link enter the EUSART's receive FIFO one frame time apart
 * (the baud rate the firmware set), when reception is on, and only into an
 * empty FIFO: with two bytes queued gpsim 0.31 hands the firmware a wrong
 * one (seen at 1 Mbaud, 100 cycles a byte); a byte the firmware has not
 * taken yet waits (no overrun is modelled). The bytes a chip model sends
 * take the same way, the first one character time after it sent it; the
 * levels a chip drives its pins to are forced on them as the stimulus'
 * are (drive_level).
 *
 * - el_pic18_sim_mark's EL_PIC18_SIM_WAIT and _IDLE: the iterations of the
 *   firmware's wait loops, counted at their bare cost as "asleep" by
 *   --report (cycles_waiting): the rest is the CPU's work.
 * Time: gpsim counts instruction cycles exactly (10 MHz at 40 MHz).
 * --fast runs flat out; otherwise the harness keeps the simulated time in
 * step with the wall clock. Exit status: 0 the run ended, 1 an error during
 * it, 2 a bad command line or input file.
 */
#include <gpsim/interface.h>
#include <gpsim/sim_context.h>
#include <gpsim/processor.h>
#include <gpsim/pic-processor.h>
#include <gpsim/gpsim_time.h>
#include <gpsim/breakpoints.h>
#include <gpsim/trigger.h>
#include <gpsim/registers.h>
#include <gpsim/intcon.h>
#include <gpsim/ioports.h>
#include <gpsim/stimuli.h>
#include <gpsim/uart.h>
#include <gpsim/eeprom.h>
#include <gpsim/pir.h>

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <stdbool.h> /* C++'s bool for the runtime's C headers (__bool_true_false_are_defined) */

#include "gpsim_hooks.h"

extern "C" {
#include "sim_model.h"
#include "sim_chips.h"

/* The chips on the buses keep no memories yet: --chips is refused. */
extern const char sim_chips_help[];
const char sim_chips_help[] = "";
}

namespace {

/* The firmware's marks (boards/pic18/pic18_hw.h). */
const unsigned MARK_INPUTS = 1u;
const unsigned MARK_INSTANT = 2u;
const unsigned MARK_BOOT = 3u;
const unsigned MARK_WAIT = 4u, MARK_IDLE = 5u; /* an iteration of a wait loop */
const unsigned KEPT_SIM_HALT = 0xA5u;

/* Special function registers (the same on both parts). */
const unsigned PORTA = 0xF80u, LATA = 0xF89u, TRISA = 0xF92u;
const unsigned TXREG = 0xFADu, RCREG = 0xFAEu, RCSTA = 0xFABu, TXSTA = 0xFACu;
const unsigned SPBRG = 0xFAFu, SPBRGH = 0xFB0u, BAUDCON = 0xFB8u;
const unsigned CCPR1L = 0xFBEu, CCP1CON = 0xFBDu, CCPR2L = 0xFBBu, CCP2CON = 0xFBAu, PR2 = 0xFCBu;
const unsigned EEADRH_ADDR = 0xFAAu, EECON1_ADDR = 0xFA6u;
const unsigned EE_RD = 0x01u, EE_CFGS = 0x40u, EE_EEPGD = 0x80u; /* EECON1 bits */

/* Quadrature edges of one encoder are this many cycles apart (125 us):
 * room for the interrupts of several encoders stepping at once. */
const guint64 ENCODER_EDGE_CYCLES = 1250u;
/* The cycles from a write of a CCP register until its duty is recorded. */
const guint64 PWM_SETTLE_CYCLES = 8u;
/* The harness serves the links and the wall clock every slice of cycles. */
const guint64 SLICE_CYCLES = 1000u;

Processor *cpu;
pic_processor *pic;
unsigned busy_count;

void on_write(unsigned address, unsigned value);
void eeprom_read_fix(unsigned eecon1);

void hook(unsigned address)
{
    cpu->registers[address] = new HookRegister(cpu, cpu->registers[address], on_write);
}

unsigned reg(unsigned address)
{
    return cpu->registers[address]->get_value() & 0xFFu;
}

IOPIN *iopin(unsigned pin)
{
    PortModule *port = dynamic_cast<PortModule *>(cpu->registers[PORTA + (pin >> 3)]->getReg());
    return port != nullptr ? port->getPin(pin & 7u) : nullptr;
}

std::vector<int> pin_driven; /* the level the harness drives an input pin to, by pin number */

/* Drive an input pin to a voltage (an analog input) or a level. */
void drive_pin(unsigned pin, double volts)
{
    IOPIN *p = iopin(pin);
    if (p != nullptr)
        p->set_nodeVoltage(volts);
}

void drive_level(unsigned pin, bool level)
{
    IOPIN *p = iopin(pin);
    pin_driven[pin] = level ? 1 : 0;
    if (p != nullptr) {
        /* With no stimulus node attached, gpsim takes a pin's digital level
           from its forced state (setDrivenState alone does not reach PORTx). */
        p->set_nodeVoltage(level ? cpu->get_Vdd() : 0.0);
        p->forceDrivenState(level ? '1' : '0');
    }
}

void set_busy()
{
    if (sim_busy_addr != 0xFFFFu)
        cpu->registers[sim_busy_addr]->put_value(busy_count != 0u ? 1u : 0u);
}

/* ---- pins (--pins) ---- */


int pwm_duty(uint8_t ccp)
{
    unsigned con = reg(ccp == 1u ? CCP1CON : CCP2CON);
    unsigned full = 4u * (reg(PR2) + 1u);
    unsigned dc = reg(ccp == 1u ? CCPR1L : CCPR2L) << 2 | ((con >> 4) & 3u);
    if ((con & 0x0Cu) != 0x0Cu)
        return 0;
    if (dc >= full)
        return 255;
    return (int)((dc * 255u + full / 2u) / full);
}

int pin_level(uint8_t pin)
{
    unsigned bit = 1u << (pin & 7u);
    if ((reg(TRISA + (pin >> 3)) & bit) == 0u)
        return (reg(LATA + (pin >> 3)) & bit) != 0u;
    return pin_driven[pin] > 0;
}

void record_pins()
{
    guint64 now = get_cycles().get();
    for (uint16_t k = 0; k < sim_pin_count; k++) {
        const sim_pin_t *p = &sim_pins[k];
        sim_pin_record(k, p->kind == SIM_PIN_PWM ? pwm_duty(p->ccp) : pin_level(p->pin), now);
    }
}

/* A duty is written in two registers (CCPRxL, then CCPxCON's low bits),
 * and the CCP module takes it at its next period: the pins are recorded a
 * few cycles after a CCP write, once both are written, not in between. */
class PwmSettle : public TriggerObject {
public:
    bool pending = false;
    void callback() override
    {
        pending = false;
        record_pins();
    }
    void after_write()
    {
        if (!pending) {
            pending = true;
            get_cycles().set_break(get_cycles().get() + PWM_SETTLE_CYCLES, this);
        }
    }
};

PwmSettle pwm_settle;

/* ---- interrupt flags raised while interrupts are off ----
 *
 * gpsim 0.31 takes an external interrupt (INT0..INT2, PORTB's change) when
 * its flag is raised with GIE set; a flag raised while GIE is clear (in the
 * handler, after it looked at the flags; in a critical section) is not
 * taken when RETFIE or the firmware sets GIE again, as the part takes it
 * (gpsim keeps GIE set in the handler and marks it `in_interrupt`):
 * an encoder lost the edge (two counts: its next interrupt saw both pins
 * changed) or counted it an instant late. After an edge driven while
 * interrupts are off, the harness looks again every few cycles until they
 * are on and, when an enabled flag is still up, has gpsim take the
 * interrupt. */
const unsigned INTCON_ADDR = 0xFF2u, INTCON3_ADDR = 0xFF0u;
const guint64 IRQ_RECHECK_CYCLES = 8u;

/* In the interrupt handler (gpsim keeps GIE set there) or GIE clear. */
bool irq_off()
{
    INTCON *intcon = dynamic_cast<INTCON *>(cpu->registers[INTCON_ADDR]);
    return !(reg(INTCON_ADDR) & 0x80u) || (intcon != nullptr && intcon->in_interrupt);
}

class IrqRecheck : public TriggerObject {
public:
    bool armed = false;
    void arm()
    {
        if (!armed) {
            armed = true;
            get_cycles().set_break(get_cycles().get() + IRQ_RECHECK_CYCLES, this);
        }
    }
    void callback() override
    {
        if (irq_off()) {
            get_cycles().set_break(get_cycles().get() + IRQ_RECHECK_CYCLES, this);
            return;
        }
        armed = false;
        unsigned intcon = reg(INTCON_ADDR), intcon3 = reg(INTCON3_ADDR);
        /* INT0IF, RBIF (INTCON bits 1, 0) under INT0IE, RBIE (bits 4, 3);
           INT1IF, INT2IF (INTCON3 bits 0, 1) under INT1IE, INT2IE (bits 3, 4) */
        bool pending = (intcon & (intcon >> 3) & 0x03u) || (intcon3 & (intcon3 >> 3) & 0x03u);
        INTCON_16 *intcon16 = dynamic_cast<INTCON_16 *>(cpu->registers[INTCON_ADDR]);
        if (pending && intcon16 != nullptr)
            intcon16->general_interrupt(true); /* IPEN clear: the vector at 0x08 */
    }
};

IrqRecheck irq_recheck;

/* ---- encoders: quadrature edges from the last count to the new one ---- */

class EncoderEdges : public TriggerObject {
public:
    uint16_t k = 0;
    void callback() override
    {
        sim_hw_state_t *s = &sim_hw_state[k];
        const sim_hw_t *h = &sim_hw[k];
        uint8_t ab, changed;
        if (s->position == s->target) {
            s->busy = false;
            busy_count--;
            set_busy();
            return;
        }
        s->position += s->target > s->position ? 1 : -1;
        ab = sim_quadrature(s->position);
        changed = (uint8_t)(ab ^ s->ab);
        s->ab = ab;
        if (changed & 2u)
            drive_level(h->a, (ab & 2u) != 0u);
        if (changed & 1u)
            drive_level(h->b, (ab & 1u) != 0u);
        if (irq_off())
            irq_recheck.arm();
        record_pins();
        get_cycles().set_break(get_cycles().get() + ENCODER_EDGE_CYCLES, this);
    }
};

std::vector<EncoderEdges> encoders;

/* ---- the EUSART's receiver: one byte per frame time ---- */

guint64 bit_cycles()
{
    unsigned n = reg(SPBRG) | reg(SPBRGH) << 8;
    bool brg16 = (reg(BAUDCON) & 0x08u) != 0u, brgh = (reg(TXSTA) & 0x04u) != 0u;
    unsigned div = brg16 ? (brgh ? 1u : 4u) : (brgh ? 4u : 16u);
    return (guint64)div * (n + 1u);
}

class RxPump : public TriggerObject {
public:
    bool scheduled = false;
    void callback() override
    {
        scheduled = false;
        pump();
    }
    /* The bytes queued start into the FIFO one character time from now. */
    void after_a_character()
    {
        if (scheduled)
            return;
        scheduled = true;
        get_cycles().set_break(get_cycles().get() + char_cycles(reg(RCSTA)), this);
    }
    void pump()
    {
        sim_link_t *u = &sim_links[0];
        _RCREG *rc = dynamic_cast<_RCREG *>(cpu->registers[RCREG]->getReg());
        unsigned rcsta = reg(RCSTA);
        if (scheduled || rc == nullptr || (rcsta & 0x90u) != 0x90u /* SPEN, CREN */
            || sim_link_ready(u, get_cycles().get(), rc->fifo_sp == 0u, char_cycles(rcsta)) == 0u)
            return;
        guint64 frame = char_cycles(rcsta);
        if (rc->fifo_sp == 0u) { /* not the FIFO's second place: see the top of the file */
            unsigned byte = u->in[0];
            if (rcsta & 0x40u) /* RX9: the 9th bit carries the parity the model's interface uses */
                byte |= (unsigned)ninth_bit(u->in[0]) << 8;
            sim_link_consume(u, 1u);
            rc->push(byte);
        }
        scheduled = true;
        get_cycles().set_break(get_cycles().get() + frame, this);
    }

private:
    /* A character on the wire: start bit, 8 or 9 data bits (RX9), stop bit. */
    static guint64 char_cycles(unsigned rcsta)
    {
        return bit_cycles() * ((rcsta & 0x40u) ? 11u : 10u);
    }
    static unsigned ninth_bit(uint8_t v)
    {
        unsigned ones = 0;
        for (; v != 0u; v = (uint8_t)(v & (v - 1u)))
            ones++;
        return (ones & 1u) ^ (sim_uart_parity == 2u ? 1u : 0u);
    }
};

RxPump rx_pump;

/* The bytes a chip sends (sim_board_uart_receive) join the link's on their
 * way into the EUSART: the first of them one character time after it was
 * sent (its reception ends then), the next one more each. */
void uart_receive_from_chip(uint8_t byte)
{
    sim_link_t *u = &sim_links[0];
    unsigned rcsta = reg(RCSTA);
    if ((rcsta & 0x90u) != 0x90u || u->in_len >= sizeof u->in) /* SPEN, CREN: the receiver is off */
        return;
    u->in[u->in_len++] = byte;
    rx_pump.after_a_character();
}

/* ---- the MSSP: the harness plays it, and the chips on its buses ----
 *
 * gpsim 0.31 emulates the MSSP at the pins: with nothing on them (no
 * pull-ups, no chip) an I2C START ends in a bus collision (BCLIF: the
 * firmware's jobs fail with EL_BUS_ERROR) and SPI reads 0x00 (SDI low).
 * The harness therefore takes the module's five registers (SSPCON1,
 * SSPCON2, SSPSTAT, SSPADD, SSPBUF) from gpsim: its MSSP never sees a
 * write, and the pins stay plain port pins. The harness completes each
 * step the firmware asks for as the MSSP would, after the time it takes
 * on the wire (the baud rate generator's SSPADD, the SPI clock's SSPM),
 * and raises SSPIF, with what the chips of sim_chip_table answered
 * (sim/sim_chips.h):
 * - I2C master (SSPM 1000): SEN and RSEN are START (the next byte written
 *   to SSPBUF is the address: sim_chips_i2c_start), a byte written to
 *   SSPBUF goes to the addressed chip (sim_chips_i2c_write) and ACKSTAT
 *   says whether it acknowledged; RCEN receives a byte (sim_chips_i2c_read)
 *   into SSPBUF with BF set; ACKEN sends ACKDT; PEN is the STOP
 *   (sim_chips_i2c_stop). An address nobody acknowledges reads ACKSTAT 1.
 * - SPI master (SSPM 0000..0011): a byte written to SSPBUF is clocked out
 *   to the selected chip (sim_chips_spi_byte); its answer is in SSPBUF,
 *   BF and SSPIF set, 8 SCK periods later: 0xFF when no chip is selected
 *   (an idle SDI, pulled up). The chip selects are the pins of the table's
 *   SPI chips, as the firmware drives them (LATx, TRISx; an input selects
 *   nothing): each change goes to sim_chips_spi_select.
 * Switching SSPEN off abandons what the module was doing (a STOP for the
 * chip addressed). Writing SSPBUF while a step is under way sets WCOL. */
const unsigned SSPCON2_ADDR = 0xFC5u, SSPCON1_ADDR = 0xFC6u, SSPSTAT_ADDR = 0xFC7u, SSPADD_ADDR = 0xFC8u,
               SSPBUF_ADDR = 0xFC9u, PIR1_ADDR = 0xF9Eu;
const unsigned SSPIF = 0x08u;                                                 /* PIR1 */
const unsigned SEN = 0x01u, RSEN = 0x02u, PEN = 0x04u, RCEN = 0x08u, ACKEN = 0x10u, ACKDT = 0x20u,
               ACKSTAT = 0x40u;                                               /* SSPCON2 */
const unsigned SSPEN = 0x20u, WCOL = 0x80u;                                   /* SSPCON1 */
const unsigned BF = 0x01u, RW = 0x04u, S_BIT = 0x08u, P_BIT = 0x10u;          /* SSPSTAT */

class Mssp : public TriggerObject {
public:
    unsigned con1 = 0, con2 = 0, stat = 0, add = 0, buf = 0;

    bool i2c() const { return (con1 & SSPEN) != 0u && (con1 & 0x0Fu) == 0x08u; }
    bool spi() const { return (con1 & SSPEN) != 0u && (con1 & 0x0Fu) <= 0x03u; }

    void write_con1(unsigned v)
    {
        bool was_on = (con1 & SSPEN) != 0u;
        con1 = v & 0xFFu;
        if (was_on && (con1 & SSPEN) == 0u)
            off();
    }

    void write_con2(unsigned v)
    {
        unsigned asked = v & (SEN | RSEN | PEN | RCEN | ACKEN) & ~con2;
        con2 = (con2 & ~(ACKDT | 0x80u)) | (v & (ACKDT | 0x80u)); /* ACKDT, GCEN */
        if (!i2c() || asked == 0u || step != NONE)
            return; /* an MSSP that is busy ignores a second request */
        /* one at a time, in the module's order of priority */
        unsigned bit = (asked & SEN) ? SEN : (asked & RSEN) ? RSEN : (asked & PEN) ? PEN : (asked & RCEN) ? RCEN : ACKEN;
        con2 |= bit;
        guint64 half = brg();
        switch (bit) {
        case SEN: begin(START, 2u * half); break;
        case RSEN: begin(START, 3u * half); break;
        case PEN: begin(STOP, 3u * half); break;
        case RCEN: begin(RECEIVE, 16u * half); break;
        default: begin(ACK, 2u * half); break;
        }
    }

    void write_stat(unsigned v)
    {
        stat = (stat & 0x3Fu) | (v & 0xC0u); /* SMP, CKE: the rest is the module's */
    }

    void write_buf(unsigned v)
    {
        v &= 0xFFu;
        if (step != NONE || (con2 & (SEN | RSEN | PEN | RCEN | ACKEN)) != 0u) {
            con1 |= WCOL;
            return;
        }
        if (i2c()) {
            out = v;
            stat |= BF | RW; /* the byte goes out */
            begin(SEND, 18u * brg() + 1u);
        } else if (spi()) {
            out = v;
            begin(SPI_BYTE, 8u * spi_bit());
        }
    }

    unsigned read_buf()
    {
        stat &= ~BF;
        return buf;
    }

    void callback() override
    {
        Step done = step;
        step = NONE;
        switch (done) {
        case START:
            con2 &= ~(SEN | RSEN);
            stat = (stat & ~P_BIT) | S_BIT;
            address_next = true;
            break;
        case STOP:
            con2 &= ~PEN;
            stat = (stat & ~S_BIT) | P_BIT;
            if (in_transaction)
                sim_chips_i2c_stop(0u);
            in_transaction = false;
            address_next = false;
            break;
        case SEND: {
            bool ack;
            if (address_next) {
                ack = sim_chips_i2c_start(0u, (uint8_t)(out >> 1), (out & 1u) != 0u);
                in_transaction = true;
                address_next = false;
            } else {
                ack = sim_chips_i2c_write(0u, (uint8_t)out);
            }
            con2 = ack ? (con2 & ~ACKSTAT) : (con2 | ACKSTAT);
            stat &= ~(BF | RW);
            break;
        }
        case RECEIVE:
            con2 &= ~RCEN;
            buf = sim_chips_i2c_read(0u);
            stat |= BF;
            break;
        case ACK:
            con2 &= ~ACKEN;
            break;
        case SPI_BYTE:
            buf = sim_chips_spi_byte(0u, (uint8_t)out);
            stat |= BF;
            break;
        default:
            return;
        }
        PIR *pir1 = dynamic_cast<PIR *>(cpu->registers[PIR1_ADDR]->getReg());
        if (pir1 != nullptr)
            pir1->setInterrupt(SSPIF);
    }

private:
    enum Step { NONE, START, STOP, SEND, RECEIVE, ACK, SPI_BYTE } step = NONE;
    unsigned out = 0;
    bool address_next = false;  /* the next byte sent is an address (after a START) */
    bool in_transaction = false; /* a chip may be addressed: its STOP is due */

    void begin(Step s, guint64 cycles)
    {
        step = s;
        get_cycles().set_break(get_cycles().get() + (cycles ? cycles : 1u), this);
    }

    /* The baud rate generator's period, TBRG: half an SCL period, in instruction cycles. */
    guint64 brg() const
    {
        guint64 half = (add + 1u) / 2u;
        return half ? half : 1u;
    }

    /* One SCK period in instruction cycles: Fosc / 4, 16, 64 (SSPM 0..2), TMR2's output / 2 (3). */
    guint64 spi_bit() const
    {
        switch (con1 & 0x03u) {
        case 0u: return 1u;
        case 1u: return 4u;
        case 2u: return 16u;
        default: return 2u * (reg(PR2) + 1u);
        }
    }

    void off()
    {
        if (step != NONE)
            get_cycles().clear_break(this);
        step = NONE;
        if (in_transaction)
            sim_chips_i2c_stop(0u);
        in_transaction = false;
        address_next = false;
        con2 = 0u;
        stat &= 0xC0u;
    }
};

Mssp mssp;

/* One of the MSSP's registers, the harness's instead of gpsim's. */
class MsspRegister : public Register {
public:
    MsspRegister(Processor *p, Register *original) : Register(p, original->name().c_str(), "EasyLab MSSP")
    {
        address = original->address;
    }
    unsigned int get() override
    {
        return address == SSPBUF_ADDR ? mssp.read_buf() : get_value();
    }
    unsigned int get_value() override
    {
        switch (address) {
        case SSPCON1_ADDR: return mssp.con1;
        case SSPCON2_ADDR: return mssp.con2;
        case SSPSTAT_ADDR: return mssp.stat;
        case SSPADD_ADDR: return mssp.add;
        default: return mssp.buf;
        }
    }
    void put(unsigned int v) override
    {
        v &= 0xFFu;
        switch (address) {
        case SSPCON1_ADDR: mssp.write_con1(v); break;
        case SSPCON2_ADDR: mssp.write_con2(v); break;
        case SSPSTAT_ADDR: mssp.write_stat(v); break;
        case SSPADD_ADDR: mssp.add = v; break;
        default: mssp.write_buf(v); break;
        }
    }
    void put_value(unsigned int v) override { put(v); }
    RegisterValue getRV() override { return RegisterValue(get(), 0u); }
    RegisterValue getRV_notrace() override { return RegisterValue(get_value(), 0u); }
    RegisterValue getRVN() override { return getRV_notrace(); }
    RegisterValue getRVN_notrace() override { return getRV_notrace(); }
    void putRV(RegisterValue rv) override { put(rv.data); }
    void putRV_notrace(RegisterValue rv) override { put(rv.data); }
    void setbit(unsigned int bit, bool v) override
    {
        unsigned m = 1u << bit;
        put(v ? (get_value() | m) : (get_value() & ~m));
    }
    bool get_bit(unsigned int bit) override { return (get_value() >> bit) & 1u; }
};

/* The chip selects of the table's SPI chips: the level each is at (an
 * input is high: selects nothing). */
std::vector<int> cs_level; /* by pin number: -1 not a chip select, 0 low, 1 high */

void cs_update()
{
    for (unsigned pin = 0; pin < cs_level.size(); pin++) {
        if (cs_level[pin] < 0)
            continue;
        unsigned bit = 1u << (pin & 7u);
        int level = (reg(TRISA + (pin >> 3)) & bit) != 0u ? 1 : (reg(LATA + (pin >> 3)) & bit) != 0u;
        if (level != cs_level[pin]) {
            cs_level[pin] = level;
            sim_chips_spi_select(0u, (uint16_t)pin, level == 0);
        }
    }
}

/* The pins the chips' devices claim: after each write of LATx or TRISx,
 * the level of each of them that is an output goes to sim_chips_pin_driven
 * (which reports the changes to the chip). */
void chip_pins_update()
{
    for (uint16_t k = 0; k < sim_chip_table_count; k++) {
        for (uint8_t j = 0; j < sim_chip_table[k].pin_count; j++) {
            unsigned pin = sim_chip_table[k].pins[j];
            unsigned bit = 1u << (pin & 7u);
            if ((reg(TRISA + (pin >> 3)) & bit) == 0u)
                sim_chips_pin_driven((uint16_t)pin, (reg(LATA + (pin >> 3)) & bit) != 0u);
        }
    }
}

void mssp_take()
{
    const unsigned regs[] = {SSPCON1_ADDR, SSPCON2_ADDR, SSPSTAT_ADDR, SSPADD_ADDR, SSPBUF_ADDR};
    for (unsigned a : regs)
        cpu->registers[a] = new MsspRegister(cpu, cpu->registers[a]);
    cs_level.assign(64, -1);
    for (uint16_t k = 0; k < sim_chip_table_count; k++)
        if (sim_chip_table[k].kind == SIM_CHIP_SPI && sim_chip_table[k].cs < cs_level.size())
            cs_level[sim_chip_table[k].cs] = 1;
}

/* ---- instants ---- */

/* The instant's tick: el_pic18_sim_tick, 32 bits (EL_TICK_32), little-endian. */
uint64_t read_tick()
{
    uint8_t b[4];
    sim_ram_read(sim_tick_addr, b, sizeof b);
    return sim_tick_extend((uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24);
}

/* ---- the software stack's guard ---- */

/* The lowest bytes of sdcc's software stack hold a pattern from the first
 * instant on (start-up clears RAM before): a stack grown into them has run
 * out (the registers it saves then overwrite the RAM below). */
const unsigned STACK_GUARD_BYTES = 4u, STACK_GUARD = 0xA5u;
bool stack_guarded;

bool stack_guard_intact()
{
    for (unsigned i = 0; i < STACK_GUARD_BYTES; i++) {
        if (!stack_guarded) {
            cpu->registers[sim_stack_addr + i]->put_value(STACK_GUARD);
        } else if (reg(sim_stack_addr + i) != STACK_GUARD) {
            el_host_error("the %s's software stack (%u bytes, board.toml's stack) ran out at cycle %llu",
                          sim_mcu, (unsigned)sim_stack_size, (unsigned long long)get_cycles().get());
            return false;
        }
    }
    stack_guarded = true;
    return true;
}

/* The cycles spent waiting, for --report's "asleep" (the PIC18 polls
 * where the AVR sleeps): each wait loop's iterations (a mark each, before
 * it polls), each at the loop's bare cost, the shortest span between two
 * of its marks in a row. What an iteration takes beyond that (a received
 * byte decoded, an interrupt) is the CPU's work. */
struct SpinLoop {
    guint64 count = 0u;
    guint64 shortest = ~(guint64)0u;
};
SpinLoop spin_loops[2];
int spin_open = -1; /* the loop whose iteration the last mark began, if it did */
guint64 spin_at;

void spin_mark(unsigned value)
{
    guint64 now = get_cycles().get();
    int loop = value == MARK_WAIT ? 0 : value == MARK_IDLE ? 1 : -1;
    if (loop >= 0 && loop == spin_open && now - spin_at < spin_loops[loop].shortest)
        spin_loops[loop].shortest = now - spin_at;
    if (loop >= 0)
        spin_loops[loop].count++;
    spin_open = loop;
    spin_at = now;
}

guint64 cycles_waiting()
{
    guint64 total = 0u;
    for (const SpinLoop &l : spin_loops)
        if (l.shortest != ~(guint64)0u)
            total += l.count * l.shortest;
    return total;
}

void on_write(unsigned address, unsigned value)
{
    if (address == sim_mark_addr) {
        spin_mark(value);
        if (value == MARK_INPUTS) {
            if (!stack_guard_intact()) {
                sim_exit_status = SIM_EXIT_RUN;
                sim_stop = true;
                get_bp().halt();
                return;
            }
            sim_instant_inputs(read_tick());
            set_busy();
            if (sim_stop)
                get_bp().halt();
        } else if (value == MARK_INSTANT) {
            sim_instant_record(read_tick());
        } else if (value == MARK_BOOT) {
            stack_guarded = false; /* the start-up cleared RAM, the guard too: set it again */
        }
    } else if (address == TXREG) {
        sim_link_output(&sim_links[0], (uint8_t)value);
        sim_chips_uart_byte(0u, (uint8_t)value);
    } else if (address == EECON1_ADDR) {
        eeprom_read_fix(value);
    } else if (address == CCPR1L || address == CCP1CON || address == CCPR2L || address == CCP2CON) {
        pwm_settle.after_write();
    } else {
        record_pins();
        cs_update();
        chip_pins_update();
    }
}

/* The end of a slice of cycles. */
class Stopper : public TriggerObject {
public:
    void callback() override { get_bp().halt(); }
};

/* The EEPROM's bytes at the end of the run. */
uint8_t *eeprom_image()
{
    static std::vector<uint8_t> image;
    image.assign(sim_nv_size, 0xFFu);
    if (pic != nullptr && pic->eeprom != nullptr) {
        Register **rom = pic->eeprom->get_rom();
        for (uint32_t i = 0; i < sim_nv_size && i < pic->eeprom->get_rom_size(); i++)
            image[i] = (uint8_t)rom[i]->get_value();
    }
    return image.data();
}

/* gpsim 0.31 gives the PIC18F4620 its 1024 bytes of data EEPROM but no
 * EEADRH (the address's high byte), and its data EEPROM read ignores
 * EEADRH even where it has one: only the first 256 bytes could be reached.
 * The harness makes the EEPROM one with EEADRH (its initialize does), puts
 * the register at its address and completes each read (eeprom_read_fix,
 * called after gpsim's own read on a write of EECON1). */
EEPROM_EXTND *long_eeprom; /* the EEPROM when it has more than 256 bytes */

void map_eeadrh()
{
    EEPROM_EXTND *ee = pic != nullptr ? dynamic_cast<EEPROM_EXTND *>(pic->eeprom) : nullptr;
    if (ee == nullptr || ee->get_rom_size() <= 256u)
        return;
    long_eeprom = ee;
    if (ee->get_reg_eeadrh() != nullptr)
        return;
    ee->initialize(ee->get_rom_size(), 64, 64, 0x300000u, true);
    pic->add_sfr_register(ee->get_reg_eeadrh(), EEADRH_ADDR, RegisterValue(0, 0), "eeadrh");
}

void eeprom_read_fix(unsigned eecon1)
{
    if (long_eeprom == nullptr || (eecon1 & (EE_RD | EE_CFGS | EE_EEPGD)) != EE_RD)
        return;
    unsigned a = long_eeprom->get_reg_eeadrh()->get_value() << 8 | long_eeprom->get_reg_eeadr()->get_value();
    if (a < long_eeprom->get_rom_size())
        long_eeprom->get_reg_eedata()->put_value(long_eeprom->get_rom()[a]->get_value());
}

void eeprom_store(const uint8_t *image)
{
    if (pic == nullptr || pic->eeprom == nullptr)
        return;
    for (uint32_t i = 0; i < sim_nv_size && i < pic->eeprom->get_rom_size(); i++)
        pic->eeprom->change_rom(i, image[i]);
}

} // namespace

/* ---- what the chips need of the board (sim/sim_chips.h) ---- */

extern "C" uint64_t sim_board_now_us(void)
{
    return get_cycles().get() * 1000000u / sim_clock_hz;
}

extern "C" void sim_board_uart_receive(uint8_t uart, uint8_t byte)
{
    if (uart == 0u) /* the EUSART */
        uart_receive_from_chip(byte);
}

extern "C" void sim_board_pin_drive(uint16_t pin, bool level)
{
    if (pin >= pin_driven.size())
        return;
    drive_level(pin, level);
    if (irq_off()) /* an edge on an interrupt pin while interrupts are off: see IrqRecheck */
        irq_recheck.arm();
    record_pins();
}

/* ---- what sim_harness.c needs of the simulator ---- */

extern "C" void sim_ram_read(uint16_t addr, void *dst, size_t n)
{
    uint8_t *d = static_cast<uint8_t *>(dst);
    for (size_t i = 0; i < n; i++)
        d[i] = (uint8_t)cpu->registers[addr + i]->get_value();
}

extern "C" void sim_ram_write(uint16_t addr, const void *src, size_t n)
{
    const uint8_t *s = static_cast<const uint8_t *>(src);
    for (size_t i = 0; i < n; i++)
        cpu->registers[addr + i]->put_value(s[i]);
}

extern "C" bool sim_drive_hardware(uint16_t k)
{
    const sim_hw_t *h = &sim_hw[k];
    sim_hw_state_t *s = &sim_hw_state[k];
    const el_item_t *it = &el_items[h->item];
    switch (h->kind) {
    case SIM_HW_ADC: {
        uint16_t v;
        memcpy(&v, s->value, sizeof v);
        if (v > 1023u) {
            el_host_error("%s = %u at %llu us: the %s's ADC gives 0..1023 (10 bits)", it->name, (unsigned)v,
                          (unsigned long long)el_sim_now_us, sim_mcu);
            return false;
        }
        /* gpsim converts round(1023 V / Vdd): the count v exactly. */
        static const uint8_t pins[13] = {0x00, 0x01, 0x02, 0x03, 0x05, 0x20, 0x21, 0x22, 0x0A, 0x0B, 0x09, 0x0C, 0x08};
        drive_pin(pins[h->a], v * (cpu->get_Vdd() / 1023.0));
        return true;
    }
    case SIM_HW_PIN_IN: {
        bool level;
        memcpy(&level, s->value, sizeof level);
        drive_level(h->a, level);
        record_pins();
        return true;
    }
    case SIM_HW_ENCODER: {
        int32_t v;
        memcpy(&v, s->value, sizeof v);
        s->target = v;
        if (s->target != s->position && !s->busy) {
            s->busy = true;
            busy_count++;
            encoders[k].k = k;
            get_cycles().set_break(get_cycles().get() + ENCODER_EDGE_CYCLES, &encoders[k]);
        }
        return true;
    }
    default:
        return true;
    }
}

extern "C" const char *sim_pin_name(uint16_t k, bool *pwm)
{
    *pwm = sim_pins[k].kind == SIM_PIN_PWM;
    return sim_pins[k].name;
}

int main(int argc, char **argv)
{
    int r = sim_parse_args(argc, argv, "--cod", "gpsim");
    if (r != SIM_EXIT_OK)
        return r == SIM_EXIT_HELP ? SIM_EXIT_OK : r;

    int loaded;
    {
        QuietStdout quiet;
        initialize_gpsim_core();
        loaded = CSimulationContext::GetContext()->LoadProgram(sim_opt.firmware, sim_processor, &cpu);
        initialization_is_complete();
        pic = dynamic_cast<pic_processor *>(cpu);
        if (loaded && cpu != nullptr)
            map_eeadrh();
    }
    if (!loaded || cpu == nullptr) {
        el_host_error("cannot load the firmware %s into gpsim's %s", sim_opt.firmware, sim_processor);
        return SIM_EXIT_USAGE;
    }
    cpu->set_frequency(4.0 * sim_clock_hz);
    pin_driven.assign(64, -1);
    encoders.resize(sim_hw_count ? sim_hw_count : 1u);

    std::vector<uint8_t> erased(sim_nv_size, 0xFFu); /* gpsim starts the EEPROM at 0; a chip's erased bytes are 0xFF */
    if (!sim_chips_start(sim_opt.chips) || !sim_start(erased.data()))
        return SIM_EXIT_USAGE;
    eeprom_store(erased.data());
    mssp_take();

    if (sim_mark_addr != 0xFFFFu)
        hook(sim_mark_addr);
    hook(TXREG);
    if (long_eeprom != nullptr)
        hook(EECON1_ADDR);
    for (unsigned p = 0; p < 5u; p++) {
        hook(LATA + p);
        hook(TRISA + p);
    }
    hook(CCPR1L);
    hook(CCP1CON);
    hook(CCPR2L);
    hook(CCP2CON);
    hook(PR2);
    if (sim_opt.halt && sim_kept_addr != 0xFFFFu) /* read by el_port_init of a debug build */
        cpu->registers[sim_kept_addr]->put_value(KEPT_SIM_HALT);

    Stopper stopper;
    while (!sim_stop && !sim_stop_signal) {
        guint64 now = get_cycles().get();
        guint64 until = now + SLICE_CYCLES;
        if (sim_opt.has_cycles && until > sim_opt.cycles)
            until = sim_opt.cycles;
        if (until <= now)
            break;
        get_cycles().set_break(until, &stopper);
        cpu->run(false);
        if (sim_stop || sim_stop_signal) /* the run's end (or an error) halted the CPU, maybe in the slice's first cycle */
            break;
        if (get_cycles().get() == now) {
            el_host_error("gpsim stopped the %s at cycle %llu (pc 0x%05x)", sim_mcu, (unsigned long long)now,
                          cpu->pc->get_value());
            sim_exit_status = SIM_EXIT_RUN;
            break;
        }
        if (sim_opt.has_cycles && get_cycles().get() >= sim_opt.cycles)
            break;
        if (!sim_service(get_cycles().get()))
            break;
        rx_pump.pump();
    }
    if (!sim_chips_finish() && sim_exit_status == SIM_EXIT_OK)
        sim_exit_status = SIM_EXIT_RUN;
    return sim_finish(get_cycles().get(), cycles_waiting(), eeprom_image());
}
