/*
 * The case-study supervisory controller as embedded-style C on libmodbus.
 *
 * Fixed scan cycle: read inputs -> rules -> write outputs. All arithmetic is on the raw register
 * values (int16, 0.1 degC), no floating point: the thresholds are compile-time integers in the
 * same unit. A lost link is retried with a back-off (1, 2, 4, 8 scans) while the outputs fall
 * back to the safe state (generators off, hysteresis forgotten); after a reconnect the first
 * writes come from fresh readings. The command registers are rewritten every scan, which is
 * also the watchdog refresh of each device ([watchdog] refresh_on in the device maps).
 *
 *   controller -h 127.0.0.1 -p 5020                 Modbus TCP, scan every 10 s
 *   controller -d /dev/ttyUSB0 -b 19200             Modbus RTU (8N1)
 *   controller -p 5020 --lockstep --cycles 8640     one stdin line per scan, one line out per scan
 *
 * Registers (device maps in devices/):
 *   storage_io      unit 5  FC4 input 0..19  t_storage_1..10, t_dhw_storage_1..10 (int16 0.1 degC)
 *   chp_neotower2   unit 1  FC6 holding 8301 run_request (0/1), 8303 modulation_set (0.1 %)
 *   boiler_wolf_cgb unit 2  FC6 holding 200  demand_voltage (0.01 V). Not 198: 0 there means
 *                                            "no preset" = boiler back on its own control.
 *   dhw_station     unit 6  FC6 holding 0    charge_enable (0/1)
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <modbus.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* unit ids and wire addresses */
enum { UNIT_CHP = 1, UNIT_BOILER = 2, UNIT_IO = 5, UNIT_DHW = 6 };
enum { REG_CHP_RUN = 8301, REG_CHP_MOD = 8303, REG_BOILER_VOLT = 200, REG_DHW_CHARGE = 0 };
enum { IO_FIRST = 0, IO_COUNT = 20 };           /* storage sensors 1..10, DHW sensors 1..10 */
enum { TOP = 10, BOTTOM = 1, DHW_TOP = 10 };    /* sensor positions, 1 = bottom */
#define SENSOR_INVALID ((int16_t)-32768)        /* served for an open-circuit sensor */

/* thresholds in 0.1 degC, as the registers count */
#define CHP_ON_BELOW 650
#define BOILER_ON_BELOW 600
#define OFF_ABOVE 700
#define DHW_ON_BELOW 500
#define DHW_OFF_ABOVE 650
#define CHP_MODULATION 1000   /* 100.0 % in 0.1 % */
#define BOILER_DEMAND 1000    /* 10.00 V in 0.01 V */
#define MAX_BACKOFF_SCANS 8

struct outputs { int chp_on, boiler_on, dhw_on; };

struct link {
    modbus_t *ctx;
    int connected;
    int configured;       /* modulation written since the last connect */
    int backoff;          /* scans to wait before the next connect attempt */
    int wait;             /* scans left of the current back-off */
};

static volatile sig_atomic_t stop_requested;
static void on_signal(int sig) { (void)sig; stop_requested = 1; }

/* The rules of plant/controllers/rule_based.py, on raw 0.1 degC values. */
static struct outputs rules(struct outputs s, int16_t top, int16_t bottom, int16_t dhw_top)
{
    if (bottom > OFF_ABOVE) {
        s.chp_on = 0;
        s.boiler_on = 0;
    } else {
        if (top < CHP_ON_BELOW) s.chp_on = 1;
        if (top < BOILER_ON_BELOW) s.boiler_on = 1;
    }
    if (dhw_top > DHW_OFF_ABOVE || top < dhw_top)
        s.dhw_on = 0;
    else if (dhw_top < DHW_ON_BELOW && dhw_top < top)
        s.dhw_on = 1;
    return s;
}

static int write_reg(modbus_t *ctx, int unit, int addr, int value)
{
    if (modbus_set_slave(ctx, unit) == -1) return -1;
    return modbus_write_register(ctx, addr, (uint16_t)value) == 1 ? 0 : -1;
}

static int write_outputs(struct link *l, struct outputs o)
{
    if (!l->configured) {
        if (write_reg(l->ctx, UNIT_CHP, REG_CHP_MOD, CHP_MODULATION)) return -1;
        l->configured = 1;
    }
    if (write_reg(l->ctx, UNIT_CHP, REG_CHP_RUN, o.chp_on)) return -1;
    if (write_reg(l->ctx, UNIT_BOILER, REG_BOILER_VOLT, o.boiler_on ? BOILER_DEMAND : 0)) return -1;
    if (write_reg(l->ctx, UNIT_DHW, REG_DHW_CHARGE, o.dhw_on)) return -1;
    return 0;
}

static void drop_link(struct link *l)
{
    if (l->connected) modbus_close(l->ctx);
    l->connected = 0;
    l->configured = 0;
    l->backoff = l->backoff ? (l->backoff * 2 > MAX_BACKOFF_SCANS ? MAX_BACKOFF_SCANS : l->backoff * 2) : 1;
    l->wait = l->backoff;
}

/* Connect if due; returns 1 when the link is up. */
static int ensure_link(struct link *l)
{
    if (l->connected) return 1;
    if (l->wait > 0) {
        l->wait--;
        return 0;
    }
    if (modbus_connect(l->ctx) == -1) {
        drop_link(l);
        return 0;
    }
    l->connected = 1;
    l->backoff = 0;
    return 1;
}

