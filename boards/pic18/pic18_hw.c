/* EasyLab PIC18 board: the hardware (pic18_hw.h) of the PIC18F4520 and
 * PIC18F4620 at 40 MHz (10 MHz crystal, PLL; 10 MIPS).
 *
 * Time: Timer2 (prescaler, PR2, postscaler) interrupts every
 * EL_PIC18_TICK_CYCLES / EL_PIC18_TICK_ISRS instruction cycles; every
 * EL_PIC18_TICK_ISRS interrupts make one LET tick (devices.py chose the
 * settings so that the tick is exact whenever it can: docs/boards.md,
 * "Tick and drift"). Timer2's period is also the PWM period of CCP1 and
 * CCP2. Timer1 counts instruction cycles; with its overflow interrupt it
 * is the 32-bit fine clock.
 *
 * Interrupts: IPEN is clear, so every source comes to one handler at the
 * high-priority vector: Timer2, Timer1, the EUSART (pic18_uart.c), the
 * MSSP as the I2C master (pic18_mssp.c), and the encoders' pins
 * (INT0..INT2, PORTB's interrupt on change of RB4..RB7).
 *
 * The watchdog (WDTPS 1:512, about 2 s) is enabled by software
 * (SWDTEN) from el_pic18_start on and kicked while the port waits.
 *
 * Compiler keywords are behind el_pic18.h's macros; configuration bits
 * use `#pragma config`, which sdcc and MPLAB XC8 both take.
 */
#define EL_PIC18_DEFINES_KEPT /* at a fixed address: sdcc refuses a plain extern declaration of it */
#include "el_pic18.h"
#include "pic18_hw.h"

#pragma config OSC = HSPLL, FCMEN = OFF, IESO = OFF
#pragma config PWRT = ON, BOREN = SBORDIS, BORV = 3
#pragma config WDT = OFF, WDTPS = 512
#pragma config MCLRE = ON, LPT1OSC = OFF, PBADEN = OFF, CCP2MX = PORTC
#pragma config STVREN = ON, LVP = OFF, XINST = OFF, DEBUG = OFF

/* The runtime's entry point (runtime_c/el_dispatch.c, or a test program's). */
void el_run(int argc, char **argv);

/* ---- reset, start ---- */

/* At the last byte of RAM, which the start-up code does not clear
 * (pic18_startup.c); a power-on leaves it undefined. */
EL_PIC18_ABSOLUTE(uint8_t el_pic18_kept, EL_PIC18_RAM_TOP);

static volatile uint32_t ticks;        /* LET ticks */
static volatile uint16_t isr_left;     /* Timer2 interrupts left in this tick */
static volatile uint16_t clock_high;   /* Timer1 overflows */

/* Channel 0..EL_PIC18_ADC_CHANNELS - 1 are analog (ADCON1's PCFG takes
 * AN0..ANn together); 0 channels: every pin digital. */
#define ADCON1_PCFG ((uint8_t)(EL_PIC18_ADC_CHANNELS == 0u ? 0x0Fu : 0x0Fu - EL_PIC18_ADC_CHANNELS))

static uint8_t reset_cause(void)
{
    uint8_t rcon = RCON;
    uint8_t cause;
    if ((rcon & 0x02u) == 0u) {        /* POR */
        cause = EL_PIC18_RESET_POWER;
    } else if ((rcon & 0x10u) == 0u) { /* RI: the RESET instruction */
        cause = EL_PIC18_RESET_SOFTWARE;
    } else if ((rcon & 0x08u) == 0u) { /* TO: the watchdog */
        cause = EL_PIC18_RESET_WATCHDOG;
    } else if ((rcon & 0x01u) == 0u) { /* BOR */
        cause = EL_PIC18_RESET_POWER;
    } else {
        cause = EL_PIC18_RESET_PIN;
    }
    RCON = (uint8_t)(rcon | 0x13u);   /* RI, POR, BOR set: the next reset shows its own cause */
    return cause;
}

uint8_t el_pic18_start(void)
{
    uint8_t cause = reset_cause();
    WDTCONbits.SWDTEN = 0;
    INTCON = 0u;
    RCONbits.IPEN = 0;
    ADCON1 = ADCON1_PCFG;
    CMCON = 0x07u;                     /* comparators off: RA0..RA3 digital or analog as ADCON1 says */
    ticks = 0u;
    isr_left = EL_PIC18_TICK_ISRS;
    clock_high = 0u;
    /* Timer1: instruction cycles, 16-bit reads, overflow interrupt. */
    T1CON = 0x80u;
    TMR1H = 0u;
    TMR1L = 0u;
    PIR1bits.TMR1IF = 0;
    PIE1bits.TMR1IE = 1;
    T1CONbits.TMR1ON = 1;
    /* Timer2: the tick (and the PWM period). */
    T2CON = EL_PIC18_TICK_T2CON;
    PR2 = EL_PIC18_TICK_PR2;
    TMR2 = 0u;
    PIR1bits.TMR2IF = 0;
    PIE1bits.TMR2IE = 1;
    T2CONbits.TMR2ON = 1;
    INTCONbits.PEIE = 1;
    INTCONbits.GIE = 1;
    WDTCONbits.SWDTEN = 1;
    return cause;
}

