/* The fuzzer's plain single in C: one case on a fresh connection, written whole with our FIN, read to the close.
 *
 * Rules (fuzz/single.py, fuzz/poller.py and fuzz/lanes.py are the only callers; the Python ``single.Single`` is the
 * fallback and the oracle, tests/fuzz/test_single.py holds the two to the same verdicts):
 * - Single(pool, host, port, data, budget) opens a non-blocking socket, connects, writes ``data`` whole and shuts
 *   its write side (our FIN) at once where loopback allows it (it nearly always does), else when the socket
 *   becomes writable (start=False: made, not connected; a Run starts it). It then reads until the target closes
 *   (or resets, or refuses); the caller ends it at its deadline (timeout()). It keeps only what the verdict
 *   needs: the bytes received (rx, got), how it ended (refused, closed, timed_out, reset), when our FIN went and
 *   when it ended (monotonic seconds, as Python's time.monotonic), and the order of its writes among all writes
 *   of the campaign (next_write()).
 * - Pool is one epoll for the lanes: a Single given a pool registers its own socket there (its pointer as the
 *   event's data) and is driven inside poll() without a Python call; Python's own flights register their sockets
 *   with register()/modify()/unregister() and poll() hands back their (fd, events) as select.epoll does. A
 *   closed socket leaves the epoll by itself; a Single closes its socket when it ends (or is freed).
 * - Run(pool, depth) is one port's plain singles in bulk (fuzz/lanes.py): Singles made with start=False are added
 *   in their order (led, chain: others may wait behind it, allowance: its budget beyond the base deadline) and
 *   started by the run as the lanes would - a fresh connection each, up to ``depth`` on the port while the last
 *   one started is connected, sent whole and chains; a waiting one's deadline from its turn (from the one before
 *   it, restarted when the port's head finishes); the allowances of the other Runs' singles (and of Python's
 *   units on other ports, set_others) lent to it and its own granted to theirs, SHARED_UNITS of the largest at
 *   most. poll() times them out and goes on without Python until a Run has REPORT singles finished in port order
 *   (or fewer, once it stopped or has nothing on the port), is hungry for more, Python's sockets have events or
 *   the timeout passed. A single not admitted (refused, or led and nothing back) or past its deadline stops the
 *   run: nothing more starts (unstarted() gives the rest back).
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
#define SHARED_UNITS 2 /* allowances of units started on other ports a single gets at most (inflight.SHARED_UNITS) */
#define REPORT 8       /* singles a Run finishes before poll() hands back to Python */
#define LOW 4          /* a hungry Run asks Python for more when fewer wait to start */
#define TAG_FD 1u      /* epoll data of a Python flight's socket: (fd << 1) | 1; a Single's is its (aligned) pointer */

static const unsigned char HEADER[4] = {0xFF, 0x01, 0xFE, 0x02};
static long long writes = 0; /* one order over every write of every flight (flight.Flight.sends) */

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* ------------------------------------------------------------------------------------------------ the pool */

#define MAX_RUNS 16 /* ports with a Run at once */

struct Run;

