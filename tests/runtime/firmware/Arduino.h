/* Arduino.h for host builds of firmware/omnikin_wheel (tests only): the Arduino API the sketch
 * uses, on a simulated clock, with pins, PWM, external interrupts and a serial port whose
 * input is scheduled by the test and whose output is recorded with its time. One translation
 * unit only (the globals are defined here). */
#ifndef OMNIKIN_TEST_ARDUINO_H
#define OMNIKIN_TEST_ARDUINO_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <utility>
#include <vector>

#define HIGH 1
#define LOW 0
#define INPUT 0
#define OUTPUT 1
#define INPUT_PULLUP 2
#define CHANGE 1
#define FALLING 2
#define RISING 3

namespace sim {
uint64_t now_us = 0;
int pins[32];
int pin_modes[32];
int pwm[32];
void (*isr[2])() = {nullptr, nullptr};
int isr_mode[2] = {0, 0};
const int isr_pin[2] = {2, 3};
std::vector<uint8_t> rx;
size_t rx_pos = 0;
std::vector<std::pair<uint64_t, std::vector<uint8_t> > > tx;

/* Change an input pin as the hardware would, firing attached interrupts. */
void set_pin(int pin, int level) {
    int old = pins[pin];
    pins[pin] = level;
    for (int n = 0; n < 2; n++) {
        if (!isr[n] || isr_pin[n] != pin || old == level) continue;
        if (isr_mode[n] == CHANGE || (isr_mode[n] == RISING && level) || (isr_mode[n] == FALLING && !level)) isr[n]();
    }
}
}  // namespace sim

inline unsigned long millis() { return (unsigned long)((sim::now_us / 1000u) & 0xFFFFFFFFu); }
inline unsigned long micros() { return (unsigned long)(sim::now_us & 0xFFFFFFFFu); }
inline void pinMode(int pin, int mode) {
    sim::pin_modes[pin] = mode;
    if (mode == INPUT_PULLUP) sim::pins[pin] = HIGH;
}
inline int digitalRead(int pin) { return sim::pins[pin]; }
inline void digitalWrite(int pin, int value) { sim::pins[pin] = value ? HIGH : LOW; }
inline void analogWrite(int pin, int value) { sim::pwm[pin] = value; }
inline int digitalPinToInterrupt(int pin) { return pin == 2 ? 0 : (pin == 3 ? 1 : -1); }
inline void attachInterrupt(int n, void (*f)(), int mode) {
    sim::isr[n] = f;
    sim::isr_mode[n] = mode;
}
inline void noInterrupts() {}
inline void interrupts() {}

struct SerialPort {
    void begin(unsigned long) {}
    int available() { return (int)(sim::rx.size() - sim::rx_pos); }
    int read() { return sim::rx_pos < sim::rx.size() ? sim::rx[sim::rx_pos++] : -1; }
    size_t write(const uint8_t *data, size_t n) {
        sim::tx.push_back(std::make_pair(sim::now_us, std::vector<uint8_t>(data, data + n)));
        return n;
    }
    size_t write(uint8_t b) { return write(&b, 1); }
    int availableForWrite() { return 63; }  /* the core's 64-byte ring buffer, empty */
};
SerialPort Serial;

#endif