uint32_t el_pic18_ticks(void)
{
    uint32_t t;
    uint8_t gie = INTCONbits.GIE;
    INTCONbits.GIE = 0;
    t = ticks;
    INTCONbits.GIE = gie;
    return t;
}

void el_pic18_resync(uint32_t tick)
{
    uint8_t gie = INTCONbits.GIE;
    INTCONbits.GIE = 0;
    ticks = tick;
    isr_left = EL_PIC18_TICK_ISRS;
    TMR2 = 0u;                         /* clears the prescaler and the postscaler too */
    PIR1bits.TMR2IF = 0;
    INTCONbits.GIE = gie;
}

uint32_t el_pic18_clock(void)
{
    uint16_t high;
    uint8_t low, mid;
    uint8_t gie = INTCONbits.GIE;
    INTCONbits.GIE = 0;
    high = clock_high;
    low = TMR1L;                        /* latches TMR1H (RD16) */
    mid = TMR1H;
    if (PIR1bits.TMR1IF && mid < 0x80u) { /* an overflow not yet counted, before this reading */
        high++;
    }
    INTCONbits.GIE = gie;
    return (uint32_t)high << 16 | (uint16_t)((uint16_t)mid << 8 | low);
}

#if defined(EL_PIC18_I2C) && EL_PIC18_I2C
/* The same without touching GIE: only the I2C bus's jobs need it. */
uint32_t el_pic18_clock_isr(void)
{
    uint16_t high = clock_high;
    uint8_t low = TMR1L;
    uint8_t mid = TMR1H;
    if (PIR1bits.TMR1IF && mid < 0x80u) {
        high++;
    }
    return (uint32_t)high << 16 | (uint16_t)((uint16_t)mid << 8 | low);
}
#endif

uint8_t el_pic18_irq_save(void)
{
    uint8_t state = INTCON & 0x80u;
    INTCONbits.GIE = 0;
    return state;
}

void el_pic18_irq_restore(uint8_t state)
{
    if (state != 0u) {
        INTCONbits.GIE = 1;
    }
}

bool el_pic18_irq_enabled(void)
{
    return INTCONbits.GIE != 0;
}

void el_pic18_watchdog_kick(void)
{
    EL_PIC18_CLRWDT();
}

void el_pic18_reset(void)
{
    EL_PIC18_RESET();
}

void el_pic18_stop(void)
{
    INTCONbits.GIE = 0;
    WDTCONbits.SWDTEN = 0;
    for (;;) {
        EL_PIC18_SLEEP();
    }
}

/* ---- pins ---- */

#define PIN_MASK(pin) ((uint8_t)(1u << ((pin) & 7u)))

void el_pic18_pin_input(el_pic18_pin_t pin)
{
    uint8_t m = PIN_MASK(pin);
    switch (pin >> 3) {
    case 0u: TRISA |= m; break;
    case 1u: TRISB |= m; break;
    case 2u: TRISC |= m; break;
    case 3u: TRISD |= m; break;
    default: TRISE |= m; break;
    }
}

void el_pic18_pin_output(el_pic18_pin_t pin)
{
    uint8_t m = PIN_MASK(pin);
    uint8_t k = (uint8_t)~m;
    switch (pin >> 3) {
    case 0u: LATA &= k; TRISA &= k; break;
    case 1u: LATB &= k; TRISB &= k; break;
    case 2u: LATC &= k; TRISC &= k; break;
    case 3u: LATD &= k; TRISD &= k; break;
    default: LATE &= k; TRISE &= k; break;
    }
}

bool el_pic18_pin_read(el_pic18_pin_t pin)
{
    uint8_t v;
    switch (pin >> 3) {
    case 0u: v = PORTA; break;
    case 1u: v = PORTB; break;
    case 2u: v = PORTC; break;
    case 3u: v = PORTD; break;
    default: v = PORTE; break;
    }
    return (v & PIN_MASK(pin)) != 0u;
}

