/* Runs firmware/omnikin_wheel/omnikin_wheel.ino on the host against a simulated DC motor and
 * quadrature encoder (tests/runtime/test_protocol.py builds and drives it).
 *
 *   sim_main SCHEDULE DURATION_US [STEP_US]
 *
 * SCHEDULE: lines "<time_us> <hex bytes>": bytes arriving on the serial input at that time.
 * Output: "TX <time_us> <hex>" for every Serial.write, "STATE <time_us> <wheel speed rad/s>
 * <pwm output> <encoder count>" every 10 ms. */
#include "Arduino.h"
#include "omnikin_wheel.ino"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static const double MOTOR_SPEED_AT_FULL_PWM = 40.0; /* rad/s */
static const double MOTOR_TAU = 0.05;               /* s */

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: %s SCHEDULE DURATION_US [STEP_US]\n", argv[0]);
        return 2;
    }
    std::vector<std::pair<uint64_t, std::vector<uint8_t> > > schedule;
    FILE *f = fopen(argv[1], "r");
    if (!f) { perror(argv[1]); return 2; }
    char line[8192];
    while (fgets(line, sizeof line, f)) {
        char *p = line;
        uint64_t t = strtoull(p, &p, 10);
        std::vector<uint8_t> bytes;
        for (;;) {
            while (*p == ' ') p++;
            if (!isxdigit((unsigned char)p[0]) || !isxdigit((unsigned char)p[1])) break;
            char hex[3] = {p[0], p[1], 0};
            bytes.push_back((uint8_t)strtoul(hex, nullptr, 16));
            p += 2;
        }
        schedule.push_back(std::make_pair(t, bytes));
    }
    fclose(f);
    const uint64_t duration = strtoull(argv[2], nullptr, 10);
    const uint64_t step = argc > 3 ? strtoull(argv[3], nullptr, 10) : 20;
    /* quadrature states per wheel radian, in the encoder's own direction */
    const double states_per_rad = TICKS_PER_REV * GEAR_RATIO * (ENCODER_X4 ? 1.0 : 4.0) / 6.283185307179586;
    const double encoder_sign = ENCODER_INVERT ? -1.0 : 1.0;
    const double motor_sign = MOTOR_INVERT ? -1.0 : 1.0;
    static const int quad_a[4] = {0, 1, 1, 0}, quad_b[4] = {0, 0, 1, 1};
    double omega = 0.0, angle = 0.0;
    long quad = 0;
    sim::pins[PIN_ENC_A] = 0;
    sim::pins[PIN_ENC_B] = 0;
    setup();
    sim::set_pin(PIN_ENC_A, 0);
    sim::set_pin(PIN_ENC_B, 0);
    size_t next = 0;
    for (sim::now_us = 0; sim::now_us <= duration; sim::now_us += step) {
        while (next < schedule.size() && schedule[next].first <= sim::now_us) {
            sim::rx.insert(sim::rx.end(), schedule[next].second.begin(), schedule[next].second.end());
            next++;
        }
        /* motor: first order, PWM and DIR pins */
        double dir = (sim::pins[PIN_DIR] == HIGH ? 1.0 : -1.0) * motor_sign;
        double drive = dir * sim::pwm[PIN_PWM] / 255.0 * MOTOR_SPEED_AT_FULL_PWM;
        double dt = step * 1e-6;
        omega += (drive - omega) * dt / MOTOR_TAU;
        angle += omega * dt;
        long want = (long)floor(encoder_sign * angle * states_per_rad);
        while (quad != want) {
            quad += quad < want ? 1 : -1;
            int s = (int)(((quad % 4) + 4) % 4);
            if (sim::pins[PIN_ENC_A] != quad_a[s]) sim::set_pin(PIN_ENC_A, quad_a[s]);
            if (sim::pins[PIN_ENC_B] != quad_b[s]) sim::set_pin(PIN_ENC_B, quad_b[s]);
        }
        loop();
        if (sim::now_us % 10000 == 0)
            printf("STATE %llu %.6f %d %ld\n", (unsigned long long)sim::now_us, omega, (int)motor_output,
                   (long)(int32_t)encoder_count);
    }
    for (size_t i = 0; i < sim::tx.size(); i++) {
        printf("TX %llu ", (unsigned long long)sim::tx[i].first);
        for (size_t k = 0; k < sim::tx[i].second.size(); k++) printf("%02x", sim::tx[i].second[k]);
        printf("\n");
    }
    return 0;
}
