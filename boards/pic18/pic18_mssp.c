/* EasyLab PIC18 board: the MSSP as the I2C master of i2c[0] or the SPI
 * master of spi[0] (runtime_c/el_bus.h; docs/boards.md, "Buses"). The part
 * has one MSSP: a model uses it as one of the two (the board's check
 * refuses both), and el_pic18_config.h says which (EL_PIC18_I2C,
 * EL_PIC18_SPI).
 *
 * I2C (SDA RC4, SCL RC3, both inputs: the MSSP drives them open-drain;
 * external pull-ups belong on the bus): jobs wait in a queue (a list
 * through the callers' own job structures: no heap) and run one after the
 * other from the MSSP's interrupt (SSPIF), one step per interrupt: START,
 * the address, each byte written, a repeated START, each byte received and
 * its acknowledge, STOP. The MSSP takes one step at a time (a START only
 * once the STOP before it is done), so the state machine knows what it
 * asked for last. el_i2c_submit returns at once, and only el_i2c_wait
 * waits, at most EL_I2C_WAIT_US. A job whose chip does not acknowledge its
 * address goes back to the end of the queue when it asks for it
 * (EL_I2C_RETRY_BUSY: an EEPROM in its write cycle), for at most
 * EL_I2C_BUSY_US; when it is the only job it waits parked, the bus idle,
 * and is tried again at the next interrupt of the tick's timer (at least
 * every millisecond) or as soon as another job comes. A bus collision
 * (BCLIF) resets the MSSP and fails the job (EL_BUS_ERROR).
 *
 * SPI (SCK RC3 and SDO RC5 outputs, SDI RC4 input): a transfer is done in
 * place, byte after byte, polling BF: at Fosc / 16 (2.5 MHz) a byte takes
 * 32 instruction cycles, less than an interrupt per byte would cost. A chip
 * select is any pin (struct el_pin: the hardware layer's pin number). The
 * wait for a byte is bounded: an MSSP that never finishes one (switched
 * off under the transfer) gives EL_BUS_TIMEOUT.
 */
#include "el_pic18.h"
#include "pic18_hw.h"

#if (defined(EL_PIC18_I2C) && EL_PIC18_I2C) || (defined(EL_PIC18_SPI) && EL_PIC18_SPI)

#include "el_bus.h"

#define SSPEN 0x20u /* SSPCON1 */
#define CKP 0x10u
#define CKE 0x40u   /* SSPSTAT */

#endif

#if defined(EL_PIC18_I2C) && EL_PIC18_I2C

#define SSPM_I2C_MASTER 0x08u

/* What the MSSP was asked for last: the step its next SSPIF ends. */
#define STEP_IDLE 0u
#define STEP_START 1u   /* SEN, or RSEN (a repeated START) */
#define STEP_ADDRESS 2u /* the address byte */
#define STEP_WRITE 3u   /* a data byte written */
#define STEP_READ 4u    /* RCEN: a byte received */
#define STEP_ACK 5u     /* ACKEN: its acknowledge (or not, after the last) */
#define STEP_STOP 6u    /* PEN */

static el_i2c_job_t *volatile head; /* the job on the bus, then the queue */
static el_i2c_job_t *volatile tail;
static volatile uint8_t step;
static volatile uint8_t tx_at;      /* bytes of the head job sent */
static volatile uint8_t rx_at;      /* bytes of the head job received */
static volatile bool reading;       /* the head job is in its read part */
volatile bool el_pic18_i2c_parked;  /* the head job waits for its busy chip, the bus idle */
static volatile uint16_t failures;

#define CYCLES_PER_US (EL_PIC18_FCY / 1000000UL)
#define WAIT_CYCLES ((uint32_t)EL_I2C_WAIT_US * CYCLES_PER_US)
#define BUSY_CYCLES ((uint32_t)EL_I2C_BUSY_US * CYCLES_PER_US)

