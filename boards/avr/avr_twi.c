/* EasyLab AVR board: the I2C bus i2c[0] on the TWI, master only
 * (runtime_c/el_bus.h; docs/boards.md, "Buses").
 *
 * Jobs wait in a queue (a list through the callers' own job structures:
 * no heap) and run one after the other from the TWI interrupt, so a
 * transfer never holds the CPU: el_i2c_submit returns at once, and only
 * el_i2c_wait waits, at most EL_I2C_WAIT_US. A job whose chip does not
 * acknowledge its address goes back to the end of the queue when it asks
 * for it (EL_I2C_RETRY_BUSY: an EEPROM in its write cycle), for at most
 * EL_I2C_BUSY_US; so a page written to an EEPROM never delays a sensor's
 * read by more than the transfer on the bus at that moment. When it is the
 * only job it waits parked, the bus idle, and is tried again at the next
 * interrupt of the tick's timer (el_avr_twi_poll: at least every
 * millisecond) or as soon as another job comes: polling a busy chip never
 * keeps the CPU in the TWI's interrupt.
 *
 * The bus runs at EL_AVR_I2C_HZ (el_avr_config.h, from board.toml) with the
 * pins' internal pull-ups on (external 4.7 kOhm pull-ups belong on a real
 * bus). Status codes are the ATmega's (TWSR & 0xF8). Debian's simavr 1.6
 * reports an acknowledged SLA+W as 0x28 and an unacknowledged one as 0x30
 * (a data byte's codes): the state machine tells them apart by what it
 * has sent, so both simavr and the chip work.
 */
#include "avr_internal.h"

#if defined(EL_AVR_I2C) && EL_AVR_I2C

#include "el_bus.h"
#include "el_port.h"

#include <avr/wdt.h>

#define TWCR_NEXT (_BV(TWINT) | _BV(TWEN) | _BV(TWIE))
#define TWCR_START (TWCR_NEXT | _BV(TWSTA))
#define TWCR_STOP (_BV(TWINT) | _BV(TWEN) | _BV(TWSTO))
#define TWCR_STOP_START (TWCR_START | _BV(TWSTO))

/* TWBR for the bus clock, prescaler 1: SCL = F_CPU / (16 + 2 TWBR). */
#define EL_AVR_TWBR ((F_CPU / EL_AVR_I2C_HZ - 16UL) / 2UL)
#if EL_AVR_TWBR > 255UL
#error "EL_AVR_I2C_HZ is too slow for the TWI with prescaler 1"
#endif

static el_i2c_job_t *volatile head; /* the job on the bus, then the queue */
static el_i2c_job_t *volatile tail;
static volatile uint8_t tx_at;      /* bytes of the head job sent */
static volatile uint8_t rx_at;      /* bytes of the head job received */
static volatile bool reading;       /* the head job is in its read part */
static volatile bool parked;        /* the head job waits for its busy chip, the bus idle */
static volatile uint16_t failures;
static uint32_t busy_bound;         /* EL_I2C_BUSY_US in fine-clock periods */

static void twi_on(void)
{
    EL_AVR_I2C_PORT |= EL_AVR_I2C_PULLUPS; /* SDA and SCL pulled up */
    TWSR = 0u;                             /* prescaler 1 */
    TWBR = (uint8_t)EL_AVR_TWBR;
    TWCR = _BV(TWEN);
    busy_bound = el_avr_clock_from_us(EL_I2C_BUSY_US);
}

/* Put the head job on the bus (STOP first when one is due). */
static void start_head(bool after_stop)
{
    parked = false;
    tx_at = 0u;
    rx_at = 0u;
    reading = head->tx_len == 0u;
    TWCR = after_stop ? TWCR_STOP_START : TWCR_START;
}

/* The head job is over: its status, then the next job or STOP. Called
 * from the interrupt or with interrupts off. */
static void finish(el_bus_status_t status, bool stop)
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
    if (head != 0) {
        start_head(stop);
    } else if (stop) {
        TWCR = TWCR_STOP;
    }
}

/* The head job's chip did not acknowledge its address. */
static void not_acknowledged(void)
{
    el_i2c_job_t *job = head;
    if ((job->flags & EL_I2C_RETRY_BUSY) != 0u && el_avr_clock() - job->since < busy_bound) {
        if (job->next != 0) { /* to the end of the queue: the others first */
            head = job->next;
            job->next = 0;
            tail->next = job;
            tail = job;
            start_head(true);
        } else { /* alone: STOP, and try again at the next poll */
            TWCR = TWCR_STOP;
            parked = true;
        }
        return;
    }
    finish(EL_BUS_NACK, true);
}

