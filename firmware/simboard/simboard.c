/*
 * simboard: a simulated Arduino Nano (ATmega328P at 16 MHz) on libsimavr 1.6, with a wheel on
 * its pins: a stepper (A4988 style) or DC motor driving a shaft, a quadrature encoder on that
 * shaft, a pseudo-terminal on USART0, and measurements (stack, interrupt load, control period,
 * step timing) in exact simulated cycles. Controlled by one-line commands on stdin; answers one
 * JSON object per line on stdout. `simboard --help` documents pins, models and commands.
 *
 * Build: cc -std=gnu11 -O2 -Wall -Wextra -Werror -I/usr/include/simavr simboard.c -o simboard \
 *        -lsimavr -lutil -lm
 */
#define _GNU_SOURCE
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "avr_extint.h"
#include "avr_ioport.h"
#include "avr_uart.h"
#include "sim_avr.h"
#include "sim_cycle_timers.h"
#include "sim_elf.h"
#include "sim_interrupts.h"
#include "sim_irq.h"

#define F_CPU 16000000.0
#define F_CPU_INT 16000000ULL
#define RAMEND 0x8FF
#define FLASH_BYTES 32768u
#define EEPROM_BYTES 1024u
#define EM_AVR 83

/* data-space addresses of the ATmega328P registers the board reads */
#define REG_PORTB 0x25
#define REG_PIND 0x29
#define REG_PORTD 0x2B
#define REG_SPL 0x5D
#define REG_SPH 0x5E
#define REG_TCCR1A 0x80
#define REG_OCR1AL 0x88
#define REG_UCSR0A 0xC0
#define REG_UCSR0C 0xC2
#define REG_UBRR0L 0xC4
#define REG_UBRR0H 0xC5
#define BIT_COM1A1 7
#define BIT_U2X0 1

#define POLL_CYCLES 1600u      /* host I/O every 100 us simulated */
#define PACE_CYCLES 16000u     /* wall-clock pacing every 1 ms simulated */
#define DC_UPDATE_CYCLES 160u  /* DC motor model update every 10 us simulated */
#define BEHIND_REBASE_S 0.1
#define TX_BUF 65536u
#define RX_BUF 65536u
#define LINE_MAX_LEN 1024u
#define NVECTORS 32

enum motor { MOTOR_STEPPER, MOTOR_DC, MOTOR_NONE };

static struct {
    enum motor motor;
    long ppr, steps_per_rev, microsteps;
    double dc_top_speed, dc_tau;
    bool shaft_given;
    double shaft_speed;
    double speed, duration;
    bool duration_given, pty, lockstep;
    const char *link, *elf;
} opt = {MOTOR_STEPPER, 600, 200, 8, 40.0, 0.05, false, 0.0, 1.0, 0.0, false, true, false, NULL, NULL};

/* ------------------------------------------------------------------ usage and errors */

static void die_usage(const char *fmt, ...) __attribute__((noreturn, format(printf, 1, 2)));
static void die_usage(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("simboard: error: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputs("\n", stderr);
    va_end(ap);
    exit(2);
}

/* at most 40 printable characters of a user's argument, for an error message */
static const char *shorten(const char *s)
{
    static char buf[64];
    size_t n = 0;
    for (; s[n] && n < 40; n++)
        buf[n] = (s[n] >= 0x20 && s[n] < 0x7f && s[n] != '"' && s[n] != '\\') ? s[n] : '?';
    buf[n] = 0;
    if (s[n])
        strcpy(buf + n, "...");
    return buf;
}

static const char HELP[] =
    "usage: simboard [options] FIRMWARE.elf\n"
    "\n"
    "A simulated Arduino Nano (ATmega328P, 16 MHz, simavr 1.6) with a wheel on its pins.\n"
    "\n"
    "Pins: encoder A = D2 (PD2, INT0), encoder B = D3 (PD3, INT1), driven by the board;\n"
    "  STEP (stepper) / PWM (DC) = D9 (PB1, OC1A); DIR = D8 (PB0), high = forward;\n"
    "  ENABLE = D7 (PD7), active low (A4988); probe = A0 (PC0), high during a control step.\n"
    "\n"
    "Options:\n"
    "  --motor stepper|dc|none  motor model (default stepper); none: use with --shaft-speed\n"
    "  --ppr N                  encoder pulses per shaft turn (600); quadrature: 4N states/turn\n"
    "  --steps-per-rev N        stepper full steps per turn (200)\n"
    "  --microsteps N           stepper microsteps per full step (8); each STEP rising edge\n"
    "                           with ENABLE low turns the shaft by 2 pi/(N_steps N_micro),\n"
    "                           forward when DIR is high; steps with ENABLE high are counted\n"
    "  --dc-top-speed W         DC: shaft speed at full duty [rad/s] (40)\n"
    "  --dc-tau S               DC: time constant [s] (0.05): tau dw/dt = W u - w with\n"
    "                           u = duty (+ DIR high, - low), duty = OCR1AL/255 when TCCR1A\n"
    "                           COM1A1 is set, else the PB1 level; integrated exactly every 10 us\n"
    "  --shaft-speed W          shaft turns at constant W [rad/s], motor output ignored;\n"
    "                           each encoder transition at its exact cycle\n"
    "  --speed F                simulated seconds per wall second (1); 0 = as fast as possible\n"
    "  --duration S             stop after S simulated seconds (final stats line, exit 0)\n"
    "  --no-pty                 no pseudo-terminal: UART output counted and discarded\n"
    "  --lockstep               the host steps simulated time: the board starts paused at cycle 0\n"
    "                           and runs only on 'run N'; its UART is on the command channel\n"
    "                           ('rx HEX' in, the bytes sent in each run's answer), no pty, no\n"
    "                           pacing; what the chip does is then the same whatever the host's pace\n"
    "  --link PATH              also make PATH a symlink to the pty (removed on exit)\n"
    "  --help                   this text\n"
    "\n"
    "Encoder: q = floor(angle 4 ppr / 2 pi); A = [0,1,1,0][q mod 4], B = [0,0,1,1][q mod 4];\n"
    "  every change of q is emitted as single transitions in order.\n"
    "UART: USART0 on a raw pty; host-to-board bytes at most one per frame (10 bit times at the\n"
    "  baud rate the firmware set). The board keeps the pty slave open: a host may close and\n"
    "  reopen it; bytes sent while no host reads wait in the pty (bounded; overflow counted).\n"
    "\n"
    "Commands on stdin (one per line; answers are JSON lines on stdout):\n"
    "  silence on|off      drop the board's UART output (the wire is cut)\n"
    "  corrupt tx|rx N     flip one bit (index cycling 0..7) in every Nth byte; N = 0: off\n"
    "  reset               reset the chip (the shaft keeps its angle)\n"
    "  stats               measurements; clear: restart the measurement window\n"
    "  peek ADDR N         N (1..256) bytes of data memory from ADDR (decimal or 0x hex)\n"
    "  rx HEX              bytes (2 hex digits each, at most 510) reach the RX pin from this\n"
    "                      cycle on, back to back at the line rate, after any still queued\n"
    "  run N               --lockstep: run N (1..16e12) cycles, then answer {ok: run, cycle,\n"
    "                      tx: HEX of the bytes the chip sent since the previous run answer};\n"
    "                      later commands wait until the run is over\n"
    "  nudge +1|-1         --motor none without --shaft-speed: the shaft moves by one quadrature\n"
    "                      transition (a wheel at rest shaking on an encoder edge)\n"
    "  quit                final stats line and exit 0 (also on SIGTERM, SIGINT, and on EOF\n"
    "                      unless --duration is given: then the board runs its duration)\n"
    "\n"
    "Measurements (cycles are exact simulated cycles, 16 per us): cycle, time_s, wall_s,\n"
    "  behind_s; sp_min, ramend, stack_bytes; window_cycles, isr_cycles, isr {vector: {cycles,\n"
    "  count}} (an instruction counts for the innermost running vector; simavr 1.6 enters a\n"
    "  vector in 0 cycles, the real chip takes 4); probe {count, last_rise (the cycle of the\n"
    "  latest rising edge; clear keeps it), period_*, high_*}; steps {count, forward,\n"
    "  backward, ignored, interval_*}; q, transitions, angle, omega; duty,\n"
    "  enabled, dir; rx_bytes, tx_bytes, tx_dropped, corrupted_tx, corrupted_rx,\n"
    "  rx_backlog_max, baud.\n";

static long parse_long(const char *name, const char *s, long lo, long hi)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (!*s || *end || errno || v < lo || v > hi)
        die_usage("%s: expected an integer from %ld to %ld, got '%s'", name, lo, hi, shorten(s));
    return v;
}

