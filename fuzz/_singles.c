/* The fuzzer's plain single in C: one case on a fresh connection, written whole with our FIN, read to the close.
 *
 * Rules (fuzz/single.py and fuzz/poller.py are the only callers; the Python ``single.Single`` is the fallback and
 * the oracle, tests/fuzz/test_single.py holds the two to the same verdicts):
 * - Single(pool, host, port, data, budget) opens a non-blocking socket, connects, writes ``data`` whole and shuts
 *   its write side (our FIN) at once where loopback allows it (it nearly always does), else when the socket
 *   becomes writable. It then reads until the target closes (or resets, or refuses); the caller ends it at its
 *   deadline (timeout()). It keeps only what the verdict needs: the bytes received (rx, got), how it ended
 *   (refused, closed, timed_out, reset), when our FIN went and when it ended (monotonic seconds, as Python's
 *   time.monotonic), and the order of its writes among all writes of the campaign (next_write()).
 * - Pool is one epoll for the lanes: a Single given a pool registers its own socket there (its pointer as the
 *   event's data) and is driven inside poll() without a Python call; Python's own flights register their sockets
 *   with register()/modify()/unregister() and poll() hands back their (fd, events) as select.epoll does. A
 *   closed socket leaves the epoll by itself; a Single closes its socket when it ends (or is freed).
 * - frames() walks rx by the wire format (guide 6.2, "Message Format": the header m_cHeader = 255, 1, 254, 2,
 *   then "the number of data bytes (N)" in four bytes, MSB first, then the N data bytes, the first of them the
 *   telegram id): the ids of the whole frames and whether the stream is nothing but whole frames. Strict decoding
 *   of the replies stays in Python (pltf.fuzz.single.decode_replies), remembered by their bytes.
 * - Nothing here raises for what the peer does; only a socket that cannot be created raises OSError.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdint.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define NAGLE_FREE 1024  /* bytes: larger writes go with TCP_NODELAY (as flight.NAGLE_FREE) */
#define RECV_CHUNK 65536 /* bytes per recv (as target.RECV) */
#define MAX_EVENTS 64
#define TAG_FD 1u /* epoll data of a Python flight's socket: (fd << 1) | 1; a Single's is its (aligned) pointer */

static const unsigned char HEADER[4] = {0xFF, 0x01, 0xFE, 0x02};
static long long writes = 0; /* one order over every write of every flight (flight.Flight.sends) */

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* ------------------------------------------------------------------------------------------------ the pool */

typedef struct {
    PyObject_HEAD int ep;
} Pool;

static int pool_init(Pool *self, PyObject *args, PyObject *kwds) {
    static char *kw[] = {NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "", kw)) return -1;
    self->ep = epoll_create1(EPOLL_CLOEXEC);
    if (self->ep < 0) {
        PyErr_SetFromErrno(PyExc_OSError);
        return -1;
    }
    return 0;
}

static PyObject *pool_new(PyTypeObject *type, PyObject *args, PyObject *kwds) {
    (void)args, (void)kwds;
    Pool *self = (Pool *)type->tp_alloc(type, 0);
    if (self != NULL) self->ep = -1;
    return (PyObject *)self;
}

