/* fast_pin.h: reading and writing a pin in a few cycles, for interrupt handlers and timing probes.
 *
 * digitalRead/digitalWrite look the pin up in flash tables on every call (about 50-70 cycles on
 * the ATmega328P); a fast_pin_t holds the pin's port register and bit mask, looked up once, so a
 * read is one load and an AND. Off the AVR (the host builds of the tests) it falls back to the
 * Arduino calls, which the host's stand-in Arduino.h simulates.
 */
#ifndef OMNIKIN_FAST_PIN_H
#define OMNIKIN_FAST_PIN_H

#ifdef __AVR__
typedef struct {
    volatile uint8_t *in;   /* PINx */
    volatile uint8_t *out;  /* PORTx */
    uint8_t mask;
} fast_pin_t;

static inline fast_pin_t fast_pin(uint8_t pin) {
    fast_pin_t p;
    p.in = portInputRegister(digitalPinToPort(pin));
    p.out = portOutputRegister(digitalPinToPort(pin));
    p.mask = digitalPinToBitMask(pin);
    return p;
}
static inline uint8_t fast_read(const fast_pin_t *p) { return (uint8_t)((*p->in & p->mask) != 0); }
/* Call with interrupts off, or on a port no interrupt handler writes (read-modify-write). */
static inline void fast_write(const fast_pin_t *p, uint8_t level) {
    if (level) *p->out |= p->mask; else *p->out &= (uint8_t)~p->mask;
}
#else
typedef struct {
    uint8_t pin;
} fast_pin_t;

static inline fast_pin_t fast_pin(uint8_t pin) {
    fast_pin_t p;
    p.pin = pin;
    return p;
}
static inline uint8_t fast_read(const fast_pin_t *p) { return (uint8_t)(digitalRead(p->pin) != 0); }
static inline void fast_write(const fast_pin_t *p, uint8_t level) { digitalWrite(p->pin, level ? HIGH : LOW); }
#endif

#endif /* OMNIKIN_FAST_PIN_H */
