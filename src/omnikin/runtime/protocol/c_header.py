"""Generator of the firmware's C header ``firmware/omnikin_wheel/omnikin_protocol.h``.

Implements, in C99 / C++ without allocation, everything ``docs/protocol.md`` specifies for a
wheel controller, from the same ``protocol.yaml``: the constants (timing in ms, baud rate,
sync bytes, sizes), frame type ids, error codes and status masks, the CRC (bitwise; on an AVR
avr-libc's update step when the polynomial is 0x1021), one struct with pack / unpack / encode
functions per frame type (fields as wire integers; a field's physical value [its unit] = raw x
its ``*_SCALE``), the byte-by-byte frame parser and the sequence rules. Little-endian on the
wire whatever the CPU. A test compiles it with gcc/g++ and compares it with Python frame by
frame; another compares the committed header with :func:`generate_header`::

    python -m omnikin.runtime.protocol --header > firmware/omnikin_wheel/omnikin_protocol.h
"""

from __future__ import annotations

from .schema import CRC_BYTES, INT_TYPES, Field, Protocol, load_protocol

HEADER_COMMAND = "python -m omnikin.runtime.protocol --header > firmware/omnikin_wheel/omnikin_protocol.h"


def _c_float(x: float) -> str:
    s = repr(float(x))
    if "e" not in s and "." not in s:
        s += ".0"
    return s + "f"


def _c_comment(text: str) -> str:
    return text.replace("*/", "* /")


def _ms(seconds: float) -> int:
    return round(seconds * 1000)