static void pool_dealloc(Pool *self) {
    if (self->ep >= 0) close(self->ep);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *pool_close(Pool *self, PyObject *Py_UNUSED(ignored)) {
    if (self->ep >= 0) close(self->ep);
    self->ep = -1;
    Py_RETURN_NONE;
}

static PyObject *pool_ctl(Pool *self, PyObject *args, int op) {
    int fd;
    unsigned int mask = 0;
    if (!PyArg_ParseTuple(args, op == EPOLL_CTL_DEL ? "i" : "iI", &fd, &mask)) return NULL;
    struct epoll_event ev = {.events = mask, .data.u64 = ((uint64_t)(unsigned)fd << 1) | TAG_FD};
    if (epoll_ctl(self->ep, op, fd, &ev) < 0) return PyErr_SetFromErrno(PyExc_OSError);
    Py_RETURN_NONE;
}

static PyObject *pool_register(Pool *self, PyObject *args) {
    return pool_ctl(self, args, EPOLL_CTL_ADD);
}

static PyObject *pool_modify(Pool *self, PyObject *args) {
    return pool_ctl(self, args, EPOLL_CTL_MOD);
}

static PyObject *pool_unregister(Pool *self, PyObject *args) {
    return pool_ctl(self, args, EPOLL_CTL_DEL);
}

/* ------------------------------------------------------------------------------------------------ a single */

typedef struct {
    PyObject_HEAD int fd;
    Pool *pool; /* the epoll its socket is on (NULL: driven by select through readable()/writable()) */
    PyObject *data;
    Py_ssize_t pos;
    char *rx;
    Py_ssize_t got, cap;
    long long *sends; /* (order, end offset) pairs */
    Py_ssize_t nsends, sends_cap;
    double started, deadline, budget, fin_at, end_at; /* fin_at, end_at: -1 until then */
    char done, refused, timed_out, closed, reset, connected, sending, polled_out;
} Single;

static void single_end(Single *s, int refused, int closed, int timed_out) {
    if (s->done) return;
    s->done = 1, s->sending = 0;
    s->refused = (char)refused, s->closed = (char)closed, s->timed_out = (char)timed_out;
    s->end_at = now_s();
    if (s->fd >= 0) close(s->fd); /* it leaves the epoll by itself */
    s->fd = -1;
}

static void single_want(Single *s, int out) {
    if (s->pool == NULL || s->pool->ep < 0 || s->fd < 0 || s->polled_out == out) return;
    struct epoll_event ev = {.events = EPOLLIN | (out ? EPOLLOUT : 0), .data.ptr = s};
    epoll_ctl(s->pool->ep, EPOLL_CTL_MOD, s->fd, &ev);
    s->polled_out = (char)out;
}

static int note_send(Single *s) {
    if (s->nsends == s->sends_cap) {
        Py_ssize_t cap = s->sends_cap ? 2 * s->sends_cap : 2;
        long long *more = PyMem_Realloc(s->sends, (size_t)cap * 2 * sizeof(long long));
        if (more == NULL) return -1;
        s->sends = more, s->sends_cap = cap;
    }
    s->sends[2 * s->nsends] = writes++;
    s->sends[2 * s->nsends + 1] = s->pos;
    s->nsends++;
    return 0;
}

/* One write of what is left; our FIN once all of it went (as single.Single._send). */
static void single_send(Single *s) {
    Py_ssize_t len = PyBytes_GET_SIZE(s->data);
    ssize_t n = send(s->fd, PyBytes_AS_STRING(s->data) + s->pos, (size_t)(len - s->pos), MSG_NOSIGNAL);
    if (n < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return;
        if (errno == ECONNREFUSED) return single_end(s, 1, 0, 0);
        if (errno == ENOTCONN || errno == EINPROGRESS || errno == EALREADY) return;
        s->connected = 1, s->sending = 0; /* the peer is gone; read what it said before it went */
        s->reset = errno == ECONNRESET || errno == EPIPE;
        return single_want(s, 0);
    }
    s->connected = 1;
    s->pos += n;
    if (note_send(s) < 0) PyErr_Clear();
    if (s->pos < len) return single_want(s, 1);
    s->sending = 0;
    s->fin_at = now_s();
    shutdown(s->fd, SHUT_WR);
    single_want(s, 0);
}

static int socket_error(int fd) {
    int code = 0;
    socklen_t n = sizeof(code);
    if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &code, &n) < 0) return errno;
    return code;
}

static void single_writable(Single *s) {
    if (s->done) return;
    if (!s->connected) {
        int code = socket_error(s->fd);
        if (code) return single_end(s, code == ECONNREFUSED, code != ECONNREFUSED, 0);
        s->connected = 1;
    }
    if (s->sending) single_send(s);
}

static int take(Single *s, const char *buf, Py_ssize_t n) {
    if (s->got + n > s->cap) {
        Py_ssize_t cap = s->cap ? s->cap : 256;
        while (cap < s->got + n) cap *= 2;
        char *more = PyMem_Realloc(s->rx, (size_t)cap);
        if (more == NULL) return -1;
        s->rx = more, s->cap = cap;
    }
    memcpy(s->rx + s->got, buf, (size_t)n);
    s->got += n;
    return 0;
}

/* Read what is there, to the peer's close (as single.Single.readable, without a poll round between them). */
static void single_readable(Single *s) {
    static char buf[RECV_CHUNK];
    while (!s->done) {
        ssize_t n = recv(s->fd, buf, sizeof(buf), 0);
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return;
        if (n < 0 && errno == ECONNREFUSED) return single_end(s, 1, 0, 0);
        if (n < 0) s->reset = errno == ECONNRESET || errno == EPIPE;
        if (n > 0) {
            s->connected = 1;
            if (take(s, buf, n) < 0) PyErr_Clear();
            if (n < (ssize_t)sizeof(buf)) continue; /* most likely the close (or EAGAIN) next */
            return;
        }
        if (!s->connected && socket_error(s->fd) == ECONNREFUSED) return single_end(s, 1, 0, 0);
        s->connected = 1;
        return single_end(s, 0, 1, 0);
    }
}

