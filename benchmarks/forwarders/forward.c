/* The floor of a user-space TCP forwarder (benchmarks/bench_proxy.py, issue 21): the design of pltf proxy's
   forwarding core (proxy/network.py) in C, without the rest. One connection at a time, loopback only:
   `forward TARGET_PORT` listens at 127.0.0.1 on a free port, prints "proxy listening at 127.0.0.1:PORT", and for
   each client connects to 127.0.0.1:TARGET_PORT and runs two threads, one per direction, each blocking in recv
   and sending what it read at once; a FIN read is passed on as a FIN (shutdown SHUT_WR). Measurement aid only:
   no error handling beyond what keeps it serving. Built at bench time with `cc -O2 -pthread`. */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <unistd.h>

struct pair {
    int from, to;
};

static void *pump(void *arg) {
    struct pair *p = arg;
    char buf[65536];
    ssize_t n;
    while ((n = recv(p->from, buf, sizeof buf, 0)) > 0)
        for (ssize_t sent = 0, k; sent < n; sent += k)
            if ((k = send(p->to, buf + sent, (size_t)(n - sent), MSG_NOSIGNAL)) <= 0) goto done;
done:
    shutdown(p->to, SHUT_WR);
    return 0;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: forward TARGET_PORT\n");
        return 2;
    }
    signal(SIGPIPE, SIG_IGN);
    int one = 1, listener = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in addr = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t len = sizeof addr;
    if (bind(listener, (struct sockaddr *)&addr, sizeof addr) || listen(listener, 16) ||
        getsockname(listener, (struct sockaddr *)&addr, &len)) {
        perror("forward");
        return 1;
    }
    printf("proxy listening at 127.0.0.1:%d\n", ntohs(addr.sin_port));
    fflush(stdout);
    struct sockaddr_in target = addr;
    target.sin_port = htons((unsigned short)atoi(argv[1]));
    for (;;) {
        int client = accept(listener, 0, 0), server = socket(AF_INET, SOCK_STREAM, 0);
        if (client < 0) continue;
        if (connect(server, (struct sockaddr *)&target, sizeof target) == 0) {
            setsockopt(client, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
            setsockopt(server, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
            struct pair up = {client, server}, down = {server, client};
            pthread_t a, b;
            pthread_create(&a, 0, pump, &up);
            pthread_create(&b, 0, pump, &down);
            pthread_join(a, 0);
            pthread_join(b, 0);
        }
        close(client);
        close(server);
    }
}
