/* The forwarding loop of pltf proxy in C (proxy/network.py, issue 21): one thread per connection moves the bytes
 * of both directions, with the GIL released, and spins briefly after it moved bytes before it sleeps in poll().
 *
 * Why: a hop through a proxy whose thread sleeps in recv costs a wakeup of that thread, and on a virtual machine a
 * wakeup on another CPU costs 15-30 us, as much as the reference server takes to answer a GET_POSITION (about 60
 * us). A request/reply exchange pays two such wakeups through the proxy. Polling both sockets for SPIN after each
 * chunk (with sched_yield, so a client or a server that needs the CPU gets it) picks up the client's next request
 * or the target's reply without a wakeup. In Python such a spin cost more than it saved (proxy/README.md).
 *
 * Rules (the same as the threads of network.py, which stay as the fallback without a compiler):
 * - Bytes first: a chunk read from one side is sent on unchanged at once. A copy of it, with the time it was read
 *   and its side, is kept for the recorder (copied before it is sent, so a request is always kept before the
 *   reply it causes) and handed over in order, as a list of (side, time, bytes), to on_data - under the GIL, off
 *   the path of the bytes: when the loop is about to sleep, before an end is reported, and while bytes keep
 *   flowing every HAND_OVER_NS or HAND_OVER_BYTES. Calling into Python for every chunk cost more than a hop.
 *   A callback that raises is reported (sys.unraisablehook) and forwarding goes on: the proxy never dies of what
 *   passes through it.
 * - Flow control per direction: while a chunk of one direction waits for its receiver (EAGAIN), that direction's
 *   sender is not read; the other direction goes on. At most one chunk (READ_SIZE) per direction is held.
 * - A FIN read from a side, once everything before it was sent: on_eof(side), which passes the FIN on (network.py
 *   does the shutdown); a true result means the connection is closing and the loop returns.
 * - A failed recv or send returns (side, errno): the side whose socket failed. A readable wake fd (the proxy's
 *   teardown) returns None at once. Both directions ended: None.
 * - Sockets come in non-blocking; nothing here closes or shuts down a socket.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <errno.h>
#include <poll.h>
#include <sched.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define READ_SIZE 65536
#define HAND_OVER_NS 20000000LL   /* 20 ms: the oldest copy kept waits at most about this long for on_data */
#define HAND_OVER_BYTES (1 << 20) /* or until so many bytes are kept */

struct way { /* one direction: bytes read from src, sent to dst */
    int src, dst;
    int side;    /* 1: client -> target (network.py's side True), 0: target -> client */
    int reading; /* src has not sent its FIN yet */
    int ended;   /* FIN passed on */
    char *buf;
    size_t off, len; /* the chunk held back: buf[off:len] not sent yet */
};

static long long now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long long)t.tv_sec * 1000000000LL + t.tv_nsec;
}

/* The copies kept for the recorder: records of [side (1 byte)][time (double)][length (size_t)][bytes]. */
struct kept {
    char *buf;
    size_t len, cap, count;
    long long first; /* now_ns() of the oldest record kept */
};

