/* omnikin_protocol.h: the omnikin wheel-controller protocol for C and C++ (Arduino).
 *
 * GENERATED from src/omnikin/runtime/protocol.yaml by
 *   python -m omnikin.runtime.protocol --header > firmware/omnikin_wheel/omnikin_protocol.h
 * Do not edit: change protocol.yaml and regenerate. Specification: docs/protocol.md.
 */
#ifndef OMNIKIN_PROTOCOL_H
#define OMNIKIN_PROTOCOL_H

#include <stdint.h>
#include <string.h>

#define OMNIKIN_PROTOCOL_VERSION 1
#define OMNIKIN_SYNC_0 0xAA
#define OMNIKIN_SYNC_1 0x55
#define OMNIKIN_SYNC_SIZE 2
#define OMNIKIN_HEADER_SIZE 6 /* sync, version, type, sequence, length */
#define OMNIKIN_CRC_SIZE 2
#define OMNIKIN_MAX_PAYLOAD 64
#define OMNIKIN_MAX_FRAME (OMNIKIN_HEADER_SIZE + OMNIKIN_MAX_PAYLOAD + OMNIKIN_CRC_SIZE)
#define OMNIKIN_WHEEL_INDEX_MAX 254
#define OMNIKIN_SEQ_RESYNC_AFTER 3
#define OMNIKIN_COUNTER_BITS 32

/* serial link */
#define OMNIKIN_BAUD 115200UL

/* timing [ms] */
#define OMNIKIN_HEARTBEAT_PERIOD_MS 100UL
#define OMNIKIN_REPORT_PERIOD_MS 20UL
#define OMNIKIN_LINK_TIMEOUT_MS 500UL
#define OMNIKIN_CONNECT_TIMEOUT_MS 3000UL

/* CRC-16/CCITT-FALSE: version, type, sequence, length and payload (every byte after the sync, before the CRC) */
#define OMNIKIN_CRC_POLY 0x1021u
#define OMNIKIN_CRC_INIT 0xFFFFu
#define OMNIKIN_CRC_XOROUT 0x0000u
#define OMNIKIN_CRC_CHECK 0x29B1u /* of the ASCII bytes "123456789" */

/* frame types */
#define OMNIKIN_TYPE_SPEED_CMD 0x01 /* host to controller */
#define OMNIKIN_TYPE_ENCODER_REPORT 0x02 /* controller to host */
#define OMNIKIN_TYPE_ERROR_REPORT 0x03 /* controller to host */
#define OMNIKIN_TYPE_HEARTBEAT 0x04 /* both */

/* error codes (ERROR_REPORT.code) */
#define OMNIKIN_ERR_LINK_LOST 1 /* no valid frame from the host within link_timeout; the motor was stopped */
#define OMNIKIN_ERR_CRC 2 /* the controller received a frame whose CRC failed */
#define OMNIKIN_ERR_BAD_VERSION 3 /* the controller received a frame of another protocol version */
#define OMNIKIN_ERR_UNKNOWN_TYPE 4 /* the controller received a frame type it does not know */
#define OMNIKIN_ERR_SPEED_CLAMPED 5 /* a commanded speed was beyond the controller's limit and was clamped */
#define OMNIKIN_ERR_MOTOR_FAULT 6 /* motor driver fault or stall; the motor was stopped */
#define OMNIKIN_ERR_ENCODER_FAULT 7 /* impossible encoder transition or speed */
#define OMNIKIN_ERR_RESET 8 /* the controller (re)started: its counter and sequence numbers restart from 0 */
#define OMNIKIN_ERR_OTHER 255 /* see the text */

/* status flags (HEARTBEAT.status), bit masks */
#define OMNIKIN_STATUS_LINK_OK 0x01 /* the controller hears the host */
#define OMNIKIN_STATUS_MOTOR_ENABLED 0x02 /* the motor is driven (not stopped by link loss or fault) */
#define OMNIKIN_STATUS_FAULT 0x04 /* a fault is latched (see the last ERROR_REPORT) */

