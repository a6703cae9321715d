/* A pulse train on PC0 (the probe) counted in cycles: sbi (2) + HIGH_CYCLES + cbi (2) +
 * LOW_CYCLES + rjmp (2) per period; the pin is high from the sbi to the cbi. */
#include <avr/io.h>

#define HIGH_CYCLES 3000
#define LOW_CYCLES 7000

int main(void)
{
    DDRC = _BV(PC0);
    for (;;) {
        PORTC |= _BV(PC0);
        __builtin_avr_delay_cycles(HIGH_CYCLES);
        PORTC &= ~_BV(PC0);
        __builtin_avr_delay_cycles(LOW_CYCLES);
    }
}