static int parse_address(const char *host, int port, struct sockaddr_storage *addr, socklen_t *len) {
    memset(addr, 0, sizeof(*addr));
    if (strchr(host, ':') != NULL) {
        struct sockaddr_in6 *a = (struct sockaddr_in6 *)addr;
        a->sin6_family = AF_INET6, a->sin6_port = htons((uint16_t)port), *len = sizeof(*a);
        return inet_pton(AF_INET6, host, &a->sin6_addr) == 1 ? 0 : -1;
    }
    struct sockaddr_in *a = (struct sockaddr_in *)addr;
    a->sin_family = AF_INET, a->sin_port = htons((uint16_t)port), *len = sizeof(*a);
    return inet_pton(AF_INET, host, &a->sin_addr) == 1 ? 0 : -1;
}

static int single_open(Single *s, const char *host, int port) {
    struct sockaddr_storage addr;
    socklen_t len;
    if (parse_address(host, port, &addr, &len) < 0) {
        PyErr_Format(PyExc_ValueError, "not a numeric address: %s", host);
        return -1;
    }
    s->fd = socket(addr.ss_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (s->fd < 0) {
        PyErr_SetFromErrno(PyExc_OSError);
        return -1;
    }
    if (PyBytes_GET_SIZE(s->data) > NAGLE_FREE) {
        int one = 1;
        setsockopt(s->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    }
    if (connect(s->fd, (struct sockaddr *)&addr, len) < 0 && errno != EINPROGRESS) {
        single_end(s, errno == ECONNREFUSED, errno != ECONNREFUSED, 0);
        return 0;
    }
    s->sending = 1;
    single_send(s); /* on loopback the handshake is done when connect returns */
    return 0;
}

static void single_enrol(Single *s) {
    if (s->pool == NULL || s->pool->ep < 0 || s->fd < 0) return;
    s->polled_out = s->sending;
    struct epoll_event ev = {.events = EPOLLIN | (s->sending ? EPOLLOUT : 0), .data.ptr = s};
    if (epoll_ctl(s->pool->ep, EPOLL_CTL_ADD, s->fd, &ev) < 0 && errno == EEXIST)
        epoll_ctl(s->pool->ep, EPOLL_CTL_MOD, s->fd, &ev);
}

static PyTypeObject PoolType;

static int single_init(Single *s, PyObject *args, PyObject *kwds) {
    static char *kw[] = {"pool", "host", "port", "data", "budget", NULL};
    PyObject *pool, *data;
    const char *host;
    int port;
    double budget;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "OsiSd", kw, &pool, &host, &port, &data, &budget)) return -1;
    if (s->data != NULL || s->fd >= 0) {
        PyErr_SetString(PyExc_RuntimeError, "a Single runs once");
        return -1;
    }
    if (pool != Py_None && !PyObject_TypeCheck(pool, &PoolType)) {
        PyErr_SetString(PyExc_TypeError, "pool: a Pool or None");
        return -1;
    }
    Py_INCREF(data);
    s->data = data;
    s->pool = pool == Py_None ? NULL : (Pool *)Py_NewRef(pool);
    s->budget = budget;
    s->started = now_s();
    s->deadline = s->started + budget;
    if (single_open(s, host, port) < 0) return -1;
    single_enrol(s);
    return 0;
}

static PyObject *single_new(PyTypeObject *type, PyObject *args, PyObject *kwds) {
    (void)args, (void)kwds;
    Single *s = (Single *)type->tp_alloc(type, 0);
    if (s == NULL) return NULL;
    s->fd = -1;
    s->fin_at = s->end_at = -1.0;
    return (PyObject *)s;
}

static void single_dealloc(Single *s) {
    if (s->fd >= 0) close(s->fd);
    Py_XDECREF(s->data);
    Py_XDECREF(s->pool);
    PyMem_Free(s->rx);
    PyMem_Free(s->sends);
    Py_TYPE(s)->tp_free((PyObject *)s);
}

static PyObject *single_readable_py(Single *s, PyObject *Py_UNUSED(ignored)) {
    if (s->fd >= 0) single_readable(s);
    Py_RETURN_NONE;
}

static PyObject *single_writable_py(Single *s, PyObject *Py_UNUSED(ignored)) {
    if (s->fd >= 0) single_writable(s);
    Py_RETURN_NONE;
}