static double parse_double(const char *name, const char *s, double lo, double hi, bool lo_open)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (!*s || *end || errno || !isfinite(v) || v < lo || v > hi || (lo_open && v == lo))
        die_usage("%s: expected a number %s %g and <= %g, got '%s'", name, lo_open ? ">" : ">=", lo,
                  hi, shorten(s));
    return v;
}

static void parse_args(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(HELP, stdout);
            exit(0);
        }
        if (strcmp(a, "--no-pty") == 0) {
            opt.pty = false;
            continue;
        }
        if (strcmp(a, "--lockstep") == 0) {
            opt.lockstep = true;
            continue;
        }
        if (strcmp(a, "--") == 0) {
            if (i + 2 != argc)
                die_usage("expected exactly one FIRMWARE.elf after --");
            if (opt.elf)
                die_usage("more than one firmware: '%s'", shorten(argv[i + 1]));
            opt.elf = argv[i + 1];
            break;
        }
        if (a[0] != '-' || a[1] == 0) {
            if (opt.elf)
                die_usage("more than one firmware: '%s'", shorten(a));
            opt.elf = a;
            continue;
        }
        /* options with a value: --name VALUE or --name=VALUE */
        char name[32];
        const char *val = NULL;
        const char *eq = strchr(a, '=');
        size_t n = eq ? (size_t)(eq - a) : strlen(a);
        if (n >= sizeof name)
            die_usage("unknown option '%s' (see --help)", shorten(a));
        memcpy(name, a, n);
        name[n] = 0;
        static const char *const valued[] = {"--motor",        "--ppr",         "--steps-per-rev",
                                             "--microsteps",   "--dc-top-speed", "--dc-tau",
                                             "--shaft-speed",  "--speed",        "--duration",
                                             "--link"};
        bool known = false;
        for (size_t k = 0; k < sizeof valued / sizeof *valued; k++)
            known |= strcmp(name, valued[k]) == 0;
        if (!known)
            die_usage("unknown option '%s' (see --help)", shorten(a));
        if (eq)
            val = eq + 1;
        else if (i + 1 < argc)
            val = argv[++i];
        else
            die_usage("%s: missing value", name);

        if (strcmp(name, "--motor") == 0) {
            if (strcmp(val, "stepper") == 0)
                opt.motor = MOTOR_STEPPER;
            else if (strcmp(val, "dc") == 0)
                opt.motor = MOTOR_DC;
            else if (strcmp(val, "none") == 0)
                opt.motor = MOTOR_NONE;
            else
                die_usage("--motor: expected stepper, dc or none, got '%s'", shorten(val));
        } else if (strcmp(name, "--ppr") == 0)
            opt.ppr = parse_long(name, val, 1, 1000000);
        else if (strcmp(name, "--steps-per-rev") == 0)
            opt.steps_per_rev = parse_long(name, val, 1, 100000);
        else if (strcmp(name, "--microsteps") == 0)
            opt.microsteps = parse_long(name, val, 1, 256);
        else if (strcmp(name, "--dc-top-speed") == 0)
            opt.dc_top_speed = parse_double(name, val, -1e5, 1e5, false);
        else if (strcmp(name, "--dc-tau") == 0)
            opt.dc_tau = parse_double(name, val, 0.0, 1e3, true);
        else if (strcmp(name, "--shaft-speed") == 0) {
            opt.shaft_speed = parse_double(name, val, -1e6, 1e6, false);
            opt.shaft_given = true;
        } else if (strcmp(name, "--speed") == 0)
            opt.speed = parse_double(name, val, 0.0, 1e6, false);
        else if (strcmp(name, "--duration") == 0) {
            opt.duration = parse_double(name, val, 0.0, 1e7, true);
            opt.duration_given = true;
        } else if (strcmp(name, "--link") == 0) {
            if (!*val)
                die_usage("--link: empty path");
            opt.link = val;
        }
    }
    if (!opt.elf)
        die_usage("missing FIRMWARE.elf (see --help)");
    if (opt.motor == MOTOR_DC && opt.dc_tau * F_CPU < DC_UPDATE_CYCLES / 1000.0)
        die_usage("--dc-tau: %g s is too short for the 10 us model update", opt.dc_tau);
    if (opt.shaft_given && fabs(opt.shaft_speed) * 4.0 * (double)opt.ppr / (2 * M_PI) > F_CPU / 4)
        die_usage("--shaft-speed: %g rad/s with --ppr %ld gives more than one encoder transition "
                  "per 4 cycles",
                  opt.shaft_speed, opt.ppr);
    if (opt.link && (!opt.pty || opt.lockstep))
        die_usage("--link: needs the pty (drop --no-pty and --lockstep)");
    if (opt.lockstep)
        opt.pty = false; /* the UART is on the command channel */
}