typedef struct {
    PyObject_HEAD int ep;
    struct Run *runs[MAX_RUNS]; /* the Runs on this epoll (each holds the pool; it leaves when freed) */
    int nruns;
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
    /* in a Run: where to connect once its turn comes, and what the lanes' rules need */
    struct sockaddr_storage addr;
    socklen_t addrlen;
    double allowance, shared, largest; /* s of its budget beyond the base deadline; granted by other ports; */
    char led, chain, behind;           /* opens with the lead; others may wait behind it; waited behind one */
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

static int single_address(Single *s, const char *host, int port) {
    if (parse_address(host, port, &s->addr, &s->addrlen) == 0) return 0;
    PyErr_Format(PyExc_ValueError, "not a numeric address: %s", host);
    return -1;
}

/* Connect, and write at once where loopback allows it. */
static int single_open(Single *s) {
    s->fd = socket(s->addr.ss_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (s->fd < 0) {
        PyErr_SetFromErrno(PyExc_OSError);
        return -1;
    }
    if (PyBytes_GET_SIZE(s->data) > NAGLE_FREE) {
        int one = 1;
        setsockopt(s->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    }
    if (connect(s->fd, (struct sockaddr *)&s->addr, s->addrlen) < 0 && errno != EINPROGRESS) {
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
    static char *kw[] = {"pool", "host", "port", "data", "budget", "start", NULL};
    PyObject *pool, *data;
    const char *host;
    int port, start = 1;
    double budget;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "OsiSd|p", kw, &pool, &host, &port, &data, &budget, &start)) return -1;
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
    if (single_address(s, host, port) < 0) return -1;
    if (!start) return 0; /* a Run starts it in its turn */
    if (single_open(s) < 0) return -1;
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
    {"behind", T_BOOL, offsetof(Single, behind), READONLY, "connected behind another of its Run (pipelined)"},
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

/* ------------------------------------------------------------------------------------------------ a run */

/* The plain singles the lanes hand one port at once, in their order: started as the lanes would start them (a
 * fresh connection each; while the last one started is connected, has sent all and owes nothing but statuses,
 * up to ``depth`` on the port; a waiting one's deadline from its turn), finished in port order (``take``). */
typedef struct Run {
    PyObject_HEAD Pool *pool;
    Single **items; /* [taken, popped): finished, for Python; [popped, started): on the port; then waiting */
    Py_ssize_t n, cap, taken, popped, started, reported_starts;
    int depth;
    char halted, hungry;
    double *others; /* (deadline, allowance) of the units of other ports that Python drives */
    Py_ssize_t nothers;
} Run;

static double clamp_lend(double deadline, double allowance, double now) {
    double left = deadline - now < allowance ? deadline - now : allowance;
    return left > 0 ? left : 0;
}

/* What the singles of ``r`` on the port lend a unit started elsewhere now (their allowances, no more than the
 * time they have left), and the grant of that unit's allowance ``mine`` to each (SHARED_UNITS of the largest). */
static double run_lend(Run *r, double mine, double now) {
    double lent = 0;
    for (Py_ssize_t i = r->popped; i < r->started; i++) {
        Single *t = r->items[i];
        if (t->done) continue;
        lent += clamp_lend(t->deadline, t->allowance, now);
        if (mine > t->largest) t->largest = mine;
        double grant = SHARED_UNITS * t->largest - t->shared;
        grant = grant < mine ? grant : mine;
        if (grant > 0) t->deadline += grant, t->shared += grant;
    }
    return lent;
}

/* Its turn has come: the deadline from now (behind the last one on the port: from that one's), the allowances of
 * the other ports' units, then the connect. */
static void run_start(Run *r, Single *s, double now) {
    Single *last = r->started > r->popped ? r->items[r->started - 1] : NULL;
    s->started = now;
    s->behind = last != NULL;
    s->deadline = (last != NULL ? last->deadline : now) + s->budget;
    for (int j = 0; j < r->pool->nruns; j++)
        if (r->pool->runs[j] != r) s->deadline += run_lend(r->pool->runs[j], s->allowance, now);
    for (Py_ssize_t i = 0; i < r->nothers; i++) s->deadline += clamp_lend(r->others[2 * i], r->others[2 * i + 1], now);
    r->started++;
    if (single_open(s) < 0) {
        PyErr_Clear(); /* no socket to be had: it ends at once, closed unanswered (not admitted) */
        single_end(s, 0, 1, 0);
        return;
    }
    single_enrol(s);
}

static int may_start(Run *r) {
    if (r->halted || r->started >= r->n) return 0;
    Py_ssize_t on_port = r->started - r->popped;
    if (on_port == 0) return 1;
    Single *last = r->items[r->started - 1];
    return on_port < r->depth && last->chain && last->connected && !last->sending;
}

/* A single not admitted (refused, or led and nothing back) or past its deadline stops the run: Python decides. */
static int stops_run(Single *s) {
    return s->refused || s->timed_out || (s->led && s->got == 0);
}

/* Deadlines, the port's finished head(s) (the clocks of the ones behind restart), then what may start. */
static void run_advance(Run *r, double now) {
    for (Py_ssize_t i = r->popped; i < r->started; i++)
        if (!r->items[i]->done && now >= r->items[i]->deadline) single_end(r->items[i], 0, 0, 1);
    while (1) {
        int popped = 0;
        while (r->popped < r->started && r->items[r->popped]->done) {
            if (stops_run(r->items[r->popped])) r->halted = 1;
            r->popped++, popped = 1;
        }
        if (popped) {
            double t = now;
            for (Py_ssize_t i = r->popped; i < r->started; i++) t += r->items[i]->budget, r->items[i]->deadline = t;
        }
        if (!may_start(r)) return;
        run_start(r, r->items[r->started], now);
    }
}

static int run_wants_python(Run *r) {
    Py_ssize_t ready = r->popped - r->taken;
    if (ready >= REPORT || (ready > 0 && (r->halted || r->popped == r->started))) return 1;
    return r->hungry && !r->halted && r->n - r->started < LOW;
}

static double runs_nearest(Pool *p, double until) {
    for (int j = 0; j < p->nruns; j++) {
        Run *r = p->runs[j];
        for (Py_ssize_t i = r->popped; i < r->started; i++)
            if (!r->items[i]->done && r->items[i]->deadline < until) until = r->items[i]->deadline;
    }
    return until;
}

static int runs_advance(Pool *p, double now) {
    int wants = 0;
    for (int j = 0; j < p->nruns; j++) {
        run_advance(p->runs[j], now);
        wants |= run_wants_python(p->runs[j]);
    }
    return wants;
}

static int run_init(Run *r, PyObject *args, PyObject *kwds) {
    static char *kw[] = {"pool", "depth", NULL};
    PyObject *pool;
    int depth;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "O!i", kw, &PoolType, &pool, &depth)) return -1;
    Pool *p = (Pool *)pool;
    if (r->pool != NULL || p->nruns >= MAX_RUNS) {
        PyErr_SetString(PyExc_RuntimeError, "a Run is made once, at most 16 on a pool");
        return -1;
    }
    r->pool = (Pool *)Py_NewRef(pool);
    r->depth = depth < 1 ? 1 : depth;
    p->runs[p->nruns++] = r;
    return 0;
}

static PyObject *run_new(PyTypeObject *type, PyObject *args, PyObject *kwds) {
    (void)args, (void)kwds;
    return type->tp_alloc(type, 0);
}

static void run_dealloc(Run *r) {
    Pool *p = r->pool;
    for (int j = 0; p != NULL && j < p->nruns; j++)
        if (p->runs[j] == r) p->runs[j] = p->runs[--p->nruns];
    for (Py_ssize_t i = r->taken; i < r->n; i++) Py_DECREF(r->items[i]);
    PyMem_Free(r->items);
    PyMem_Free(r->others);
    Py_XDECREF(p);
    Py_TYPE(r)->tp_free((PyObject *)r);
}

/* The finished ones go; the rest move to the front. */
static void run_compact(Run *r) {
    if (r->taken == 0) return;
    memmove(r->items, r->items + r->taken, (size_t)(r->n - r->taken) * sizeof(Single *));
    r->n -= r->taken, r->popped -= r->taken, r->started -= r->taken;
    r->reported_starts = r->reported_starts > r->taken ? r->reported_starts - r->taken : 0;
    r->taken = 0;
}

static PyObject *run_add(Run *r, PyObject *args) {
    PyObject *single;
    int led, chain;
    double allowance;
    if (!PyArg_ParseTuple(args, "O!ppd", &SingleType, &single, &led, &chain, &allowance)) return NULL;
    Single *s = (Single *)single;
    if (s->fd >= 0 || s->done || s->pool != r->pool) {
        PyErr_SetString(PyExc_ValueError, "a Run takes a Single made on its pool with start=False");
        return NULL;
    }
    run_compact(r);
    if (r->n == r->cap) {
        Py_ssize_t cap = r->cap ? 2 * r->cap : 32;
        Single **more = PyMem_Realloc(r->items, (size_t)cap * sizeof(Single *));
        if (more == NULL) return PyErr_NoMemory();
        r->items = more, r->cap = cap;
    }
    s->led = (char)led, s->chain = (char)chain, s->allowance = allowance;
    r->items[r->n++] = (Single *)Py_NewRef(single);
    Py_RETURN_NONE;
}

static PyObject *singles_list(Run *r, Py_ssize_t from, Py_ssize_t to) {
    PyObject *out = PyList_New(to - from);
    for (Py_ssize_t i = from; out != NULL && i < to; i++) PyList_SET_ITEM(out, i - from, (PyObject *)r->items[i]);
    return out;
}

static PyObject *run_take(Run *r, PyObject *Py_UNUSED(ignored)) {
    PyObject *out = singles_list(r, r->taken, r->popped); /* the list takes the run's references */
    if (out != NULL) r->taken = r->popped;
    return out;
}

static PyObject *run_unstarted(Run *r, PyObject *Py_UNUSED(ignored)) {
    PyObject *out = singles_list(r, r->started, r->n);
    if (out != NULL) r->n = r->started;
    return out;
}

static PyObject *run_new_starts(Run *r, PyObject *Py_UNUSED(ignored)) {
    Py_ssize_t from = r->reported_starts > r->taken ? r->reported_starts : r->taken;
    PyObject *out = PyList_New(0);
    for (Py_ssize_t i = from; out != NULL && i < r->started; i++) {
        PyObject *a = PyFloat_FromDouble(r->items[i]->allowance);
        if (a == NULL || PyList_Append(out, a) < 0) Py_CLEAR(out);
        Py_XDECREF(a);
    }
    r->reported_starts = r->started;
    return out;
}

static PyObject *run_lend_py(Run *r, PyObject *args) {
    double mine;
    if (!PyArg_ParseTuple(args, "d", &mine)) return NULL;
    return PyFloat_FromDouble(run_lend(r, mine, now_s()));
}

static PyObject *run_set_others(Run *r, PyObject *args) {
    PyObject *seq;
    if (!PyArg_ParseTuple(args, "O", &seq)) return NULL;
    PyObject *fast = PySequence_Fast(seq, "others: (deadline, allowance) pairs");
    if (fast == NULL) return NULL;
    Py_ssize_t n = PySequence_Fast_GET_SIZE(fast);
    double *more = PyMem_Realloc(r->others, (size_t)(n ? n : 1) * 2 * sizeof(double));
    if (more == NULL) {
        Py_DECREF(fast);
        return PyErr_NoMemory();
    }
    r->others = more, r->nothers = 0;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *pair = PySequence_Fast_GET_ITEM(fast, i);
        if (!PyArg_ParseTuple(pair, "dd", &more[2 * i], &more[2 * i + 1])) break;
        r->nothers = i + 1;
    }
    Py_DECREF(fast);
    if (PyErr_Occurred()) return NULL;
    Py_RETURN_NONE;
}