/* --- little-endian helpers ------------------------------------------------------------ */
static inline void omnikin_put_u16(uint8_t *p, uint16_t v) {
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8);
}
static inline void omnikin_put_u32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline uint16_t omnikin_get_u16(const uint8_t *p) {
    return (uint16_t)(p[0] | ((uint16_t)p[1] << 8));
}
static inline uint32_t omnikin_get_u32(const uint8_t *p) {
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* --- CRC (no table in RAM) --------------------------------------------------------------- */
#if defined(__AVR__) && OMNIKIN_CRC_POLY == 0x1021u
/* avr-libc's XMODEM step is the byte update of this polynomial, not reflected (the initial value
 * is the caller's): about 20 cycles a byte where the bitwise loop below takes about 100 */
#include <util/crc16.h>
static inline uint16_t omnikin_crc16_update(uint16_t crc, uint8_t byte) {
    return _crc_xmodem_update(crc, byte);
}
#else
static inline uint16_t omnikin_crc16_update(uint16_t crc, uint8_t byte) {
    uint8_t i;
    crc ^= (uint16_t)((uint16_t)byte << 8);
    for (i = 0; i < 8; i++) {
        crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ OMNIKIN_CRC_POLY) : (uint16_t)(crc << 1);
    }
    return crc;
}
#endif
static inline uint16_t omnikin_crc16(const uint8_t *data, uint16_t n) {
    uint16_t crc = OMNIKIN_CRC_INIT;
    uint16_t i;
    for (i = 0; i < n; i++) crc = omnikin_crc16_update(crc, data[i]);
    return (uint16_t)(crc ^ OMNIKIN_CRC_XOROUT);
}

/* --- framing ------------------------------------------------------------------------------ */
/* Write a whole frame into out (room for OMNIKIN_MAX_FRAME bytes); returns its size. */
static inline uint8_t omnikin_frame(uint8_t *out, uint8_t type, uint8_t seq, const uint8_t *payload, uint8_t len) {
    uint16_t crc;
    if (len > OMNIKIN_MAX_PAYLOAD) return 0;
    out[0] = OMNIKIN_SYNC_0;
    out[1] = OMNIKIN_SYNC_1;
    out[2] = OMNIKIN_PROTOCOL_VERSION;
    out[3] = type;
    out[4] = seq;
    out[5] = len;
    memcpy(out + OMNIKIN_HEADER_SIZE, payload, len);
    crc = omnikin_crc16(out + OMNIKIN_SYNC_SIZE, (uint16_t)(OMNIKIN_HEADER_SIZE - OMNIKIN_SYNC_SIZE + len));
    omnikin_put_u16(out + OMNIKIN_HEADER_SIZE + len, crc);
    return (uint8_t)(OMNIKIN_HEADER_SIZE + len + OMNIKIN_CRC_SIZE);
}

/* Streaming parser: feed bytes one by one; omnikin_parse_byte returns 1 when a frame with a
 * valid CRC and this protocol version is complete: type p->buf[3], sequence p->buf[4],
 * payload p->buf + OMNIKIN_HEADER_SIZE of p->buf[5] bytes (valid until the next call).
 * After a rejected candidate it rescans from the byte after its first sync byte. */
typedef struct {
    uint8_t buf[OMNIKIN_MAX_FRAME];
    uint8_t n;           /* bytes held */
    uint8_t frame_size;  /* size of the frame returned by the previous call, to drop */
    uint16_t frames_ok, crc_errors, bad_version, skipped;
} omnikin_parser_t;

static inline void omnikin_parser_init(omnikin_parser_t *p) {
    memset(p, 0, sizeof(*p));
}

static inline void omnikin_parser_drop(omnikin_parser_t *p, uint8_t k) {
    memmove(p->buf, p->buf + k, (size_t)(p->n - k));
    p->n = (uint8_t)(p->n - k);
}

/* Drop k bytes that are not part of an accepted frame, and count them. */
static inline void omnikin_parser_discard(omnikin_parser_t *p, uint8_t k) {
    omnikin_parser_drop(p, k);
    p->skipped = (uint16_t)(p->skipped + k);
}

/* Discard the bytes before the next first sync byte at or after `from` (all, if there is none),
 * in one move: a rescan costs one pass over the buffer, not one per dropped byte. */
static inline void omnikin_parser_skip(omnikin_parser_t *p, uint8_t from) {
    const uint8_t *next = (const uint8_t *)memchr(p->buf + from, OMNIKIN_SYNC_0, (size_t)(p->n - from));
    omnikin_parser_discard(p, next ? (uint8_t)(next - p->buf) : p->n);
}

static inline uint8_t omnikin_parser_scan(omnikin_parser_t *p) {
    for (;;) {
        uint8_t len, size;
        if (p->n >= 1 && p->buf[0] != OMNIKIN_SYNC_0) { omnikin_parser_skip(p, 0); continue; }
        if (p->n >= 2 && p->buf[1] != OMNIKIN_SYNC_1) { omnikin_parser_skip(p, 1); continue; }
        if (p->n < OMNIKIN_HEADER_SIZE) return 0;
        len = p->buf[5];
        if (len > OMNIKIN_MAX_PAYLOAD) { p->crc_errors++; omnikin_parser_skip(p, 1); continue; }
        size = (uint8_t)(OMNIKIN_HEADER_SIZE + len + OMNIKIN_CRC_SIZE);
        if (p->n < size) return 0;
        if (omnikin_crc16(p->buf + OMNIKIN_SYNC_SIZE, (uint16_t)(OMNIKIN_HEADER_SIZE - OMNIKIN_SYNC_SIZE + len))
                != omnikin_get_u16(p->buf + OMNIKIN_HEADER_SIZE + len)) {
            p->crc_errors++; omnikin_parser_skip(p, 1); continue;
        }
        if (p->buf[2] != OMNIKIN_PROTOCOL_VERSION) {
            p->bad_version++; omnikin_parser_discard(p, size); continue;
        }
        p->frames_ok++;
        p->frame_size = size;
        return 1;
    }
}