/* Check the file is a 32-bit little-endian AVR ELF before libsimavr reads it. */
static void check_elf(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        die_usage("%s: %s", shorten(path), strerror(errno));
    unsigned char h[20];
    size_t n = fread(h, 1, sizeof h, f);
    fclose(f);
    if (n < sizeof h || memcmp(h, "\177ELF", 4) != 0)
        die_usage("%s: not an ELF file", shorten(path));
    if (h[4] != 1 || h[5] != 1)
        die_usage("%s: not a 32-bit little-endian ELF (not built for AVR)", shorten(path));
    unsigned machine = h[18] | (h[19] << 8);
    if (machine != EM_AVR)
        die_usage("%s: ELF for machine %u, not AVR (83)", shorten(path), machine);
}

/* ------------------------------------------------------------------ the board's state */

static avr_t *avr;
static avr_uart_t *uart0;
static avr_irq_t *irq_enc_a, *irq_enc_b;

/* encoder and shaft */
static int64_t q;                /* quadrature state */
static uint64_t transitions;
static double angle, omega;      /* [rad], [rad/s] (DC model) */
#define STEP_MOVE_MAX_CYCLES 32000 /* 2 ms */
static int64_t step_pos;         /* stepper: microsteps from the start */
static int64_t step_q_target;    /* stepper: the quadrature state of step_pos */
static uint64_t last_step_cycle; /* stepper: when the previous step came */
static bool have_last_step;
static avr_cycle_count_t step_spacing; /* stepper: cycles between the transitions of one move */
static double shaft_period;      /* --shaft-speed: cycles per quadrature state */
static int enc_a, enc_b;

/* pins */
static int pb1_level, pc0_level;

/* window measurements */
static uint64_t window_start;
static uint64_t isr_cycles;
static struct { uint64_t cycles, count; } isr_vec[NVECTORS];
/* a series of durations [cycles]: count, extremes, exact mean (sum / n), spread (Welford) */
struct durations {
    uint64_t n, min, max, sum;
    double mean, m2;
};
static struct {
    uint64_t count, last_rise;
    struct durations period, high;
    bool rise_valid;
} probe;
static struct {
    uint64_t count, forward, backward, ignored, last;
    struct durations interval;
    bool last_valid;
} steps;

/* totals */
static uint16_t sp_min = 0xFFFF;
static double behind_s, wall_start;
static double pace_wall;
static uint64_t pace_cycle, next_poll, next_pace;

/* UART */
static int pty_master = -1, pty_slave = -1;
static char pty_name[128];
static uint8_t txbuf[TX_BUF];
static size_t tx_head, tx_len;
static uint8_t rxbuf[RX_BUF];
static size_t rx_head, rx_len, rx_backlog_max;
static uint64_t rx_bytes, tx_bytes, tx_dropped, corrupted_tx, corrupted_rx;
static uint64_t tx_seen, rx_seen;
static unsigned corrupt_tx_every, corrupt_rx_every, corrupt_tx_bit, corrupt_rx_bit;
static bool silence, xoff, rx_timer_armed;
/* --lockstep: the board runs until run_until, then waits for the host's next command */
static uint64_t run_until;
static bool run_pending;
static uint32_t uart_config = 0xFFFFFFFF;

static volatile sig_atomic_t stop_signal;
static bool quitting;

/* Flush an answer; a host that closed our stdout ends the board (nobody hears it any more). */
static void flush_out(void)
{
    if (fflush(stdout) != 0 || ferror(stdout))
        quitting = true;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int64_t floor_div(int64_t a, int64_t b)
{
    int64_t d = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? d - 1 : d;
}

static void durations_add(struct durations *s, uint64_t d)
{
    if (!s->n || d < s->min)
        s->min = d;
    if (d > s->max)
        s->max = d;
    s->n++;
    s->sum += d;
    double delta = (double)d - s->mean;
    s->mean += delta / (double)s->n;
    s->m2 += delta * ((double)d - s->mean);
}

static double durations_mean(const struct durations *s)
{
    return s->n ? (double)s->sum / (double)s->n : 0.0;
}

/* ------------------------------------------------------------------ encoder */

static const int ENC_A[4] = {0, 1, 1, 0};
static const int ENC_B[4] = {0, 0, 1, 1};

/* Drive PD2/PD3 to the encoder levels. The levels are also the port's "external" values so that
 * the firmware writing PORTD (pull-ups) does not override them. */
static void drive_encoder_pins(bool force)
{
    int idx = (int)(((q % 4) + 4) % 4);
    int a = ENC_A[idx], b = ENC_B[idx];
    avr_ioport_external_t ext = {.name = 'D', .mask = (1 << 2) | (1 << 3),
                                 .value = (uint8_t)((a << 2) | (b << 3))};
    avr_ioctl(avr, AVR_IOCTL_IOPORT_SET_EXTERNAL('D'), &ext);
    if (force || a != enc_a)
        avr_raise_irq(irq_enc_a, (uint32_t)a);
    if (force || b != enc_b)
        avr_raise_irq(irq_enc_b, (uint32_t)b);
    if (force)
        avr->data[REG_PIND] = (uint8_t)((avr->data[REG_PIND] & ~0x0C) | (a << 2) | (b << 3));
    enc_a = a;
    enc_b = b;
}

/* Move the quadrature state to `target` one transition at a time (never A and B at once). */
static void encoder_to(int64_t target)
{
    while (q != target) {
        q += target > q ? 1 : -1;
        transitions++;
        drive_encoder_pins(false);
    }
}

static int64_t q_of_angle(double a)
{
    return (int64_t)floor(a * 4.0 * (double)opt.ppr / (2 * M_PI));
}

/* DC motor: tau dw/dt = W u - w, exact over one update of dt with u held. */
static avr_cycle_count_t dc_update(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)param;
    double duty = (a->data[REG_TCCR1A] & (1 << BIT_COM1A1)) ? a->data[REG_OCR1AL] / 255.0
                                                           : (double)pb1_level;
    double u = duty * ((a->data[REG_PORTB] & 1) ? 1.0 : -1.0);
    double dt = DC_UPDATE_CYCLES / F_CPU;
    double e = exp(-dt / opt.dc_tau);
    double w_inf = opt.dc_top_speed * u;
    angle += w_inf * dt + (omega - w_inf) * opt.dc_tau * (1.0 - e);
    omega = w_inf + (omega - w_inf) * e;
    encoder_to(q_of_angle(angle));
    return when + DC_UPDATE_CYCLES;
}

/* --shaft-speed: the next transition's exact cycle, the first cycle at which the angle W c / F
 * has crossed the state boundary: forward q + 1 at c >= (q + 1) P, backward q - 1 at c > -q P,
 * P = F 2 pi / (4 ppr |W|) cycles per state. */
static avr_cycle_count_t shaft_next_cycle(void)
{
    long double t = opt.shaft_speed > 0 ? (long double)(q + 1) * shaft_period
                                        : (long double)(-q) * shaft_period;
    long double c = opt.shaft_speed > 0 ? ceill(t) : floorl(t) + 1;
    return c < 1 ? 1 : (avr_cycle_count_t)c;
}

