/* motor_dc.h: the DC-motor variant of the omnikin wheel controller (build with MOTOR_STEPPER=0).
 *
 * A brushed DC motor behind a PWM + direction driver (an L298N or a VNH-style H-bridge): the
 * Arduino core's analogWrite on PIN_PWM (Timer1, phase-correct 8-bit PWM, 490 Hz on the Nano's
 * pin 9) sets the duty, PIN_DIR the direction. The wheel speed is closed with a PI loop and a
 * feed-forward term on the encoder-measured speed:
 *
 *     u = KFF * target + KP * (target - measured) + KI * integral(target - measured) dt   [PWM counts]
 *
 * clamped to +-PWM_MAX, the integral clamped the same way (anti-windup). A zero set-point
 * switches the motor off (no holding torque), as does a lost link.
 */
#ifndef OMNIKIN_MOTOR_DC_H
#define OMNIKIN_MOTOR_DC_H

#ifndef KP
#define KP 12.0f               /* PWM counts per rad/s of speed error */
#endif
#ifndef KI
#define KI 120.0f              /* PWM counts per rad of integrated error */
#endif
#ifndef KFF
#define KFF 6.0f               /* feed-forward PWM counts per rad/s of set-point */
#endif
#define PWM_MAX 255
static_assert(KP >= 0.0f && KI >= 0.0f && KFF >= 0.0f, "KP, KI and KFF must be >= 0");

static int16_t motor_output = 0;   /* signed PWM counts last written */
static float integral = 0.0f;      /* PWM counts */

static void motor(float u) {
    int16_t pwm;
    uint8_t forward;
    if (u > PWM_MAX) u = PWM_MAX;
    if (u < -PWM_MAX) u = -PWM_MAX;
    pwm = (int16_t)(u >= 0.0f ? u + 0.5f : u - 0.5f);
    motor_output = pwm;
    forward = (uint8_t)(pwm >= 0);
    if (MOTOR_INVERT) forward = (uint8_t)!forward;
    digitalWrite(PIN_DIR, forward ? HIGH : LOW);
    analogWrite(PIN_PWM, pwm >= 0 ? pwm : -pwm);
}

static void drive_begin() {
    pinMode(PIN_PWM, OUTPUT);
    pinMode(PIN_DIR, OUTPUT);
    motor(0.0f);
}

/* Motor off at once: link lost, fault, zero set-point. */
static void drive_off() {
    integral = 0.0f;
    motor(0.0f);
}

/* One step of the speed loop: target and measured wheel speeds [rad/s], dt [s]. */
static void drive_control(float target, float measured, float dt) {
    float error, u;
    if (target == 0.0f) {
        drive_off();
        return;
    }
    error = target - measured;
    integral += KI * error * dt;
    if (integral > PWM_MAX) integral = PWM_MAX;
    if (integral < -PWM_MAX) integral = -PWM_MAX;
    u = KFF * target + KP * error + integral;
    motor(u);
}

/* The driver is powered (for the heartbeat's MOTOR_ENABLED): a DC motor has no enable line. */
static uint8_t drive_enabled() { return 1; }

#endif /* OMNIKIN_MOTOR_DC_H */