static PyObject *single_timeout(Single *s, PyObject *Py_UNUSED(ignored)) {
    single_end(s, 0, 0, 1);
    Py_RETURN_NONE;
}

static PyObject *single_fileno(Single *s, PyObject *Py_UNUSED(ignored)) {
    return PyLong_FromLong(s->fd);
}

static PyObject *single_rx(Single *s, void *Py_UNUSED(closure)) {
    return PyBytes_FromStringAndSize(s->rx ? s->rx : "", s->got);
}

static PyObject *single_sends(Single *s, void *Py_UNUSED(closure)) {
    PyObject *out = PyList_New(s->nsends);
    for (Py_ssize_t i = 0; out != NULL && i < s->nsends; i++) {
        PyObject *pair = Py_BuildValue("(Ln)", s->sends[2 * i], (Py_ssize_t)s->sends[2 * i + 1]);
        if (pair == NULL) Py_CLEAR(out);
        if (out != NULL) PyList_SET_ITEM(out, i, pair);
    }
    return out;
}

static PyObject *optional_time(double t) {
    if (t < 0) Py_RETURN_NONE;
    return PyFloat_FromDouble(t);
}

static PyObject *single_fin_at(Single *s, void *Py_UNUSED(closure)) {
    return optional_time(s->fin_at);
}

static PyObject *single_end_at(Single *s, void *Py_UNUSED(closure)) {
    return optional_time(s->end_at);
}

/* The ids of the whole frames of rx (guide 6.2: header, N MSB first, N data bytes, the id first) and whether rx is
 * nothing but whole frames. */
static PyObject *single_frames(Single *s, PyObject *Py_UNUSED(ignored)) {
    const unsigned char *p = (const unsigned char *)s->rx;
    Py_ssize_t at = 0, n = 0;
    char ids[256];
    while (at + 8 <= s->got && memcmp(p + at, HEADER, 4) == 0) {
        uint32_t len = (uint32_t)p[at + 4] << 24 | (uint32_t)p[at + 5] << 16 | (uint32_t)p[at + 6] << 8 | p[at + 7];
        if (len == 0 || (Py_ssize_t)len > s->got - at - 8) break;
        if (n < (Py_ssize_t)sizeof(ids)) ids[n++] = (char)p[at + 8];
        at += 8 + (Py_ssize_t)len;
    }
    return Py_BuildValue("(y#O)", ids, n, at == s->got ? Py_True : Py_False);
}

static PyMethodDef single_methods[] = {
    {"readable", (PyCFunction)single_readable_py, METH_NOARGS, "Read what is there, to the close."},
    {"writable", (PyCFunction)single_writable_py, METH_NOARGS, "The connect's result; the write if still due."},
    {"timeout", (PyCFunction)single_timeout, METH_NOARGS, "End it at its deadline."},
    {"fileno", (PyCFunction)single_fileno, METH_NOARGS, "Its socket (-1 once it ended)."},
    {"frames", (PyCFunction)single_frames, METH_NOARGS, "(ids of rx's whole frames, rx is whole frames only)."},
    {NULL, NULL, 0, NULL},
};

static PyMemberDef single_members[] = {
    {"data", T_OBJECT, offsetof(Single, data), READONLY, "the bytes sent"},
    {"pos", T_PYSSIZET, offsetof(Single, pos), READONLY, "bytes written so far"},
    {"got", T_PYSSIZET, offsetof(Single, got), READONLY, "bytes received"},
    {"started", T_DOUBLE, offsetof(Single, started), READONLY, "monotonic s of the connect"},
    {"deadline", T_DOUBLE, offsetof(Single, deadline), 0, "monotonic s it is ended at"},
    {"budget", T_DOUBLE, offsetof(Single, budget), READONLY, "s from its turn"},
    {"done", T_BOOL, offsetof(Single, done), READONLY, NULL},
    {"refused", T_BOOL, offsetof(Single, refused), READONLY, NULL},
    {"timed_out", T_BOOL, offsetof(Single, timed_out), READONLY, NULL},
    {"closed", T_BOOL, offsetof(Single, closed), READONLY, NULL},
    {"reset", T_BOOL, offsetof(Single, reset), READONLY, NULL},
    {"connected", T_BOOL, offsetof(Single, connected), READONLY, NULL},
    {"sending", T_BOOL, offsetof(Single, sending), READONLY, NULL},
    {NULL, 0, 0, 0, NULL},
};

