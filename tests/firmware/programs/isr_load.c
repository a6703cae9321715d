/* Timer1 CTC compare match A every OCR1A + 1 = 2000 cycles; its ISR is naked: the vector's
 * jmp (3 cycles), BUSY_CYCLES, reti (4). The main loop touches no register the ISR uses. */
#include <avr/interrupt.h>
#include <avr/io.h>

#define BUSY_CYCLES 500

ISR(TIMER1_COMPA_vect, ISR_NAKED)
{
    __builtin_avr_delay_cycles(BUSY_CYCLES);
    reti();
}

int main(void)
{
    OCR1A = 1999;
    TCCR1B = _BV(WGM12) | _BV(CS10); /* CTC, prescaler 1 */
    TIMSK1 = _BV(OCIE1A);
    sei();
    for (;;) {
    }
}
