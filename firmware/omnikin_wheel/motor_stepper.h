/* motor_stepper.h: the stepper variant of the omnikin wheel controller (MOTOR_STEPPER=1, the
 * default: Tomasi and Todt drive each wheel with a NEMA 17 stepper motor).
 *
 * A STEP/DIR/ENABLE driver such as the A4988: one step per rising edge of STEP, direction from
 * DIR (set before the first step of a run), ENABLE active low. Wiring on the Nano: STEP on pin 9
 * (OC1A), DIR on pin 8, ENABLE on pin 7.
 *
 * Step generation. Timer1 runs in CTC mode and toggles OC1A at every compare match, so every STEP
 * edge is made by the timer hardware at an exact timer tick, whatever the interrupts are doing.
 * The compare interrupt only loads the length of the next half period into OCR1A; a fractional
 * accumulator (1/256 tick) alternates between the two nearest whole tick counts so that the mean
 * step rate is the commanded one to 1/256 of a tick, with at most one tick (0.5 us at clk/8) of
 * deliberate period jitter:
 *
 *     half period [ticks] = F_CPU / prescaler / (2 * rate),    rate [steps/s] = |w| * STEPS_PER_RAD
 *
 * clk/8 (0.5 us ticks) above 2e6 / 2 / 65536 = 15.3 steps/s, clk/64 (4 us) down to 1.9 steps/s,
 * below which the motor stands still. The rate follows the set-point with an acceleration limit
 * (STEP_ACCEL, wheel rad/s^2) applied at every control step, so a step change of the set-point
 * does not ask the motor for more torque than it has (a stepper that is asked too much loses
 * steps). Direction changes and prescaler changes restart the timer with DIR already set.
 * With the link alive the driver is enabled, also at zero speed (holding torque); a lost link or a
 * fault stops the steps at once and disables the driver.
 */
#ifndef OMNIKIN_MOTOR_STEPPER_H
#define OMNIKIN_MOTOR_STEPPER_H

#ifndef __AVR_ATmega328P__
#error "the stepper variant drives Timer1 of the ATmega328P (Arduino Nano/Uno); build the DC variant elsewhere"
#endif

#ifndef STEPS_PER_REV
#define STEPS_PER_REV 200      /* full steps per motor turn (1.8 deg NEMA 17) */
#endif
#ifndef MICROSTEPS
#define MICROSTEPS 8           /* the driver's MS1-MS3 setting */
#endif
#ifndef STEP_GEAR
#define STEP_GEAR 1.0f         /* motor turns per wheel turn (1: wheel on the motor shaft) */
#endif
#ifndef STEP_ACCEL
#define STEP_ACCEL 60.0f       /* wheel acceleration limit [rad/s^2] */
#endif
#ifndef PIN_ENABLE
#define PIN_ENABLE 7
#endif
#define PIN_STEP 9             /* OC1A: fixed by the timer that makes the edges */

#define STEPS_PER_RAD ((float)STEPS_PER_REV * (float)MICROSTEPS * STEP_GEAR / 6.2831853f)
static_assert(STEPS_PER_REV >= 1 && MICROSTEPS >= 1 && STEP_GEAR > 0.0f, "STEPS_PER_REV and MICROSTEPS must be >= 1, STEP_GEAR > 0");
static_assert(STEP_ACCEL > 0.0f, "STEP_ACCEL must be > 0 rad/s^2");
#define STEP_TICK_HZ_FAST (F_CPU / 8.0f)    /* clk/8 */
#define STEP_TICK_HZ_SLOW (F_CPU / 64.0f)   /* clk/64 */
#define STEP_CS_FAST (_BV(CS11))
#define STEP_CS_SLOW (_BV(CS11) | _BV(CS10))
#define STEP_RATE_MIN (STEP_TICK_HZ_SLOW / 2.0f / 65536.0f)   /* steps/s */