static avr_cycle_count_t shaft_transition(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)a;
    (void)when;
    (void)param;
    encoder_to(q + (opt.shaft_speed > 0 ? 1 : -1));
    return shaft_next_cycle();
}

/* ------------------------------------------------------------------ UART */

static unsigned uart_bit_cycles(void)
{
    unsigned ubrr = (unsigned)(avr->data[REG_UBRR0L] | ((avr->data[REG_UBRR0H] & 0x0F) << 8));
    return (avr->data[REG_UCSR0A] & (1 << BIT_U2X0) ? 8u : 16u) * (ubrr + 1);
}

/* simavr 1.6 always counts a parity bit in its byte time (11 bit times for 8N1); set the frame
 * the firmware configured: start + data + parity (if enabled) + stop bits. Called when the
 * UART's registers change. */
static void uart_fix_frame(void)
{
    uint8_t c = avr->data[REG_UCSR0C];
    static const int databits[8] = {5, 6, 7, 8, 8, 8, 8, 9};
    int db = databits[(c >> 1) & 3]; /* UCSZ02 lives in UCSR0B; 9-bit frames are not modelled */
    int parity = (c >> 4) & 3 ? 1 : 0;
    int stop = (c & (1 << 3)) ? 2 : 1;
    if (uart0)
        uart0->cycles_per_byte = (avr_cycle_count_t)uart_bit_cycles() * (unsigned)(1 + db + parity + stop);
}

static void tx_push(uint8_t b)
{
    if (tx_len == TX_BUF) {
        tx_dropped++;
        return;
    }
    txbuf[(tx_head + tx_len) % TX_BUF] = b;
    tx_len++;
}

static void on_uart_output(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    uint8_t b = (uint8_t)value;
    tx_bytes++;
    if (silence) {
        tx_dropped++;
        return;
    }
    tx_seen++;
    if (corrupt_tx_every && tx_seen % corrupt_tx_every == 0) {
        b ^= (uint8_t)(1u << (corrupt_tx_bit++ & 7));
        corrupted_tx++;
    }
    if (pty_master >= 0 || opt.lockstep)
        tx_push(b);
}

static void rx_arm(void);

static void on_xoff(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    xoff = value != 0;
}

static void on_xon(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (value) {
        xoff = false;
        rx_arm(); /* the receive FIFO is empty: hand over the next host byte */
    }
}

/* Host-to-board bytes. A byte whose frame starts at S is readable at S + frame (its stop bit),
 * frames back to back: S = max(the byte reached the board, the previous byte's end). simavr 1.6
 * makes a byte readable one byte time after it enters an empty receive FIFO, and lets the chip
 * read a second queued byte at once; so a byte is handed over only into an empty FIFO, with
 * simavr's byte time set for that hand-over to end exactly at the byte's stop bit. */
static uint64_t rx_arrival, rx_line_free;

static avr_cycle_count_t rx_inject(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)when;
    (void)param;
    if (!rx_len || !uart0 || xoff || uart0->input.read != uart0->input.write) {
        rx_timer_armed = false; /* on_xon arms again when the chip has read its byte */
        return 0;
    }
    uint64_t frame = 10ull * uart_bit_cycles();
    uint64_t start = rx_arrival > rx_line_free ? rx_arrival : rx_line_free;
    uint64_t ready = start + frame;
    if (ready <= a->cycle)
        ready = a->cycle + 1; /* the chip read late: the byte waited in the receive buffer */
    uint8_t b = rxbuf[rx_head];
    rx_head = (rx_head + 1) % RX_BUF;
    rx_len--;
    rx_seen++;
    if (corrupt_rx_every && rx_seen % corrupt_rx_every == 0) {
        b ^= (uint8_t)(1u << (corrupt_rx_bit++ & 7));
        corrupted_rx++;
    }
    rx_bytes++;
    avr_cycle_count_t byte_time = uart0->cycles_per_byte;
    uart0->cycles_per_byte = ready - a->cycle;
    avr_raise_irq(avr_io_getirq(a, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT), b);
    uart0->cycles_per_byte = byte_time;
    rx_line_free = ready;
    return ready; /* try the next byte when this one is readable (if the chip dropped it) */
}

static void rx_arm(void)
{
    if (rx_timer_armed || !rx_len)
        return;
    rx_timer_armed = true;
    avr_cycle_timer_register(avr, 1, rx_inject, NULL);
}

/* Bytes from the command channel ('rx HEX'): on the wire from this cycle on, after any queued. */
static bool rx_queue(const uint8_t *b, size_t n)
{
    if (n > RX_BUF - rx_len)
        return false;
    if (!rx_len)
        rx_arrival = avr->cycle;
    for (size_t i = 0; i < n; i++)
        rxbuf[(rx_head + rx_len + i) % RX_BUF] = b[i];
    rx_len += n;
    if (rx_len > rx_backlog_max)
        rx_backlog_max = rx_len;
    rx_arm();
    return true;
}

/* --lockstep: the answer to 'run N' when the run is over, with the bytes the chip sent. */
static void answer_run(void)
{
    printf("{\"ok\": \"run\", \"cycle\": %llu, \"tx\": \"", (unsigned long long)avr->cycle);
    for (; tx_len; tx_len--, tx_head = (tx_head + 1) % TX_BUF)
        printf("%02x", txbuf[tx_head]);
    printf("\"}\n");
}

static void uart_stdio_off(void)
{
    uint32_t f = 0;
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &f);
    f &= ~AVR_UART_FLAG_STDIO;
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &f);
}

static void pty_io(void)
{
    if (pty_master < 0)
        return;
    /* board to host */
    while (tx_len) {
        size_t chunk = tx_len;
        if (tx_head + chunk > TX_BUF)
            chunk = TX_BUF - tx_head;
        ssize_t w = write(pty_master, txbuf + tx_head, chunk);
        if (w <= 0)
            break; /* EAGAIN: the pty is full; EIO: no host; keep the bytes (bounded) */
        tx_head = (tx_head + (size_t)w) % TX_BUF;
        tx_len -= (size_t)w;
    }
    /* host to board */
    if (!rx_len)
        rx_arrival = avr->cycle;
    while (rx_len < RX_BUF) {
        size_t tail = (rx_head + rx_len) % RX_BUF;
        size_t room = tail >= rx_head ? RX_BUF - tail : rx_head - tail;
        if (room > RX_BUF - rx_len)
            room = RX_BUF - rx_len;
        ssize_t r = read(pty_master, rxbuf + tail, room);
        if (r <= 0)
            break; /* EAGAIN or EIO (host closed the slave): not an error */
        rx_len += (size_t)r;
    }
    if (rx_len > rx_backlog_max)
        rx_backlog_max = rx_len;
    rx_arm();
}