static PyObject *run_advance_py(Run *r, PyObject *Py_UNUSED(ignored)) {
    run_advance(r, now_s());
    Py_RETURN_NONE;
}

static PyObject *run_halt(Run *r, PyObject *Py_UNUSED(ignored)) {
    r->halted = 1;
    Py_RETURN_NONE;
}

static PyObject *run_count(Run *r, void *which) {
    Py_ssize_t counts[] = {r->n - r->started, r->started - r->popped, r->popped - r->taken};
    return PyLong_FromSsize_t(counts[(intptr_t)which]);
}

static PyObject *run_active(Run *r, void *Py_UNUSED(closure)) {
    return PyBool_FromLong(r->n > r->taken);
}

static PyMethodDef run_methods[] = {
    {"add", (PyCFunction)run_add, METH_VARARGS, "add(single, led, chain, allowance): the next single of the port."},
    {"take", (PyCFunction)run_take, METH_NOARGS, "The singles finished, in port order (each once)."},
    {"unstarted", (PyCFunction)run_unstarted, METH_NOARGS, "The singles not started, taken out of the run."},
    {"new_starts", (PyCFunction)run_new_starts, METH_NOARGS, "The allowances of the singles started since."},
    {"lend", (PyCFunction)run_lend_py, METH_VARARGS, "lend(mine): a unit started elsewhere: s lent, mine granted."},
    {"set_others", (PyCFunction)run_set_others, METH_VARARGS, "set_others(pairs): other ports' Python units."},
    {"advance", (PyCFunction)run_advance_py, METH_NOARGS, "Deadlines, the port's head, what may start: now."},
    {"halt", (PyCFunction)run_halt, METH_NOARGS, "Start nothing more."},
    {NULL, NULL, 0, NULL},
};