static float step_rate = 0.0f;              /* signed, ramped [steps/s] (positive: +wheel) */
static volatile uint16_t step_half = 0;     /* whole ticks of a half period */
static volatile uint8_t step_half_frac = 0; /* and its fraction [1/256 tick] */
static uint8_t step_frac_acc = 0;           /* used by the interrupt only */
static uint8_t step_cs = 0;                 /* running prescaler bits, 0 = stopped */
static uint8_t step_forward = 1;            /* DIR as last set */

ISR(TIMER1_COMPA_vect) {   /* right after a match (TCNT1 restarted at 0): load the next half period */
    uint16_t acc = (uint16_t)step_frac_acc + step_half_frac;
    step_frac_acc = (uint8_t)acc;
    OCR1A = (uint16_t)(step_half - 1u + (acc >> 8));
}

static void stepper_stop() {   /* no more edges: the timer's clock off */
    TCCR1B = _BV(WGM12);
    step_cs = 0;
}

/* Run the step generator at `rate` [steps/s, signed]. */
static void stepper_run(float rate) {
    float magnitude = rate >= 0.0f ? rate : -rate;
    uint8_t forward = (uint8_t)(rate >= 0.0f);
    uint8_t cs;
    float ticks;
    uint32_t q8;
    if (MOTOR_INVERT) forward = (uint8_t)!forward;
    if (magnitude < STEP_RATE_MIN) {
        stepper_stop();
        return;
    }
    ticks = STEP_TICK_HZ_FAST / (2.0f * magnitude);
    cs = STEP_CS_FAST;
    if (ticks > 65535.0f) {
        ticks = STEP_TICK_HZ_SLOW / (2.0f * magnitude);
        cs = STEP_CS_SLOW;
    }
    q8 = (uint32_t)(ticks * 256.0f + 0.5f);
    if (q8 < 512u) q8 = 512u;   /* 2 ticks: the compare interrupt must finish before the next match */
    noInterrupts();
    step_half = (uint16_t)(q8 >> 8);
    step_half_frac = (uint8_t)q8;
    if (cs != step_cs || forward != step_forward) {   /* (re)start with DIR settled */
        TCCR1B = _BV(WGM12);
        digitalWrite(PIN_DIR, forward ? HIGH : LOW);
        step_forward = forward;
        TCNT1 = 0;
        OCR1A = (uint16_t)(step_half - 1u);
        step_frac_acc = 0;
        TIFR1 = _BV(OCF1A);
        TCCR1B = (uint8_t)(_BV(WGM12) | cs);
        step_cs = cs;
    }
    interrupts();
}

static void drive_begin() {
    pinMode(PIN_ENABLE, OUTPUT);
    digitalWrite(PIN_ENABLE, HIGH);   /* disabled until the host speaks */
    pinMode(PIN_DIR, OUTPUT);
    digitalWrite(PIN_DIR, HIGH);
    pinMode(PIN_STEP, OUTPUT);
    noInterrupts();
    TCCR1A = _BV(COM1A0);             /* toggle OC1A on compare match (replaces the core's PWM set-up) */
    TCCR1B = _BV(WGM12);              /* CTC on OCR1A, stopped */
    TIMSK1 = _BV(OCIE1A);
    interrupts();
    step_cs = 0;
    step_forward = 1;
}

/* Steps stop at once and the driver lets go: link lost or fault. */
static void drive_off() {
    stepper_stop();
    step_rate = 0.0f;
    digitalWrite(PIN_ENABLE, HIGH);
}

/* One control step: ramp the step rate towards `target` [wheel rad/s] by at most STEP_ACCEL * dt. */
static void drive_control(float target, float measured, float dt) {
    float want = target * STEPS_PER_RAD;
    float dv = STEP_ACCEL * STEPS_PER_RAD * (dt < 0.05f ? dt : 0.05f);
    (void)measured;   /* open loop: the steps set the speed; the encoder reports it */
    if (want > step_rate + dv) step_rate += dv;
    else if (want < step_rate - dv) step_rate -= dv;
    else step_rate = want;
    digitalWrite(PIN_ENABLE, LOW);
    stepper_run(step_rate);
}

static uint8_t drive_enabled() { return (uint8_t)(digitalRead(PIN_ENABLE) == LOW); }

#endif /* OMNIKIN_MOTOR_STEPPER_H */