/* One scan. Returns 0 on success, -1 when the link is down (outputs in the safe state). */
static int scan(struct link *l, struct outputs *state, int16_t t[3], const char **why)
{
    uint16_t regs[IO_COUNT];
    *why = "";
    if (!ensure_link(l)) {
        *why = l->wait == l->backoff ? "connect failed" : "back-off";
        goto safe;
    }
    if (modbus_set_slave(l->ctx, UNIT_IO) == -1 ||
        modbus_read_input_registers(l->ctx, IO_FIRST, IO_COUNT, regs) != IO_COUNT) {
        *why = modbus_strerror(errno);
        drop_link(l);
        goto safe;
    }
    t[0] = (int16_t)regs[TOP - 1];
    t[1] = (int16_t)regs[BOTTOM - 1];
    t[2] = (int16_t)regs[10 + DHW_TOP - 1];
    if (t[0] == SENSOR_INVALID || t[1] == SENSOR_INVALID || t[2] == SENSOR_INVALID) {
        /* a broken sensor is no reason to run a generator: command off, keep the link */
        *why = "sensor fault";
        *state = (struct outputs){0, 0, 0};
        if (write_outputs(l, *state)) drop_link(l);
        return -1;
    }
    {
        struct outputs next = rules(*state, t[0], t[1], t[2]);
        if (write_outputs(l, next)) {
            *why = modbus_strerror(errno);
            drop_link(l);
            goto safe;
        }
        *state = next;
    }
    return 0;
safe:
    *state = (struct outputs){0, 0, 0};
    return -1;
}

static void sleep_ms(long ms)
{
    struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
    while (nanosleep(&ts, &ts) == -1 && errno == EINTR && !stop_requested) {}
}

static long now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long)ts.tv_sec * 1000L + ts.tv_nsec / 1000000L;
}

static void usage(const char *prog)
{
    fprintf(stderr,
            "usage: %s [-h HOST] [-p PORT] | [-d SERIAL -b BAUD] [--period MS] [--lockstep] [--cycles N]\n"
            "  -h HOST      Modbus TCP host (default 127.0.0.1)\n"
            "  -p PORT      Modbus TCP port (default 5020)\n"
            "  -d SERIAL    Modbus RTU serial device (8N1), instead of TCP\n"
            "  -b BAUD      RTU baud rate (default 19200)\n"
            "  --period MS  scan period in ms (default 10000)\n"
            "  --lockstep   scan once per line on stdin, print one line per scan (test harness)\n"
            "  --cycles N   stop after N scans\n",
            prog);
}

int main(int argc, char **argv)
{
    const char *host = "127.0.0.1", *serial = NULL;
    int port = 5020, baud = 19200, lockstep = 0;
    long period_ms = 10000, cycles = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--lockstep")) { lockstep = 1; continue; }
        if (!v) { usage(argv[0]); return 2; }
        if (!strcmp(a, "-h")) host = v;
        else if (!strcmp(a, "-p")) port = atoi(v);
        else if (!strcmp(a, "-d")) serial = v;
        else if (!strcmp(a, "-b")) baud = atoi(v);
        else if (!strcmp(a, "--period")) period_ms = atol(v);
        else if (!strcmp(a, "--cycles")) cycles = atol(v);
        else { usage(argv[0]); return 2; }
        i++;
    }
    if (port <= 0 || port > 65535 || baud <= 0 || period_ms <= 0 || cycles < 0) {
        usage(argv[0]);
        return 2;
    }

    struct link l = {0};
    l.ctx = serial ? modbus_new_rtu(serial, baud, 'N', 8, 1) : modbus_new_tcp(host, port);
    if (!l.ctx) {
        fprintf(stderr, "controller: cannot create the Modbus context: %s\n", modbus_strerror(errno));
        return 1;
    }
    modbus_set_response_timeout(l.ctx, 0, 500000);   /* 0.5 s, well inside a 10 s scan */
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGPIPE, SIG_IGN);                          /* a dropped socket is an error, not death */

    struct outputs state = {0, 0, 0};
    char line[256];
    for (long n = 1; !stop_requested && (!cycles || n <= cycles); n++) {
        long t0 = now_ms();
        if (lockstep && !fgets(line, sizeof line, stdin)) break;
        int16_t t[3] = {0, 0, 0};
        const char *why;
        int rc = scan(&l, &state, t, &why);
        if (rc == 0)
            printf("scan=%ld top=%d bottom=%d dhw_top=%d chp=%d boiler=%d dhw=%d\n", n, t[0], t[1], t[2],
                   state.chp_on, state.boiler_on, state.dhw_on);
        else
            printf("scan=%ld link=%s (%s) chp=%d boiler=%d dhw=%d\n", n, l.connected ? "up" : "down", why,
                   state.chp_on, state.boiler_on, state.dhw_on);
        fflush(stdout);
        if (!lockstep) {
            long left = period_ms - (now_ms() - t0);
            if (left > 0) sleep_ms(left);
        }
    }
    /* Leave the plant safe: generators off (best effort), then close. In lock-step the harness
     * may still be stepping the plant after the last scan: wait for its end of input first, so
     * this write lands after the run and not inside the last scan period. */
    if (lockstep)
        while (!stop_requested && fgets(line, sizeof line, stdin)) {}
    if (l.connected) {
        state = (struct outputs){0, 0, 0};
        write_outputs(&l, state);
        modbus_close(l.ctx);
    }
    modbus_free(l.ctx);
    return 0;
}