static void mssp_on(void)
{
    TRISC |= 0x18u; /* SCL (RC3) and SDA (RC4) inputs: the MSSP pulls them low */
    SSPSTAT = EL_PIC18_I2C_SSPSTAT; /* SMP: slew-rate control at 400 kHz only */
    SSPADD = EL_PIC18_I2C_SSPADD;
    SSPCON2 = 0u;
    SSPCON1 = (uint8_t)(SSPEN | SSPM_I2C_MASTER);
    PIR1bits.SSPIF = 0;
    PIR2bits.BCLIF = 0;
    PIE1bits.SSPIE = 1;
    PIE2bits.BCLIE = 1;
    step = STEP_IDLE;
}

/* The MSSP off and on again: the lines released, whatever it was doing. */
static void mssp_reset(void)
{
    SSPCON1 = 0u;
    mssp_on();
}

/* Put the head job on the bus: its START (the bus is idle). */
static void start_head(void)
{
    el_pic18_i2c_parked = false;
    tx_at = 0u;
    rx_at = 0u;
    reading = head->tx_len == 0u;
    step = STEP_START;
    SSPCON2bits.SEN = 1;
}

/* The bus is idle (after a STOP, a reset): the next job, if any is due. */
static void next_job(void)
{
    step = STEP_IDLE;
    if (head != 0 && !el_pic18_i2c_parked) {
        start_head();
    }
}

static void stop(void)
{
    step = STEP_STOP;
    SSPCON2bits.PEN = 1;
}

/* The head job is over: its status, then a STOP (the next job starts when
 * it is done) or, after a reset, the next job at once. Called from the
 * interrupt or with interrupts off. */
static void finish(el_bus_status_t status, bool with_stop)
{
    el_i2c_job_t *job = head;
    head = job->next;
    if (head == 0) {
        tail = 0;
    }
    job->next = 0;
    if (status != EL_BUS_DONE && failures != 0xFFFFu) {
        failures++;
    }
    job->status = status;
    if (with_stop) {
        stop();
    } else {
        next_job();
    }
}

/* The head job's chip did not acknowledge its address. */
static void not_acknowledged(void)
{
    el_i2c_job_t *job = head;
    if ((job->flags & EL_I2C_RETRY_BUSY) != 0u && el_pic18_clock_isr() - job->since < BUSY_CYCLES) {
        if (job->next != 0) { /* to the end of the queue: the others first */
            head = job->next;
            job->next = 0;
            tail->next = job;
            tail = job;
        } else { /* alone: STOP, and try again at the next tick's interrupt */
            el_pic18_i2c_parked = true;
        }
        stop();
        return;
    }
    finish(EL_BUS_NACK, true);
}

/* After the address or a byte written was acknowledged: the next byte,
 * the read part, or the end. */
static void after_write(void)
{
    el_i2c_job_t *job = head;
    if (tx_at < job->tx_len) {
        step = STEP_WRITE;
        SSPBUF = job->tx[tx_at];
        tx_at++;
    } else if (job->rx_len != 0u && !reading) {
        reading = true;
        step = STEP_START;
        SSPCON2bits.RSEN = 1;
    } else {
        finish(EL_BUS_DONE, true);
    }
}

void el_pic18_i2c_isr(void)
{
    el_i2c_job_t *job = head;
    if (PIR2bits.BCLIF) { /* a bus collision: the MSSP is idle again */
        PIR2bits.BCLIF = 0;
        PIR1bits.SSPIF = 0;
        mssp_reset();
        if (job != 0 && !el_pic18_i2c_parked) {
            finish(EL_BUS_ERROR, false);
        }
        return;
    }
    if (!PIR1bits.SSPIF) { /* the tick's interrupt: a parked job again */
        if (el_pic18_i2c_parked && step == STEP_IDLE) {
            start_head();
        }
        return;
    }
    PIR1bits.SSPIF = 0;
    if (step == STEP_STOP || job == 0) { /* a STOP done, or a job abandoned meanwhile */
        if (step != STEP_STOP) {
            stop();
        } else {
            next_job();
        }
        return;
    }
    switch (step) {
    case STEP_START:
        step = STEP_ADDRESS;
        SSPBUF = (uint8_t)((uint8_t)(job->address << 1) | (reading ? 1u : 0u));
        break;
    case STEP_ADDRESS:
        if (SSPCON2bits.ACKSTAT) {
            not_acknowledged();
        } else if (reading) {
            step = STEP_READ;
            SSPCON2bits.RCEN = 1;
        } else {
            after_write();
        }
        break;
    case STEP_WRITE:
        if (SSPCON2bits.ACKSTAT) {
            finish(EL_BUS_NACK, true);
        } else {
            after_write();
        }
        break;
    case STEP_READ:
        job->rx[rx_at] = SSPBUF;
        rx_at++;
        /* acknowledge every byte but the last */
        SSPCON2bits.ACKDT = rx_at < job->rx_len ? 0 : 1;
        step = STEP_ACK;
        SSPCON2bits.ACKEN = 1;
        break;
    case STEP_ACK:
        if (rx_at < job->rx_len) {
            step = STEP_READ;
            SSPCON2bits.RCEN = 1;
        } else {
            finish(EL_BUS_DONE, true);
        }
        break;
    default: /* SSPIF without a step: nothing asked for */
        break;
    }
}

