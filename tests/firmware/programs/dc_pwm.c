/* analogWrite(9, 128) as the Arduino core does it: Timer1 phase-correct 8-bit PWM, prescaler
 * 64, OC1A (PB1) non-inverting (COM1A1), OCR1A = 128; DIR (PB0) high. */
#include <avr/io.h>

int main(void)
{
    DDRB = _BV(PB1) | _BV(PB0);
    PORTB = _BV(PB0);
    TCCR1A = _BV(WGM10);
    TCCR1B = _BV(CS11) | _BV(CS10);
    OCR1A = 128;
    TCCR1A |= _BV(COM1A1);
    for (;;) {
    }
}
