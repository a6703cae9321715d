/* Host test of the generated header firmware/omnikin_wheel/omnikin_protocol.h (built by
 * tests/runtime/test_protocol.py with g++ -Wall -Wextra -Werror, output compared with Python):
 *
 *   protocol_host_test crc          CRC of "123456789" and the header's check value
 *   protocol_host_test encode       one frame of each type, fixed field values, as hex
 *   protocol_host_test decode       hex stream on stdin -> accepted frames (hex) and parser counts
 *   protocol_host_test seq          sequence numbers on stdin -> omnikin_seq_check verdicts */
#include "omnikin_protocol.h"

#include <ctype.h>
#include <stdio.h>
#include <string.h>

static void hex(const uint8_t *p, unsigned n) {
    for (unsigned i = 0; i < n; i++) printf("%02x", p[i]);
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc < 2) return 2;
    if (!strcmp(argv[1], "crc")) {
        const char *s = "123456789";
        printf("%04x %04x\n", omnikin_crc16((const uint8_t *)s, 9), (unsigned)OMNIKIN_CRC_CHECK);
        return 0;
    }
    if (!strcmp(argv[1], "encode")) {
        uint8_t out[OMNIKIN_MAX_FRAME];
        omnikin_speed_cmd_t sc = {3, -123456};
        printf("SPEED_CMD ");
        hex(out, omnikin_encode_speed_cmd(out, 7, &sc));
        omnikin_encoder_report_t er = {1, 4000000000u, -2147483647 - 1, 25000};
        printf("ENCODER_REPORT ");
        hex(out, omnikin_encode_encoder_report(out, 255, &er));
        omnikin_heartbeat_t hb = {2, OMNIKIN_STATUS_LINK_OK | OMNIKIN_STATUS_MOTOR_ENABLED, 123456789u};
        printf("HEARTBEAT ");
        hex(out, omnikin_encode_heartbeat(out, 0, &hb));
        omnikin_error_report_t e;
        e.wheel = 0;
        e.code = OMNIKIN_ERR_LINK_LOST;
        e.text_len = 4;
        memcpy(e.text, "boom", 4);
        printf("ERROR_REPORT ");
        hex(out, omnikin_encode_error_report(out, 42, &e));
        return 0;
    }
    if (!strcmp(argv[1], "decode")) {
        omnikin_parser_t p;
        omnikin_parser_init(&p);
        int c, hi = -1;
        while ((c = getchar()) != EOF) {
            if (!isxdigit(c)) continue;
            int v = isdigit(c) ? c - '0' : (tolower(c) - 'a' + 10);
            if (hi < 0) { hi = v; continue; }
            uint8_t b = (uint8_t)(hi * 16 + v);
            hi = -1;
            if (omnikin_parse_byte(&p, b)) {
                printf("FRAME ");
                hex(p.buf, (unsigned)(OMNIKIN_HEADER_SIZE + p.buf[5] + OMNIKIN_CRC_SIZE));
                if (p.buf[3] == OMNIKIN_TYPE_ENCODER_REPORT) {
                    omnikin_encoder_report_t m;
                    if (omnikin_unpack_encoder_report(p.buf + OMNIKIN_HEADER_SIZE, p.buf[5], &m))
                        printf("REPORT %u %lu %ld %ld\n", m.wheel, (unsigned long)m.time_us, (long)m.count,
                               (long)m.speed);
                }
            }
        }
        printf("STATS %u %u %u %u\n", p.frames_ok, p.crc_errors, p.bad_version, p.skipped);
        return 0;
    }
    if (!strcmp(argv[1], "seq")) {
        omnikin_seq_t s;
        memset(&s, 0, sizeof s);
        unsigned v;
        while (scanf("%u", &v) == 1) printf("%u\n", omnikin_seq_check(&s, (uint8_t)v));
        return 0;
    }
    return 2;
}