bool el_i2c_submit(el_i2c_job_t *job)
{
    uint8_t irq;
    if (job->status == EL_BUS_PENDING) { /* queued already */
        return false;
    }
    if (job->bus != 0u || job->address > 0x7Fu || (job->rx_len != 0u && job->rx == 0) ||
        (job->tx_len != 0u && job->tx == 0)) {
        job->status = EL_BUS_ERROR;
        return false;
    }
    irq = el_pic18_irq_save();
    if ((SSPCON1 & SSPEN) == 0u) {
        mssp_on();
    }
    job->status = EL_BUS_PENDING;
    job->since = el_pic18_clock_isr(); /* interrupts are off */
    job->next = 0;
    if (head == 0) {
        head = job;
        tail = job;
        if (step == STEP_IDLE) {
            start_head();
        } /* else a STOP is under way: the job starts when it is done */
    } else if (el_pic18_i2c_parked) { /* this job first, the busy chip's after it */
        job->next = head;
        head = job;
        el_pic18_i2c_parked = false;
        if (step == STEP_IDLE) {
            start_head();
        }
    } else {
        tail->next = job;
        tail = job;
    }
    el_pic18_irq_restore(irq);
    return true;
}

/* Take a job that is still pending off the bus (interrupts off). */
static void abandon(el_i2c_job_t *job)
{
    el_i2c_job_t *j;
    if (job->status != EL_BUS_PENDING) {
        return;
    }
    if (head == job) {
        el_pic18_i2c_parked = false;
        mssp_reset(); /* stop the MSSP mid-transfer: the lines are released */
        finish(EL_BUS_TIMEOUT, false);
        return;
    }
    for (j = head; j != 0 && j->next != job; j = j->next) {
    }
    if (j != 0) {
        j->next = job->next;
        if (tail == job) {
            tail = j;
        }
    }
    job->next = 0;
    job->status = EL_BUS_TIMEOUT;
    if (failures != 0xFFFFu) {
        failures++;
    }
}

el_bus_status_t el_i2c_wait(el_i2c_job_t *job)
{
    uint32_t start = el_pic18_clock();
    while (job->status == EL_BUS_PENDING) {
        el_pic18_watchdog_kick();
        if (el_pic18_clock() - start > WAIT_CYCLES) {
            uint8_t irq = el_pic18_irq_save();
            abandon(job);
            el_pic18_irq_restore(irq);
        }
    }
    return job->status;
}

el_bus_status_t el_i2c_transfer(uint8_t bus, uint8_t address, const uint8_t *tx, uint8_t tx_len, uint8_t *rx,
                                uint8_t rx_len)
{
    el_i2c_job_t job;
    job.bus = bus;
    job.address = address;
    job.flags = 0u;
    job.tx = tx;
    job.tx_len = tx_len;
    job.rx = rx;
    job.rx_len = rx_len;
    job.status = EL_BUS_DONE;
    job.next = 0;
    if (!el_i2c_submit(&job)) {
        return job.status;
    }
    return el_i2c_wait(&job);
}

