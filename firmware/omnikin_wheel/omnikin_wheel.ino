/* omnikin_wheel.ino: reference firmware of one omnikin wheel controller (Arduino Nano/Uno class,
 * ATmega328P at 16 MHz; firmware/Makefile builds it, docs/firmware.md gives its sizes and timing).
 *
 * One wheel per board, as the Arduino Nanos of Tomasi and Todt's robot: a quadrature encoder on the
 * interrupt pins, a motor driver, and the omnikin wheel protocol (docs/protocol.md; frame ids,
 * sizes, scales and timing come from omnikin_protocol.h, which is generated from
 * src/omnikin/runtime/protocol.yaml: never write them here as numbers). Two motor variants, chosen
 * at build time, speak the same protocol:
 *  - MOTOR_STEPPER=1 (default, the paper's NEMA 17): a STEP/DIR driver, timer-generated steps with
 *    an acceleration limit (motor_stepper.h);
 *  - MOTOR_STEPPER=0: a DC motor on PWM + direction with a PI speed loop (motor_dc.h).
 *
 * Behaviour:
 *  - boot: ERROR_REPORT RESET (counter and sequence numbers start at 0); motor off until the host speaks;
 *  - SPEED_CMD for WHEEL_INDEX: new set-point [rad/s], clamped to MAX_SPEED (ERROR_REPORT SPEED_CLAMPED);
 *  - every valid frame for WHEEL_INDEX keeps the link alive; frames for other wheels are ignored
 *    (several boards may share a bus); duplicate and out-of-order sequence numbers are dropped;
 *  - link loss (no valid frame for OMNIKIN_LINK_TIMEOUT_MS): set-point 0, motor off at once,
 *    ERROR_REPORT LINK_LOST; the host must send a new SPEED_CMD to move again;
 *  - the control step runs every CONTROL_PERIOD_US at a fixed rate and holds PIN_PROBE high while
 *    it runs (a scope, or the simulated board, measures the loop's period and load on that pin);
 *  - right after a control step, ENCODER_REPORT every OMNIKIN_REPORT_PERIOD_MS and HEARTBEAT every
 *    OMNIKIN_HEARTBEAT_PERIOD_MS; errors seen on the input (CRC, version, frame types this
 *    controller does not take) are counted and reported at most once per heartbeat period, so
 *    that no input makes the controller send more than the periodic frames and a few reports.
 *
 * Configuration: the #defines below (or -D flags, as firmware/Makefile passes them); they must
 * match the robot file (docs/conventions.md): the count reported is the raw counter of this
 * sketch, which the host converts with the robot file's ticks_per_rev, gear_ratio and invert.
 */
#include "omnikin_protocol.h"
#include "fast_pin.h"

/* ---- configuration ------------------------------------------------------------------------ */
#ifndef MOTOR_STEPPER
#define MOTOR_STEPPER 1        /* 1: STEP/DIR stepper driver (motor_stepper.h); 0: DC motor (motor_dc.h) */
#endif
#ifndef WHEEL_INDEX
#define WHEEL_INDEX 0          /* position of this wheel among the robot file's rolling wheels */
#endif
#ifndef TICKS_PER_REV
#define TICKS_PER_REV 600.0f   /* robot file encoder.ticks_per_rev: counts of THIS sketch per encoder turn */
#endif
#ifndef GEAR_RATIO
#define GEAR_RATIO 1.0f        /* robot file encoder.gear_ratio (encoder turns per wheel turn) */
#endif
#ifndef ENCODER_INVERT
#define ENCODER_INVERT 0       /* robot file encoder.invert */
#endif
#ifndef ENCODER_X4
#define ENCODER_X4 0           /* 1: count every edge of A and B (4 counts per pulse); 0: one count per pulse (A's edge where B is low) */
#endif
#ifndef MOTOR_INVERT
#define MOTOR_INVERT 0         /* 1 if a positive output turns the wheel negatively */
#endif
#ifndef MAX_SPEED
#define MAX_SPEED 30.0f        /* rad/s: robot file max_speed */
#endif
#ifndef PIN_ENC_A
#define PIN_ENC_A 2            /* Nano/Uno: the two external interrupt pins */
#define PIN_ENC_B 3
#endif
#ifndef PIN_PWM
#define PIN_PWM 9              /* DC variant: PWM (the stepper's STEP is OC1A, pin 9, too) */
#endif
#ifndef PIN_DIR
#define PIN_DIR 8
#endif
#ifndef PIN_PROBE
#define PIN_PROBE 14           /* A0: high during the control step */
#endif
#ifndef CONTROL_PERIOD_US
#define CONTROL_PERIOD_US 10000UL  /* speed loop period (100 Hz) */
#endif
#ifndef SPEED_FILTER
#define SPEED_FILTER 0.3f      /* weight of the newest speed sample in the low-pass filter */
#endif