static inline uint8_t omnikin_parse_byte(omnikin_parser_t *p, uint8_t b) {
    if (p->frame_size) { omnikin_parser_drop(p, p->frame_size); p->frame_size = 0; }
    if (p->n >= OMNIKIN_MAX_FRAME) { omnikin_parser_drop(p, 1); p->skipped++; }
    p->buf[p->n++] = b;
    return omnikin_parser_scan(p);
}

/* Sequence rules of one stream (one direction of one wheel), as the host applies them. */
#define OMNIKIN_SEQ_FIRST 0        /* first frame of the stream: accept */
#define OMNIKIN_SEQ_OK 1           /* next number: accept */
#define OMNIKIN_SEQ_GAP 2          /* numbers skipped (frames lost): accept */
#define OMNIKIN_SEQ_DUPLICATE 3    /* same number again: drop */
#define OMNIKIN_SEQ_OUT_OF_ORDER 4 /* a number from the past: drop */
#define OMNIKIN_SEQ_RESYNC 5       /* OMNIKIN_SEQ_RESYNC_AFTER out-of-order numbers in a row: sender restarted, accept */
typedef struct {
    uint8_t last;
    uint8_t have;
    uint8_t rejects;
} omnikin_seq_t;

static inline uint8_t omnikin_seq_check(omnikin_seq_t *s, uint8_t seq) {
    uint8_t d;
    if (!s->have) { s->have = 1; s->last = seq; s->rejects = 0; return OMNIKIN_SEQ_FIRST; }
    d = (uint8_t)(seq - s->last);
    if (d == 0) return OMNIKIN_SEQ_DUPLICATE;
    if (d < 128) { s->last = seq; s->rejects = 0; return d == 1 ? OMNIKIN_SEQ_OK : OMNIKIN_SEQ_GAP; }
    if (++s->rejects >= OMNIKIN_SEQ_RESYNC_AFTER) { s->last = seq; s->rejects = 0; return OMNIKIN_SEQ_RESYNC; }
    return OMNIKIN_SEQ_OUT_OF_ORDER;
}

static inline void omnikin_seq_restart(omnikin_seq_t *s, uint8_t seq) {
    s->have = 1; s->last = seq; s->rejects = 0;
}

/* --- frame types ----------------------------------------------------------------------------- */
/* SPEED_CMD (0x01, host to controller): Speed set-point of one wheel; the controller holds it while the link is alive. */
#define OMNIKIN_SPEED_CMD_SIZE 5
#define OMNIKIN_SPEED_CMD_SPEED_SCALE 0.0001f /* rad/s per count */
typedef struct {
    uint8_t wheel;       /* wheel index (position of the wheel among the robot file's rolling wheels) */
    int32_t speed;       /* commanded wheel speed, positive when the wheel drives its hub along +u (docs/conventions.md) [rad/s x 0.0001] */
} omnikin_speed_cmd_t;

static inline uint8_t omnikin_pack_speed_cmd(uint8_t *payload, const omnikin_speed_cmd_t *m) {
    payload[0] = (uint8_t)m->wheel;
    omnikin_put_u32(payload + 1, (uint32_t)m->speed);
    return 5;
}

static inline uint8_t omnikin_unpack_speed_cmd(const uint8_t *payload, uint8_t len, omnikin_speed_cmd_t *m) {
    if (len != 5) return 0;
    m->wheel = (uint8_t)payload[0];
    m->speed = (int32_t)omnikin_get_u32(payload + 1);
    return 1;
}

static inline uint8_t omnikin_encode_speed_cmd(uint8_t *out, uint8_t seq, const omnikin_speed_cmd_t *m) {
    uint8_t payload[5];
    uint8_t len = omnikin_pack_speed_cmd(payload, m);
    return omnikin_frame(out, OMNIKIN_TYPE_SPEED_CMD, seq, payload, len);
}

/* ENCODER_REPORT (0x02, controller to host): Encoder reading and measured speed of one wheel, sent every report_period. */
#define OMNIKIN_ENCODER_REPORT_SIZE 13
#define OMNIKIN_ENCODER_REPORT_SPEED_SCALE 0.0001f /* rad/s per count */
typedef struct {
    uint8_t wheel;       /* wheel index */
    uint32_t time_us;     /* controller clock when the count was latched [us] */
    int32_t count;       /* raw encoder counter (the host converts it with the robot file's ticks_per_rev, gear_ratio, invert) [tick] */
    int32_t speed;       /* wheel speed measured by the controller, same sign convention as SPEED_CMD [rad/s x 0.0001] */
} omnikin_encoder_report_t;