uint16_t el_i2c_errors(uint8_t bus)
{
    uint16_t n;
    uint8_t irq;
    if (bus != 0u) {
        return 0u;
    }
    irq = el_pic18_irq_save();
    n = failures;
    el_pic18_irq_restore(irq);
    return n;
}

#endif /* EL_PIC18_I2C */

#if defined(EL_PIC18_SPI) && EL_PIC18_SPI

/* Polls of BF a byte may take at the most: at Fosc / 64 a byte is 128
 * instruction cycles, a poll at least 4. */
#define SPI_POLLS 255u

static void spi_on(void)
{
    TRISC = (uint8_t)((TRISC & (uint8_t)~0x28u) | 0x10u); /* SCK (RC3), SDO (RC5) out; SDI (RC4) in */
    SSPSTAT = CKE;                                          /* mode 0 until a transfer says */
    SSPCON1 = (uint8_t)(SSPEN | EL_PIC18_SPI_SSPM);
}

/* A chip select an output at the level its LAT bit has (high): no pulse
 * low on the way (el_pic18_pin_output starts low). */
static void cs_output(el_pic18_pin_t pin)
{
    uint8_t k = (uint8_t)~(uint8_t)(1u << (pin & 7u));
    switch (pin >> 3) {
    case 0u: TRISA &= k; break;
    case 1u: TRISB &= k; break;
    case 2u: TRISC &= k; break;
    case 3u: TRISD &= k; break;
    default: TRISE &= k; break;
    }
}

el_bus_status_t el_spi_open(uint8_t bus, const el_pin_t *cs)
{
    if (bus != 0u || cs == 0) {
        return EL_BUS_ERROR;
    }
    if ((SSPCON1 & SSPEN) == 0u) {
        spi_on();
    }
    el_pic18_pin_write(cs->code, true); /* high first: selects nothing */
    cs_output(cs->code);
    return EL_BUS_DONE;
}

/* The clock's polarity (CKP) and phase (CKE: data out on the active-to-idle
 * edge) of an SPI mode. */
static void spi_mode(uint8_t mode)
{
    uint8_t ckp = (mode & 2u) != 0u ? CKP : 0u;
    uint8_t cke = (mode & 1u) == 0u ? CKE : 0u;
    if ((uint8_t)(SSPCON1 & CKP) != ckp || (uint8_t)(SSPSTAT & CKE) != cke) {
        SSPCON1 = (uint8_t)(SSPCON1 & (uint8_t)~SSPEN); /* CKE changes with the MSSP off */
        SSPSTAT = cke;
        SSPCON1 = (uint8_t)(SSPEN | ckp | EL_PIC18_SPI_SSPM);
    }
}

el_bus_status_t el_spi_transfer(uint8_t bus, const el_pin_t *cs, uint8_t mode, const uint8_t *tx, uint8_t *rx,
                                uint16_t len)
{
    uint16_t i;
    el_bus_status_t status = EL_BUS_DONE;
    if (el_spi_open(bus, cs) != EL_BUS_DONE) {
        return EL_BUS_ERROR;
    }
    spi_mode(mode);
    (void)SSPBUF; /* BF clear: nothing left from before */
    el_pic18_pin_write(cs->code, false); /* selected */
    for (i = 0u; i < len; i++) {
        uint8_t in;
        uint8_t polls = 0u;
        SSPBUF = tx != 0 ? tx[i] : 0xFFu;
        while (!SSPSTATbits.BF && polls < SPI_POLLS) {
            polls++;
        }
        if (!SSPSTATbits.BF) {
            status = EL_BUS_TIMEOUT;
            break;
        }
        in = SSPBUF;
        if (rx != 0) {
            rx[i] = in;
        }
    }
    el_pic18_pin_write(cs->code, true);
    return status;
}

#endif /* EL_PIC18_SPI */

#if !(defined(EL_PIC18_I2C) && EL_PIC18_I2C) && !(defined(EL_PIC18_SPI) && EL_PIC18_SPI)
typedef int el_pic18_mssp_unused_t; /* ISO C wants something here */
#endif
