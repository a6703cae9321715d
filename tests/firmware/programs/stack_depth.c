/* Known stack use: main records SP, takes ALLOCA_BYTES with alloca and records SP again;
 * then a recursion DEPTH deep records SP at every level (level_sp[d], d = DEPTH at the top). */
#include <alloca.h>
#include <avr/io.h>
#include <stdint.h>

#define ALLOCA_BYTES 300
#define DEPTH 10

volatile uint16_t sp_before_alloca, sp_after_alloca, level_sp[DEPTH + 1];
volatile uint8_t done;

__attribute__((noinline)) uint8_t descend(uint8_t d)
{
    volatile uint8_t frame[24];
    frame[0] = d;
    level_sp[d] = SP;
    if (d == 0)
        return frame[0];
    return (uint8_t)(descend(d - 1) + frame[0]);
}

int main(void)
{
    sp_before_alloca = SP;
    volatile uint8_t *block = alloca(ALLOCA_BYTES);
    block[0] = 1;
    block[ALLOCA_BYTES - 1] = 2;
    sp_after_alloca = SP;
    done = descend(DEPTH);
    for (;;) {
    }
}