static inline uint8_t omnikin_pack_encoder_report(uint8_t *payload, const omnikin_encoder_report_t *m) {
    payload[0] = (uint8_t)m->wheel;
    omnikin_put_u32(payload + 1, (uint32_t)m->time_us);
    omnikin_put_u32(payload + 5, (uint32_t)m->count);
    omnikin_put_u32(payload + 9, (uint32_t)m->speed);
    return 13;
}

static inline uint8_t omnikin_unpack_encoder_report(const uint8_t *payload, uint8_t len, omnikin_encoder_report_t *m) {
    if (len != 13) return 0;
    m->wheel = (uint8_t)payload[0];
    m->time_us = (uint32_t)omnikin_get_u32(payload + 1);
    m->count = (int32_t)omnikin_get_u32(payload + 5);
    m->speed = (int32_t)omnikin_get_u32(payload + 9);
    return 1;
}

static inline uint8_t omnikin_encode_encoder_report(uint8_t *out, uint8_t seq, const omnikin_encoder_report_t *m) {
    uint8_t payload[13];
    uint8_t len = omnikin_pack_encoder_report(payload, m);
    return omnikin_frame(out, OMNIKIN_TYPE_ENCODER_REPORT, seq, payload, len);
}

/* ERROR_REPORT (0x03, controller to host): Something the host should know; code from the table of error codes, optional text. */
#define OMNIKIN_ERROR_REPORT_MIN_SIZE 2
#define OMNIKIN_ERROR_REPORT_MAX_SIZE 50
#define OMNIKIN_ERROR_REPORT_TEXT_MAX 48
typedef struct {
    uint8_t wheel;       /* wheel index */
    uint8_t code;        /* error code */
    uint8_t text_len;
    char text[48]; /* optional ASCII detail (0-48 bytes, not terminated) */
} omnikin_error_report_t;

static inline uint8_t omnikin_pack_error_report(uint8_t *payload, const omnikin_error_report_t *m) {
    payload[0] = (uint8_t)m->wheel;
    payload[1] = (uint8_t)m->code;
    uint8_t n = m->text_len > 48 ? 48 : m->text_len;
    memcpy(payload + 2, m->text, n);
    return (uint8_t)(2 + n);
}

static inline uint8_t omnikin_unpack_error_report(const uint8_t *payload, uint8_t len, omnikin_error_report_t *m) {
    if (len < 2 || len > 50) return 0;
    m->wheel = (uint8_t)payload[0];
    m->code = (uint8_t)payload[1];
    m->text_len = (uint8_t)(len - 2);
    memcpy(m->text, payload + 2, m->text_len);
    return 1;
}

static inline uint8_t omnikin_encode_error_report(uint8_t *out, uint8_t seq, const omnikin_error_report_t *m) {
    uint8_t payload[50];
    uint8_t len = omnikin_pack_error_report(payload, m);
    return omnikin_frame(out, OMNIKIN_TYPE_ERROR_REPORT, seq, payload, len);
}

/* HEARTBEAT (0x04, both): Keeps the link alive when nothing else is due; carries the sender's state. */
#define OMNIKIN_HEARTBEAT_SIZE 6
typedef struct {
    uint8_t wheel;       /* wheel index (the host sends one heartbeat per wheel) */
    uint8_t status;      /* status bits (host: 0) */
    uint32_t time_us;     /* sender's clock [us] */
} omnikin_heartbeat_t;

static inline uint8_t omnikin_pack_heartbeat(uint8_t *payload, const omnikin_heartbeat_t *m) {
    payload[0] = (uint8_t)m->wheel;
    payload[1] = (uint8_t)m->status;
    omnikin_put_u32(payload + 2, (uint32_t)m->time_us);
    return 6;
}

static inline uint8_t omnikin_unpack_heartbeat(const uint8_t *payload, uint8_t len, omnikin_heartbeat_t *m) {
    if (len != 6) return 0;
    m->wheel = (uint8_t)payload[0];
    m->status = (uint8_t)payload[1];
    m->time_us = (uint32_t)omnikin_get_u32(payload + 2);
    return 1;
}

static inline uint8_t omnikin_encode_heartbeat(uint8_t *out, uint8_t seq, const omnikin_heartbeat_t *m) {
    uint8_t payload[6];
    uint8_t len = omnikin_pack_heartbeat(payload, m);
    return omnikin_frame(out, OMNIKIN_TYPE_HEARTBEAT, seq, payload, len);
}

#endif /* OMNIKIN_PROTOCOL_H */