static void open_pty(void)
{
    if (openpty(&pty_master, &pty_slave, NULL, NULL, NULL) != 0)
        die_usage("cannot open a pseudo-terminal: %s", strerror(errno));
    struct termios t;
    if (tcgetattr(pty_slave, &t) == 0) {
        cfmakeraw(&t);
        tcsetattr(pty_slave, TCSANOW, &t);
    }
    fcntl(pty_master, F_SETFL, fcntl(pty_master, F_GETFL) | O_NONBLOCK);
    fcntl(pty_master, F_SETFD, FD_CLOEXEC);
    fcntl(pty_slave, F_SETFD, FD_CLOEXEC);
    const char *name = ttyname(pty_slave);
    snprintf(pty_name, sizeof pty_name, "%s", name ? name : "");
}

static bool link_made;

/* An existing path is replaced only when it is a board's link left behind: a symlink to a
 * pseudo-terminal that is gone. Anything else (a file, a folder, a user's symlink, a live
 * board's link) stays, and the board refuses to start. */
static void make_link(void)
{
    struct stat st;
    if (lstat(opt.link, &st) == 0) {
        char target[sizeof pty_name];
        ssize_t n = S_ISLNK(st.st_mode) ? readlink(opt.link, target, sizeof target - 1) : -1;
        if (n >= 0)
            target[n] = 0;
        if (n < 0 || strncmp(target, "/dev/pts/", 9) != 0 || stat(target, &st) == 0)
            die_usage("--link: '%s' exists and is not a dead board's link to a pseudo-terminal; not replacing it",
                      shorten(opt.link));
        if (unlink(opt.link) != 0)
            die_usage("--link: cannot replace '%s': %s", shorten(opt.link), strerror(errno));
    }
    if (symlink(pty_name, opt.link) != 0)
        die_usage("--link: cannot create '%s': %s", shorten(opt.link), strerror(errno));
    link_made = true;
}

static void remove_link(void)
{
    char target[sizeof pty_name];
    if (!link_made)
        return;
    ssize_t n = readlink(opt.link, target, sizeof target - 1);
    if (n >= 0) {
        target[n] = 0;
        if (strcmp(target, pty_name) == 0)
            unlink(opt.link);
    }
    link_made = false;
}

/* ------------------------------------------------------------------ pins */

/* The stepper's rotor does not jump from one microstep to the next: at speed it turns smoothly at
 * the step rate. The encoder transitions a step causes are spread evenly over the time since the
 * previous step (at most STEP_MOVE_MAX_CYCLES, the longest a rotor takes to settle on a step), so
 * the shaft runs one step behind the STEP edges at the step rate, and two transitions never come
 * at the same cycle (an encoder whose A and B edges coincide cannot be decoded, on the chip as in
 * any model). */
static avr_cycle_count_t stepper_transition(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)a;
    (void)param;
    if (q != step_q_target)
        encoder_to(q + (step_q_target > q ? 1 : -1));
    return q == step_q_target ? 0 : when + step_spacing;
}

static void stepper_move(uint64_t now)
{
    uint64_t interval = have_last_step ? now - last_step_cycle : STEP_MOVE_MAX_CYCLES;
    if (interval > STEP_MOVE_MAX_CYCLES)
        interval = STEP_MOVE_MAX_CYCLES;
    last_step_cycle = now;
    have_last_step = true;
    step_q_target = floor_div(step_pos * 4 * opt.ppr, (int64_t)opt.steps_per_rev * opt.microsteps);
    avr_cycle_timer_cancel(avr, stepper_transition, NULL);
    int64_t n = step_q_target > q ? step_q_target - q : q - step_q_target;
    if (n == 0)
        return;
    step_spacing = (avr_cycle_count_t)(interval / (uint64_t)(n + 1));
    if (step_spacing < 1)
        step_spacing = 1;
    avr_cycle_timer_register(avr, step_spacing, stepper_transition, NULL);
}

static void on_step_pin(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    int level = (value & 0xFF) != 0;
    int rising = level && !pb1_level;
    pb1_level = level;
    if (!rising || opt.motor != MOTOR_STEPPER)
        return;
    uint64_t now = avr->cycle;
    steps.count++;
    if (steps.last_valid)
        durations_add(&steps.interval, now - steps.last);
    steps.last = now;
    steps.last_valid = true;
    if (avr->data[REG_PORTD] & (1 << 7)) {
        steps.ignored++;
        return;
    }
    int forward = avr->data[REG_PORTB] & 1;
    if (forward)
        steps.forward++;
    else
        steps.backward++;
    if (opt.shaft_given)
        return;
    step_pos += forward ? 1 : -1;
    stepper_move(now);
}

static void on_probe_pin(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    int level = (value & 0xFF) != 0;
    if (level == pc0_level)
        return;
    pc0_level = level;
    uint64_t now = avr->cycle;
    if (level) {
        probe.count++;
        if (probe.rise_valid)
            durations_add(&probe.period, now - probe.last_rise);
        probe.last_rise = now;
        probe.rise_valid = true;
    } else if (probe.rise_valid) {
        durations_add(&probe.high, now - probe.last_rise);
    }
}

/* ------------------------------------------------------------------ measurements */

static void clear_window(void)
{
    window_start = avr->cycle;
    isr_cycles = 0;
    memset(isr_vec, 0, sizeof isr_vec);
    uint64_t last_rise = probe.last_rise; /* a fact of the chip's schedule, not of the window */
    memset(&probe, 0, sizeof probe);
    probe.last_rise = last_rise;
    memset(&steps, 0, sizeof steps);
}

static double current_angle(void)
{
    if (opt.shaft_given)
        return opt.shaft_speed * (double)avr->cycle / F_CPU;
    if (opt.motor == MOTOR_STEPPER)
        return (double)step_pos * 2 * M_PI / ((double)opt.steps_per_rev * (double)opt.microsteps);
    return angle;
}

