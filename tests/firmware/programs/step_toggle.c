/* Timer1 in CTC mode toggles OC1A (PB1 = STEP) at every compare match: a rising edge every
 * 2 (OCR1A + 1) PRESCALER cycles = 2 * 250 * 8 = 4000 cycles. DIR (PB0) high unless -DBACKWARD;
 * ENABLE (PD7) low unless -DDISABLED. */
#include <avr/io.h>

int main(void)
{
    DDRB = _BV(PB1) | _BV(PB0);
#ifndef BACKWARD
    PORTB = _BV(PB0);
#endif
    DDRD = _BV(PD7);
#ifdef DISABLED
    PORTD = _BV(PD7);
#endif
    OCR1A = 249;
    TCCR1A = _BV(COM1A0);             /* toggle OC1A on compare match */
    TCCR1B = _BV(WGM12) | _BV(CS11);  /* CTC, prescaler 8 */
    for (;;) {
    }
}