void el_avr_twi_poll(void)
{
    if (parked) {
        start_head(false);
    }
}

ISR(TWI_vect)
{
    el_i2c_job_t *job = head;
    uint8_t status = (uint8_t)(TWSR & 0xF8u);
    if (job == 0) { /* abandoned meanwhile */
        TWCR = TWCR_STOP;
        return;
    }
    switch (status) {
    case 0x08u: /* START */
    case 0x10u: /* repeated START */
        TWDR = (uint8_t)((uint8_t)(job->address << 1) | (reading ? 1u : 0u));
        TWCR = TWCR_NEXT;
        break;
    case 0x18u: /* SLA+W acknowledged */
    case 0x28u: /* a data byte acknowledged (simavr: SLA+W too) */
        if (tx_at < job->tx_len) {
            TWDR = job->tx[tx_at];
            tx_at++;
            TWCR = TWCR_NEXT;
        } else if (job->rx_len != 0u) {
            reading = true;
            TWCR = TWCR_START;
        } else {
            finish(EL_BUS_DONE, true);
        }
        break;
    case 0x20u: /* SLA+W not acknowledged */
    case 0x30u: /* a data byte not acknowledged (simavr: SLA+W too) */
        if (tx_at == 0u) {
            not_acknowledged();
        } else {
            finish(EL_BUS_NACK, true);
        }
        break;
    case 0x48u: /* SLA+R not acknowledged */
        not_acknowledged();
        break;
    case 0x40u: /* SLA+R acknowledged: acknowledge every byte but the last */
        TWCR = job->rx_len > 1u ? (uint8_t)(TWCR_NEXT | _BV(TWEA)) : (uint8_t)TWCR_NEXT;
        break;
    case 0x50u: /* a byte received and acknowledged */
        job->rx[rx_at] = TWDR;
        rx_at++;
        TWCR = (uint8_t)(rx_at + 1u) < job->rx_len ? (uint8_t)(TWCR_NEXT | _BV(TWEA)) : (uint8_t)TWCR_NEXT;
        break;
    case 0x58u: /* the last byte received */
        job->rx[rx_at] = TWDR;
        rx_at++;
        finish(EL_BUS_DONE, true);
        break;
    default: /* 0x38 arbitration lost, 0x00 bus error: reset the TWI */
        TWCR = 0u;
        twi_on();
        finish(EL_BUS_ERROR, false);
        break;
    }
}

bool el_i2c_submit(el_i2c_job_t *job)
{
    el_irq_state_t irq;
    if (job->status == EL_BUS_PENDING) { /* queued already */
        return false;
    }
    if (job->bus != 0u || job->address > 0x7Fu || (job->rx_len != 0u && job->rx == 0) ||
        (job->tx_len != 0u && job->tx == 0)) {
        job->status = EL_BUS_ERROR;
        return false;
    }
    irq = el_port_irq_save();
    if ((TWCR & _BV(TWEN)) == 0u) {
        twi_on();
    }
    job->status = EL_BUS_PENDING;
    job->since = el_avr_clock();
    job->next = 0;
    if (head == 0) {
        head = job;
        tail = job;
        start_head(false);
    } else if (parked) { /* the bus is idle: this job first, the busy chip's after it */
        job->next = head;
        head = job;
        start_head(false);
    } else {
        tail->next = job;
        tail = job;
    }
    el_port_irq_restore(irq);
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
        parked = false;
        TWCR = 0u; /* stop the TWI mid-transfer: the lines are released */
        twi_on();
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
    uint32_t start = el_avr_clock();
    uint32_t bound = el_avr_clock_from_us(EL_I2C_WAIT_US);
    while (job->status == EL_BUS_PENDING) {
        wdt_reset();
        if (el_avr_clock() - start > bound) {
            el_irq_state_t irq = el_port_irq_save();
            abandon(job);
            el_port_irq_restore(irq);
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
    el_irq_state_t irq;
    if (bus != 0u) {
        return 0u;
    }
    irq = el_port_irq_save();
    n = failures;
    el_port_irq_restore(irq);
    return n;
}

#else
typedef int el_avr_twi_unused_t; /* ISO C wants something here */
#endif /* EL_AVR_I2C */
