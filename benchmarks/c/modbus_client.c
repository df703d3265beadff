/* A libmodbus TCP client that times register reads against several servers in interleaved rounds.
 *
 *   modbus_client [-n COUNT] [-a ADDRESS] [-f 3|4] [-r ROUNDS] [-w WARMUP] [-v] HOST:PORT/UNIT...
 *
 * One connection per target. Round r reads COUNT registers at ADDRESS (FC4 input registers by
 * default, -f 3 holding) from every target in turn, starting at target r mod (number of targets),
 * so that machine noise and position in the round fall on all targets alike. After WARMUP untimed rounds, prints one line per round: the round-trip time of
 * each target in nanoseconds, space-separated, in target order. -v first prints one line per
 * target with the values read ("HOST:PORT/UNIT: v0 v1 ..."); with -r 0 that is all it does.
 * Exit status 1 if a connection or a request fails (the message names the target).
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <modbus.h>

#define MAX_TARGETS 16

static long long now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static int read_regs(modbus_t *ctx, int fc, int address, int count, uint16_t *out)
{
    return fc == 3 ? modbus_read_registers(ctx, address, count, out)
                   : modbus_read_input_registers(ctx, address, count, out);
}

int main(int argc, char **argv)
{
    int count = 10, address = 0, fc = 4, rounds = 1000, warmup = 100, verbose = 0, opt;
    while ((opt = getopt(argc, argv, "n:a:f:r:w:v")) != -1) {
        switch (opt) {
        case 'n': count = atoi(optarg); break;
        case 'a': address = atoi(optarg); break;
        case 'f': fc = atoi(optarg); break;
        case 'r': rounds = atoi(optarg); break;
        case 'w': warmup = atoi(optarg); break;
        case 'v': verbose = 1; break;
        default:
            fprintf(stderr, "usage: %s [-n COUNT] [-a ADDRESS] [-f 3|4] [-r ROUNDS] [-w WARMUP] [-v] "
                            "HOST:PORT/UNIT...\n", argv[0]);
            return 2;
        }
    }
    int ntargets = argc - optind;
    if (ntargets < 1 || ntargets > MAX_TARGETS || count < 1 || count > MODBUS_MAX_READ_REGISTERS ||
        (fc != 3 && fc != 4)) {
        fprintf(stderr, "modbus_client: need 1..%d targets HOST:PORT/UNIT, -n 1..%d, -f 3 or 4\n",
                MAX_TARGETS, MODBUS_MAX_READ_REGISTERS);
        return 2;
    }
    modbus_t *ctx[MAX_TARGETS];
    const char **name = (const char **)&argv[optind];
    for (int t = 0; t < ntargets; t++) {
        char host[256];
        int port, unit;
        if (sscanf(name[t], "%255[^:]:%d/%d", host, &port, &unit) != 3) {
            fprintf(stderr, "modbus_client: %s: expected HOST:PORT/UNIT, e.g. 127.0.0.1:5020/5\n", name[t]);
            return 2;
        }
        ctx[t] = modbus_new_tcp(host, port);
        if (ctx[t] == NULL || modbus_set_slave(ctx[t], unit) < 0 || modbus_connect(ctx[t]) < 0) {
            fprintf(stderr, "modbus_client: %s: cannot connect: %s\n", name[t], modbus_strerror(errno));
            return 1;
        }
        modbus_set_response_timeout(ctx[t], 2, 0);
    }
    uint16_t regs[MODBUS_MAX_READ_REGISTERS];
    if (verbose) {
        for (int t = 0; t < ntargets; t++) {
            if (read_regs(ctx[t], fc, address, count, regs) != count) {
                fprintf(stderr, "modbus_client: %s: read failed: %s\n", name[t], modbus_strerror(errno));
                return 1;
            }
            printf("%s:", name[t]);
            for (int i = 0; i < count; i++)
                printf(" %u", regs[i]);
            printf("\n");
        }
    }
    long long *line = malloc(sizeof(long long) * (size_t)ntargets);
    for (int r = -warmup; r < rounds; r++) {
        if (r < 0 && rounds == 0)
            break;
        for (int k = 0; k < ntargets; k++) {
            int t = ((r + k) % ntargets + ntargets) % ntargets; /* rotate the first target */
            long long t0 = now_ns();
            int rc = read_regs(ctx[t], fc, address, count, regs);
            line[t] = now_ns() - t0;
            if (rc != count) {
                fprintf(stderr, "modbus_client: %s: read failed in round %d: %s\n", name[t], r,
                        modbus_strerror(errno));
                return 1;
            }
        }
        if (r >= 0) {
            for (int t = 0; t < ntargets; t++)
                printf(t ? " %lld" : "%lld", line[t]);
            printf("\n");
        }
    }
    free(line);
    for (int t = 0; t < ntargets; t++) {
        modbus_close(ctx[t]);
        modbus_free(ctx[t]);
    }
    return 0;
}