static void print_stats(const char *event)
{
    double wall = now_s() - wall_start;
    unsigned bit = uart_bit_cycles();
    printf("{\"event\": \"%s\", \"cycle\": %llu, \"time_s\": %.17g, \"wall_s\": %.6f, \"behind_s\": %.6f, "
           "\"sp_min\": %u, \"ramend\": %u, \"stack_bytes\": %u, \"window_cycles\": %llu, "
           "\"isr_cycles\": %llu, \"isr\": {",
           event, (unsigned long long)avr->cycle, (double)avr->cycle / F_CPU, wall, behind_s, sp_min,
           RAMEND, sp_min <= RAMEND ? RAMEND - sp_min : 0,
           (unsigned long long)(avr->cycle - window_start), (unsigned long long)isr_cycles);
    bool first = true;
    for (int v = 0; v < NVECTORS; v++) {
        if (!isr_vec[v].count && !isr_vec[v].cycles)
            continue;
        printf("%s\"%d\": {\"cycles\": %llu, \"count\": %llu}", first ? "" : ", ", v,
               (unsigned long long)isr_vec[v].cycles, (unsigned long long)isr_vec[v].count);
        first = false;
    }
    printf("}, \"probe\": {\"count\": %llu, \"last_rise\": %llu, \"period_min\": %llu, \"period_max\": %llu, "
           "\"period_mean\": %.3f, \"high_max\": %llu, \"high_mean\": %.3f}",
           (unsigned long long)probe.count, (unsigned long long)probe.last_rise, (unsigned long long)probe.period.min,
           (unsigned long long)probe.period.max, durations_mean(&probe.period),
           (unsigned long long)probe.high.max, durations_mean(&probe.high));
    printf(", \"steps\": {\"count\": %llu, \"forward\": %llu, \"backward\": %llu, \"ignored\": %llu, "
           "\"interval_min\": %llu, \"interval_max\": %llu, \"interval_mean\": %.3f, "
           "\"interval_std\": %.3f}",
           (unsigned long long)steps.count, (unsigned long long)steps.forward,
           (unsigned long long)steps.backward, (unsigned long long)steps.ignored,
           (unsigned long long)steps.interval.min, (unsigned long long)steps.interval.max,
           durations_mean(&steps.interval),
           steps.interval.n > 1 ? sqrt(steps.interval.m2 / (double)(steps.interval.n - 1)) : 0.0);
    double w = opt.shaft_given ? opt.shaft_speed : opt.motor == MOTOR_DC ? omega : 0.0;
    double duty = 0.0;
    if (opt.motor == MOTOR_DC)
        duty = (avr->data[REG_TCCR1A] & (1 << BIT_COM1A1)) ? avr->data[REG_OCR1AL] / 255.0
                                                           : (double)pb1_level;
    printf(", \"q\": %lld, \"transitions\": %llu, \"angle\": %.17g, \"omega\": %.17g, \"duty\": %.17g, "
           "\"enabled\": %s, \"dir\": %d",
           (long long)q, (unsigned long long)transitions, current_angle(), w, duty,
           (avr->data[REG_PORTD] & (1 << 7)) ? "false" : "true", avr->data[REG_PORTB] & 1);
    printf(", \"rx_bytes\": %llu, \"tx_bytes\": %llu, \"tx_dropped\": %llu, \"corrupted_tx\": %llu, "
           "\"corrupted_rx\": %llu, \"rx_backlog_max\": %zu, \"baud\": %.3f, \"state\": %d}\n",
           (unsigned long long)rx_bytes, (unsigned long long)tx_bytes, (unsigned long long)tx_dropped,
           (unsigned long long)corrupted_tx, (unsigned long long)corrupted_rx, rx_backlog_max,
           F_CPU / bit, avr->state);
    flush_out();
}

/* ------------------------------------------------------------------ chip setup and reset */

static void start_models(void)
{
    if (opt.shaft_given) {
        if (opt.shaft_speed != 0.0) {
            avr_cycle_count_t c = shaft_next_cycle();
            avr_cycle_timer_register(avr, c > avr->cycle ? c - avr->cycle : 1, shaft_transition, NULL);
        }
    } else if (opt.motor == MOTOR_DC) {
        avr_cycle_timer_register(avr, DC_UPDATE_CYCLES, dc_update, NULL);
    } else if (opt.motor == MOTOR_STEPPER && q != step_q_target) {
        avr_cycle_timer_register(avr, step_spacing, stepper_transition, NULL); /* a move under way */
    }
    /* simavr 1.6 polls a low INT0/INT1 pin every cycle while ISCn = 00 (the reset value), one
     * more poller at every re-raise of a low level: model level mode as a falling edge */
    avr_extint_set_strict_lvl_trig(avr, 0, 0);
    avr_extint_set_strict_lvl_trig(avr, 1, 0);
    rx_timer_armed = false;
    rx_arm();
    uart_stdio_off();
    uart_config = 0xFFFFFFFF;
    drive_encoder_pins(true);
}

static void reset_chip(void)
{
    avr_reset(avr); /* also cancels every cycle timer: start the models again */
    sp_min = (uint16_t)(avr->data[REG_SPL] | (avr->data[REG_SPH] << 8));
    xoff = false;
    start_models();
}

/* ------------------------------------------------------------------ commands */

static void reply_error(const char *what, const char *line)
{
    printf("{\"error\": \"%s: '%s'\"}\n", what, shorten(line));
    flush_out();
}

static bool parse_uint(const char *s, unsigned long max, unsigned long *out)
{
    char *end;
    int base = (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) ? 16 : 10;
    if (!*s || *s == '-' || *s == '+' || isspace((unsigned char)*s))
        return false;
    errno = 0;
    unsigned long v = strtoul(s, &end, base);
    if (*end || errno || v > max || end == s + (base == 16 ? 2 : 0))
        return false;
    *out = v;
    return true;
}

static int hex_digit(char c)
{
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
}