static PyMemberDef run_members[] = {
    {"depth", T_INT, offsetof(Run, depth), 0, "singles on the port at most (1: no pipelining)"},
    {"hungry", T_BOOL, offsetof(Run, hungry), 0, "Python has more singles for it: poll() asks when few wait"},
    {"halted", T_BOOL, offsetof(Run, halted), READONLY, "a single not admitted or past its deadline, or halt()"},
    {NULL, 0, 0, 0, NULL},
};

static PyGetSetDef run_getset[] = {
    {"waiting", (getter)run_count, NULL, "singles not started yet", (void *)0},
    {"flying", (getter)run_count, NULL, "singles on the port (connected, not yet finished in port order)", (void *)1},
    {"ready", (getter)run_count, NULL, "singles finished, not taken yet", (void *)2},
    {"active", (getter)run_active, NULL, "anything waiting, on the port or not taken", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

static PyTypeObject RunType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "pltf.fuzz._singles.Run",
    .tp_basicsize = sizeof(Run),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "The plain singles of one port, started and finished in C.",
    .tp_new = run_new,
    .tp_init = (initproc)run_init,
    .tp_dealloc = (destructor)run_dealloc,
    .tp_methods = run_methods,
    .tp_members = run_members,
    .tp_getset = run_getset,
};

/* ------------------------------------------------------------------------------------------------ poll */

static void drive(Single *s, uint32_t events) {
    Py_INCREF(s);
    if (events & EPOLLOUT) single_writable(s);
    if ((events & ~(uint32_t)EPOLLOUT) && !s->done) single_readable(s);
    Py_DECREF(s);
}

/* Drive the Singles that are ready; append the (fd, events) of Python's sockets to ``out``. */
static int python_events(struct epoll_event *ev, int n, PyObject *out) {
    for (int i = 0; i < n; i++) {
        if (!(ev[i].data.u64 & TAG_FD)) {
            drive((Single *)ev[i].data.ptr, ev[i].events);
            continue;
        }
        PyObject *pair = Py_BuildValue("(iI)", (int)(ev[i].data.u64 >> 1), ev[i].events);
        int bad = pair == NULL || PyList_Append(out, pair) < 0;
        Py_XDECREF(pair);
        if (bad) return -1;
    }
    return 0;
}

/* poll(timeout s): wait, drive the Singles that are ready, hand back the (fd, events) of Python's sockets - or,
 * with Runs on the pool, go on until Python has events, a Run wants Python (finished singles, or it is hungry)
 * or the timeout has passed. */
static PyObject *pool_poll(Pool *self, PyObject *args) {
    double timeout;
    if (!PyArg_ParseTuple(args, "d", &timeout)) return NULL;
    double now = now_s(), end = timeout < 0 ? now + 1e9 : now + timeout;
    PyObject *out = PyList_New(0);
    struct epoll_event ev[MAX_EVENTS];
    while (out != NULL && !runs_advance(self, now)) {
        double wait = runs_nearest(self, end) - now;
        int ms = wait <= 0 ? 0 : (int)(wait * 1000.0 + 0.999); /* rounded up, as select.epoll.poll */
        int n;
        Py_BEGIN_ALLOW_THREADS n = epoll_wait(self->ep, ev, MAX_EVENTS, ms);
        Py_END_ALLOW_THREADS if (n < 0 && errno != EINTR) {
            Py_DECREF(out);
            return PyErr_SetFromErrno(PyExc_OSError);
        }
        if (n > 0 && python_events(ev, n, out) < 0) Py_CLEAR(out);
        now = now_s();
        if (out == NULL || PyList_GET_SIZE(out) > 0 || now >= end || self->nruns == 0 || n < 0) break;
    }
    if (out != NULL && self->nruns > 0) runs_advance(self, now_s());
    return out;
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
    if (PyType_Ready(&PoolType) < 0 || PyType_Ready(&SingleType) < 0 || PyType_Ready(&RunType) < 0) return NULL;
    PyObject *m = PyModule_Create(&module);
    if (m == NULL) return NULL;
    if (PyModule_AddObjectRef(m, "Pool", (PyObject *)&PoolType) < 0 ||
        PyModule_AddObjectRef(m, "Single", (PyObject *)&SingleType) < 0 ||
        PyModule_AddObjectRef(m, "Run", (PyObject *)&RunType) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
