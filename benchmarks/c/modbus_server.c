/* A minimal libmodbus TCP server: the C reference the gateway's latency is measured against.
 *
 * Serves NREGS holding and NREGS input registers (all set to VALUE) to any unit id on
 * HOST:PORT and answers what libmodbus answers (FC3, FC4, FC6 among them); several clients at
 * once through select(). Prints "listening on PORT" once bound (PORT 0 = an ephemeral port).
 *   modbus_server HOST PORT [NREGS [VALUE]]
 * Runs until killed.
 */
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <modbus.h>

static int listen_on(const char *host, int port)
{
    int s = socket(AF_INET, SOCK_STREAM, 0);
    int one = 1;
    struct sockaddr_in addr;
    if (s < 0)
        return -1;
    setsockopt(s, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    memset(&addr, 0, sizeof addr);
    addr.sin_family = AF_INET;
    addr.sin_port = htons((unsigned short)port);
    if (inet_pton(AF_INET, host, &addr.sin_addr) != 1 ||
        bind(s, (struct sockaddr *)&addr, sizeof addr) < 0 || listen(s, 16) < 0) {
        close(s);
        return -1;
    }
    return s;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: %s HOST PORT [NREGS [VALUE]]\n", argv[0]);
        return 2;
    }
    int nregs = argc > 3 ? atoi(argv[3]) : 200;
    int value = argc > 4 ? atoi(argv[4]) : 215;
    modbus_t *ctx = modbus_new_tcp(argv[1], atoi(argv[2]));
    modbus_mapping_t *map = modbus_mapping_new(0, 0, nregs, nregs);
    if (ctx == NULL || map == NULL) {
        fprintf(stderr, "modbus_server: %s\n", modbus_strerror(errno));
        return 1;
    }
    for (int i = 0; i < nregs; i++) {
        map->tab_registers[i] = (uint16_t)value;
        map->tab_input_registers[i] = (uint16_t)value;
    }
    /* our own socket so that port 0 works and the bound port can be printed */
    int server = listen_on(argv[1], atoi(argv[2]));
    if (server < 0) {
        fprintf(stderr, "modbus_server: cannot listen on %s:%s: %s\n", argv[1], argv[2], strerror(errno));
        return 1;
    }
    struct sockaddr_in bound;
    socklen_t len = sizeof bound;
    getsockname(server, (struct sockaddr *)&bound, &len);
    printf("listening on %d\n", ntohs(bound.sin_port));
    fflush(stdout);

    fd_set all;
    FD_ZERO(&all);
    FD_SET(server, &all);
    int fdmax = server;
    uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
    for (;;) {
        fd_set ready = all;
        if (select(fdmax + 1, &ready, NULL, NULL, NULL) < 0) {
            if (errno == EINTR)
                continue;
            perror("select");
            return 1;
        }
        for (int fd = 0; fd <= fdmax; fd++) {
            if (!FD_ISSET(fd, &ready))
                continue;
            if (fd == server) {
                int c = accept(server, NULL, NULL);
                if (c >= 0) {
                    int one = 1;
                    setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                    FD_SET(c, &all);
                    if (c > fdmax)
                        fdmax = c;
                }
                continue;
            }
            modbus_set_socket(ctx, fd);
            int rc = modbus_receive(ctx, query);
            if (rc > 0) {
                modbus_reply(ctx, query, rc, map);
            } else if (rc < 0) { /* closed by the client, or a broken frame: drop the connection */
                close(fd);
                FD_CLR(fd, &all);
            }
        }
    }
}