/* Settings that would build into a controller that moves wrongly are refused at build time. */
static_assert(MAX_SPEED > 0.0f && MAX_SPEED <= 1000.0f, "MAX_SPEED must be in (0, 1000] rad/s");
static_assert(TICKS_PER_REV >= 1.0f && GEAR_RATIO > 0.0f, "TICKS_PER_REV must be >= 1 and GEAR_RATIO > 0");
static_assert(SPEED_FILTER > 0.0f && SPEED_FILTER <= 1.0f, "SPEED_FILTER must be in (0, 1]");
#if (MOTOR_STEPPER != 0 && MOTOR_STEPPER != 1) || (ENCODER_INVERT != 0 && ENCODER_INVERT != 1) \
    || (ENCODER_X4 != 0 && ENCODER_X4 != 1) || (MOTOR_INVERT != 0 && MOTOR_INVERT != 1)
#error "MOTOR_STEPPER, ENCODER_INVERT, ENCODER_X4 and MOTOR_INVERT must be 0 or 1"
#endif

#if MOTOR_STEPPER
#include "motor_stepper.h"
#else
#include "motor_dc.h"
#endif

static const float RAD_PER_TICK =
    (ENCODER_INVERT ? -1.0f : 1.0f) * 6.2831853f / (TICKS_PER_REV * GEAR_RATIO);

/* ---- encoder (interrupts) ------------------------------------------------------------------ */
static volatile uint32_t encoder_count = 0;   /* unsigned: wraps without undefined behaviour */
static volatile uint16_t encoder_glitches = 0;
static fast_pin_t enc_a, enc_b, probe;
#if ENCODER_X4
static volatile uint8_t encoder_state = 0;

static void encoder_isr() {
    static const int8_t step[16] = {0, -1, 1, 0, 1, 0, 0, -1, -1, 0, 0, 1, 0, 1, -1, 0};   /* [previous << 2 | now] */
    uint8_t now = (uint8_t)((fast_read(&enc_a) << 1) | fast_read(&enc_b));
    uint8_t idx = (uint8_t)((encoder_state << 2) | now);
    if ((encoder_state ^ now) == 3) encoder_glitches++;   /* both lines changed: an edge was missed */
    encoder_count += (uint32_t)(int32_t)step[idx];
    encoder_state = now;
}
#else
/* One count per cycle, at one place of it: the edge of A where B is low (quadrature states 0 and 1
 * of A = 0110, B = 0011). A rising there is a count forward, A falling there a count back, so a
 * wheel shaking on that edge counts +1 -1 +1 ...; counting only rising edges (forward with B low,
 * back with B high) counted every shake on the edge as a full turn of it forward. */
static void encoder_isr() {
    if (fast_read(&enc_b)) return;   /* the other edge of A */
    if (fast_read(&enc_a)) encoder_count += 1u; else encoder_count -= 1u;
}
#endif

static void latch_encoder(uint32_t *count, uint32_t *time_us) {
    noInterrupts();
    *count = encoder_count;
    *time_us = micros();
    interrupts();
}

/* ---- protocol state ------------------------------------------------------------------------- */
static omnikin_parser_t parser;
static omnikin_seq_t host_seq;
static uint8_t tx_seq = 0;
static uint8_t link_ok = 0;
static uint8_t fault = 0;
static uint32_t last_rx_ms = 0;
static uint32_t control_due_us = 0;    /* when the current control period began: steps every CONTROL_PERIOD_US */
static uint32_t last_control_us = 0;   /* when the last control step ran (its dt) */
static uint32_t last_count = 0;
static uint16_t unknown_types = 0;   /* frames for this wheel of a type it does not take */
static uint16_t reported_crc_errors = 0, reported_bad_version = 0, reported_glitches = 0, reported_unknown = 0;
static uint8_t clamp_pending = 0;
static float target = 0.0f;      /* rad/s */
static float measured = 0.0f;    /* rad/s, filtered */

static int32_t to_scaled(float value, float scale) {
    float x = value / scale;
    return (int32_t)(x >= 0.0f ? x + 0.5f : x - 0.5f);
}

/* Never wait for the UART: a frame that does not fit in the transmit buffer (64 bytes) is dropped
 * with its sequence number, so the host counts it as lost, and the control step keeps its period
 * (a blocking write held it up by up to a buffer's worth of bytes, 5.6 ms at 115200 baud). */
