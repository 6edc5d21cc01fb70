/* The fuzzer's drawing core in C: a block of cases of the common generators and mutators, and the strict survey.
 *
 * Rules (fuzz/draw.py compiles the tables and is the only caller):
 * - setup() is called once with flat tables built from the spec: per request telegram its id, name, whether it is
 *   answered, and its fields (wire type, repeat, constant, allowed values sorted, range, role); the STRINGS table;
 *   the origin names; the Case class and its Delivery objects. Nothing here knows a telegram by name.
 * - block() draws the cases of one block from its own generator (xoshiro256** seeded by splitmix64 from
 *   (seed, block)), so case i is a function of (seed, i, what was learnt). A case this core does not draw (an XML
 *   document, a corpus input as the mutation seed) is handed back as (intent, 64-bit seed) for Python to draw.
 * - survey() decodes a request stream strictly, as pltf.spec.codec.TelegramDecoder does (the tests hold the two
 *   equal): KEEP, CLOSE or PARTIAL and the answered ids; forbidden() finds the ids fuzz.wire.forbidden_ids finds.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------------ generator */

typedef struct {
    uint64_t s[4];
} Rng;

static uint64_t splitmix(uint64_t *x) {
    uint64_t z = (*x += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static void rng_seed(Rng *r, uint64_t seed, uint64_t block) {
    uint64_t x = seed;
    x = splitmix(&x) ^ block;
    for (int i = 0; i < 4; i++) r->s[i] = splitmix(&x);
}

static uint64_t rotl(uint64_t x, int k) {
    return (x << k) | (x >> (64 - k));
}

static uint64_t next64(Rng *r) {
    uint64_t *s = r->s, out = rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
    s[2] ^= s[0], s[3] ^= s[1], s[1] ^= s[2], s[0] ^= s[3], s[2] ^= t, s[3] = rotl(s[3], 45);
    return out;
}

static double unit(Rng *r) {
    return (double)(next64(r) >> 11) * 0x1.0p-53;
}

static uint64_t below(Rng *r, uint64_t n) { /* 0 .. n-1 (n > 0) */
    return (uint64_t)(((unsigned __int128)next64(r) * n) >> 64);
}

static int64_t between(Rng *r, int64_t lo, int64_t hi) { /* lo .. hi, both included */
    return lo + (int64_t)below(r, (uint64_t)(hi - lo) + 1);
}

#define CHOICE(r, arr) ((arr)[below((r), sizeof(arr) / sizeof((arr)[0]))])

static int weighted(Rng *r, const double *cum, int n) { /* index by running sums of the weights */
    double x = unit(r) * cum[n - 1];
    for (int i = 0; i < n - 1; i++)
        if (x < cum[i]) return i;
    return n - 1;
}

/* ------------------------------------------------------------------------------------------------ buffers */

typedef struct {
    unsigned char *p;
    Py_ssize_t n, cap;
} Buf;

static int grow(Buf *b, Py_ssize_t more) {
    if (b->n + more <= b->cap) return 0;
    Py_ssize_t cap = b->cap ? b->cap : 256;
    while (cap < b->n + more) cap *= 2;
    unsigned char *p = PyMem_Realloc(b->p, (size_t)cap);
    if (!p) return -1;
    b->p = p, b->cap = cap;
    return 0;
}

static int put(Buf *b, const void *data, Py_ssize_t n) {
    if (grow(b, n) < 0) return -1;
    if (n) memcpy(b->p + b->n, data, (size_t)n);
    b->n += n;
    return 0;
}

/* guide 6.2: "The data types are sent in the Motorola format with the most significant byte (MSB) first." */
static int put_be(Buf *b, uint64_t v, int width) {
    unsigned char w[8];
    for (int i = 0; i < width; i++) w[i] = (unsigned char)(v >> (8 * (width - 1 - i)));
    return put(b, w, width);
}

static uint64_t get_be(const unsigned char *p, int width) {
    uint64_t v = 0;
    for (int i = 0; i < width; i++) v = v << 8 | p[i];
    return v;
}

/* guide 6.2, figure 11: m_cHeader[0..3] = 255, 1, 254, 2; then "Number of data bytes (N)", MSB first */
static const unsigned char HEADER[4] = {0xFF, 0x01, 0xFE, 0x02};
#define OVERHEAD 8

static int put_frame(Buf *b, const unsigned char *data, Py_ssize_t n, uint32_t declared) {
    return put(b, HEADER, 4) || put_be(b, declared, 4) || put(b, data, n) ? -1 : 0;
}

/* ------------------------------------------------------------------------------------------------ tables */

enum { K_BYTE, K_BOOL, K_INT16, K_INT, K_DOUBLE, K_STRING, K_XML, K_GROUP };
enum { ROLE_PLAIN, ROLE_KEY, ROLE_STATION };
static const int WIDTH[] = {1, 1, 2, 4, 8, 0, 0, 0};

typedef struct Field {
    int kind, repeat, role, has_const, has_range, nallowed, nsub;
    int64_t cval, lo, hi, *allowed; /* allowed: sorted */
    char name[48];
    struct Field *sub;
    Py_ssize_t min_size, item_size; /* the fewest bytes on the wire; of a group's item: the sum of its fields' */
} Field;

typedef struct {
    int known, opaque, answered, has_xml, move_path, nf;
    Field *f;
    PyObject *name;
} Tele;

static Tele T[256];
static int CLOSE_SOCKET = -1;
static PyObject *STRINGS, *ORIGINS, *CASE, *DELIVERIES, *EXPECTS, *EMPTY, *GET_STATUS;
static PyObject *BIG[2];
static int ready;

static int64_t as_i64(PyObject *o) {
    return (int64_t)PyLong_AsLongLong(o);
}

/* (kind, repeat, const|None, allowed|None, (lo, hi)|None, subfields, role, name) */
static int read_field(PyObject *t, Field *f) {
    PyObject *cval, *allowed, *range, *sub;
    const char *name;
    if (!PyArg_ParseTuple(t, "iiOOOOis", &f->kind, &f->repeat, &cval, &allowed, &range, &sub, &f->role, &name))
        return -1;
    snprintf(f->name, sizeof f->name, "%s", name);
    f->has_const = cval != Py_None;
    if (f->has_const) f->cval = as_i64(cval);
    if (allowed != Py_None) {
        f->nallowed = (int)PyTuple_GET_SIZE(allowed);
        f->allowed = PyMem_Calloc((size_t)f->nallowed + 1, sizeof(int64_t));
        for (int i = 0; i < f->nallowed; i++) f->allowed[i] = as_i64(PyTuple_GET_ITEM(allowed, i));
    }
    f->has_range = range != Py_None;
    if (f->has_range && !PyArg_ParseTuple(range, "LL", &f->lo, &f->hi)) return -1;
    f->nsub = (int)PyList_GET_SIZE(sub);
    f->sub = PyMem_Calloc((size_t)f->nsub + 1, sizeof(Field));
    f->min_size = f->kind >= K_STRING ? 4 : WIDTH[f->kind] * (f->repeat ? f->repeat : 1);
    Py_ssize_t item = 0;
    for (int i = 0; i < f->nsub; i++) {
        if (read_field(PyList_GET_ITEM(sub, i), &f->sub[i]) < 0) return -1;
        item += f->sub[i].min_size;
    }
    f->item_size = item;
    return PyErr_Occurred() ? -1 : 0;
}

static PyObject *setup(PyObject *Py_UNUSED(self), PyObject *args) {
    PyObject *teles, *big;
    if (!PyArg_ParseTuple(args, "O!iO!O!OO!O!SO!", &PyList_Type, &teles, &CLOSE_SOCKET, &PyTuple_Type, &STRINGS,
                          &PyTuple_Type, &ORIGINS, &CASE, &PyTuple_Type, &DELIVERIES, &PyTuple_Type, &EXPECTS,
                          &GET_STATUS, &PyTuple_Type, &big))
        return NULL;
    if (ready) Py_RETURN_NONE; /* once per process: the tables do not change */
    for (Py_ssize_t k = 0; k < PyList_GET_SIZE(teles); k++) {
        PyObject *fields, *name;
        int id, opaque, answered, move_path;
        if (!PyArg_ParseTuple(PyList_GET_ITEM(teles, k), "iUiiiO!", &id, &name, &opaque, &answered, &move_path,
                              &PyList_Type, &fields))
            return NULL;
        Tele *t = &T[id & 0xFF];
        t->known = 1, t->opaque = opaque, t->answered = answered, t->move_path = move_path;
        t->name = Py_NewRef(name);
        t->nf = (int)PyList_GET_SIZE(fields);
        t->f = PyMem_Calloc((size_t)t->nf + 1, sizeof(Field));
        for (int i = 0; i < t->nf; i++) {
            if (read_field(PyList_GET_ITEM(fields, i), &t->f[i]) < 0) return NULL;
            t->has_xml |= t->f[i].kind == K_XML;
        }
    }
    for (int i = 0; i < 2; i++) BIG[i] = Py_NewRef(PyTuple_GET_ITEM(big, i));
    Py_INCREF(STRINGS), Py_INCREF(ORIGINS), Py_INCREF(CASE), Py_INCREF(DELIVERIES), Py_INCREF(EXPECTS);
    Py_INCREF(GET_STATUS);
    EMPTY = PyTuple_New(0);
    ready = 1;
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------------------------------ the survey */

enum { KEEP, CLOSE, PARTIAL };
#define MAX_LENGTH (16 * 1024 * 1024) /* pltf.spec.codec.DEFAULT_MAX_LENGTH (erratum E-WIRE-004) */

static int allowed_has(const Field *f, int64_t v) {
    int lo = 0, hi = f->nallowed - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2;
        if (f->allowed[mid] == v) return 1;
        if (f->allowed[mid] < v)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return 0;
}

static int64_t read_scalar(const unsigned char *p, int kind) { /* BYTE/BOOL unsigned, INT16/INT signed */
    uint64_t v = get_be(p, WIDTH[kind]);
    if (kind == K_INT16) return (int16_t)v;
    if (kind == K_INT) return (int32_t)v;
    return (int64_t)v;
}

/* the fields of one telegram from b[*pos] to end, as the generated decoders of pltf.spec.compiler: 0 or -1 */
static int decode_fields(const Field *fs, int nf, const unsigned char *b, Py_ssize_t *pos, Py_ssize_t end) {
    for (int i = 0; i < nf; i++) {
        const Field *f = &fs[i];
        if (f->kind < K_STRING) {
            int n = f->repeat ? f->repeat : 1, w = WIDTH[f->kind];
            if (*pos + (Py_ssize_t)n * w > end) return -1; /* Truncated */
            for (int k = 0; k < n && f->kind != K_DOUBLE; k++) {
                int64_t v = read_scalar(b + *pos + k * w, f->kind);
                if (f->has_const && v != f->cval) return -1;
                if (f->allowed && !allowed_has(f, v)) return -1;
                if (f->has_range && (v < f->lo || v > f->hi)) return -1;
            }
            *pos += (Py_ssize_t)n * w;
            continue;
        }
        if (*pos + 4 > end) return -1;
        int64_t n = (int32_t)get_be(b + *pos, 4); /* a length or count is INT: a negative one is refused */
        *pos += 4;
        if (f->kind != K_GROUP) {
            if (n < 0 || n > end - *pos) return -1; /* LengthMismatch */
            *pos += n;
            continue;
        }
        if (n < 0 || n * f->item_size > end - *pos) return -1;
        for (int64_t k = 0; k < n; k++)
            if (decode_fields(f->sub, f->nsub, b, pos, end) < 0) return -1;
    }
    return 0;
}

/* the kind; ids[] gets the answered ids (at most cap are kept, *nids counts them all) */
static int survey_bytes(const unsigned char *b, Py_ssize_t len, uint8_t *ids, Py_ssize_t cap, Py_ssize_t *nids) {
    Py_ssize_t pos = 0;
    int expect = KEEP;
    *nids = 0;
    while (pos < len) {
        Py_ssize_t avail = len - pos;
        if (avail < OVERHEAD) /* a header's prefix waits for more; anything else is a bad header */
            return memcmp(b + pos, HEADER, (size_t)(avail < 4 ? avail : 4)) ? CLOSE
                                                                            : (expect == CLOSE ? CLOSE : PARTIAL);
        if (memcmp(b + pos, HEADER, 4)) return CLOSE;
        uint64_t length = get_be(b + pos + 4, 4);
        if (length > MAX_LENGTH) return CLOSE;
        if ((uint64_t)avail < OVERHEAD + length) return expect == CLOSE ? CLOSE : PARTIAL;
        Py_ssize_t data = pos + OVERHEAD, end = data + (Py_ssize_t)length, p = data + 1;
        if (!length || !T[b[data]].known) return CLOSE; /* empty or unknown telegram */
        const Tele *t = &T[b[data]];
        if (!t->opaque && (decode_fields(t->f, t->nf, b, &p, end) < 0 || p != end)) return CLOSE;
        if (t->answered) {
            if (*nids < cap) ids[*nids] = b[data];
            ++*nids;
        } else if (b[data] == CLOSE_SOCKET) {
            expect = CLOSE;
        }
        pos = end;
    }
    return expect;
}

/* fuzz.wire.forbidden_ids: frames walked by their length, and every header anywhere (a resynchronising reader) */
static int has_forbidden(const unsigned char *b, Py_ssize_t len, const unsigned char *mask) {
    for (Py_ssize_t pos = 0; pos + OVERHEAD <= len && !memcmp(b + pos, HEADER, 4);) {
        uint64_t n = get_be(b + pos + 4, 4);
        if (!n || (uint64_t)(len - pos - OVERHEAD) < n) break;
        if (mask[b[pos + OVERHEAD]]) return 1;
        pos += OVERHEAD + (Py_ssize_t)n;
    }
    const unsigned char *p = b, *end = b + len;
    while ((p = memmem(p, (size_t)(end - p), HEADER, 4)) != NULL) {
        if (p + OVERHEAD < end && mask[p[OVERHEAD]]) return 1;
        p++;
    }
    return 0;
}

#define MAX_IDS (1 << 16)
static uint8_t IDS[MAX_IDS]; /* answered ids of the case surveyed (the interpreter lock is held) */

static PyObject *ids_tuple(const uint8_t *ids, Py_ssize_t n) {
    PyObject *t = PyTuple_New(n);
    for (Py_ssize_t i = 0; t && i < n; i++) PyTuple_SET_ITEM(t, i, PyLong_FromLong(ids[i]));
    return t;
}

static PyObject *survey(PyObject *Py_UNUSED(self), PyObject *args) {
    Py_buffer data;
    if (!PyArg_ParseTuple(args, "y*", &data)) return NULL;
    Py_ssize_t n;
    int kind = survey_bytes(data.buf, data.len, IDS, MAX_IDS, &n);
    PyBuffer_Release(&data);
    if (n > MAX_IDS) Py_RETURN_NONE; /* too many for this path: the caller asks the codec */
    PyObject *t = ids_tuple(IDS, n);
    return t ? Py_BuildValue("(ON)", PyTuple_GET_ITEM(EXPECTS, kind), t) : NULL;
}

static PyObject *forbidden(PyObject *Py_UNUSED(self), PyObject *args) {
    Py_buffer data, mask;
    if (!PyArg_ParseTuple(args, "y*y*", &data, &mask)) return NULL;
    int found = mask.len >= 256 && has_forbidden(data.buf, data.len, mask.buf);
    PyBuffer_Release(&data), PyBuffer_Release(&mask);
    return PyBool_FromLong(found);
}

/* ------------------------------------------------------------------------------------------------ drawing */

#define MAX_FRAMES 8
enum { G_BOUNDARY, G_HOSTILE, G_ANY_ID, G_LENGTH, G_XML, N_GEN };
enum {
    M_BIT_FLIP,
    M_BYTE_SET,
    M_HEADER,
    M_LENGTH_LIE,
    M_TRUNCATE,
    M_INSERT_DELETE,
    M_INT_FIELD,
    M_SPLICE,
    M_BYTEWISE,
    M_SLOW,
    M_HALF_CLOSE,
    M_FLOOD,
    N_MUT
};
/* ORIGINS, in this order (fuzz/draw.py passes them) */
enum {
    O_BOUNDARY,
    O_HOSTILE,
    O_ANY_ID,
    O_LENGTH,
    O_BIT_FLIP,
    O_BYTE_SET,
    O_HEADER,
    O_LENGTH_LIE,
    O_TRUNCATE,
    O_DELETE,
    O_INSERT,
    O_INT_FIELD,
    O_SPLICE,
    O_BYTEWISE,
    O_SLOW,
    O_HALF_CLOSE,
    O_FLOOD
};
enum { D_WHOLE, D_BYTEWISE, D_SLOW2, D_SLOW3, D_SLOW4 }; /* DELIVERIES */
/* intents handed back to Python (fuzz/draw.py INTENTS) */
enum { I_TELEGRAM, I_LENGTH, I_XML, I_POOL, I_FALLBACK };

static const int64_t I32_MIN = -2147483648LL, I32_MAX = 2147483647LL;
static const int64_t INT_EDGES[] = {
    0, 1, -1, 2, 255, 256, 32767, 32768, 65535, 65536, 2147483647LL, -2147483648LL, 2147483646LL, -2147483647LL};
static const int64_t BOUNDARY[][6] = {{0, 1, 0x7F, 0x80, 0xFE, 0xFF}, {0, 1, 0, 1, 0, 1}, {0, 1, -1, 32767, -32768, 0}};
static const int NBOUNDARY[] = {6, 2, 5};
static const char *HOSTILE_DOUBLES[] = {"7ff8000000000000", "7ff0000000000000", "fff0000000000000", "7ff0000000000001",
                                        "fff8000000000000"};
static const unsigned char INTERESTING[] = {0x00, 0x01, 0x7F, 0x80, 0xFE, 0xFF};

typedef struct { /* what the campaign learnt (pltf.fuzz.knowledge) and what may be sent */
    PyObject *keys, *stations;
    int64_t pose[3];
    const unsigned char *mask;
    const uint8_t *picks, *free_ids;
    const double *pick_cum, *gen_cum, *mut_cum;
    int npicks, nfree, pool;
    double big_share;
} Ctx;

typedef struct { /* a case being drawn */
    Buf f[MAX_FRAMES];
    int nf, origin, delivery, half_close, repeat;
    PyObject *telegram;
    char note[256];
    size_t used; /* of note */
} Draft;

static void note(Draft *d, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    if (d->used < sizeof d->note) {
        int n = vsnprintf(d->note + d->used, sizeof d->note - d->used, fmt, ap);
        d->used = n < 0 ? d->used : d->used + (size_t)n;
        if (d->used > sizeof d->note - 1) d->used = sizeof d->note - 1;
    }
    va_end(ap);
}

static void sep(Draft *d) {
    if (d->used) note(d, "; ");
}

static int put_scalar(Buf *b, int kind, int64_t v) {
    if (kind == K_DOUBLE) {
        double x = (double)v;
        uint64_t u;
        memcpy(&u, &x, 8);
        return put_be(b, u, 8);
    }
    return put_be(b, (uint64_t)v, WIDTH[kind]);
}

static int64_t valid_scalar(Rng *r, const Field *f) {
    if (f->allowed) return f->allowed[below(r, (uint64_t)f->nallowed)];
    if (f->has_range) {
        int64_t lo = f->lo < I32_MIN ? I32_MIN : f->lo, hi = f->hi > I32_MAX ? I32_MAX : f->hi;
        int64_t pick[3] = {lo, hi, between(r, lo, hi)};
        return CHOICE(r, pick);
    }
    if (f->kind == K_INT) return unit(r) < 0.6 ? CHOICE(r, INT_EDGES) : (int32_t)next64(r);
    if (f->kind == K_DOUBLE) return between(r, -1000000, 1000000);
    int k = f->kind == K_INT16 ? 2 : f->kind;
    if (unit(r) < 0.6) return BOUNDARY[k][below(r, (uint64_t)NBOUNDARY[k])];
    return f->kind == K_INT16 ? (int16_t)next64(r) : (int64_t)below(r, 256);
}

static int64_t hostile_scalar(Rng *r, const Field *f) {
    int64_t picks[16];
    int n = 0;
    if (f->allowed) {
        picks[n++] = f->allowed[f->nallowed - 1] + 1, picks[n++] = f->allowed[0] - 1;
        picks[n++] = 0xFF, picks[n++] = -1;
    }
    if (f->has_range) picks[n++] = f->lo - 1, picks[n++] = f->hi + 1;
    if (f->kind == K_INT)
        for (int i = 9; i < 14; i++) picks[n++] = INT_EDGES[i];
    else
        picks[n++] = 0xFF, picks[n++] = 0x80;
    return picks[below(r, (uint64_t)n)];
}

static int put_hex(Buf *b, const char *hex) { /* a DOUBLE's exact bit pattern */
    for (int i = 0; i < 8; i++) {
        unsigned int byte;
        sscanf(hex + 2 * i, "%2x", &byte);
        unsigned char c = (unsigned char)byte;
        if (put(b, &c, 1) < 0) return -1;
    }
    return 0;
}

static PyObject *pick_string(Rng *r, const Field *f, const Ctx *c) {
    PyObject *known = f->role == ROLE_KEY ? c->keys : f->role == ROLE_STATION ? c->stations : NULL;
    double share = f->role == ROLE_KEY ? 0.8 : 0.7;
    if (known && PyList_GET_SIZE(known) && unit(r) < share)
        return PyList_GET_ITEM(known, (Py_ssize_t)below(r, (uint64_t)PyList_GET_SIZE(known)));
    if (unit(r) < 0.01) return BIG[below(r, 2)];
    return PyTuple_GET_ITEM(STRINGS, (Py_ssize_t)below(r, (uint64_t)PyTuple_GET_SIZE(STRINGS)));
}

static int put_value(Rng *r, Buf *b, const Field *f, int hostile, Draft *d);

static int put_group(Rng *r, Buf *b, const Field *f, int hostile, Draft *d, const Ctx *c, int move_path) {
    static const int64_t COUNTS[] = {0, 1, 2, 8, 100};
    int64_t n = CHOICE(r, COUNTS), declared = n;
    if (hostile) {
        int64_t lies[] = {-1, I32_MIN, I32_MAX, n + 1, n ? n - 1 : 1, 0x40000000, 0x80000000LL};
        declared = CHOICE(r, lies);
        sep(d), note(d, "%s.count=%d (items %lld)", f->name, (int32_t)(uint32_t)declared, (long long)n);
    }
    if (put_be(b, (uint64_t)declared, 4) < 0) return -1;
    int near = move_path && n && f->nsub == 3 && unit(r) < 0.5; /* CMD_MOVE_PATH near where the robot is */
    for (int64_t k = 0; k < n; k++) {
        if (near) {
            int64_t x = c->pose[0] + between(r, -2000, 2000), y = c->pose[1] + between(r, -2000, 2000);
            if (put_be(b, (uint64_t)x, 4) || put_be(b, (uint64_t)y, 4) || put_be(b, (uint64_t)c->pose[2], 4)) return -1;
            continue;
        }
        for (int i = 0; i < f->nsub; i++)
            if (put_value(r, b, &f->sub[i], 0, d) < 0) return -1;
    }
    return 0;
}

static const Ctx *CTX; /* the context of the block being drawn (strings need the knowledge) */

static int put_value(Rng *r, Buf *b, const Field *f, int hostile, Draft *d) {
    if (f->has_const) return put_scalar(b, f->kind, f->cval);
    if (f->kind == K_GROUP) return put_group(r, b, f, hostile, d, CTX, 0);
    if (f->kind == K_STRING || f->kind == K_XML) {
        PyObject *s = pick_string(r, f, CTX);
        Py_ssize_t len = PyBytes_GET_SIZE(s);
        int64_t declared = len;
        if (hostile) {
            int64_t lies[] = {-1, I32_MIN, 0, len + 1, len - 1, I32_MAX, 0x80000000LL, 0xFFFFFFFFLL};
            declared = CHOICE(r, lies);
            sep(d), note(d, "%s.length=%lld (bytes %zd)", f->name, (long long)declared, len);
        }
        return put_be(b, (uint64_t)declared, 4) || put(b, PyBytes_AS_STRING(s), len) ? -1 : 0;
    }
    int n = f->repeat ? f->repeat : 1;
    if (hostile && f->kind == K_DOUBLE) {
        const char *hex = CHOICE(r, HOSTILE_DOUBLES);
        sep(d), note(d, "%s=%s", f->name, hex);
        for (int k = 0; k < n; k++)
            if (put_hex(b, hex) < 0) return -1;
        return 0;
    }
    if (hostile) {
        int64_t v = hostile_scalar(r, f);
        sep(d), note(d, "%s=%lld", f->name, (long long)v);
        for (int k = 0; k < n; k++)
            if (put_scalar(b, f->kind, v) < 0) return -1;
        return 0;
    }
    for (int k = 0; k < n; k++)
        if (put_scalar(b, f->kind, valid_scalar(r, f)) < 0) return -1;
    return 0;
}

/* the telegram's data (identifier first) with values of the given hostility; notes on the hostile ones */
static int put_telegram(Rng *r, Buf *b, const Tele *t, int id, double hostility, Draft *d) {
    unsigned char ident = (unsigned char)id;
    if (put(b, &ident, 1) < 0) return -1;
    for (int i = 0; i < t->nf; i++) {
        const Field *f = &t->f[i];
        int hostile = !f->has_const && unit(r) < hostility;
        int rc = f->kind == K_GROUP && !f->has_const ? put_group(r, b, f, hostile, d, CTX, t->move_path)
                                                     : put_value(r, b, f, hostile, d);
        if (rc < 0) return -1;
    }
    return 0;
}

static int pick(Rng *r, const Ctx *c) {
    return c->picks[weighted(r, c->pick_cum, c->npicks)];
}

static int random_bytes(Rng *r, Buf *b, Py_ssize_t n) {
    for (Py_ssize_t i = 0; i < n; i++) {
        unsigned char x = (unsigned char)below(r, 256);
        if (put(b, &x, 1) < 0) return -1;
    }
    return 0;
}

static void hex_note(Draft *d, const unsigned char *p, Py_ssize_t n) {
    for (Py_ssize_t i = 0; i < n; i++) note(d, "%02x", p[i]);
}

/* gen.boundary / gen.hostile: one telegram, hostile values at ``hostility``, maybe a lying tail */
static int gen_telegram(Rng *r, Draft *d, int id, double hostility) {
    Buf data = {0};
    const Tele *t = &T[id];
    int rc = put_telegram(r, &data, t, id, hostility, d);
    double tail = unit(r);
    if (!rc && hostility && tail < 0.08) {
        static const int TRAILING[] = {1, 3, 8};
        rc = random_bytes(r, &data, CHOICE(r, TRAILING));
        sep(d), note(d, "trailing bytes");
    } else if (!rc && hostility && tail < 0.16 && data.n > 1) {
        data.n = (Py_ssize_t)between(r, 1, data.n - 1);
        sep(d), note(d, "data cut to %zd bytes", data.n);
    }
    rc = rc || put_frame(&d->f[0], data.p, data.n, (uint32_t)data.n);
    PyMem_Free(data.p);
    d->nf = 1, d->telegram = t->name;
    return rc;
}

static int gen_any_id(Rng *r, Draft *d, const Ctx *c) {
    static const int SIZES[] = {0, 0, 1, 4, 8, 16};
    unsigned char ident = c->free_ids[below(r, (uint64_t)c->nfree)];
    Buf data = {0};
    int rc = put(&data, &ident, 1) || random_bytes(r, &data, CHOICE(r, SIZES));
    note(d, "payload "), hex_note(d, data.p + 1, data.n - 1);
    rc = rc || put_frame(&d->f[0], data.p, data.n, (uint32_t)data.n);
    PyMem_Free(data.p);
    d->nf = 1, d->telegram = NULL;
    d->origin = O_ANY_ID;
    d->repeat = ident; /* the telegram is "id N": named by the caller */
    return rc;
}

static int gen_length(Rng *r, Draft *d, int id) {
    Buf data = {0};
    Draft quiet = {0};
    int rc = put_telegram(r, &data, &T[id], id, 0.0, &quiet);
    int64_t n = data.n, lies[] = {0, n - 1, n + 1, 0x00FFFFFF, 0x7FFFFFFF, 0x80000000LL, 0xFFFFFFFFLL};
    int64_t declared = CHOICE(r, lies);
    note(d, "length=%lld (data %zd)", (long long)declared, data.n);
    rc = rc || put_frame(&d->f[0], data.p, data.n, (uint32_t)declared);
    PyMem_Free(data.p);
    d->nf = 1, d->telegram = T[id].name, d->origin = O_LENGTH;
    return rc;
}

/* ---- mutations of a boundary seed (fuzz/mutate.py: the same mutators, the same notes) */

static int joined(const Draft *d, Buf *out) {
    for (int i = 0; i < d->nf; i++)
        if (put(out, d->f[i].p, d->f[i].n) < 0) return -1;
    return 0;
}

static int split_into(Draft *d, const unsigned char *p, Py_ssize_t end) { /* fuzz.wire.split_frames */
    for (int i = 0; i < d->nf; i++) d->f[i].n = 0;
    Py_ssize_t pos = 0;
    d->nf = 0;
    while (pos + OVERHEAD <= end && !memcmp(p + pos, HEADER, 4) && d->nf < MAX_FRAMES - 2) {
        uint64_t n = get_be(p + pos + 4, 4);
        if ((uint64_t)(end - pos - OVERHEAD) < n) break;
        if (put(&d->f[d->nf++], p + pos, OVERHEAD + (Py_ssize_t)n) < 0) return -1;
        pos += OVERHEAD + (Py_ssize_t)n;
    }
    if (pos < end || !d->nf)
        if (put(&d->f[d->nf++], p + pos, end - pos) < 0) return -1;
    return 0;
}

static int mutate(Rng *r, Draft *d, int m) {
    static const char *LIES[] = {"zero", "one_short", "one_long", "huge", "over_2_31", "max"};
    int i = (int)below(r, (uint64_t)d->nf);
    Buf *f = &d->f[i];
    Py_ssize_t n = f->n;
    switch (m) {
        case M_BIT_FLIP: {
            static const int FLIPS[] = {1, 1, 2, 4};
            int k = CHOICE(r, FLIPS);
            note(d, "frame %d bits ", i);
            for (int j = 0; j < k; j++) {
                Py_ssize_t pos = (Py_ssize_t)below(r, (uint64_t)n);
                int bit = (int)below(r, 8);
                f->p[pos] ^= (unsigned char)(1 << bit);
                note(d, j ? ",%zd:%d" : "%zd:%d", pos, bit);
            }
            d->origin = O_BIT_FLIP;
            return 0;
        }
        case M_BYTE_SET: {
            Py_ssize_t pos = n > OVERHEAD ? (Py_ssize_t)between(r, OVERHEAD, n - 1) : (Py_ssize_t)below(r, (uint64_t)n);
            f->p[pos] = unit(r) < 0.7 ? CHOICE(r, INTERESTING) : (unsigned char)below(r, 256);
            note(d, "frame %d byte %zd=0x%02x", i, pos, f->p[pos]);
            d->origin = O_BYTE_SET;
            return 0;
        }
        case M_HEADER: {
            static const unsigned char REVERSED[4] = {0x02, 0xFE, 0x01, 0xFF};
            int how = (int)below(r, 4);
            Buf b = {0};
            int rc = 0;
            d->origin = O_HEADER;
            if (how == 0) {
                int pos = (int)below(r, 4);
                f->p[pos] ^= (unsigned char)between(r, 1, 255);
                note(d, "frame %d: header byte %d changed", i, pos);
                return 0;
            }
            if (how == 1)
                rc = put(&b, f->p + 4, n - 4);
            else if (how == 2)
                rc = put(&b, HEADER, 4) || put(&b, f->p, n);
            else
                rc = put(&b, REVERSED, 4) || put(&b, f->p + 4, n - 4);
            note(d, "frame %d: header %s", i, how == 1 ? "missing" : how == 2 ? "doubled" : "reversed");
            PyMem_Free(f->p);
            *f = b;
            return rc;
        }
        case M_LENGTH_LIE: {
            int kind = (int)below(r, 6);
            int64_t len = n - OVERHEAD;
            int64_t lies[] = {0,
                              len - 1,
                              len + 1,
                              0x00FFFFFF + (int64_t)below(r, 1 << 24),
                              0x80000000LL + (int64_t)below(r, 1 << 16),
                              0xFFFFFFFFLL};
            uint64_t declared = (uint64_t)lies[kind] & 0xFFFFFFFFu;
            for (int k = 0; k < 4; k++) f->p[4 + k] = (unsigned char)(declared >> (24 - 8 * k));
            note(d, "frame %d length %s", i, LIES[kind]);
            d->origin = O_LENGTH_LIE;
            return 0;
        }
        case M_TRUNCATE: {
            Buf all = {0};
            if (joined(d, &all) < 0) return -1;
            Py_ssize_t cut = all.n > 1 ? (Py_ssize_t)between(r, 1, all.n - 1) : 0;
            note(d, "cut at byte %zd of %zd", cut, all.n);
            int rc = split_into(d, all.p, cut);
            PyMem_Free(all.p);
            d->origin = O_TRUNCATE, d->half_close = 1;
            return rc;
        }
        case M_INSERT_DELETE: {
            Py_ssize_t pos = (Py_ssize_t)below(r, (uint64_t)n + 1);
            Buf b = {0};
            int rc = put(&b, f->p, pos);
            if (unit(r) < 0.5 && n > 1) {
                Py_ssize_t k = pos < n ? (Py_ssize_t)between(r, 1, n - pos < 8 ? n - pos : 8) : 1;
                rc = rc || put(&b, f->p + pos + (pos < n ? k : 0), n - pos - (pos < n ? k : 0));
                note(d, "frame %d: %zd bytes deleted at %zd", i, k, pos);
                d->origin = O_DELETE;
            } else {
                static const int BLOB[] = {1, 2, 4, 8};
                Py_ssize_t start = b.n;
                rc = rc || random_bytes(r, &b, CHOICE(r, BLOB));
                note(d, "frame %d: ", i), hex_note(d, b.p + start, b.n - start), note(d, " inserted at %zd", pos);
                rc = rc || put(&b, f->p + pos, n - pos);
                d->origin = O_INSERT;
            }
            PyMem_Free(f->p);
            *f = b;
            return rc;
        }
        case M_INT_FIELD: {
            static const uint32_t WORDS[] = {0, 0xFFFFFFFF, 0x7FFFFFFF, 0x80000000, 0x00010000, 0xFFFF0000};
            if (n < OVERHEAD + 5) return mutate(r, d, M_LENGTH_LIE);
            Py_ssize_t pos = (Py_ssize_t)between(r, OVERHEAD + 1, n - 4);
            uint32_t v = CHOICE(r, WORDS);
            for (int k = 0; k < 4; k++) f->p[pos + k] = (unsigned char)(v >> (24 - 8 * k));
            note(d, "frame %d: word at %zd = 0x%08x", i, pos, v);
            d->origin = O_INT_FIELD;
            return 0;
        }
        case M_SPLICE: {
            Buf all = {0};
            if (joined(d, &all) < 0) return -1;
            Py_ssize_t len = all.n, a = (Py_ssize_t)between(r, 1, len), b = (Py_ssize_t)between(r, a, 2 * len);
            int rc = grow(&all, len); /* the data twice */
            if (!rc) memcpy(all.p + len, all.p, (size_t)len), all.n = 2 * len;
            for (int k = 0; k < d->nf; k++) d->f[k].n = 0;
            rc = rc || put(&d->f[0], all.p, a) || put(&d->f[1], all.p + b, 2 * len - b);
            PyMem_Free(all.p);
            note(d, "bytes [%zd:%zd] removed", a, b);
            d->nf = 2, d->origin = O_SPLICE;
            return rc;
        }
        case M_BYTEWISE:
        case M_SLOW:
        case M_HALF_CLOSE: {
            Py_ssize_t size = 0;
            for (int k = 0; k < d->nf; k++) size += d->f[k].n;
            if (m == M_BYTEWISE && size > 512) m = M_SLOW; /* mutate.BYTEWISE_MAX */
            if (put(&d->f[d->nf++], PyBytes_AS_STRING(GET_STATUS), PyBytes_GET_SIZE(GET_STATUS)) < 0) return -1;
            if (m == M_BYTEWISE) d->origin = O_BYTEWISE, d->delivery = D_BYTEWISE, note(d, "one write per byte");
            if (m == M_HALF_CLOSE)
                d->origin = O_HALF_CLOSE, d->half_close = 1, note(d, "write side shut after the frames");
            if (m == M_SLOW) {
                int pieces = 2 + (int)below(r, 3);
                d->origin = O_SLOW, d->delivery = D_SLOW2 + pieces - 2, note(d, "%d writes 1 ms apart", pieces);
            }
            return 0;
        }
        default: { /* M_FLOOD */
            static const int COPIES[] = {100, 300, 1000};
            Py_ssize_t size = 0;
            for (int k = 0; k < d->nf; k++) size += d->f[k].n;
            int64_t copies = CHOICE(r, COPIES), fit = (1 << 18) / (size ? size : 1);
            d->repeat = (int)(copies < fit ? copies : fit > 1 ? fit : 1);
            note(d, "%d copies", d->repeat);
            d->origin = O_FLOOD;
            return 0;
        }
    }
}

/* ---- one case */

static void reset(Draft *d) {
    for (int i = 0; i < MAX_FRAMES; i++) d->f[i].n = 0;
    d->nf = 0, d->origin = 0, d->delivery = D_WHOLE, d->half_close = 0, d->repeat = 0, d->telegram = NULL;
    d->used = 0, d->note[0] = 0;
}

static int pick_plain(Rng *r, const Ctx *c) { /* a telegram this core can draw: no XML field */
    for (;;) {
        int id = pick(r, c);
        if (!T[id].has_xml) return id;
    }
}

/* draws into d, or returns an intent (>= 0) with d->repeat the telegram id for Python; -1 error, -2 drawn */
static int draw(Rng *r, Draft *d, const Ctx *c) {
    if (unit(r) < 0.55) { /* schedule.GEN_SHARE */
        int g = weighted(r, c->gen_cum, N_GEN);
        if (g == G_XML) return I_XML;
        if (g == G_ANY_ID) return gen_any_id(r, d, c) < 0 ? -1 : -2;
        int id = pick(r, c);
        d->repeat = id;
        if (g == G_LENGTH) return T[id].has_xml ? I_LENGTH : gen_length(r, d, id) < 0 ? -1 : -2;
        if (T[id].has_xml) {
            d->repeat = id | (g == G_HOSTILE) << 8;
            return I_TELEGRAM;
        }
        d->origin = g == G_HOSTILE ? O_HOSTILE : O_BOUNDARY;
        return gen_telegram(r, d, id, g == G_HOSTILE ? 0.35 : 0.0) < 0 ? -1 : -2;
    }
    if (c->pool && unit(r) < 0.3) return I_POOL;
    Draft extra = {0};
    int id = pick_plain(r, c), rc = gen_telegram(r, d, id, 0.0);
    if (!rc && unit(r) < 0.2) { /* a little valid conversation around it */
        rc = gen_telegram(r, &extra, pick_plain(r, c), 0.0) || put(&d->f[1], extra.f[0].p, extra.f[0].n);
        d->nf = 2;
    }
    PyMem_Free(extra.f[0].p);
    d->telegram = T[id].name, d->used = 0, d->note[0] = 0;
    return rc || mutate(r, d, weighted(r, c->mut_cum, N_MUT)) ? -1 : -2;
}

static int set(PyObject *o, const char *name, PyObject *v) { /* steals v */
    if (!v) return -1;
    PyObject *key = PyUnicode_InternFromString(name);
    int rc = key ? PyObject_GenericSetAttr(o, key, v) : -1;
    Py_XDECREF(key);
    Py_DECREF(v);
    return rc;
}

/* the Case (frozen: its attributes set as dataclasses' __init__ sets them, past __setattr__) */
static PyObject *make_case(Draft *d, int kind, const uint8_t *ids, Py_ssize_t nids, Py_ssize_t size) {
    int copies = d->origin == O_FLOOD ? d->repeat : 1;
    PyObject *frames = PyTuple_New((Py_ssize_t)d->nf * copies), *empty = PyTuple_New(0);
    PyObject *c = frames && empty ? PyBaseObject_Type.tp_new((PyTypeObject *)CASE, empty, NULL) : NULL;
    Py_XDECREF(empty);
    if (!c) {
        Py_XDECREF(frames);
        return NULL;
    }
    for (int i = 0; i < d->nf; i++) {
        PyObject *b = PyBytes_FromStringAndSize((const char *)d->f[i].p, d->f[i].n);
        if (!b) return Py_DECREF(frames), Py_DECREF(c), NULL;
        for (int k = 0; k < copies; k++) PyTuple_SET_ITEM(frames, (Py_ssize_t)k * d->nf + i, Py_NewRef(b));
        Py_DECREF(b);
    }
    PyObject *telegram = d->telegram ? Py_NewRef(d->telegram) : PyUnicode_FromFormat("id %d", d->repeat);
    if (set(c, "frames", frames) || set(c, "origin", Py_NewRef(PyTuple_GET_ITEM(ORIGINS, d->origin))) ||
        set(c, "telegram", telegram) || set(c, "note", PyUnicode_FromStringAndSize(d->note, (Py_ssize_t)d->used)) ||
        set(c, "delivery", Py_NewRef(PyTuple_GET_ITEM(DELIVERIES, d->delivery))) ||
        set(c, "half_close", PyBool_FromLong(d->half_close)) ||
        set(c, "expect", Py_NewRef(PyTuple_GET_ITEM(EXPECTS, d->half_close ? CLOSE : kind))) ||
        set(c, "tags", Py_NewRef(EMPTY)) || set(c, "answered", ids_tuple(ids, nids)) ||
        set(c, "size", PyLong_FromSsize_t(size)))
        return Py_DECREF(c), NULL;
    return c;
}

#define MAX_DRAWS 20       /* schedule.MAX_DRAWS */
#define BIG_CASE (1 << 20) /* schedule.BIG_CASE */

/* a case: a Case, (intent, telegram id, seed) for Python to draw, or NULL */
static PyObject *one(Rng *r, Draft *d, const Ctx *c, Py_ssize_t *dropped) {
    for (int k = 0; k < MAX_DRAWS; k++) {
        reset(d);
        int rc = draw(r, d, c);
        if (rc == -1) return PyErr_NoMemory();
        if (rc >= 0) return Py_BuildValue("(iiK)", rc, d->repeat, (unsigned long long)next64(r));
        Buf all = {0};
        if (joined(d, &all) < 0) return PyErr_NoMemory();
        Py_ssize_t one = all.n, copies = d->origin == O_FLOOD ? d->repeat : 1, nids = 0;
        if (copies > 1 && grow(&all, one * (copies - 1)) < 0) return PyErr_NoMemory();
        for (Py_ssize_t i = 1; i < copies; i++) memcpy(all.p + i * one, all.p, (size_t)one);
        all.n = one * copies;
        int skip = !all.n || (all.n > BIG_CASE && unit(r) >= c->big_share), kind = KEEP;
        if (!skip && has_forbidden(all.p, all.n, c->mask)) skip = 1, ++*dropped;
        if (!skip) kind = survey_bytes(all.p, all.n, IDS, MAX_IDS, &nids);
        PyMem_Free(all.p);
        if (skip) continue;
        if (nids > MAX_IDS) break;
        return make_case(d, kind, IDS, nids, one * copies);
    }
    return Py_BuildValue("(iiK)", I_FALLBACK, 0, 0ULL); /* nothing safe was drawn: the fallback case */
}

static PyObject *block(PyObject *Py_UNUSED(self), PyObject *args) {
    unsigned long long seed, number;
    Py_ssize_t n;
    Py_buffer mask, picks, pick_cum, free_ids, gen_cum, mut_cum;
    Ctx c = {0};
    if (!ready) return PyErr_Format(PyExc_RuntimeError, "_draw.setup() was not called");
    if (!PyArg_ParseTuple(args, "KKny*y*y*y*y*y*O!O!(LLL)pd", &seed, &number, &n, &mask, &picks, &pick_cum, &free_ids,
                          &gen_cum, &mut_cum, &PyList_Type, &c.keys, &PyList_Type, &c.stations, &c.pose[0], &c.pose[1],
                          &c.pose[2], &c.pool, &c.big_share))
        return NULL;
    c.mask = mask.buf, c.picks = picks.buf, c.npicks = (int)picks.len, c.pick_cum = pick_cum.buf;
    c.free_ids = free_ids.buf, c.nfree = (int)free_ids.len, c.gen_cum = gen_cum.buf, c.mut_cum = mut_cum.buf;
    PyObject *out = NULL, *list = PyList_New(n);
    Py_ssize_t dropped = 0;
    if (!list) goto done;
    if (mask.len < 256 || !c.npicks || !c.nfree || gen_cum.len < N_GEN * 8 || mut_cum.len < N_MUT * 8) {
        PyErr_SetString(PyExc_ValueError, "_draw.block: bad tables");
        goto done;
    }
    Rng r;
    Draft d = {0};
    rng_seed(&r, seed, number);
    CTX = &c;
    for (Py_ssize_t i = 0; list && i < n; i++) {
        PyObject *item = one(&r, &d, &c, &dropped);
        if (!item) goto free;
        PyList_SET_ITEM(list, i, item);
    }
    out = Py_BuildValue("(On)", list, dropped);
free:
    for (int i = 0; i < MAX_FRAMES; i++) PyMem_Free(d.f[i].p);
done:
    Py_XDECREF(list);
    PyBuffer_Release(&mask), PyBuffer_Release(&picks), PyBuffer_Release(&pick_cum);
    PyBuffer_Release(&free_ids), PyBuffer_Release(&gen_cum), PyBuffer_Release(&mut_cum);
    return out;
}

static PyMethodDef METHODS[] = {
    {"setup", setup, METH_VARARGS,
     "setup(telegrams, close_socket, strings, origins, case, deliveries, expects, "
     "get_status, big): the tables, once per process"},
    {"block", block, METH_VARARGS,
     "block(seed, number, n, mask, picks, pick_cum, free_ids, gen_cum, mut_cum, "
     "keys, stations, pose, pool, big_share) -> (items, dropped)"},
    {"survey", survey, METH_VARARGS, "survey(data) -> (kind, answered ids) | None (too many ids)"},
    {"forbidden", forbidden, METH_VARARGS, "forbidden(data, mask) -> a forbidden id in data"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef MODULE = {
    PyModuleDef_HEAD_INIT, .m_name = "_draw", .m_doc = NULL, .m_size = -1, .m_methods = METHODS,
};

PyMODINIT_FUNC PyInit__draw(void) {
    return PyModule_Create(&MODULE);
}