void el_pic18_pin_write(el_pic18_pin_t pin, bool level)
{
    uint8_t m = PIN_MASK(pin);
    if (level) {
        switch (pin >> 3) {
        case 0u: LATA |= m; break;
        case 1u: LATB |= m; break;
        case 2u: LATC |= m; break;
        case 3u: LATD |= m; break;
        default: LATE |= m; break;
        }
    } else {
        m = (uint8_t)~m;
        switch (pin >> 3) {
        case 0u: LATA &= m; break;
        case 1u: LATB &= m; break;
        case 2u: LATC &= m; break;
        case 3u: LATD &= m; break;
        default: LATE &= m; break;
        }
    }
}

/* ---- the ADC: right-justified, Tad = 64 Tosc (1.6 us), acquisition 4 Tad ---- */

/* The pin of each channel (40-pin parts). */
static const el_pic18_pin_t adc_pin[13] = {
    0x00u, 0x01u, 0x02u, 0x03u, 0x05u, 0x20u, 0x21u, 0x22u, /* RA0 RA1 RA2 RA3 RA5 RE0 RE1 RE2 */
    0x0Au, 0x0Bu, 0x09u, 0x0Cu, 0x08u                       /* RB2 RB3 RB1 RB4 RB0 */
};

void el_pic18_adc_open(uint8_t channel)
{
    if (channel < 13u) {
        el_pic18_pin_input(adc_pin[channel]);
    }
    ADCON2 = 0x96u; /* ADFM, ACQT 4 Tad, ADCS Fosc/64 */
    ADCON1 = ADCON1_PCFG;
    ADCON0 = 0x01u; /* ADON */
}

uint16_t el_pic18_adc_read(uint8_t channel)
{
    ADCON0 = (uint8_t)((channel & 0x0Fu) << 2 | 0x01u);
    ADCON0bits.GO = 1;
    while (ADCON0bits.GO) {
    }
    return (uint16_t)((uint16_t)ADRESH << 8 | ADRESL);
}

/* ---- PWM: CCP1 (RC2) and CCP2 (RC1, CCP2MX = PORTC) on Timer2 ---- */

/* 10-bit duty counts of a full period: 4 (PR2 + 1). */
#define PWM_FULL ((uint32_t)4u * ((uint32_t)EL_PIC18_TICK_PR2 + 1u))

void el_pic18_pwm_open(uint8_t ccp)
{
    if (ccp == 1u) {
        CCPR1L = 0u;
        CCP1CON = 0x0Cu;
        el_pic18_pin_output(0x12u); /* RC2 */
    } else {
        CCPR2L = 0u;
        CCP2CON = 0x0Cu;
        el_pic18_pin_output(0x11u); /* RC1 */
    }
}

void el_pic18_pwm_set(uint8_t ccp, uint8_t duty)
{
    /* round(duty * PWM_FULL / 255): x / 255 as (x + x / 256 + 1) / 256
     * with the rounding half added, exact below 2^24. */
    uint32_t x = (uint32_t)duty * PWM_FULL + 127u;
    uint16_t dc = (uint16_t)((x + (x >> 8) + 1u) >> 8);
    uint8_t low = (uint8_t)(0x0Cu | (uint8_t)((dc & 3u) << 4));
    uint8_t high = (uint8_t)(dc >> 2);
    if (ccp == 1u) {
        CCPR1L = high;
        CCP1CON = low;
    } else {
        CCPR2L = high;
        CCP2CON = low;
    }
}

/* ---- encoders: 4x quadrature counting in the pins' interrupts ---- */

#if EL_PIC18_ENCODERS > 0
/* Every interrupt pin is on PORTB: the interrupt reads PORTB once and
 * takes each encoder's bits by mask (no calls: a call in the interrupt
 * makes sdcc save its whole call context). */
typedef struct {
    uint8_t a_mask, b_mask; /* the pins' bits in PORTB */
    uint8_t last;           /* A << 1 | B */
    volatile int32_t count;
} encoder_t;

static encoder_t encoders[EL_PIC18_ENCODERS];
static uint8_t encoder_slots; /* slots opened */

/* Index: previous A B << 2 | new A B. */
static const int8_t encoder_steps[16] = {0, -1, 1, 0, 1, 0, 0, -1, -1, 0, 0, 1, 0, 1, -1, 0};

static uint8_t encoder_ab(const encoder_t *e, uint8_t portb)
{
    return (uint8_t)(((portb & e->a_mask) != 0u ? 2u : 0u) | ((portb & e->b_mask) != 0u ? 1u : 0u));
}

/* The external interrupts sense one edge: the other one next. */
static void int_edges(uint8_t portb)
{
    INTCON2bits.INTEDG0 = (portb & 0x01u) != 0u ? 0 : 1;
    INTCON2bits.INTEDG1 = (portb & 0x02u) != 0u ? 0 : 1;
    INTCON2bits.INTEDG2 = (portb & 0x04u) != 0u ? 0 : 1;
}

