/* USART0 at 115200 baud (UBRR0 = 16, U2X0): sends the boot byte 'B', then echoes every byte.
 * Timer1 counts at F_CPU / 8: the arrival ticks of the first and the latest byte are kept. */
#include <avr/io.h>
#include <stdint.h>

volatile uint16_t received, first_tick, last_tick;

static void send(uint8_t b)
{
    while (!(UCSR0A & _BV(UDRE0))) {
    }
    UDR0 = b;
}

int main(void)
{
    TCCR1B = _BV(CS11); /* prescaler 8 */
    UBRR0 = 16;
    UCSR0A = _BV(U2X0);
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00); /* 8N1 */
    UCSR0B = _BV(RXEN0) | _BV(TXEN0);
    send('B');
    for (;;) {
        if (UCSR0A & _BV(RXC0)) {
            uint16_t now = TCNT1;
            uint8_t b = UDR0;
            if (received == 0)
                first_tick = now;
            last_tick = now;
            received++;
            send(b);
        }
    }
}