static PyGetSetDef single_getset[] = {
    {"rx", (getter)single_rx, NULL, "the bytes received", NULL},
    {"sends", (getter)single_sends, NULL, "(order among all writes, end offset) per write", NULL},
    {"fin_at", (getter)single_fin_at, NULL, "monotonic s of our FIN (None: not sent)", NULL},
    {"end_at", (getter)single_end_at, NULL, "monotonic s of its end (None: not yet)", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject SingleType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "pltf.fuzz._singles.Single",
    .tp_basicsize = sizeof(Single),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE,
    .tp_doc = "A plain single on its own connection.",
    .tp_new = single_new,
    .tp_init = (initproc)single_init,
    .tp_dealloc = (destructor)single_dealloc,
    .tp_methods = single_methods,
    .tp_members = single_members,
    .tp_getset = single_getset,
};

/* ------------------------------------------------------------------------------------------------ poll */

static void drive(Single *s, uint32_t events) {
    Py_INCREF(s);
    if (events & EPOLLOUT) single_writable(s);
    if ((events & ~(uint32_t)EPOLLOUT) && !s->done) single_readable(s);
    Py_DECREF(s);
}

static PyObject *python_events(struct epoll_event *ev, int n) {
    PyObject *out = PyList_New(0);
    for (int i = 0; out != NULL && i < n; i++) {
        if (!(ev[i].data.u64 & TAG_FD)) {
            drive((Single *)ev[i].data.ptr, ev[i].events);
            continue;
        }
        PyObject *pair = Py_BuildValue("(iI)", (int)(ev[i].data.u64 >> 1), ev[i].events);
        if (pair == NULL || PyList_Append(out, pair) < 0) Py_CLEAR(out);
        Py_XDECREF(pair);
    }
    return out;
}

/* poll(timeout s): wait, drive the Singles that are ready, hand back the (fd, events) of Python's sockets. */
static PyObject *pool_poll(Pool *self, PyObject *args) {
    double timeout;
    if (!PyArg_ParseTuple(args, "d", &timeout)) return NULL;
    int ms = timeout < 0 ? -1 : (int)(timeout * 1000.0 + 0.999); /* rounded up, as select.epoll.poll */
    struct epoll_event ev[MAX_EVENTS];
    int n;
    Py_BEGIN_ALLOW_THREADS n = epoll_wait(self->ep, ev, MAX_EVENTS, ms);
    Py_END_ALLOW_THREADS if (n < 0) {
        if (errno == EINTR) return PyList_New(0);
        return PyErr_SetFromErrno(PyExc_OSError);
    }
    return python_events(ev, n);
}

static PyObject *next_write(PyObject *Py_UNUSED(module), PyObject *Py_UNUSED(ignored)) {
    return PyLong_FromLongLong(writes++);
}

static PyMethodDef pool_methods[] = {
    {"register", (PyCFunction)pool_register, METH_VARARGS, "register(fd, mask): a Python flight's socket."},
    {"modify", (PyCFunction)pool_modify, METH_VARARGS, "modify(fd, mask)"},
    {"unregister", (PyCFunction)pool_unregister, METH_VARARGS, "unregister(fd)"},
    {"poll", (PyCFunction)pool_poll, METH_VARARGS, "poll(timeout): the Python sockets' (fd, events)."},
    {"close", (PyCFunction)pool_close, METH_NOARGS, "Close the epoll."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject PoolType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "pltf.fuzz._singles.Pool",
    .tp_basicsize = sizeof(Pool),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "One epoll for the lanes: Singles driven in C, Python's sockets handed back.",
    .tp_new = pool_new,
    .tp_init = (initproc)pool_init,
    .tp_dealloc = (destructor)pool_dealloc,
    .tp_methods = pool_methods,
};

static PyMethodDef module_methods[] = {
    {"next_write", (PyCFunction)next_write, METH_NOARGS, "The next place in the order of all writes."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, .m_name = "_singles",        .m_doc = "The fuzzer's plain single in C (fuzz/singles.py).",
    .m_size = -1,          .m_methods = module_methods,
};

PyMODINIT_FUNC PyInit__singles(void) {
    if (PyType_Ready(&PoolType) < 0 || PyType_Ready(&SingleType) < 0) return NULL;
    PyObject *m = PyModule_Create(&module);
    if (m == NULL) return NULL;
    if (PyModule_AddObjectRef(m, "Pool", (PyObject *)&PoolType) < 0 ||
        PyModule_AddObjectRef(m, "Single", (PyObject *)&SingleType) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