static void encoders_update(uint8_t portb)
{
    uint8_t i;
    for (i = 0u; i < encoder_slots; i++) {
        uint8_t ab = encoder_ab(&encoders[i], portb);
        if (ab != encoders[i].last) {
            encoders[i].count += encoder_steps[(uint8_t)(encoders[i].last << 2) | ab];
            encoders[i].last = ab;
        }
    }
}

/* An edge flagged and enabled (INT0..INT2, PORTB's change). */
static bool encoder_edge(void)
{
    return (INTCONbits.INT0IE && INTCONbits.INT0IF) || (INTCON3bits.INT1IE && INTCON3bits.INT1IF) ||
           (INTCON3bits.INT2IE && INTCON3bits.INT2IF) || (INTCONbits.RBIE && INTCONbits.RBIF);
}

static void pin_interrupt_on(el_pic18_pin_t pin)
{
    switch (pin) {
    case 0x08u: INTCONbits.INT0IF = 0; INTCONbits.INT0IE = 1; break;   /* RB0: INT0 */
    case 0x09u: INTCON3bits.INT1IF = 0; INTCON3bits.INT1IE = 1; break; /* RB1: INT1 */
    case 0x0Au: INTCON3bits.INT2IF = 0; INTCON3bits.INT2IE = 1; break; /* RB2: INT2 */
    default:                                                           /* RB4..RB7: change */
        (void)PORTB;
        INTCONbits.RBIF = 0;
        INTCONbits.RBIE = 1;
        break;
    }
}

void el_pic18_encoder_open(uint8_t slot, el_pic18_pin_t a, el_pic18_pin_t b)
{
    uint8_t state = el_pic18_irq_save();
    encoder_t *e = &encoders[slot];
    el_pic18_pin_input(a);
    el_pic18_pin_input(b);
    e->a_mask = PIN_MASK(a);
    e->b_mask = PIN_MASK(b);
    e->count = 0;
    e->last = encoder_ab(e, PORTB);
    if (encoder_slots <= slot) {
        encoder_slots = (uint8_t)(slot + 1u);
    }
    int_edges(PORTB);
    pin_interrupt_on(a);
    pin_interrupt_on(b);
    el_pic18_irq_restore(state);
}

int32_t el_pic18_encoder_count(uint8_t slot)
{
    int32_t n;
    uint8_t state = el_pic18_irq_save();
    n = encoders[slot].count;
    el_pic18_irq_restore(state);
    return n;
}
#endif

/* ---- the interrupt handler ---- */

void el_pic18_uart_isr(void); /* pic18_uart.c */

EL_PIC18_ISR(el_pic18_isr)
{
#if defined(EL_PIC18_I2C) && EL_PIC18_I2C
    bool tick = PIR1bits.TMR2IF;
#endif
    if (PIR1bits.TMR2IF) {
        PIR1bits.TMR2IF = 0;
        if (--isr_left == 0u) {
            isr_left = EL_PIC18_TICK_ISRS;
            ticks++;
        }
    }
    if (PIR1bits.TMR1IF) {
        PIR1bits.TMR1IF = 0;
        clock_high++;
    }
#if defined(EL_PIC18_UART_RX)
    if ((PIE1bits.RCIE && PIR1bits.RCIF) || (PIE1bits.TXIE && PIR1bits.TXIF)) {
        el_pic18_uart_isr();
    }
#endif
#if defined(EL_PIC18_I2C) && EL_PIC18_I2C
    if ((PIE1bits.SSPIE && PIR1bits.SSPIF) || (PIE2bits.BCLIE && PIR2bits.BCLIF) || (tick && el_pic18_i2c_parked)) {
        el_pic18_i2c_isr();
    }
#endif
#if EL_PIC18_ENCODERS > 0
    /* Until no edge is flagged and PORTB holds still: an edge during this
     * loop is counted in it (a flag raised inside the handler would wait
     * for the next interrupt, and the pin's next edge could come first).
     * The INTx flags are cleared before PORTB is read, RBIF after (the read
     * ends the change condition of RB4..RB7). */
    if (encoder_edge()) {
        uint8_t portb;
        do {
            INTCONbits.INT0IF = 0;
            INTCON3bits.INT1IF = 0;
            INTCON3bits.INT2IF = 0;
            portb = PORTB;
            INTCONbits.RBIF = 0;
            int_edges(portb);
            encoders_update(portb);
        } while (encoder_edge() || PORTB != portb);
    }
#endif
}

/* ---- the program (test programs bring their own el_run) ---- */

void main(void)
{
    el_run(0, (char **)0);
    el_pic18_stop();
}