static int keep(struct kept *k, int side, const char *data, size_t n) {
    size_t need = 1 + sizeof(double) + sizeof(size_t) + n;
    if (k->len + need > k->cap) {
        size_t cap = k->cap ? k->cap : 65536;
        while (cap < k->len + need) cap *= 2;
        char *buf = realloc(k->buf, cap);
        if (buf == NULL) return -1;
        k->buf = buf, k->cap = cap;
    }
    struct timespec t;
    clock_gettime(CLOCK_REALTIME, &t);
    double when = (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
    char *p = k->buf + k->len;
    *p = (char)side;
    memcpy(p + 1, &when, sizeof when);
    memcpy(p + 1 + sizeof when, &n, sizeof n);
    memcpy(p + 1 + sizeof when + sizeof n, data, n);
    if (k->count++ == 0) k->first = now_ns();
    k->len += need;
    return 0;
}

/* The kept copies as a list of (side, time, bytes) (with the GIL), and the store emptied; NULL on no memory. */
static PyObject *kept_list(struct kept *k) {
    PyObject *list = PyList_New((Py_ssize_t)k->count);
    if (list == NULL) return NULL;
    const char *p = k->buf;
    for (size_t i = 0; i < k->count; i++) {
        double when;
        size_t n;
        memcpy(&when, p + 1, sizeof when);
        memcpy(&n, p + 1 + sizeof when, sizeof n);
        PyObject *item =
            Py_BuildValue("(Ody#)", *p ? Py_True : Py_False, when, p + 1 + sizeof when + sizeof n, (Py_ssize_t)n);
        if (item == NULL) {
            Py_DECREF(list);
            return NULL;
        }
        PyList_SET_ITEM(list, (Py_ssize_t)i, item);
        p += 1 + sizeof when + sizeof n + n;
    }
    k->len = k->count = 0;
    return list;
}

/* Call back into Python (the GIL is taken and given back): on_data with the kept copies (when there are any),
 * then fn(side) unless fn is NULL; fn's result's truth, or 0 after reporting an error. */
static int call(PyThreadState **ts, struct kept *k, PyObject *on_data, PyObject *fn, int side) {
    if (k->count == 0 && fn == NULL) return 0;
    PyEval_RestoreThread(*ts);
    if (k->count) {
        PyObject *list = kept_list(k), *res = list ? PyObject_CallOneArg(on_data, list) : NULL;
        if (res == NULL) PyErr_WriteUnraisable(on_data);
        Py_XDECREF(res);
        Py_XDECREF(list);
        k->len = k->count = 0; /* what could not be handed over is dropped (reported): forwarding goes on */
        PyErr_Clear();
    }
    PyObject *res = fn ? PyObject_CallFunction(fn, "O", side ? Py_True : Py_False) : NULL;
    int truth = 0;
    if (res == NULL) {
        if (fn) PyErr_WriteUnraisable(fn);
    } else {
        truth = PyObject_IsTrue(res) > 0;
        Py_DECREF(res);
    }
    PyErr_Clear();
    *ts = PyEval_SaveThread();
    return truth;
}

/* Send what `w` holds; 1 when it moved bytes, 0 when the receiver is full or nothing was held, -1 on a failure. */
static int push(struct way *w) {
    int moved = 0;
    while (w->off < w->len) {
        ssize_t k = send(w->dst, w->buf + w->off, w->len - w->off, MSG_DONTWAIT | MSG_NOSIGNAL);
        if (k > 0) {
            w->off += (size_t)k;
            moved = 1;
        } else if (k < 0 && errno == EINTR) {
            continue;
        } else if (k < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            return moved;
        } else {
            if (k == 0) errno = EPIPE;
            return -1;
        }
    }
    w->off = w->len = 0;
    return moved;
}

/* What to wait for: fds[0] the wake fd, fds[1] the client's socket, fds[2] the target's; a socket with nothing to
 * wait for is left out (fd -1), so that a peer's hang-up on a way that waits for its other end is not a busy loop. */
static void interest(struct pollfd fds[3], int wake, int client, int target, const struct way ways[2]) {
    fds[0] = (struct pollfd){wake, POLLIN, 0};
    fds[1] = (struct pollfd){client, 0, 0};
    fds[2] = (struct pollfd){target, 0, 0};
    for (int i = 0; i < 2; i++) {
        const struct way *w = &ways[i];
        struct pollfd *src = &fds[w->src == client ? 1 : 2], *dst = &fds[w->dst == client ? 1 : 2];
        if (w->len)
            dst->events |= POLLOUT;
        else if (w->reading)
            src->events |= POLLIN;
    }
    for (int i = 1; i < 3; i++)
        if (fds[i].events == 0) fds[i].fd = -1;
}

static PyObject *run(PyObject *self, PyObject *args) {
    (void)self;
    int client, target, wake;
    long long spin_us;
    PyObject *on_data, *on_eof;
    if (!PyArg_ParseTuple(args, "iiiLOO:run", &client, &target, &wake, &spin_us, &on_data, &on_eof)) return NULL;
    if (!PyCallable_Check(on_data) || !PyCallable_Check(on_eof)) {
        PyErr_SetString(PyExc_TypeError, "run: on_data and on_eof must be callable");
        return NULL;
    }
    struct way ways[2] = {
        {client, target, 1, 1, 0, malloc(READ_SIZE), 0, 0},
        {target, client, 0, 1, 0, malloc(READ_SIZE), 0, 0},
    };
    if (ways[0].buf == NULL || ways[1].buf == NULL) {
        free(ways[0].buf);
        free(ways[1].buf);
        return PyErr_NoMemory();
    }
    long long spin_ns = spin_us * 1000LL, last = now_ns();
    int failed_side = -1, failed_errno = 0;
    struct kept kept = {NULL, 0, 0, 0, 0};
    PyThreadState *ts = PyEval_SaveThread();
    for (;;) {
        int moved = 0;
        for (int i = 0; i < 2 && failed_side < 0; i++) {
            struct way *w = &ways[i];
            if (w->len) { /* a chunk held back: its receiver first */
                int r = push(w);
                if (r < 0) failed_side = !w->side, failed_errno = errno;
                moved |= r > 0;
            }
            if (w->len == 0 && w->reading && failed_side < 0) {
                ssize_t n = recv(w->src, w->buf, READ_SIZE, MSG_DONTWAIT);
                if (n > 0) {
                    if (keep(&kept, w->side, w->buf, (size_t)n) < 0) { /* no memory: hand over, keep again */
                        call(&ts, &kept, on_data, NULL, 0);
                        (void)keep(&kept, w->side, w->buf, (size_t)n); /* failing again: not recorded */
                    }
                    w->off = 0, w->len = (size_t)n, moved = 1;
                    if (push(w) < 0) failed_side = !w->side, failed_errno = errno;
                } else if (n == 0) {
                    w->reading = 0;
                } else if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
                    failed_side = w->side, failed_errno = errno;
                }
            }
        }
        if (failed_side >= 0) break;
        int closing = 0;
        for (int i = 0; i < 2 && !closing; i++) {
            struct way *w = &ways[i];
            if (!w->reading && !w->ended && w->len == 0) {
                w->ended = 1;
                closing = call(&ts, &kept, on_data, on_eof, w->side);
            }
        }
        if (closing || (ways[0].ended && ways[1].ended)) break;
        if (moved) {
            last = now_ns();
            if (kept.count && (kept.len >= HAND_OVER_BYTES || last - kept.first >= HAND_OVER_NS))
                call(&ts, &kept, on_data, NULL, 0);
            continue;
        }
        struct pollfd fds[3];
        if (now_ns() - last < spin_ns) {
            /* spin: look without waiting (one poll for both sockets and the wake fd), yield the CPU between looks */
            interest(fds, wake, client, target, ways);
            int ready;
            while ((ready = poll(fds, 3, 0)) == 0 && now_ns() - last < spin_ns) sched_yield();
            if (ready > 0 && fds[0].revents) break;
            if (ready != 0) continue;
        }
        call(&ts, &kept, on_data, NULL, 0);        /* idle: the recorder's turn */
        interest(fds, wake, client, target, ways); /* sleep until a socket is ready for what its ways wait for */
        if (poll(fds, 3, -1) < 0 && errno != EINTR) {
            failed_side = 1, failed_errno = errno;
            break;
        }
        if (fds[0].revents) break;
        last = now_ns();
    }
    call(&ts, &kept, on_data, NULL, 0);
    PyEval_RestoreThread(ts);
    free(kept.buf);
    free(ways[0].buf);
    free(ways[1].buf);
    if (failed_side < 0) Py_RETURN_NONE;
    return Py_BuildValue("(Oi)", failed_side ? Py_True : Py_False, failed_errno);
}

static PyMethodDef methods[] = {
    {"run", run, METH_VARARGS,
     "run(client_fd, target_fd, wake_fd, spin_us, on_data, on_eof) -> None | (side, errno): forward one "
     "connection both ways until both ends passed a FIN, on_eof says it is closing, wake_fd is readable, or a "
     "socket fails (side True: the client's)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, .m_name = "_forward", .m_doc = NULL, .m_size = -1, .m_methods = methods,
};

PyMODINIT_FUNC PyInit__forward(void) {
    return PyModule_Create(&module);
}
