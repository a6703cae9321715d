/* Counts rising edges of encoder A on INT0 (PD2); b_high counts those at which encoder B (PD3)
 * was high (turning backward). */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <stdint.h>

volatile uint32_t rising, b_high;

ISR(INT0_vect)
{
    rising++;
    if (PIND & _BV(PD3))
        b_high++;
}

int main(void)
{
    EICRA = _BV(ISC01) | _BV(ISC00); /* INT0 on rising edges */
    EIMSK = _BV(INT0);
    sei();
    for (;;) {
    }
}