static void command(char *line)
{
    char *argv[4] = {0};
    int argc = 0;
    for (char *tok = strtok(line, " \t\r"); tok; tok = strtok(NULL, " \t\r")) {
        if (argc == 4) {
            reply_error("too many words", line);
            return;
        }
        argv[argc++] = tok;
    }
    if (argc == 0)
        return;
    const char *c = argv[0];
    if (strcmp(c, "stats") == 0 && argc == 1)
        print_stats("stats");
    else if (strcmp(c, "clear") == 0 && argc == 1) {
        clear_window();
        printf("{\"ok\": \"clear\", \"cycle\": %llu}\n", (unsigned long long)avr->cycle);
    } else if (strcmp(c, "quit") == 0 && argc == 1)
        quitting = true;
    else if (strcmp(c, "reset") == 0 && argc == 1) {
        reset_chip();
        printf("{\"ok\": \"reset\", \"cycle\": %llu}\n", (unsigned long long)avr->cycle);
    } else if (strcmp(c, "silence") == 0 && argc == 2 &&
               (strcmp(argv[1], "on") == 0 || strcmp(argv[1], "off") == 0)) {
        silence = strcmp(argv[1], "on") == 0;
        printf("{\"ok\": \"silence\", \"silence\": %s}\n", silence ? "true" : "false");
    } else if (strcmp(c, "corrupt") == 0 && argc == 3 &&
               (strcmp(argv[1], "tx") == 0 || strcmp(argv[1], "rx") == 0)) {
        unsigned long n;
        if (!parse_uint(argv[2], 1000000000ul, &n)) {
            reply_error("corrupt: N must be an integer from 0 to 1000000000", argv[2]);
            return;
        }
        if (argv[1][0] == 't') {
            corrupt_tx_every = (unsigned)n;
            tx_seen = 0;
        } else {
            corrupt_rx_every = (unsigned)n;
            rx_seen = 0;
        }
        printf("{\"ok\": \"corrupt\", \"direction\": \"%s\", \"every\": %lu}\n", argv[1], n);
    } else if (strcmp(c, "nudge") == 0 && argc == 2 && opt.motor == MOTOR_NONE && !opt.shaft_given &&
               (strcmp(argv[1], "+1") == 0 || strcmp(argv[1], "-1") == 0)) {
        int d = argv[1][0] == '+' ? 1 : -1; /* one quadrature transition, as a shaft at rest shaking */
        angle += d * 2 * M_PI / (4.0 * (double)opt.ppr);
        encoder_to(q + d);
        printf("{\"ok\": \"nudge\", \"q\": %lld}\n", (long long)q);
    } else if (strcmp(c, "rx") == 0 && argc == 2) {
        static uint8_t bytes[LINE_MAX_LEN / 2];
        size_t len = strlen(argv[1]), n = len / 2;
        bool ok = len % 2 == 0 && n <= sizeof bytes;
        for (size_t i = 0; ok && i < n; i++) {
            int hi = hex_digit(argv[1][2 * i]), lo = hex_digit(argv[1][2 * i + 1]);
            ok = hi >= 0 && lo >= 0;
            bytes[i] = (uint8_t)(hi << 4 | lo);
        }
        if (!ok) {
            reply_error("rx: expected bytes as pairs of hex digits", argv[1]);
            return;
        }
        if (!rx_queue(bytes, n)) {
            reply_error("rx: the board's receive queue is full", argv[1]);
            return;
        }
        printf("{\"ok\": \"rx\", \"bytes\": %zu, \"cycle\": %llu}\n", n, (unsigned long long)avr->cycle);
    } else if (strcmp(c, "run") == 0 && argc == 2) {
        unsigned long n;
        if (!opt.lockstep) {
            reply_error("run: only with --lockstep (without it the board runs by itself)", line);
            return;
        }
        if (!parse_uint(argv[1], 16000000000000ul, &n) || n == 0) {
            reply_error("run: N must be an integer from 1 to 16000000000000 cycles", argv[1]);
            return;
        }
        run_until = avr->cycle + n;
        run_pending = true;
        return; /* answered when the run is over */
    } else if (strcmp(c, "peek") == 0 && argc == 3) {
        unsigned long addr, n;
        if (!parse_uint(argv[1], RAMEND, &addr)) {
            reply_error("peek: ADDR must be 0..0x8FF (decimal or 0x hex)", argv[1]);
            return;
        }
        if (!parse_uint(argv[2], 256, &n) || n == 0 || addr + n - 1 > RAMEND) {
            reply_error("peek: N must be 1..256 and ADDR+N-1 <= 0x8FF", argv[2]);
            return;
        }
        printf("{\"peek\": %lu, \"hex\": \"", addr);
        for (unsigned long i = 0; i < n; i++)
            printf("%02x", avr->data[addr + i]);
        printf("\"}\n");
    } else {
        reply_error("unknown or malformed command (silence on|off, corrupt tx|rx N, reset, stats, "
                    "clear, peek ADDR N, rx HEX, run N with --lockstep, nudge +1|-1 with --motor none "
                    "and no --shaft-speed, quit)",
                    line);
        return;
    }
    flush_out();
}

static char cmdline[LINE_MAX_LEN + 1];
static size_t cmd_len;
static bool cmd_overflow, stdin_open = true;
static char inbuf[4096];
static size_t in_len;

static bool running(void)
{
    return opt.lockstep && avr->cycle < run_until;
}

/* Read what the host sent (waiting up to wait_ms for it) and carry out its commands; with
 * --lockstep, the commands after a 'run' wait in inbuf until the run is over. */
static void stdin_io(int wait_ms)
{
    if (stdin_open && !in_len) {
        struct pollfd p = {.fd = 0, .events = POLLIN};
        if (poll(&p, 1, wait_ms) <= 0 || !(p.revents & (POLLIN | POLLHUP | POLLERR)))
            return;
        ssize_t r = read(0, inbuf, sizeof inbuf);
        if (r < 0 && (errno == EAGAIN || errno == EINTR))
            return;
        if (r <= 0) {   /* no more commands: the end, unless --duration says when */
            stdin_open = false;
            if (!opt.duration_given)
                quitting = true;
            return;
        }
        in_len = (size_t)r;
    }
    size_t i = 0;
    while (i < in_len && !quitting && !running()) {
        char ch = inbuf[i++];
        if (ch == '\n') {
            if (cmd_overflow)
                reply_error("command longer than 1024 characters", cmdline);
            else {
                cmdline[cmd_len] = 0;
                if (memchr(cmdline, 0, cmd_len))
                    reply_error("NUL byte in command", "");
                else
                    command(cmdline);
            }
            cmd_len = 0;
            cmd_overflow = false;
        } else if (cmd_len < LINE_MAX_LEN)
            cmdline[cmd_len++] = ch;
        else {
            cmdline[LINE_MAX_LEN] = 0;
            cmd_overflow = true;
        }
    }
    memmove(inbuf, inbuf + i, in_len - i);
    in_len -= i;
}

/* ------------------------------------------------------------------ main loop */

#define SP_TORN_MAX 4 /* instructions between the two halves (gcc: out SPH; out SREG; out SPL) */

/* Whether the instruction at byte address pc is an OUT to SPL (0x3D) or SPH (0x3E):
 * 1011 1AAr rrrr AAAA. */
static int sp_half_written(avr_flashaddr_t pc)
{
    if (pc + 1 > avr->flashend)
        return 0;
    unsigned op = avr->flash[pc] | (avr->flash[pc + 1] << 8);
    if ((op & 0xF800) != 0xB800)
        return 0;
    unsigned a = ((op >> 5) & 0x30) | (op & 0x0F);
    return a == 0x3D || a == 0x3E;
}

static void no_sleep(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    (void)how_long; /* pacing is done by the main loop */
}

static void on_signal(int sig)
{
    stop_signal = sig;
}

static void pace(void)
{
    if (opt.speed <= 0 || opt.lockstep)
        return;
    double target = pace_wall + (double)(avr->cycle - pace_cycle) / F_CPU / opt.speed;
    double now = now_s();
    if (now < target) {
        double d = target - now;
        struct timespec ts = {(time_t)d, (long)((d - floor(d)) * 1e9)};
        nanosleep(&ts, NULL);
    } else if (now - target > BEHIND_REBASE_S) {
        if (now - target > behind_s)
            behind_s = now - target;
        pace_wall = now;
        pace_cycle = avr->cycle;
    }
}

static void host_io(void)
{
    uint32_t cfg = (uint32_t)avr->data[REG_UBRR0L] | ((uint32_t)avr->data[REG_UBRR0H] << 8) |
                   ((uint32_t)(avr->data[REG_UCSR0A] & (1 << BIT_U2X0)) << 16) |
                   ((uint32_t)avr->data[REG_UCSR0C] << 24);
    if (cfg != uart_config) {
        uart_config = cfg;
        uart_fix_frame();
    }
    pty_io();
    if (!opt.lockstep)
        stdin_io(0); /* with --lockstep, commands wait until the run is over */
}

static void quiet_logger(avr_t *a, const int level, const char *format, va_list ap)
{
    (void)a;
    (void)level;
    (void)format;
    (void)ap;
}