static void send(const uint8_t *frame, uint8_t n) {
    if (Serial.availableForWrite() >= n) Serial.write(frame, n);
}

static uint8_t format_uint(char *out, uint16_t v) {   /* decimal, no printf on the AVR */
    char tmp[6];
    uint8_t n = 0, i;
    do { tmp[n++] = (char)('0' + v % 10); v /= 10; } while (v && n < sizeof(tmp));
    for (i = 0; i < n; i++) out[i] = tmp[n - 1 - i];
    return n;
}

static void send_error(uint8_t code, const char *text, uint16_t number) {
    uint8_t frame[OMNIKIN_MAX_FRAME];
    omnikin_error_report_t m;
    uint8_t n = 0;
    m.wheel = WHEEL_INDEX;
    m.code = code;
    while (text[n] && n < OMNIKIN_ERROR_REPORT_TEXT_MAX - 6) { m.text[n] = text[n]; n++; }
    if (number) n = (uint8_t)(n + format_uint(m.text + n, number));
    m.text_len = n;
    send(frame, omnikin_encode_error_report(frame, tx_seq++, &m));
}

static void send_report() {
    uint8_t frame[OMNIKIN_MAX_FRAME];
    omnikin_encoder_report_t m;
    uint32_t count, time_us;
    latch_encoder(&count, &time_us);
    m.wheel = WHEEL_INDEX;
    m.time_us = time_us;
    m.count = (int32_t)count;
    m.speed = to_scaled(measured, OMNIKIN_ENCODER_REPORT_SPEED_SCALE);
    send(frame, omnikin_encode_encoder_report(frame, tx_seq++, &m));
}

static void send_heartbeat() {
    uint8_t frame[OMNIKIN_MAX_FRAME];
    omnikin_heartbeat_t m;
    m.wheel = WHEEL_INDEX;
    m.status = (uint8_t)((link_ok ? OMNIKIN_STATUS_LINK_OK : 0) |
                         (link_ok && !fault && drive_enabled() ? OMNIKIN_STATUS_MOTOR_ENABLED : 0) |
                         (fault ? OMNIKIN_STATUS_FAULT : 0));
    m.time_us = micros();
    send(frame, omnikin_encode_heartbeat(frame, tx_seq++, &m));
}

static void stop_motor() {
    target = 0.0f;
    drive_off();
}

/* A frame with a valid CRC and version is in parser.buf. */
static void handle_frame() {
    const uint8_t type = parser.buf[3];
    const uint8_t seq = parser.buf[4];
    const uint8_t len = parser.buf[5];
    const uint8_t *payload = parser.buf + OMNIKIN_HEADER_SIZE;
    uint8_t verdict;
    if (len < 1 || payload[0] != WHEEL_INDEX) return;   /* another wheel's frame */
    if (type != OMNIKIN_TYPE_SPEED_CMD && type != OMNIKIN_TYPE_HEARTBEAT) {
        unknown_types++;   /* reported once per heartbeat period: an answer per frame would crowd out the reports */
        return;
    }
    verdict = omnikin_seq_check(&host_seq, seq);
    if (verdict == OMNIKIN_SEQ_DUPLICATE || verdict == OMNIKIN_SEQ_OUT_OF_ORDER) return;
    if (type == OMNIKIN_TYPE_SPEED_CMD) {
        omnikin_speed_cmd_t m;
        float speed;
        if (!omnikin_unpack_speed_cmd(payload, len, &m)) return;
        speed = (float)m.speed * OMNIKIN_SPEED_CMD_SPEED_SCALE;
        if (speed > MAX_SPEED) { speed = MAX_SPEED; clamp_pending = 1; }
        if (speed < -MAX_SPEED) { speed = -MAX_SPEED; clamp_pending = 1; }
        target = speed;
    } else {
        omnikin_heartbeat_t m;
        if (!omnikin_unpack_heartbeat(payload, len, &m)) return;
    }
    link_ok = 1;
    last_rx_ms = millis();
}

static void control(uint32_t now_us) {
    float dt = (float)(now_us - last_control_us) * 1e-6f;
    uint32_t count, time_us;
    int32_t delta;
    fast_write(&probe, 1);
    last_control_us = now_us;
    control_due_us += CONTROL_PERIOD_US;   /* a fixed rate: a late step does not shift the next ones */
    if (now_us - control_due_us >= CONTROL_PERIOD_US) control_due_us = now_us;   /* fell behind */
    latch_encoder(&count, &time_us);
    delta = (int32_t)(count - last_count);
    last_count = count;
    if (dt > 0.0f) {
        measured += SPEED_FILTER * ((float)delta * RAD_PER_TICK / dt - measured);
        if (!link_ok || fault) drive_off();
        else drive_control(target, measured, dt);
    }
    fast_write(&probe, 0);
}