def generate_header(protocol: Protocol | None = None) -> str:
    """The C header of the firmware (C99 / C++, no allocation, little-endian wire)."""
    p = protocol or load_protocol()
    t = p.timing
    L: list[str] = []
    a = L.append
    a("/* omnikin_protocol.h: the omnikin wheel-controller protocol for C and C++ (Arduino).")
    a(" *")
    a(" * GENERATED from src/omnikin/runtime/protocol.yaml by")
    a(f" *   {HEADER_COMMAND}")
    a(" * Do not edit: change protocol.yaml and regenerate. Specification: docs/protocol.md.")
    a(" */")
    a("#ifndef OMNIKIN_PROTOCOL_H")
    a("#define OMNIKIN_PROTOCOL_H")
    a("")
    a("#include <stdint.h>")
    a("#include <string.h>")
    a("")
    a(f"#define OMNIKIN_PROTOCOL_VERSION {p.version}")
    for i, b in enumerate(p.sync):
        a(f"#define OMNIKIN_SYNC_{i} 0x{b:02X}")
    a(f"#define OMNIKIN_SYNC_SIZE {len(p.sync)}")
    a(f"#define OMNIKIN_HEADER_SIZE {p.header_size} /* sync, version, type, sequence, length */")
    a(f"#define OMNIKIN_CRC_SIZE {CRC_BYTES}")
    a(f"#define OMNIKIN_MAX_PAYLOAD {p.max_payload}")
    a("#define OMNIKIN_MAX_FRAME (OMNIKIN_HEADER_SIZE + OMNIKIN_MAX_PAYLOAD + OMNIKIN_CRC_SIZE)")
    a(f"#define OMNIKIN_WHEEL_INDEX_MAX {p.wheel_index_max}")
    a(f"#define OMNIKIN_SEQ_RESYNC_AFTER {p.resync_after}")
    a(f"#define OMNIKIN_COUNTER_BITS {p.counter_bits}")
    a("")
    a("/* serial link */")
    a(f"#define OMNIKIN_BAUD {int(p.serial['baud'])}UL")
    a("")
    a("/* timing [ms] */")
    a(f"#define OMNIKIN_HEARTBEAT_PERIOD_MS {_ms(t.heartbeat_period)}UL")
    a(f"#define OMNIKIN_REPORT_PERIOD_MS {_ms(t.report_period)}UL")
    a(f"#define OMNIKIN_LINK_TIMEOUT_MS {_ms(t.link_timeout)}UL")
    a(f"#define OMNIKIN_CONNECT_TIMEOUT_MS {_ms(t.connect_timeout)}UL")
    a("")
    a(f"/* {p.crc.name}: {_c_comment(p.crc.covers)} */")
    a(f"#define OMNIKIN_CRC_POLY 0x{p.crc.poly:04X}u")
    a(f"#define OMNIKIN_CRC_INIT 0x{p.crc.init:04X}u")
    a(f"#define OMNIKIN_CRC_XOROUT 0x{p.crc.xorout:04X}u")
    a(f'#define OMNIKIN_CRC_CHECK 0x{p.crc.check:04X}u /* of the ASCII bytes "123456789" */')
    a("")
    a("/* frame types */")
    for ft in p.frames.values():
        a(f"#define OMNIKIN_TYPE_{ft.name} 0x{ft.id:02X} /* {ft.direction.replace('_', ' ')} */")
    a("")
    a("/* error codes (ERROR_REPORT.code) */")
    for c in p.error_codes:
        a(f"#define OMNIKIN_ERR_{c.name} {c.value} /* {_c_comment(c.description)} */")
    a("")
    a("/* status flags (HEARTBEAT.status), bit masks */")
    for c in p.status_flags:
        a(f"#define OMNIKIN_STATUS_{c.name} 0x{1 << c.value:02X} /* {_c_comment(c.description)} */")
    a("")
    a(_C_HELPERS)
    for ft in p.frames.values():
        low = ft.name.lower()
        a(f"/* {ft.name} (0x{ft.id:02X}, {ft.direction.replace('_', ' ')}): {_c_comment(ft.description)} */")
        if ft.text is None:
            a(f"#define OMNIKIN_{ft.name}_SIZE {ft.min_size}")
        else:
            a(f"#define OMNIKIN_{ft.name}_MIN_SIZE {ft.min_size}")
            a(f"#define OMNIKIN_{ft.name}_MAX_SIZE {ft.max_size}")
            a(f"#define OMNIKIN_{ft.name}_{ft.text.name.upper()}_MAX {ft.text.max_length}")
        for f in ft.fixed:
            if f.scale is not None:
                a(f"#define OMNIKIN_{ft.name}_{f.name.upper()}_SCALE {_c_float(f.scale)} /* {f.unit} per count */")
        a("typedef struct {")
        for f in ft.fixed:
            unit = f" [{f.unit}{' x ' + _c_float(f.scale)[:-1] if f.scale else ''}]" if f.unit else ""
            pad = " " * max(1, 12 - len(f.name))
            a(f"    {INT_TYPES[f.type][2]} {f.name};{pad}/* {_c_comment(f.description)}{unit} */")
        if ft.text is not None:
            a(f"    uint8_t {ft.text.name}_len;")
            a(f"    char {ft.text.name}[{ft.text.max_length}]; /* {_c_comment(ft.text.description)} */")
        a(f"}} omnikin_{low}_t;")
        a("")
        a(f"static inline uint8_t omnikin_pack_{low}(uint8_t *payload, const omnikin_{low}_t *m) {{")
        off = 0
        for f in ft.fixed:
            a("    " + _c_put(f, off))
            off += f.size
        if ft.text is not None:
            tn = ft.text.name
            a(f"    uint8_t n = m->{tn}_len > {ft.text.max_length} ? {ft.text.max_length} : m->{tn}_len;")
            a(f"    memcpy(payload + {off}, m->{tn}, n);")
            a(f"    return (uint8_t)({off} + n);")
        else:
            a(f"    return {off};")
        a("}")
        a("")
        a(f"static inline uint8_t omnikin_unpack_{low}(const uint8_t *payload, uint8_t len, omnikin_{low}_t *m) {{")
        if ft.text is None:
            a(f"    if (len != {ft.min_size}) return 0;")
        else:
            a(f"    if (len < {ft.min_size} || len > {ft.max_size}) return 0;")
        off = 0
        for f in ft.fixed:
            a("    " + _c_get(f, off))
            off += f.size
        if ft.text is not None:
            tn = ft.text.name
            a(f"    m->{tn}_len = (uint8_t)(len - {off});")
            a(f"    memcpy(m->{tn}, payload + {off}, m->{tn}_len);")
        a("    return 1;")
        a("}")
        a("")
        a(f"static inline uint8_t omnikin_encode_{low}(uint8_t *out, uint8_t seq, const omnikin_{low}_t *m) {{")
        a(f"    uint8_t payload[{ft.max_size}];")
        a(f"    uint8_t len = omnikin_pack_{low}(payload, m);")
        a(f"    return omnikin_frame(out, OMNIKIN_TYPE_{ft.name}, seq, payload, len);")
        a("}")
        a("")
    a("#endif /* OMNIKIN_PROTOCOL_H */")
    return "\n".join(L) + "\n"


def _c_put(f: Field, off: int) -> str:
    size = f.size
    if size == 1:
        return f"payload[{off}] = (uint8_t)m->{f.name};"
    return f"omnikin_put_u{8 * size}(payload + {off}, (uint{8 * size}_t)m->{f.name});"


def _c_get(f: Field, off: int) -> str:
    size, ctype = f.size, INT_TYPES[f.type][2]
    if size == 1:
        return f"m->{f.name} = ({ctype})payload[{off}];"
    return f"m->{f.name} = ({ctype})omnikin_get_u{8 * size}(payload + {off});"


_C_HELPERS = r"""/* --- little-endian helpers ------------------------------------------------------------ */
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

/* --- frame types ----------------------------------------------------------------------------- */"""  # noqa: E501 (C text of the generated header, kept as is)