/* Point stdout and stderr at /dev/null (on) or back (off) around libsimavr's chatty loaders. */
static void hush(bool on)
{
    static int saved_out = -1, saved_err = -1;
    fflush(stdout);
    fflush(stderr);
    if (on) {
        int devnull = open("/dev/null", O_WRONLY);
        if (devnull < 0)
            return;
        saved_out = dup(1);
        saved_err = dup(2);
        dup2(devnull, 1);
        dup2(devnull, 2);
        close(devnull);
    } else {
        if (saved_out >= 0)
            dup2(saved_out, 1), close(saved_out);
        if (saved_err >= 0)
            dup2(saved_err, 2), close(saved_err);
        saved_out = saved_err = -1;
    }
}

int main(int argc, char **argv)
{
    parse_args(argc, argv);
    check_elf(opt.elf);

    /* libsimavr prints its own diagnostics: stdout carries only our JSON, stderr one line */
    avr_global_logger_set(quiet_logger);
    elf_firmware_t fw;
    memset(&fw, 0, sizeof fw);
    /* libsimavr's ELF reader trusts the file's tables (a damaged ELF can crash it): read it
     * once in a child process first */
    fflush(stdout);
    fflush(stderr);
    pid_t child = fork();
    if (child == 0) {
        hush(true);
        _exit(elf_read_firmware(opt.elf, &fw) == 0 ? 0 : 1);
    }
    int status = 0;
    if (child < 0 || waitpid(child, &status, 0) != child)
        die_usage("cannot check '%s': %s", shorten(opt.elf), strerror(errno));
    if (WIFSIGNALED(status))
        die_usage("%s: damaged ELF (libsimavr's reader crashed on it)", shorten(opt.elf));
    int rc = WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : 1;
    if (rc == 0) {
        hush(true);
        rc = elf_read_firmware(opt.elf, &fw);
        hush(false);
    }
    if (rc != 0)
        die_usage("%s: libsimavr cannot read this ELF", shorten(opt.elf));
    if (fw.flashsize == 0)
        die_usage("%s: no program in this ELF", shorten(opt.elf));
    if (fw.flashsize > FLASH_BYTES || fw.eesize > EEPROM_BYTES)
        die_usage("%s: program (%u bytes) or EEPROM (%u bytes) too large for the ATmega328P",
                  shorten(opt.elf), fw.flashsize, fw.eesize);
    if (fw.mmcu[0] && strcmp(fw.mmcu, "atmega328p") != 0)
        die_usage("%s: built for '%s', not atmega328p", shorten(opt.elf), shorten(fw.mmcu));

    avr = avr_make_mcu_by_name("atmega328p");
    if (!avr)
        die_usage("libsimavr has no atmega328p");
    avr_init(avr);
    avr->log = 0;
    hush(true);
    avr_load_firmware(avr, &fw);
    hush(false);
    avr->frequency = (uint32_t)F_CPU_INT;
    avr->sleep = no_sleep;

    for (avr_io_t *io = avr->io_port; io; io = io->next)
        if (io->kind && strcmp(io->kind, "uart") == 0 && ((avr_uart_t *)io)->name == '0')
            uart0 = (avr_uart_t *)io;

    irq_enc_a = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), 2);
    irq_enc_b = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), 3);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 1), on_step_pin, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('C'), 0), on_probe_pin, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
                            on_uart_output, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF), on_xoff,
                            NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON), on_xon,
                            NULL);

    if (opt.shaft_given)
        shaft_period = F_CPU * 2 * M_PI / (4.0 * (double)opt.ppr * fabs(opt.shaft_speed));
    if (opt.pty) {
        open_pty();
        if (opt.link)
            make_link();
    }

    signal(SIGPIPE, SIG_IGN);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);

    start_models();
    wall_start = pace_wall = now_s();
    pace_cycle = avr->cycle;
    uint64_t end_cycle = opt.duration_given ? (uint64_t)llround(opt.duration * F_CPU) : UINT64_MAX;

    if (opt.pty)
        printf("{\"event\": \"ready\", \"pty\": \"%s\", \"pid\": %d}\n", pty_name, (int)getpid());
    else
        printf("{\"event\": \"ready\", \"pty\": null, \"pid\": %d}\n", (int)getpid());
    flush_out();

    bool halted_reported = false;
    int sp_torn = 0;
    while (!quitting && !stop_signal && avr->cycle < end_cycle) {
        if (opt.lockstep && !running()) { /* paused: the host's turn */
            if (run_pending) {
                run_pending = false;
                host_io(); /* the UART's configuration */
                answer_run();
                flush_out();
            }
            if (!stdin_open && !in_len)
                break;
            stdin_io(100);
            continue;
        }
        int sp_half = sp_half_written(avr->pc);
        uint8_t before = avr->interrupts.running_ptr;
        avr_int_vector_t *vec = before ? avr->interrupts.running[before - 1] : NULL;
        uint64_t c0 = avr->cycle;
        int state = avr_run(avr);
        /* the instruction ran in the vector that was running before it (a RETI pops the vector
         * during its own instruction; simavr 1.6 enters a vector after the instruction, in 0
         * cycles) */
        if (vec) {
            uint64_t d = avr->cycle - c0;
            isr_cycles += d;
            if (vec->vector < NVECTORS)
                isr_vec[vec->vector].cycles += d;
        }
        uint8_t after = avr->interrupts.running_ptr;
        if (after > before) {
            unsigned v = avr->interrupts.running[after - 1]->vector;
            if (v < NVECTORS)
                isr_vec[v].count++;
        }
        /* SP is two 8-bit registers: between the writes of its two halves (a frame set up
         * or taken down, alloca) it holds neither the old nor the new value; skip those */
        if (sp_half)
            sp_torn = sp_torn ? 0 : SP_TORN_MAX;
        else if (sp_torn)
            sp_torn--;
        uint16_t sp = (uint16_t)(avr->data[REG_SPL] | (avr->data[REG_SPH] << 8));
        if (!sp_torn && sp < sp_min)
            sp_min = sp;
        if (state == cpu_Done || state == cpu_Crashed) {
            if (!halted_reported) {
                printf("{\"event\": \"halted\", \"state\": \"%s\", \"cycle\": %llu, \"pc\": %u}\n",
                       state == cpu_Done ? "done" : "crashed", (unsigned long long)avr->cycle,
                       (unsigned)avr->pc);
                flush_out();
                halted_reported = true;
            }
            avr->cycle += POLL_CYCLES; /* time goes on; the host may still reset the chip */
        } else
            halted_reported = false;
        if (avr->cycle >= next_poll) {
            next_poll = avr->cycle + POLL_CYCLES;
            host_io();
            if (avr->cycle >= next_pace) {
                next_pace = avr->cycle + PACE_CYCLES;
                pace();
            }
        }
    }
    print_stats("final");
    remove_link();
    return 0;
}