/* The periodic frames go out right after a control step, in the same loop pass: they never hold
 * a control step back (sending a report, a heartbeat and error reports takes about 0.5 ms), and
 * their periods are whole numbers of control periods. */
#define REPORT_TICKS (OMNIKIN_REPORT_PERIOD_MS * 1000UL / CONTROL_PERIOD_US)
#define HEARTBEAT_TICKS (OMNIKIN_HEARTBEAT_PERIOD_MS * 1000UL / CONTROL_PERIOD_US)
#if REPORT_TICKS < 1 || HEARTBEAT_TICKS < 1 || (OMNIKIN_REPORT_PERIOD_MS * 1000UL) % CONTROL_PERIOD_US != 0 \
    || (OMNIKIN_HEARTBEAT_PERIOD_MS * 1000UL) % CONTROL_PERIOD_US != 0
#error "CONTROL_PERIOD_US must divide the protocol's report and heartbeat periods"
#endif
static uint16_t report_ticks = 0, heartbeat_ticks = 0;

/* ERROR_REPORT `code` with the number of events counted since the last report, if any. */
static void report_new(uint8_t code, const char *text, uint16_t count, uint16_t *reported) {
    if (count == *reported) return;
    send_error(code, text, (uint16_t)(count - *reported));
    *reported = count;
}

static void send_periodic() {
    if (++report_ticks >= REPORT_TICKS) {
        report_ticks = 0;
        send_report();
    }
    if (++heartbeat_ticks < HEARTBEAT_TICKS) return;
    heartbeat_ticks = 0;
    send_heartbeat();
    report_new(OMNIKIN_ERR_CRC, "frames: ", parser.crc_errors, &reported_crc_errors);
    report_new(OMNIKIN_ERR_UNKNOWN_TYPE, "frames: ", unknown_types, &reported_unknown);
    report_new(OMNIKIN_ERR_BAD_VERSION, "frames: ", parser.bad_version, &reported_bad_version);
    report_new(OMNIKIN_ERR_ENCODER_FAULT, "missed edges: ", encoder_glitches, &reported_glitches);   /* read once */
    if (clamp_pending) {
        clamp_pending = 0;
        send_error(OMNIKIN_ERR_SPEED_CLAMPED, "", 0);
    }
}

void setup() {
    pinMode(PIN_ENC_A, INPUT_PULLUP);
    pinMode(PIN_ENC_B, INPUT_PULLUP);
    pinMode(PIN_PROBE, OUTPUT);
    enc_a = fast_pin(PIN_ENC_A);
    enc_b = fast_pin(PIN_ENC_B);
    probe = fast_pin(PIN_PROBE);
    fast_write(&probe, 0);
    drive_begin();
#if ENCODER_X4
    encoder_state = (uint8_t)((fast_read(&enc_a) << 1) | fast_read(&enc_b));
    attachInterrupt(digitalPinToInterrupt(PIN_ENC_A), encoder_isr, CHANGE);
    attachInterrupt(digitalPinToInterrupt(PIN_ENC_B), encoder_isr, CHANGE);
#else
    attachInterrupt(digitalPinToInterrupt(PIN_ENC_A), encoder_isr, CHANGE);
#endif
    Serial.begin(OMNIKIN_BAUD);
    omnikin_parser_init(&parser);
    memset(&host_seq, 0, sizeof(host_seq));
    last_control_us = control_due_us = micros();
    send_error(OMNIKIN_ERR_RESET, "boot", 0);
}

void loop() {
    uint32_t now_ms, now_us;
    while (Serial.available() > 0) {
        if (omnikin_parse_byte(&parser, (uint8_t)Serial.read())) handle_frame();
    }
    now_ms = millis();
    now_us = micros();
    if (link_ok && now_ms - last_rx_ms > OMNIKIN_LINK_TIMEOUT_MS) {
        link_ok = 0;
        stop_motor();
        memset(&host_seq, 0, sizeof(host_seq));   /* a restarted host starts a new sequence */
        send_error(OMNIKIN_ERR_LINK_LOST, "host silent; motor off", 0);
    }
    if (now_us - control_due_us >= CONTROL_PERIOD_US) {
        control(now_us);
        send_periodic();
    }
}
